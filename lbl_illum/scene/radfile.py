"""Radiance scene files (``.rad``, ``.mat``) as geometry and materials.

A Radiance scene description is a list of primitives, each ``modifier type identifier``
followed by three argument lists (strings, integers, reals), each given by its count
(Radiance reference manual, "Scene Description"; ``src/common/readobj.c``); ``#`` starts
a comment, and a line beginning with ``!`` is a command whose output Radiance reads.

**Surfaces** (:func:`rad_surfaces`), one :class:`~lbl_illum.scene.geometry.MeshPart` per
modifier, which the scene file maps to a material like an OBJ ``usemtl`` name:

* ``polygon``: triangulated as drawn by the even–odd rule that Radiance's own ray test
  uses (:mod:`lbl_illum.scene.polygons`), so keyhole polygons keep their holes;
* ``sphere``/``bubble``, ``cylinder``/``tube``, ``cone``/``cup`` and ``ring``: tessellated
  with :data:`SEGMENTS` sides around (a sphere: an icosphere of :data:`SPHERE_LEVEL`
  subdivisions), radii scaled so that the triangles' area equals the true surface's
  (tested to 10⁻⁶): a fixed sagitta of about 1 % of the radius, the exact area.  Radiance's
  cylinders and cones have no end caps, and neither have these;
* ``mesh``: through the OBJ it was compiled from, beside its ``.rtm`` (:func:`_mesh_source`).

**Modifiers** (:func:`material_tables`): ``plastic``, ``metal``, ``glass``, ``mirror``,
``trans``, ``light``, ``glow``, ``illum`` and ``BRTDfunc`` definitions become tables of the scene file's
``[materials]`` form; patterns and textures that modify them are left out, and
``alias`` names are followed.  Everything else is skipped, each kind counted in one
warning.  Lengths are in the file's unit, scaled to metres by the caller.

**Commands** (lines starting with ``!``): ``!xform`` is read here, without Radiance
(:func:`xform_primitives`: ``-t -rx -ry -rz -s -mx -my -mz -i -a -m -n``, nested files,
relative paths from the top file's folder as ``oconv`` run there resolves them, then from
the including file's); any other (``!genbox``, ``!gensky`` ...) is run with Radiance's
programs when they are installed (the pyradiance wheel), its output read as scene text,
and otherwise refused in one line naming it.  A missing file or a file that includes
itself is refused in one line.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..photometry import RADIANCE_WHITE_EFFICACY

__all__ = ["RadPrimitive", "read_rad", "files_read", "xform_primitives", "rad_surfaces", "modifier_definitions",
           "material_tables", "read_rad_surfaces", "material_name", "SURFACE_TYPES", "SEGMENTS", "SPHERE_LEVEL"]

#: Radiance's surface types read here (the rest are skipped with a warning).
SURFACE_TYPES = ("polygon", "sphere", "bubble", "cylinder", "tube", "cone", "cup", "ring")
#: Sides of the tessellated circles of cylinders, cones and rings: the chords then stay
#: within 1 − cos(π/24) = 0.86 % of the radius of the true circle.
SEGMENTS = 24
#: Icosphere subdivisions of a Radiance sphere (320 triangles, chords within 1.4 % of r).
SPHERE_LEVEL = 2
#: Radiance's material types (modifiers of surfaces); ``MATERIAL_TYPES`` are converted.
MATERIAL_TYPES = ("plastic", "metal", "glass", "mirror", "trans", "light", "glow", "BRTDfunc", "illum")
#: Radiance's luminous efficacy for its RGB radiance: luminance [cd/m²] = 179 × radiance.
WHITE_EFFICACY = RADIANCE_WHITE_EFFICACY
#: Types that modify others without being a material this reader converts.
OTHER_MODIFIERS = frozenset((
    "plastic2", "metal2", "trans2", "dielectric", "interface", "spotlight", "mist", "prism1",
    "prism2", "plasfunc", "metfunc", "transfunc", "plasdata", "metdata", "transdata", "BSDF",
    "aBSDF", "antimatter", "ashik2", "WGMDfunc", "texfunc", "texdata", "colorfunc", "brightfunc", "colordata",
    "brightdata", "colorpict", "colortext", "brighttext", "mixfunc", "mixdata", "mixpict", "mixtext",
    "spectrum", "specfile", "specfunc", "specdata", "specpict",
))
#: Patterns and textures: a surface or material they modify takes its material from their
#: own modifier (Radiance applies them on the way down the chain; they are left out here).
PATTERN_TYPES = frozenset(("texfunc", "texdata", "colorfunc", "brightfunc", "colordata", "brightdata",
                           "colorpict", "colortext", "brighttext", "specfunc", "specdata", "specpict"))
#: Mixtures of two modifiers: the first one is taken.
MIXTURE_TYPES = frozenset(("mixfunc", "mixdata", "mixpict", "mixtext"))
#: Radiance's other primitive types (skipped with a warning); a type in none of these sets
#: is no Radiance primitive at all (a typing error) and is refused.
OTHER_SURFACES = frozenset(("source", "instance", "mesh"))
_REAL_COUNTS = {"sphere": (4,), "bubble": (4,), "cylinder": (7,), "tube": (7,), "cone": (8,), "cup": (8,),
                "ring": (8,)}


#: The files :func:`read_rad` reads while :func:`files_read` records them (None for a
#: command's output, which is not a file).
_READS: ContextVar[list | None] = ContextVar("lbl_illum_radfile_reads", default=None)


@contextmanager
def files_read():
    """Record, in the list this yields, every file :func:`read_rad` reads meanwhile (the
    file itself, the files ``!xform`` includes, the OBJ a ``mesh`` is read through) and
    None for the output of any other ``!`` command, whose program it does not read."""
    token = _READS.set([])
    try:
        yield _READS.get()
    finally:
        _READS.reset(token)


def _record(path: Path | None) -> None:
    reads = _READS.get()
    if reads is not None:
        reads.append(path)


@dataclass
class RadPrimitive:
    """One primitive: ``modifier type identifier`` and its arguments, with its line."""

    modifier: str
    kind: str
    name: str
    strings: list
    reals: np.ndarray
    line: int


def read_rad(path: str | Path, where: str, root: Path | None = None, _stack: tuple = ()) -> list[RadPrimitive]:
    """Every primitive of a Radiance scene file, in order, with the ``!`` commands expanded:
    ``!xform`` here (:func:`xform_primitives`), any other command by running it when
    Radiance's programs are at hand (:func:`_run_command`).  A malformed primitive, a
    missing or recursive include, a command that cannot run is an :class:`InputError`
    naming the file and line.

    ``root``: the folder relative paths of commands start from, as Radiance's ``oconv``
    run in the top file's folder resolves them (default: this file's folder); a path not
    found there is looked for beside the file that names it.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{where}: is a folder, not a scene file ({path})")
    if not path.is_file():
        raise InputError(f"{where}: no such file ({path})")
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except PermissionError:
        raise InputError(f"{where}: cannot read the file (permission denied)") from None
    _record(path)
    root = path.parent if root is None else root
    stack = _stack + (path.resolve(),)
    out: list[RadPrimitive] = []
    words: list[str] = []
    lines: list[int] = []
    for number, line in enumerate(text.splitlines(), 1):
        body = line.split("#", 1)[0] if not line.lstrip().startswith("!") else line
        if body.lstrip().startswith("!"):
            out += _parse_words(words, lines, where)        # what came before the command
            words, lines = [], []
            out += _command(body.strip()[1:], path, root, f"{where}: line {number}", stack)
            continue
        parts = body.split()
        words.extend(parts)
        lines.extend([number] * len(parts))
    out += _parse_words(words, lines, where)
    if any(p.kind == "mesh" for p in out):
        out = [q for p in out for q in (_mesh_source(p, path, root, where) if p.kind == "mesh" else [p])]
    return out


