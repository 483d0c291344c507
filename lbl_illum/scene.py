"""The scene: geometry, materials, sky, sun and default settings, read from a TOML scene file.

A scene file (schema 1) has the top-level keys ``schema`` (optional, 1), ``units``
(m, cm, mm, km, ft, in; default m), ``[[geometry]]`` entries, ``[materials.NAME]``
tables, ``[sky]``, ``[sun]`` and ``[settings]``.  A geometry entry either loads a file
(``file``, relative to the scene file, with a default ``material`` and a ``materials``
table mapping sub-mesh names to materials) or is a primitive (``shape`` = sphere, box,
polygon or rectangle, with a required ``material``).  In a ``materials`` table a
sub-mesh is found by, in this order, its glTF node name, its trimesh geometry name
(OBJ ``GROUP_MATERIAL``, glTF mesh name), its OBJ ``g`` group and its OBJ ``usemtl``
or glTF material name.

Every length of the file, of its geometry files and of ``[settings]``
(``min_spacing``, ``max_spacing``) is in ``units`` and converted to metres.  Every
problem is an :class:`~lbl_illum.errors.InputError` with a one-line message starting
with the scene file's name and the key path (``geometry[2]``, ``[materials.wall]``)
or the line and column.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from .errors import InputError, check_keys, plural
from .geometry import Triangles, degenerate_mask, duplicate_mask, load_mesh_file, shape_from_table
from .materials import Material, MaterialTable, material_from_table
from .options import Options
from .sky import Sky, sky_from_table
from .sun import Sun, sun_from_table
from .units import metres_per_unit

__all__ = ["Scene", "load_scene", "scene_from_dict", "SCHEMA", "TOP_LEVEL_KEYS"]

#: The scene-file schema this version reads.
SCHEMA = 1
#: Keys allowed at the top of a scene file.
TOP_LEVEL_KEYS = ("schema", "units", "geometry", "materials", "sky", "sun", "settings")
#: Keys of a ``[[geometry]]`` entry that loads a file.
FILE_KEYS = ("file", "material", "materials")


@dataclass
class Scene:
    """A loaded scene; every length in metres.

    path : the scene file (or None for scenes built in code)
    units : unit of the scene file's lengths; ``unit_scale`` metres per unit
    triangles : all surfaces; ``materials[i]`` is the material of id i
    sky, sun : the daylight (``sun`` None when there is none)
    options : quality options from ``[settings]`` (defaults otherwise)
    warnings : things worth telling the user that are not errors
    """

    triangles: Triangles
    materials: list[Material]
    sky: Sky
    sun: Sun | None = None
    options: Options = field(default_factory=Options)
    units: str = "m"
    unit_scale: float = 1.0
    path: Path | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def material_table(self) -> MaterialTable:
        return MaterialTable.from_materials(self.materials)


# ---------------------------------------------------------------------------
# Reading a scene file
# ---------------------------------------------------------------------------

def load_scene(path: str | Path) -> Scene:
    """Read a TOML scene file (schema 1); every length of the result is in metres.

    Geometry files are found relative to the scene file.  Every problem is an
    :class:`InputError` whose one-line message starts with the file's name.
    """
    path = Path(path)
    name = path.name or str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{name}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.strerror or exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(_toml_error(name, exc)) from None
    scene = scene_from_dict(data, path.parent, name)
    scene.path = path
    return scene


def _toml_error(name: str, exc: Exception) -> str:
    """``scene.toml: line L, column C: message`` from a TOML syntax error."""
    message = str(exc).splitlines()[0] if str(exc) else "invalid TOML"
    found = re.search(r"^(.*?)\s*\(at line (\d+), column (\d+)\)$", message)
    if found:
        return f"{name}: line {found[2]}, column {found[3]}: {found[1]}"
    found = re.search(r"^(.*?)\s*\(at end of document\)$", message)
    if found:
        return f"{name}: end of file: {found[1]}"
    return f"{name}: {message}"


def scene_from_dict(data: Mapping[str, Any], base_dir: str | Path, where: str) -> Scene:
    """Build a :class:`Scene` from a parsed scene file (a plain dict).

    ``base_dir`` is where geometry files are looked up; ``where`` names the source in
    messages (normally the scene file's name).  Lengths are in ``data["units"]`` and
    come out in metres; the ``[settings]`` spacings stay in scene units (the
    integrator converts them with ``unit_scale``).
    """
    if not isinstance(data, Mapping):
        raise InputError(f"{where}: a scene must be a table of keys, got {type(data).__name__}")
    check_keys(data, TOP_LEVEL_KEYS, where)
    _check_schema(data, where)
    units = data.get("units", "m")
    scale = metres_per_unit(units, f"{where}: 'units'")
    materials = _materials(_table(data, "materials", where, "[materials]"), where)
    sun = sun_from_table(_table(data, "sun", where, "[sun]"), f"{where}: [sun]")
    sky = sky_from_table(_table(data, "sky", where, "[sky]"), f"{where}: [sky]",
                         sun_horizontal_illuminance=float(sun.horizontal_illuminance) if sun else 0.0)
    options = _options(_table(data, "settings", where, "[settings]"), f"{where}: [settings]", scale)
    warnings = list(sun.warnings) if sun else []
    triangles = _geometry(data.get("geometry"), where, Path(base_dir), scale,
                          {m.name: i for i, m in enumerate(materials)}, warnings)
    used = set(np.unique(triangles.material).tolist())
    warnings += [f"{where}: [materials.{m.name}] is not used by any geometry"
                 for i, m in enumerate(materials) if i not in used]
    return Scene(triangles=triangles, materials=materials, sky=sky, sun=sun, options=options,
                 units=units, unit_scale=scale, warnings=warnings)


def _check_schema(data: Mapping[str, Any], where: str) -> None:
    schema = data.get("schema", SCHEMA)
    if isinstance(schema, bool) or schema != SCHEMA:
        raise InputError(f"{where}: 'schema' {schema!r} is not supported (this version reads schema {SCHEMA})")


def _table(data: Mapping[str, Any], key: str, where: str, label: str) -> Mapping[str, Any] | None:
    """``data[key]`` when it is a table, None when absent; anything else is an error."""
    value = data.get(key)
    if value is not None and not isinstance(value, Mapping):
        raise InputError(f"{where}: {label} must be a table, got {value!r}")
    return value


def _materials(table: Mapping[str, Any] | None, where: str) -> list[Material]:
    """All ``[materials.NAME]`` tables in file order (index = material id)."""
    materials = []
    for name, entry in (table or {}).items():
        label = f"{where}: [materials.{name}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label} must be a table, got {entry!r}")
        materials.append(material_from_table(name, entry, label))
    return materials


def _options(table: Mapping[str, Any] | None, where: str, scale: float) -> Options:
    """``[settings]``.  Spacings stay in scene units, as on the command line; the
    integrator converts them with ``Scene.unit_scale``."""
    return Options.from_table(table, where)


# ---------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------

@dataclass
class _Chunk:
    """Triangles of one ``[[geometry]]`` entry [m], with material and sphere ids."""

    label: str
    vertices: np.ndarray
    material: np.ndarray
    sphere: np.ndarray


def _geometry(entries: Any, where: str, base_dir: Path, scale: float, ids: dict[str, int],
              warnings: list[str]) -> Triangles:
    """All triangles of the ``[[geometry]]`` entries, cleaned (see :func:`_assemble`)."""
    if entries is None:
        raise InputError(f"{where}: the scene has no geometry (add [[geometry]] entries)")
    if not isinstance(entries, (list, tuple)):
        raise InputError(f"{where}: 'geometry' must be an array of tables ([[geometry]]), got {entries!r}")
    chunks, centers, radii = [], [], []
    for i, entry in enumerate(entries):
        label = f"{where}: geometry[{i}]"
        if not isinstance(entry, Mapping):
            raise InputError(f"{label}: must be a table, got {entry!r}")
        if "file" in entry and "shape" in entry:
            raise InputError(f"{label}: give either 'file' or 'shape', not both")
        if "file" in entry:
            chunks.append(_file_chunk(entry, label, base_dir, scale, ids))
        elif "shape" in entry:
            chunk, shape = _shape_chunk(entry, label, scale, ids, len(centers))
            chunks.append(chunk)
            if shape.sphere_center is not None:
                centers.append(shape.sphere_center)
                radii.append(shape.sphere_radius)
        else:
            raise InputError(f"{label}: needs 'file' (a geometry file) or 'shape' "
                             "(sphere, box, polygon, rectangle)")
    triangles = _assemble(chunks, warnings)
    if len(triangles) == 0:
        raise InputError(f"{where}: the scene has no triangles")
    triangles.sphere_center = np.array(centers, dtype=np.float64).reshape(-1, 3)
    triangles.sphere_radius = np.array(radii, dtype=np.float64)
    return triangles


def _material_id(name: Any, label: str, ids: dict[str, int]) -> int:
    """Id of a defined material; unknown names are an error with a suggestion."""
    if not isinstance(name, str):
        raise InputError(f"{label}: a material must be given by its name (a string), got {name!r}")
    if name not in ids:
        near = difflib.get_close_matches(name, list(ids), n=1)
        hint = f" (did you mean '{near[0]}'?)" if near else (
            " (no [materials] are defined)" if not ids else f" (defined: {', '.join(ids)})")
        raise InputError(f"{label}: unknown material '{name}'{hint}")
    return ids[name]


def _shape_chunk(entry: Mapping[str, Any], label: str, scale: float, ids: dict[str, int], sphere_index: int):
    """A primitive entry (``shape = ...``) as a chunk and its :class:`~lbl_illum.geometry.Shape`."""
    shape = shape_from_table(entry, label, scale, extra_keys=("material",))
    if "material" not in entry:
        raise InputError(f"{label}: missing key 'material'")
    n = len(shape.vertices)
    material = np.full(n, _material_id(entry["material"], label, ids), dtype=np.int32)
    sphere = np.full(n, sphere_index if shape.sphere_center is not None else -1, dtype=np.int32)
    return _Chunk(label, shape.vertices, material, sphere), shape


def _file_chunk(entry: Mapping[str, Any], label: str, base_dir: Path, scale: float,
                ids: dict[str, int]) -> _Chunk:
    """A geometry-file entry: every sub-mesh gets its mapped material or the default."""
    check_keys(entry, FILE_KEYS, label)
    file = entry["file"]
    if not isinstance(file, str) or not file:
        raise InputError(f"{label}: 'file' must be a file name, got {file!r}")
    default = _material_id(entry["material"], label, ids) if "material" in entry else None
    mapping = entry.get("materials", {})
    if not isinstance(mapping, Mapping):
        raise InputError(f"{label}: 'materials' must be a table of name = material, got {mapping!r}")
    mapped = {key: _material_id(value, f"{label}: materials.{key}", ids) for key, value in mapping.items()}
    label = f"{label} {file}"
    parts = load_mesh_file(base_dir / file, label, scale)
    vertices, material, matched = [], [], set()
    for part in parts:
        key = next((k for k in part.keys if k in mapped), None)
        if key is None and default is None:
            raise InputError(f"{label}: no material for sub-mesh {part.label}: map it in 'materials' "
                             "or give a default 'material'")
        matched.add(key)
        vertices.append(part.vertices)
        material.append(np.full(len(part.vertices), default if key is None else mapped[key], dtype=np.int32))
    _check_mapping_used(mapped, matched, parts, label)
    v = np.concatenate(vertices)
    return _Chunk(label, v, np.concatenate(material), np.full(len(v), -1, dtype=np.int32))


def _check_mapping_used(mapped: dict[str, int], matched: set, parts: list, label: str) -> None:
    """A ``materials`` key naming no sub-mesh is a typo: refuse it, suggesting the names found."""
    names = list(dict.fromkeys(k for part in parts for k in part.keys))
    for key in mapped:
        if key not in matched:
            near = difflib.get_close_matches(key, names, n=1)
            hint = f"did you mean '{near[0]}'?" if near else (
                f"names in the file: {', '.join(names)}" if names else "the file has no names")
            raise InputError(f"{label}: 'materials' key '{key}' names no material, group or mesh "
                             f"of the file ({hint})")


def _assemble(chunks: list[_Chunk], warnings: list[str]) -> Triangles:
    """Concatenate the chunks; refuse non-finite corners, drop zero-area and duplicate triangles.

    Duplicates (same three corners in any order, also across entries) keep their
    first occurrence; each entry that lost triangles gets one warning.
    """
    for chunk in chunks:
        bad = ~np.isfinite(chunk.vertices).all(axis=(1, 2))
        if bad.any():
            raise InputError(f"{chunk.label}: {plural(int(bad.sum()), 'triangle')} with a NaN or "
                             "infinite vertex coordinate")
    if not chunks:
        return Triangles(np.zeros((0, 3, 3)), np.zeros(0, np.int32), np.zeros(0, np.int32))
    vertices = np.concatenate([c.vertices for c in chunks]).astype(np.float64)
    owner = np.concatenate([np.full(len(c.vertices), i) for i, c in enumerate(chunks)]).astype(np.int64)
    zero = degenerate_mask(vertices)
    dup = np.zeros(len(vertices), dtype=bool)
    dup[~zero] = duplicate_mask(vertices[~zero])
    n_zero = np.bincount(owner[zero], minlength=len(chunks))
    n_dup = np.bincount(owner[dup], minlength=len(chunks))
    for chunk, z, d in zip(chunks, n_zero, n_dup):
        if z or d:
            what = " and ".join(f"{n} {kind}" for n, kind in ((z, "zero-area"), (d, "duplicate")) if n)
            warnings.append(f"{chunk.label}: dropped {what} {'triangle' if z + d == 1 else 'triangles'}")
    keep = ~(zero | dup)
    return Triangles(
        vertices=vertices[keep],
        material=np.concatenate([c.material for c in chunks])[keep].astype(np.int32),
        sphere=np.concatenate([c.sphere for c in chunks])[keep].astype(np.int32),
    )