def _parse_words(words: list[str], lines: list[int], where: str) -> list[RadPrimitive]:
    """The primitives of a run of words (each with its line)."""
    out = []
    i, n = 0, len(words)
    while i < n:
        start = lines[i]
        if i + 3 > n:
            raise InputError(f"{where}: line {start}: incomplete primitive at the end of the file")
        modifier, kind, name = words[i:i + 3]
        i += 3
        if kind == "alias":                 # ``mod alias identifier reference``: no argument lists
            if i >= n:
                raise InputError(f"{where}: line {start}: alias '{name}': missing the modifier it refers to")
            out.append(RadPrimitive(modifier, kind, name, [words[i]], np.zeros(0), start))
            i += 1
            continue
        args = []
        for what in ("string", "integer", "real"):
            if i >= n:
                raise InputError(f"{where}: line {start}: {kind} '{name}': missing its {what} argument count")
            try:
                count = int(words[i])
            except ValueError:
                raise InputError(f"{where}: line {lines[i]}: {kind} '{name}': the {what} argument count must be a "
                                 f"whole number, got '{words[i]}'") from None
            if count < 0 or i + 1 + count > n:
                raise InputError(f"{where}: line {lines[i]}: {kind} '{name}': {count} {what} arguments announced, "
                                 f"{max(0, n - i - 1)} left in the file")
            args.append(words[i + 1:i + 1 + count])
            i += 1 + count
        try:
            reals = np.array(args[2], np.float64)
        except ValueError:
            raise InputError(f"{where}: line {start}: {kind} '{name}': a real argument is not a number") from None
        out.append(RadPrimitive(modifier, kind, name, args[0], reals, start))
    return out


# ---------------------------------------------------------------------------
# Commands: !xform, and the others through Radiance
# ---------------------------------------------------------------------------

def _command(text: str, path: Path, root: Path, where: str, stack: tuple) -> list[RadPrimitive]:
    """The primitives a ``!`` command line gives."""
    import shlex

    try:
        argv = shlex.split(text)
    except ValueError as exc:
        raise InputError(f"{where}: the command '!{text[:60]}' cannot be read ({exc})") from None
    if not argv:
        return []
    if Path(argv[0]).name == "xform":
        return _xform(argv, path, root, where, stack)
    return _run_command(argv, text, path, root, where)


def _find(name: str, path: Path, root: Path) -> Path | None:
    for folder in (root, path.parent):
        candidate = (folder / name)
        if candidate.is_file():
            return candidate
    return None


def _xform(argv: list[str], path: Path, root: Path, where: str, stack: tuple) -> list[RadPrimitive]:
    """``!xform [options] FILE...``: the files' primitives, transformed (:func:`xform_primitives`)."""
    options, files = _xform_options(argv[1:], where)
    if not files:
        raise InputError(f"{where}: !xform without a file (reading its standard input is not supported)")
    prims: list[RadPrimitive] = []
    for name in files:
        if name.startswith("!") or name == "-":
            raise InputError(f"{where}: !xform of '{name}': only files can be transformed here")
        found = _find(name, path, root)
        if found is None:
            raise InputError(f"{where}: !xform: no such file '{name}' (looked in {root} and {path.parent})")
        if found.resolve() in stack:
            raise InputError(f"{where}: !xform {name}: the file includes itself (recursive include)")
        prims += read_rad(found, f"{where}: {name}", root, stack)
    return xform_primitives(prims, options, where)


#: The kind given to the triangles of a ``mesh`` read through its source OBJ
#: (:func:`_mesh_source`): reals are 9 per triangle, corners in order.
MESH_TRIANGLES = "mesh-triangles"


def _mesh_source(p: RadPrimitive, path: Path, root: Path, where: str) -> list[RadPrimitive]:
    """A ``mesh`` primitive (``mod mesh id  1+ file.rtm [xform args]  0  0``) read through
    the Wavefront OBJ it was compiled from by ``obj2mesh``: ``file.obj`` beside
    ``file.rtm`` (the compiled mesh itself is Radiance's binary format, not read here).
    Its faces are triangulated as drawn (:func:`lbl_illum.scene.geometry.load_mesh_file`),
    moved by the xform arguments as an ``instance`` is, and take, as Radiance's mesh does,
    the primitive's modifier on every surface, or with modifier ``void`` the materials the
    mesh stores: each face's ``usemtl`` name (else its group, else ``white``, the rule of
    ``obj2rad``).  Without a source OBJ the mesh is left out, with a warning (it is then
    counted among the skipped primitives).  Returns primitives of kind
    :data:`MESH_TRIANGLES`, one per modifier and copy."""
    from .geometry import load_mesh_file

    label = f"{where}: line {p.line}: mesh '{p.name}'"
    if not p.strings:
        raise InputError(f"{label}: needs the mesh file as its first string argument")
    options, rest = _xform_options(list(p.strings[1:]), label)
    if rest:
        raise InputError(f"{label}: unexpected argument '{rest[0]}' after the mesh file")
    compiled = Path(p.strings[0])
    source = next((f for f in (_find(str(compiled.with_suffix(s)), path, root) for s in (".obj", ".OBJ"))
                   if f is not None), None)
    if source is None:
        _record(None)                                # an OBJ put there later would change it
        return [p]                                   # skipped, and counted, by rad_surfaces
    parts = load_mesh_file(source, f"{label}: {source.name}", 1.0)
    _record(source)
    prims = []
    for part in parts:
        modifier = p.modifier if p.modifier != "void" else (part.material or part.group or "white")
        prims.append(RadPrimitive(modifier, MESH_TRIANGLES, p.name, [], part.vertices.reshape(-1), p.line))
    return xform_primitives(prims, options, label) if options else prims


#: xform options of one number (the rest take three, or none).
_XFORM_ONE = ("-rx", "-ry", "-rz", "-s", "-i", "-a")


def _xform_options(args: list[str], where: str) -> tuple[list[tuple], list[str]]:
    """Parse xform's options: ``(options, files)``; options as (flag, value) in order."""
    out, i = [], 0
    while i < len(args):
        flag = args[i]
        if not flag.startswith("-") or flag == "-":
            break
        if flag not in ("-t", "-mx", "-my", "-mz", "-e", "-c", "-m", "-n") + _XFORM_ONE:
            raise InputError(f"{where}: !xform option '{flag}' is not supported here (read: -t -rx -ry -rz -s "
                             "-mx -my -mz -i -a -m -n -e -c)")
        try:
            if flag == "-t":
                out.append((flag, tuple(float(x) for x in args[i + 1:i + 4])))
                if len(out[-1][1]) != 3:
                    raise IndexError
                i += 4
            elif flag in _XFORM_ONE:
                value = float(args[i + 1]) if flag not in ("-i", "-a") else int(args[i + 1])
                out.append((flag, value))
                i += 2
            elif flag in ("-mx", "-my", "-mz", "-e", "-c"):
                out.append((flag, None))
                i += 1
            else:                                                   # -m, -n
                out.append((flag, args[i + 1]))
                i += 2
        except (IndexError, ValueError):
            raise InputError(f"{where}: !xform option '{flag}': missing or bad value") from None
    return out, args[i:]


def _rotation(axis: int, degrees: float) -> np.ndarray:
    a = np.radians(degrees)
    c, s_ = np.cos(a), np.sin(a)
    m = np.eye(4)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s_, s_, c
    return m


def _xform_matrices(options: list[tuple]) -> list[np.ndarray]:
    """The 4 × 4 transforms of every copy xform makes: the transforms in order, each ``-a N``
    making N copies with what follows it applied 0 … N − 1 times, each ``-i N`` applying
    what follows it N times (until the next ``-a`` or ``-i``)."""
    copies = [np.eye(4)]
    segment, kind, count = np.eye(4), "once", 1

    def close():
        nonlocal copies
        if kind == "array":
            steps = [np.linalg.matrix_power(segment, k) for k in range(count)]
            copies = [s @ m for m in copies for s in steps]
        else:
            step = np.linalg.matrix_power(segment, count if kind == "iterate" else 1)
            copies = [step @ m for m in copies]

    for flag, value in options:
        m = None
        if flag == "-t":
            m = np.eye(4)
            m[:3, 3] = value
        elif flag in ("-rx", "-ry", "-rz"):
            m = _rotation("xyz".index(flag[2]), value)
        elif flag == "-s":
            m = np.diag([value, value, value, 1.0])
        elif flag in ("-mx", "-my", "-mz"):
            m = np.eye(4)
            m["xyz".index(flag[2]), "xyz".index(flag[2])] = -1.0
        elif flag in ("-a", "-i"):
            close()
            segment, kind, count = np.eye(4), "array" if flag == "-a" else "iterate", int(value)
        if m is not None:
            segment = m @ segment
    close()
    return copies


def xform_primitives(prims: list[RadPrimitive], options: list[tuple], where: str = "") -> list[RadPrimitive]:
    """Radiance's ``xform`` on primitives (``xform.c``): each copy's transform moves the
    surfaces' points and scales their radii (uniform scale only), turns ring normals and
    source directions, and reverses a polygon's vertices when it mirrors (so that its
    normal stays on the side it was); ``-m`` sets the surfaces' modifier, ``-n`` prefixes
    every identifier."""
    modifier = next((v for f, v in reversed(options) if f == "-m"), None)
    prefix = next((v for f, v in reversed(options) if f == "-n"), None)
    out = []
    copies = _xform_matrices(options)
    for c, m in enumerate(copies):
        linear = m[:3, :3]
        scale = abs(np.linalg.det(linear)) ** (1.0 / 3.0)
        mirror = np.linalg.det(linear) < 0.0
        for p in prims:
            r = p.reals
            kind = p.kind
            geometric = kind in SURFACE_TYPES or kind in ("source", "instance", "mesh", MESH_TRIANGLES)
            if kind == "polygon":
                pts = r.reshape(-1, 3) @ linear.T + m[:3, 3]
                if mirror:
                    pts = pts[::-1]
                r = pts.ravel()
            elif kind == MESH_TRIANGLES:
                tri = (r.reshape(-1, 3) @ linear.T + m[:3, 3]).reshape(-1, 3, 3)
                r = (tri[:, ::-1] if mirror else tri).ravel()
            elif kind in ("sphere", "bubble") and len(r) == 4:
                r = np.r_[linear @ r[:3] + m[:3, 3], r[3] * scale]
            elif kind in ("cylinder", "tube") and len(r) == 7:
                r = np.r_[linear @ r[:3] + m[:3, 3], linear @ r[3:6] + m[:3, 3], r[6] * scale]
            elif kind in ("cone", "cup") and len(r) == 8:
                r = np.r_[linear @ r[:3] + m[:3, 3], linear @ r[3:6] + m[:3, 3], r[6:8] * scale]
            elif kind == "ring" and len(r) == 8:
                normal = linear @ r[3:6]
                r = np.r_[linear @ r[:3] + m[:3, 3], normal / max(np.linalg.norm(normal), 1e-300) *
                          np.linalg.norm(r[3:6]), r[6:8] * scale]
            elif kind == "source" and len(r) == 4:
                d = linear @ r[:3]
                r = np.r_[d / max(np.linalg.norm(d), 1e-300) * np.linalg.norm(r[:3]), r[3]]
            name = p.name if prefix is None else (f"{prefix}.{c}.{p.name}" if len(copies) > 1 else f"{prefix}.{p.name}")
            out.append(RadPrimitive(modifier if (modifier is not None and geometric) else p.modifier, kind, name,
                                    p.strings, r, p.line))
    return out


def _run_command(argv: list[str], text: str, path: Path, root: Path, where: str) -> list[RadPrimitive]:
    """Any other command (``!genbox``, ``!gensky`` ...), run by the shell in ``root`` with
    Radiance's programs, its output read as scene text; without Radiance, one line naming it."""
    import os
    import subprocess
    import tempfile

    from ..io.radiance import radiance_programs

    programs = radiance_programs()
    name = Path(argv[0]).name
    if programs is None or programs.get("root") is None or not (Path(programs["root"]) / "bin" / name).is_file():
        raise InputError(f"{where}: the command '!{text[:60]}' needs Radiance's {name} (pip install pyradiance), "
                         "or expand the file first")
    env = dict(programs["env"])
    env["PATH"] = os.pathsep.join([str(Path(programs["root"]) / "bin"), env.get("PATH", "")])
    run = subprocess.run(text, shell=True, cwd=root, env=env, capture_output=True, text=True)
    if run.returncode != 0:
        message = (run.stderr.strip().splitlines() or ["no message"])[0]
        raise InputError(f"{where}: the command '!{text[:60]}' failed: {message}")
    _record(None)
    with tempfile.NamedTemporaryFile("w", suffix=".rad", delete=False) as tmp:
        tmp.write(run.stdout)
    try:
        return read_rad(tmp.name, f"{where}: output of !{name}", root, (path.resolve(),))
    finally:
        os.unlink(tmp.name)


# ---------------------------------------------------------------------------
# Surfaces
# ---------------------------------------------------------------------------

def rad_surfaces(prims: list[RadPrimitive], where: str, scale: float = 1.0, warnings: list[str] | None = None):
    """The surfaces of ``prims`` as :class:`~lbl_illum.scene.geometry.MeshPart` s, one per
    modifier in order of appearance, in metres (``scale`` metres per file unit).

    Surface types other than :data:`SURFACE_TYPES` are counted in one warning appended to
    ``warnings``; so are polygons whose triangles' area differs from the polygon's.
    """
    from .geometry import MeshPart
    from .polygons import area_warnings, triangulate_faces

    coords, lines, names, owners = [], [], [], []
    quadric_tris: list[tuple[str, np.ndarray | int]] = []
    laterals: list[tuple[str, tuple]] = []      # (kind, (p0, p1, r0, r1)) of each
    skipped: dict[str, int] = {}
    order: dict[str, None] = {}
    for p in prims:
        if p.kind == "polygon":
            if len(p.reals) < 9 or len(p.reals) % 3:
                raise InputError(f"{where}: line {p.line}: polygon '{p.name}': needs 3 reals per vertex and at "
                                 f"least 3 vertices, got {len(p.reals)} reals")
            coords.append(p.reals.reshape(-1, 3))
            lines.append(p.line)
            names.append(p.name)
            owners.append(p.modifier)
            order.setdefault(p.modifier)
        elif p.kind == MESH_TRIANGLES:
            quadric_tris.append((p.modifier, p.reals.reshape(-1, 3, 3)))
            order.setdefault(p.modifier)
        elif p.kind in _REAL_COUNTS:
            if len(p.reals) not in _REAL_COUNTS[p.kind]:
                raise InputError(f"{where}: line {p.line}: {p.kind} '{p.name}': needs {_REAL_COUNTS[p.kind][0]} "
                                 f"reals, got {len(p.reals)}")
            if p.kind in LATERAL_TYPES:                 # tessellated all at once below
                arguments = _lateral_arguments(p, where)
                if arguments is not None:
                    quadric_tris.append((p.modifier, len(laterals)))
                    laterals.append((p.kind, arguments))
                    order.setdefault(p.modifier)
                continue
            tri = _quadric(p, where)
            if len(tri):
                quadric_tris.append((p.modifier, tri))
                order.setdefault(p.modifier)
        elif p.kind not in MATERIAL_TYPES and p.kind not in OTHER_MODIFIERS and p.kind != "alias":
            if p.kind not in OTHER_SURFACES | PATTERN_TYPES | MIXTURE_TYPES:
                raise InputError(f"{where}: line {p.line}: '{p.kind}' is not a Radiance primitive type "
                                 f"({p.modifier} {p.kind} {p.name})")
            skipped[p.kind] = skipped.get(p.kind, 0) + 1
    if warnings is not None and skipped:
        what = ", ".join(f"{count} '{kind}'" for kind, count in skipped.items())
        hint = "; a mesh is read through the OBJ it was compiled from, NAME.obj beside NAME.rtm" \
            if "mesh" in skipped else ""
        warnings.append(f"{where}: skipped {what} {'primitive' if sum(skipped.values()) == 1 else 'primitives'} "
                        f"(read: {', '.join(SURFACE_TYPES)}, mesh{hint})")
    per_modifier: dict[str, list[np.ndarray]] = {m: [] for m in order}
    if coords:
        sizes = np.array([len(v) for v in coords])
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        vertices = np.concatenate(coords)
        result = triangulate_faces(vertices, [np.arange(offsets[k], offsets[k + 1]) for k in range(len(coords))])
        if warnings is not None:
            warnings += area_warnings(result, where, lambda f: f"line {lines[f]} (polygon {names[f]})", scale * scale)
        owner = np.array(owners, object)[result.face]
        for modifier in order:
            sel = result.triangles[owner == modifier]
            if len(sel):
                per_modifier[modifier].append(vertices[sel])
    lateral_tris = _lateral_surfaces(laterals)
    for modifier, tri in quadric_tris:
        per_modifier[modifier].append(lateral_tris[tri] if isinstance(tri, int) else tri)
    return [MeshPart(m, m, None, m, np.concatenate(parts) * scale) for m, parts in per_modifier.items() if parts]


def _circle(n: int) -> np.ndarray:
    """(n, 2) unit circle points, counter-clockwise from angle 0."""
    a = 2.0 * np.pi * np.arange(n) / n
    return np.stack([np.cos(a), np.sin(a)], axis=1)


def _frame(axis: np.ndarray):
    """Two unit vectors completing ``axis`` (unit) to a right-handed frame."""
    from .geometry import orthonormal_basis

    t, b = orthonormal_basis(axis[None])
    return t[0], b[0]


#: Primitives whose surface lies between two circles (:func:`_lateral_surfaces`).
LATERAL_TYPES = ("cylinder", "tube", "cone", "cup")


def _lateral_arguments(p: RadPrimitive, where: str):
    """``(p0, p1, r0, r1)`` of a cylinder, tube, cone or cup, or None when it is degenerate
    (no length, or both radii zero); negative radii are an :class:`InputError`."""
    r = p.reals
    p0, p1 = r[:3], r[3:6]
    r0, r1 = (r[6], r[6]) if p.kind in ("cylinder", "tube") else (r[6], r[7])
    if np.linalg.norm(p1 - p0) == 0.0 or (r0 == 0.0 and r1 == 0.0):
        return None
    if r0 < 0 or r1 < 0:
        raise InputError(f"{where}: line {p.line}: {p.kind} '{p.name}': radii must not be negative")
    return p0, p1, r0, r1


def _lateral_surfaces(prims: list[tuple[str, tuple]]) -> list[np.ndarray]:
    """(m, 3, 3) triangles of each (non-degenerate) cylinder, tube, cone or cup of
    ``prims``, (type, :func:`_lateral_arguments`) each, all tessellated at once: the lateral surface between two :data:`SEGMENTS`-gons
    whose circumradii are k r0 and k r1, k first making the n-gons' perimeters the circles'
    and then solved by four secant steps so that the triangles' area equals the true
    surface's, π (r0 + r1) √(L² + (r1 − r0)²).  Zero-area triangles (at a cone's apex) are
    dropped; tubes and cups face inward."""
    from .geometry import orthonormal_basis

    if not prims:
        return []
    args = [a for _, a in prims]
    p0 = np.array([a[0] for a in args])
    p1 = np.array([a[1] for a in args])
    r0 = np.array([a[2] for a in args], np.float64)
    r1 = np.array([a[3] for a in args], np.float64)
    axis = p1 - p0
    length = np.linalg.norm(axis, axis=1)
    t, b = orthonormal_basis(axis / length[:, None])
    c = _circle(SEGMENTS)
    ring = c[None, :, :1] * t[:, None, :] + c[None, :, 1:] * b[:, None, :]       # (n, S, 3)
    j = np.roll(np.arange(SEGMENTS), -1)
    exact = np.pi * (r0 + r1) * np.hypot(length, r1 - r0)

    def lateral(k):
        a = p0[:, None, :] + (k * r0)[:, None, None] * ring
        b_ = p1[:, None, :] + (k * r1)[:, None, None] * ring
        return np.concatenate([np.stack([a, a[:, j], b_[:, j]], 2), np.stack([a, b_[:, j], b_], 2)], axis=1)

    def twice_areas(tri):
        return np.linalg.norm(np.cross(tri[..., 1, :] - tri[..., 0, :], tri[..., 2, :] - tri[..., 0, :]), axis=-1)

    k = np.full(len(prims), np.pi / (SEGMENTS * np.sin(np.pi / SEGMENTS)))   # perimeter of the n-gon = the circle's
    active = np.ones(len(prims), bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for _ in range(4):                                       # then the area exactly (secant on k)
            area = 0.5 * twice_areas(lateral(k)).sum(axis=1)
            k2 = k * 1.001
            slope = (0.5 * twice_areas(lateral(k2)).sum(axis=1) - area) / (k2 - k)
            active &= slope > 0
            k = np.where(active, k + (exact - area) / slope, k)
    tri = lateral(k)
    keep = twice_areas(tri) > 0
    inward = np.array([kind in ("tube", "cup") for kind, _ in prims])
    return [tri[i][keep[i]][:, [0, 2, 1]] if inward[i] else tri[i][keep[i]] for i in range(len(prims))]


def _quadric(p: RadPrimitive, where: str) -> np.ndarray:
    """(m, 3, 3) triangles of a sphere, bubble or ring primitive (module text); empty for a
    degenerate sphere (zero radius).  Cylinders, tubes, cones and cups:
    :func:`_lateral_surfaces`."""
    r = p.reals
    if p.kind in ("sphere", "bubble"):
        centre, radius = r[:3], abs(r[3])
        if radius == 0.0:
            return np.zeros((0, 3, 3))
        tri = _unit_sphere() * radius + centre
        return tri[:, [0, 2, 1]] if p.kind == "bubble" else tri
    if p.kind == "ring":
        centre, normal = r[:3], r[3:6]
        r0, r1 = sorted((r[6], r[7]))            # Radiance takes the radii in either order
        length = np.linalg.norm(normal)
        if length == 0.0 or r0 < 0 or r1 == r0:
            raise InputError(f"{where}: line {p.line}: ring '{p.name}': needs a normal and two different, "
                             "non-negative radii")
        axis = normal / length
        t, b = _frame(axis)
        c = _circle(SEGMENTS)
        k = np.sqrt(np.pi / (0.5 * SEGMENTS * np.sin(2.0 * np.pi / SEGMENTS)))      # n-gon area = disk area
        ring = c[:, :1] * t + c[:, 1:] * b
        outer = centre + k * r1 * ring
        j = np.roll(np.arange(SEGMENTS), -1)
        if r0 == 0.0:
            return np.stack([np.broadcast_to(centre, outer.shape), outer, outer[j]], axis=1)
        inner = centre + k * r0 * ring
        return np.concatenate([np.stack([inner, outer, outer[j]], 1), np.stack([inner, outer[j], inner[j]], 1)])
    raise ValueError(f"not a sphere or ring: {p.kind}")


def _area(tri: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())


_SPHERE = None


def _unit_sphere() -> np.ndarray:
    """(320, 3, 3) icosphere of :data:`SPHERE_LEVEL` subdivisions scaled to the unit sphere's
    area (4π), outward winding; built by trimesh once, then kept between runs
    (:func:`lbl_illum.scene.geometry_cache.kept_shape`)."""
    global _SPHERE
    if _SPHERE is None:
        from .geometry_cache import kept_shape

        tri = kept_shape(f"unit-icosphere-{SPHERE_LEVEL}", _build_unit_sphere)
        tri.setflags(write=False)
        _SPHERE = tri
    return _SPHERE


def _build_unit_sphere() -> np.ndarray:
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=SPHERE_LEVEL, radius=1.0)
    tri = np.asarray(mesh.vertices, np.float64)[np.asarray(mesh.faces)]
    tri *= np.sqrt(4.0 * np.pi / _area(tri))
    return tri


# ---------------------------------------------------------------------------
# Modifiers as materials
# ---------------------------------------------------------------------------

def modifier_definitions(prims: list[RadPrimitive]) -> dict[str, RadPrimitive]:
    """The modifiers ``prims`` define, by name; a later definition replaces an earlier
    one, as in Radiance."""
    return {p.name: p for p in prims if p.kind in MATERIAL_TYPES or p.kind in OTHER_MODIFIERS or p.kind == "alias"}


def material_tables(definitions: dict[str, tuple[RadPrimitive, str]], names, warnings: list[str] | None = None
                    ) -> dict[str, dict]:
    """Tables in the form of the scene file's ``[materials.NAME]`` for the modifiers
    ``names``, from ``definitions`` (name → (primitive, where it was read)).

    ``plastic`` (C, s, α): diffuse C when s = 0, else our plastic; ``metal``: our metal
    with the same arguments (specular part coloured by C); ``glass`` (t_n per channel, n): Fresnel glass of
    the same normal transmittance; ``mirror``: mirror; ``trans`` (C, s, α, t_d, t_s):
    translucent, diffuse reflectance (1 − s)(1 − t_d) C and diffuse transmittance
    (1 − s) t_d C (a specular part of either is warned: its reflection is dropped, its
    transmission made diffuse); ``light``, ``glow``:
    light surfaces of luminance 179 × radiance; ``BRTDfunc`` in the forms ``lbl-illum
    export radiance`` writes (:func:`_brtdfunc`); ``illum``: its alternate material (the
    first string argument), or without one an opening (sampled as a portal, seen by no
    ray: what Radiance's illum without an alternate is to rays that are not shadow rays).
    A pattern that modifies a material is left out (warned).  ``alias`` is followed.  A
    modifier that is not defined, or whose type is not converted, is an
    :class:`InputError` naming it.
    """
    from .materials import glazing_optics

    out: dict[str, dict] = {}
    notes: dict[str, int] = {}
    for name in names:
        seen = set()
        prim, where = _resolve(name, definitions, seen, notes)
        a = prim.reals
        label = f"{where}: line {prim.line}: {prim.kind} '{prim.name}'"
        if prim.kind == "illum":
            if prim.strings and prim.strings[0] != "void":
                prim, where = _resolve(prim.strings[0], definitions, set(seen), notes)
                a, label = prim.reals, f"{where}: line {prim.line}: {prim.kind} '{prim.name}'"
                notes["illum read as its alternate material"] = notes.get("illum read as its alternate material", 0) + 1
            else:
                out[name] = {"type": "opening"}
                notes["illum without an alternate read as an opening"] = \
                    notes.get("illum without an alternate read as an opening", 0) + 1
                continue
        if prim.kind == "BRTDfunc":
            out[name] = _brtdfunc(prim, label)
            continue
        need = {"plastic": 5, "metal": 5, "glass": 3, "mirror": 3, "trans": 7, "light": 3, "glow": 4}[prim.kind]
        if len(a) < need or (prim.kind == "glass" and len(a) not in (3, 4)):
            raise InputError(f"{label}: needs {need} reals, got {len(a)}")
        if prim.modifier != "void":
            _resolve_patterns(prim.modifier, definitions, notes)
        rgb = [float(v) for v in a[:3]]
        if prim.kind in ("plastic", "metal"):
            s, alpha = float(a[3]), float(a[4])
            out[name] = ({"type": "diffuse", "reflectance": rgb} if s == 0.0 else
                         {"type": prim.kind, "reflectance": rgb, "specularity": s, "roughness": alpha})
        elif prim.kind == "glass":
            index = float(a[3]) if len(a) == 4 else 1.52
            tau, _ = glazing_optics(np.ones(1), np.clip(np.array(rgb), 0.0, 1.0), index)
            out[name] = {"type": "glass", "transmittance": [float(t) for t in tau[0]], "refractive_index": index}
        elif prim.kind == "mirror":
            out[name] = {"type": "mirror", "reflectance": rgb}
        elif prim.kind == "trans":
            # Radiance's trans: diffuse reflectance C (1 − s)(1 − t_d), transmitted C (1 − s) t_d,
            # of which t_s specularly; both transmitted parts become diffuse transmission
            s, td, ts = float(a[3]), float(a[5]), float(a[6])
            if s > 0.0 or ts > 0.0:
                what = "trans read as translucent (its specular reflection dropped, its specular transmission diffuse)"
                notes[what] = notes.get(what, 0) + 1
            out[name] = {"type": "translucent", "reflectance": [c * (1.0 - s) * (1.0 - td) for c in rgb],
                         "transmittance": [c * (1.0 - s) * td for c in rgb]}
        else:                       # light, glow
            out[name] = {"type": "light", "luminance": [WHITE_EFFICACY * c for c in rgb]}
    if warnings is not None and notes:
        warnings.append("Radiance modifiers: " + "; ".join(f"{count} {what}" for what, count in notes.items()))
    return out


def _brtdfunc(prim: RadPrimitive, label: str) -> dict:
    """A ``BRTDfunc`` as ``lbl-illum export radiance`` writes it (io/radiance.py):

    * constant glass: strings ρ_r ρ_g ρ_b τ_r τ_g τ_b 0 0 0 ``.``, nine zero reals →
      ``glass``, model ``constant``;
    * Fresnel panes: strings ``glz_rr … glz_tb 0 0 0 lbl_glazing.cal``, reals nine zeros,
      n, t_n (RGB), panes → ``glass``, model ``fresnel`` of those panes;
    * translucent: strings of zeros and ``.``, reals ρ (front), ρ (back), τ_d (RGB) →
      ``translucent``.

    Any other form is an :class:`InputError`: map the modifier in ``materials``."""
    from .materials import glazing_optics

    st, a = prim.strings, prim.reals
    if len(st) == 10 and st[9] == "." and len(a) == 9 and not np.any(a):
        try:
            values = [float(v) for v in st[:9]]
        except ValueError:
            values = None
        if values is not None and not any(values[6:9]):
            return {"type": "glass", "model": "constant", "reflectance": values[:3], "transmittance": values[3:6]}
    if len(st) == 10 and st[:6] == ["glz_rr", "glz_rg", "glz_rb", "glz_tr", "glz_tg", "glz_tb"] and len(a) == 14:
        index, tn, panes = float(a[9]), np.clip(a[10:13], 0.0, 1.0), int(round(a[13]))
        if panes in (1, 2):
            tau, _ = glazing_optics(np.ones(1), tn, index, panes)
            return {"type": "glass", "transmittance": [float(t) for t in tau[0]], "refractive_index": index,
                    "panes": panes}
    if len(st) == 10 and st[9] == "." and all(v == "0" for v in st[:9]) and len(a) == 9:
        if np.allclose(a[0:3], a[3:6]):
            return {"type": "translucent", "reflectance": [float(v) for v in a[0:3]],
                    "transmittance": [float(v) for v in a[6:9]]}
    raise InputError(f"{label}: this BRTDfunc's form is not read (read: the constant glass, Fresnel panes and "
                     "translucent forms lbl-illum export radiance writes); map the modifier to a material in "
                     "'materials'")


def _resolve(name: str, definitions, seen: set, notes: dict):
    """(primitive, where) of the material of modifier ``name``, following ``alias``, the
    modifiers of patterns and textures, and the first modifier of mixtures (each such
    step counted in ``notes``)."""
    if name in seen:
        raise InputError(f"modifier '{name}': its chain of modifiers forms a loop")
    seen.add(name)
    if name not in definitions:
        raise InputError(f"modifier '{name}' is not defined in the Radiance files of the scene (add the .mat or "
                         ".rad file that defines it as a [[geometry]] entry, or map it in 'materials')")
    prim, where = definitions[name]
    if prim.kind == "alias":
        return _resolve(prim.strings[0], definitions, seen, notes)
    if prim.kind in PATTERN_TYPES:
        notes["patterns and textures left out"] = notes.get("patterns and textures left out", 0) + 1
        return _resolve(prim.modifier, definitions, seen, notes)
    if prim.kind in MIXTURE_TYPES and prim.strings:
        notes["mixtures read as their first modifier"] = notes.get("mixtures read as their first modifier", 0) + 1
        return _resolve(prim.strings[0], definitions, seen, notes)
    if prim.kind not in MATERIAL_TYPES:
        raise InputError(f"{where}: line {prim.line}: modifier '{name}' is a '{prim.kind}', which is not read "
                         f"(read: {', '.join(MATERIAL_TYPES)}); map it to a material in 'materials'")
    return prim, where


def material_name(name: str, definitions) -> str:
    """The name of the material that modifier ``name`` ends at: ``name`` itself for a
    material (or an undefined name), else the material its aliases, patterns and
    mixtures lead to (:func:`_resolve`)."""
    try:
        return _resolve(name, definitions, set(), {})[0].name
    except InputError:
        return name


def _resolve_patterns(name: str, definitions, notes: dict) -> None:
    """Count the patterns and textures that modify a material (left out)."""
    seen = set()
    while name != "void" and name in definitions and name not in seen:
        seen.add(name)
        prim = definitions[name][0]
        if prim.kind in PATTERN_TYPES or prim.kind in MIXTURE_TYPES:
            notes["patterns and textures left out"] = notes.get("patterns and textures left out", 0) + 1
        name = prim.modifier if prim.kind != "alias" else prim.strings[0]


def read_rad_surfaces(path: str | Path, where: str, scale: float = 1.0, warnings: list[str] | None = None):
    """:func:`rad_surfaces` of the Radiance file ``path``."""
    return rad_surfaces(read_rad(path, where), where, scale, warnings)
