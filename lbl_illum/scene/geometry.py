"""Scene geometry as one triangle soup in metres, with a material per triangle.

Loaders for geometry files (through trimesh) and for the scene file's primitives
(sphere, box, polygon, rectangle) are added below the container.
"""

from __future__ import annotations

import difflib
import io
import logging
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import InputError, check_keys, get_number, get_vector, show

__all__ = [
    "orthonormal_basis",
    "Triangles", "MeshPart", "Shape", "SHAPE_KEYS", "SPHERE_SUBDIVISIONS", "SPHERE_MAX_DEVIATION",
    "PLANAR_TOLERANCE", "load_mesh_file", "shape_from_table", "sphere_triangles", "box_triangles",
    "rectangle_triangles", "polygon_triangles", "degenerate_mask",
    "duplicate_mask", "TriangleSampler", "MAX_COORDINATE", "check_coordinates",
]

#: Largest magnitude of a coordinate [m] the scene, its geometry files and the sensor points
#: may use.  No daylighting scene comes near it (it is 2.6 times the distance to the Moon),
#: and below it squared lengths and cross products stay far inside the float64 range, so
#: a mistyped exponent is refused instead of overflowing in the geometry code.
MAX_COORDINATE = 1e9


def check_coordinates(values, where: str, what: str = "coordinate") -> np.ndarray:
    """``values`` [m] as a float64 array; refuse NaN, infinite and out-of-range
    (|x| > :data:`MAX_COORDINATE`) entries with a one-line :class:`InputError`."""
    with np.errstate(all="ignore"):
        v = np.asarray(values, dtype=np.float64)
        bad = ~np.isfinite(v)
        if bad.any():
            raise InputError(f"{where}: {what} must be finite, got {v[bad].flat[0]!r}")
        far = np.abs(v) > MAX_COORDINATE
    if far.any():
        raise InputError(f"{where}: {what} {v[far].flat[0]:g} m is beyond ±{MAX_COORDINATE:g} m")
    return v


@dataclass
class Triangles:
    """All triangles of a scene.

    vertices : (T, 3, 3) float64 — corner positions [m]
    material : (T,) int32 — index into ``Scene.materials``
    sphere : (T,) int32 — index of the sphere primitive a triangle tessellates, or -1
    sphere_center : (S, 3) float64 [m];  sphere_radius : (S,) float64 [m]
    """

    vertices: np.ndarray
    material: np.ndarray
    sphere: np.ndarray
    sphere_center: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    sphere_radius: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return int(self.vertices.shape[0])

    @property
    def normals(self) -> np.ndarray:
        """(T, 3) unit face normals by the right-hand rule over the corners [-]."""
        v = self.vertices
        n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return n / np.where(length > 0, length, 1.0)

    @property
    def areas(self) -> np.ndarray:
        """(T,) triangle areas [m²]."""
        v = self.vertices
        return 0.5 * np.linalg.norm(np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]), axis=1)

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) min and max corner of all triangles [m]."""
        return corner_bounds(self.vertices)


def corner_bounds(vertices: np.ndarray) -> np.ndarray:
    """(2, 3) min and max over the corners of (T, 3, 3) triangles, per axis; taken column by
    column (numpy's reduction over the rows of an (n, 3) array took 5 times as long:
    0.02 s for the cabin's 204,216 triangles)."""
    flat = np.asarray(vertices).reshape(-1, 3)
    return np.array([[flat[:, k].min() for k in range(3)], [flat[:, k].max() for k in range(3)]])


# ---------------------------------------------------------------------------
# Geometry files (through trimesh)
# ---------------------------------------------------------------------------

#: Name of the material library synthesised for OBJ files (see :func:`_read_obj`).
_NAMES_MTL = "__lbl_illum_usemtl_names__.mtl"


@dataclass
class MeshPart:
    """One sub-mesh of a geometry file, with the names a scene file may map to a material.

    name : trimesh's geometry name.  OBJ (loaded with ``split_groups``): ``GROUP_MATERIAL``
        when the file uses several ``usemtl`` names and the faces follow a ``g`` line,
        otherwise the group, the ``usemtl`` name, the ``o`` object or the file name.
        glTF: the mesh name.  PLY, STL, OFF: the file name.
    node : the scene-graph node (glTF node name; equal to ``name`` for the other formats)
    group : the OBJ ``g`` group (or ``o`` object) recovered from ``name`` (None when there is none)
    material : the OBJ ``usemtl`` name or the glTF material name (None when there is none)
    vertices : (T, 3, 3) float64 corners [m], scene-graph transform applied
    """

    name: str
    node: str
    group: str | None
    material: str | None
    vertices: np.ndarray

    @property
    def keys(self) -> tuple[str, ...]:
        """Names a ``materials`` table may use for this part, most specific first."""
        names = (self.node, self.name, self.group, self.material)
        return tuple(dict.fromkeys(n for n in names if n))

    @property
    def label(self) -> str:
        """The part for messages, e.g. ``'A_Floor' (group 'A', material 'Floor')``."""
        extra = [f"{what} '{n}'" for what, n in (("node", self.node), ("group", self.group),
                                                   ("material", self.material))
                 if n and n != self.name]
        return f"'{self.name}'" + (f" ({', '.join(extra)})" if extra else "")


def load_mesh_file(path: Path, where: str, scale: float = 1.0, warnings: list[str] | None = None
                   ) -> list[MeshPart]:
    """The triangles of a geometry file as named parts, in metres.

    ``scale`` is metres per file unit.  Any format trimesh reads (OBJ, PLY, STL, glTF/GLB,
    OFF, ...) is accepted; faces are neither merged nor reordered (``process=False``,
    ``maintain_order=True``) and scene-graph transforms are applied.  OBJ faces of more
    than three vertices are triangulated as drawn, holes and keyhole seams included
    (:mod:`lbl_illum.scene.polygons`), not fanned; a face whose triangles' area differs from its
    polygon's by more than 0.1 %, or that has no area, is reported in ``warnings`` (a
    list the messages are appended to).  A Radiance scene file (``.rad``) gives its
    surfaces, one part per modifier (:func:`lbl_illum.scene.radfile.read_rad_surfaces`).  A
    missing or unreadable file, or one without triangles, is an :class:`InputError`
    starting with ``where``.  A file read before (same bytes, scale and ``where``) comes
    from :mod:`lbl_illum.scene.geometry_cache` without being parsed again.
    """
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{where}: is a folder, not a geometry file ({path})")
    if not path.is_file():
        raise InputError(f"{where}: no such file ({path})")
    if path.suffix.lower() in (".rad", ".mat"):
        from .radfile import read_rad_surfaces

        parts = read_rad_surfaces(path, where, scale, warnings)
        if not parts:
            raise InputError(f"{where}: the file contains no surfaces")
        return parts
    from . import geometry_cache

    key = geometry_cache.cache_key(path, where, scale)
    kept = geometry_cache.load(key)
    if kept is not None:                 # read before: no parse, no trimesh import
        parts, notes = kept
        if warnings is not None:
            warnings.extend(notes)
        return parts
    notes: list[str] = []
    _quiet_trimesh()
    try:
        scene = _load_trimesh_scene(path, where, scale, notes)
        parts = _scene_parts(scene, scale, obj_name=path.name if path.suffix.lower() == ".obj" else None,
                             where=where)
    except InputError:
        raise
    except PermissionError:
        raise InputError(f"{where}: cannot read the file (permission denied)") from None
    except FileNotFoundError as exc:   # a file the geometry file refers to (glTF buffers, textures)
        raise InputError(f"{where}: cannot read the file (it refers to a missing file: "
                         f"{show(str(exc.filename or exc))})") from None
    except Exception as exc:  # trimesh raises anything from ValueError to KeyError
        raise InputError(f"{where}: cannot read the file ({_reason(exc)})") from None
    if not parts:
        raise InputError(f"{where}: the file contains no triangles")
    geometry_cache.store(key, parts, notes)
    if warnings is not None:
        warnings.extend(notes)
    return parts


def _reason(exc: BaseException) -> str:
    """One line saying what an exception of a file reader was: ``Type: first line``."""
    text = str(exc).strip()
    first = text.splitlines()[0] if text else ""
    first = first if len(first) <= 100 else first[:97] + "..."
    return f"{type(exc).__name__}: {first}" if first else type(exc).__name__


def _quiet_trimesh() -> None:
    """Give trimesh's logger a NullHandler, as libraries should: without any handler,
    Python prints its warnings about odd files on standard error, beside our one-line
    messages.  An application that configures logging still receives them."""
    log = logging.getLogger("trimesh")
    if not any(isinstance(h, logging.NullHandler) for h in log.handlers):
        log.addHandler(logging.NullHandler())


def _load_trimesh_scene(path: Path, where: str, scale: float, warnings: list[str] | None):
    """``trimesh.Scene`` of a file; OBJ files go through :func:`_read_obj`."""
    import trimesh

    if path.suffix.lower() == ".obj":
        return _read_obj(path, where, scale, warnings)
    return trimesh.load(str(path), force="scene", process=False, maintain_order=True)


def _read_obj(path: Path, where: str = "obj", scale: float = 1.0, warnings: list[str] | None = None):
    """Load an OBJ keeping every ``usemtl`` name and ``g`` group, its polygons as drawn.

    trimesh splits an OBJ at every ``usemtl`` but only remembers the name when the
    ``.mtl`` library loads, so a library naming every ``usemtl`` is synthesised (the
    scene file defines the materials; the ``.mtl`` colours are not used).  Groups
    become separate sub-meshes (``split_groups``); ``group_material`` stays on, since
    without it trimesh merges a group's faces of different materials.  Faces of more
    than three vertices are replaced by their triangles first (:func:`_triangulate_obj`):
    trimesh would fan them.
    """
    import trimesh

    text = path.read_bytes().decode("utf-8", errors="replace")
    text = _triangulate_obj(text, where, scale, warnings)
    names = list(dict.fromkeys(" ".join(m.split()) for m in
                               re.findall(r"^[ \t]*usemtl[ \t]+(.+?)[ \t]*\r?$", text, flags=re.M)))
    resolver = {}
    if names:
        text = f"mtllib {_NAMES_MTL}\n" + text
        resolver[_NAMES_MTL] = "".join(f"newmtl {n}\n" for n in names).encode()
    stream = io.BytesIO(text.encode())
    stream.name = path.name
    return trimesh.load(stream, file_type="obj", resolver=resolver, force="scene", process=False,
                        maintain_order=True, split_groups=True, group_material=True)


#: A face line of four or more vertices (``f a b c d ...``, each ``v``, ``v/t``, ``v//n`` or ``v/t/n``).
_OBJ_POLYGON = re.compile(r"^[ \t]*f(?:[ \t]+[^\s#]+){4,}", re.M)


def _triangulate_obj(text: str, where: str, scale: float, warnings: list[str] | None) -> str:
    """``text`` with every OBJ face of more than three vertices replaced by its triangles,
    read as drawn by the even–odd rule (:func:`lbl_illum.scene.polygons.triangulate_faces`):
    non-convex outlines, holes joined by keyhole seams, either winding.  Each triangle
    keeps its corners' ``v/t/n`` references.  Faces whose triangles' area differs from
    the polygon's by more than :data:`~lbl_illum.scene.polygons.AREA_TOLERANCE`, and faces of
    zero area (dropped), are reported in ``warnings`` by line, with both areas in m².
    Text without such faces is returned unchanged."""
    from .polygons import area_warnings, triangulate_faces

    if not _OBJ_POLYGON.search(text):
        return text
    lines = text.split("\n")
    coords, polygons = [], []          # vertex lines' numbers; (line, vertex tokens) of polygons
    for i, line in enumerate(lines):
        head = line.lstrip()[:2]
        if head == "v " or head == "v\t":
            coords.append(line.split()[1:4])
        elif head == "f " or head == "f\t":
            tokens = line.split("#", 1)[0].split()[1:]
            if len(tokens) > 3:
                polygons.append((i, tokens, len(coords)))
    try:
        V = np.array(coords, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        return text                    # malformed vertices: trimesh says what is wrong
    points, faces, offset = [], [], 0
    for line, tokens, defined in polygons:
        index = []
        for token in tokens:
            try:
                k = int(token.split("/", 1)[0])
            except ValueError:
                return text
            index.append(k - 1 if k > 0 else defined + k)
        index = np.array(index, np.int64)
        if index.min() < 0 or index.max() >= len(V):
            return text                # trimesh refuses the reference (see _scene_parts)
        points.append(V[index])
        faces.append(np.arange(offset, offset + len(index)))
        offset += len(index)
    result = triangulate_faces(np.concatenate(points), faces)
    first = np.concatenate([[0], np.cumsum([len(t) for _, t, _ in polygons])])
    out = [[] for _ in polygons]
    for face, tri in zip(result.face, result.triangles):
        tokens = polygons[face][1]
        base = first[face]
        out[face].append("f " + " ".join(tokens[int(c) - base] for c in tri))
    for (line, _, _), triangles in zip(polygons, out):
        lines[line] = "\n".join(triangles)
    if warnings is not None:
        warnings += area_warnings(result, where, lambda f: f"line {polygons[f][0] + 1} ({len(polygons[f][1])} "
                                  "vertices)", scale * scale)
    return "\n".join(lines)


def _scene_parts(scene, scale: float, obj_name: str | None, where: str = "geometry file") -> list[MeshPart]:
    """The triangle meshes of a trimesh scene as :class:`MeshPart` s in metres.

    ``obj_name`` is the file name of an OBJ file (None for other formats); ``where`` names
    the file in messages.  A face whose vertex index is out of range is an :class:`InputError`.
    """
    import trimesh

    parts = []
    for node in scene.graph.nodes_geometry:
        transform, geom_name = scene.graph[node]
        mesh = scene.geometry[geom_name]
        if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
            continue
        faces = np.asarray(mesh.faces, dtype=np.int64)
        vertices = np.asarray(mesh.vertices, dtype=np.float64).reshape(-1, 3)
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.min() < 0 or faces.max() >= len(vertices):
            raise InputError(f"{where}: sub-mesh '{geom_name}': a face refers to a vertex the file does not "
                             f"have ({len(vertices)} vertices)")
        with np.errstate(all="ignore"):     # NaN, infinite and huge corners are refused by the caller
            tri = _transform(vertices[faces], np.asarray(transform, dtype=np.float64)) * scale
        material = getattr(getattr(mesh.visual, "material", None), "name", None) or None
        group = _obj_group(str(geom_name), material, obj_name) if obj_name else None
        parts.append(MeshPart(str(geom_name), str(node), group, material, tri))
    return parts


def _transform(tri: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Apply a 4×4 affine transform to (T, 3, 3) corners, keeping outward winding."""
    out = tri @ matrix[:3, :3].T + matrix[:3, 3]
    if np.linalg.det(matrix[:3, :3]) < 0:       # a mirror flips the winding: swap two corners
        out = out[:, [0, 2, 1]]
    return out


def _obj_group(name: str, material: str | None, file_name: str) -> str | None:
    """The ``g`` group (or ``o`` object) in a trimesh OBJ sub-mesh name ``GROUP_MATERIAL``."""
    if material and name.endswith("_" + material) and len(name) > len(material) + 1:
        return name[: -len(material) - 1]
    if name in (material, file_name, "geometry"):
        return None
    return name


# ---------------------------------------------------------------------------
# Primitives of the scene file
# ---------------------------------------------------------------------------

#: Icosphere subdivision level of sphere primitives: 20·4⁶ = 81,920 triangles.
SPHERE_SUBDIVISIONS = 6
#: Largest distance between the facets and the true sphere, as a fraction of the radius,
#: measured (tests/test_geometry.py) as 1 − min over facets of the plane's distance from
#: the centre: 7.12e-5.  The edge-midpoint deviation r(1 − cos(θ_max/2)), θ_max = 1.1845°
#: the largest edge angle, is smaller, 5.34e-5; subdivision 5 would give 2.85e-4.
SPHERE_MAX_DEVIATION = 7.2e-5
#: Polygons whose vertices leave their mean plane by more than this fraction of the
#: polygon's diameter are refused as non-planar.
PLANAR_TOLERANCE = 1e-4
#: Relative size below which a cross product counts as zero (collinear corners).
_EPS = 1e-12

#: Keys of each primitive (all required).
SHAPE_KEYS = {
    "sphere": ("center", "radius"),
    "box": ("center", "size"),
    "polygon": ("vertices",),
    "rectangle": ("origin", "u", "v"),
}


@dataclass
class Shape:
    """Triangles of one primitive [m]; spheres also keep their true centre [m] and radius [m]."""

    vertices: np.ndarray
    sphere_center: np.ndarray | None = None
    sphere_radius: float | None = None


def shape_from_table(table: Mapping[str, Any], where: str, scale: float = 1.0,
                     extra_keys: tuple[str, ...] = ()) -> Shape:
    """The primitive of a ``[[geometry]]`` table with a ``shape`` key.

    Lengths are in scene units, multiplied by ``scale`` (metres per unit).  Keys other
    than ``shape``, the shape's own keys and ``extra_keys`` are refused.
    """
    kind = table.get("shape")
    if not isinstance(kind, str) or kind not in SHAPE_KEYS:
        near = difflib.get_close_matches(kind, SHAPE_KEYS, n=1) if isinstance(kind, str) else []
        hint = f" (did you mean '{near[0]}'?)" if near else f" (valid: {', '.join(SHAPE_KEYS)})"
        raise InputError(f"{where}: unknown shape {show(kind)}{hint}")
    check_keys(table, ("shape",) + SHAPE_KEYS[kind] + tuple(extra_keys), where, required=SHAPE_KEYS[kind])

    def length(key, value):
        return check_coordinates(np.asarray(value, dtype=np.float64) * scale, where, f"'{key}'")

    if kind == "sphere":
        center = length("center", get_vector(table, "center", where))
        radius = float(length("radius", get_number(table, "radius", where, minimum=0.0, min_inclusive=False)))
        if radius <= 0.0:
            raise InputError(f"{where}: 'radius' must be > 0, got {table['radius']!r} (zero in metres)")
        return Shape(sphere_triangles(center, radius), center, radius)
    if kind == "box":
        size = np.array(get_vector(table, "size", where))
        if np.any(size <= 0):
            raise InputError(f"{where}: 'size' must be > 0 along every axis, got {show(table['size'])}")
        return Shape(box_triangles(length("center", get_vector(table, "center", where)), length("size", size)))
    if kind == "rectangle":
        origin, u, v = (length(k, get_vector(table, k, where)) for k in ("origin", "u", "v"))
        return Shape(rectangle_triangles(origin, u, v, where))
    return Shape(polygon_triangles(length("vertices", _get_points(table, "vertices", where)), where))


def _get_points(table: Mapping[str, Any], key: str, where: str) -> np.ndarray:
    """(n, 3) array from a list of ``[x, y, z]`` in ``table[key]``, every number finite."""
    value = table[key]
    if not isinstance(value, (list, tuple)):
        raise InputError(f"{where}: '{key}' must be a list of [x, y, z] points, got {show(value)}")
    points = [get_vector({f"{key}[{i}]": p}, f"{key}[{i}]", where) for i, p in enumerate(value)]
    return np.array(points, dtype=np.float64).reshape(-1, 3)


@lru_cache(maxsize=1)
def _unit_icosphere() -> np.ndarray:
    """(81920, 3, 3) corners of the unit icosphere, outward winding, vertices on the sphere."""
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=1.0)
    tri = np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces)]
    tri.setflags(write=False)
    return tri


def sphere_triangles(center, radius: float) -> np.ndarray:
    """(81920, 3, 3) triangles inscribed in the sphere (``center``, ``radius``), normals outward.

    Vertices lie on the sphere; facets are within ``SPHERE_MAX_DEVIATION``·radius of it.
    Units are those of the arguments (metres in the scene).
    """
    return np.asarray(center, dtype=np.float64) + float(radius) * _unit_icosphere()


#: Corner k of a box is at center + size/2 · _BOX_SIGNS[k] (bit 0: x, bit 1: y, bit 2: z).
_BOX_SIGNS = np.array([[1 if k & b else -1 for b in (1, 2, 4)] for k in range(8)], dtype=np.float64)
#: Two outward-wound triangles per face: -x, +x, -y, +y, -z, +z.
_BOX_FACES = np.array([[0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5], [0, 1, 5], [0, 5, 4],
                       [2, 6, 7], [2, 7, 3], [0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6]])


def box_triangles(center, size) -> np.ndarray:
    """(12, 3, 3) triangles of an axis-aligned box, normals outward (units of the arguments)."""
    corners = np.asarray(center, dtype=np.float64) + 0.5 * np.asarray(size, dtype=np.float64) * _BOX_SIGNS
    return corners[_BOX_FACES]


def rectangle_triangles(origin, u, v, where: str = "rectangle") -> np.ndarray:
    """(2, 3, 3) triangles of the parallelogram origin + s·u + t·v, s, t ∈ [0, 1].

    The normal is along u × v.  Units are those of the arguments.
    """
    o, u, v = (check_coordinates(a, where) for a in (origin, u, v))
    if np.linalg.norm(np.cross(u, v)) <= _EPS * np.linalg.norm(u) * np.linalg.norm(v) or not (
            np.any(u) and np.any(v)):
        raise InputError(f"{where}: 'u' and 'v' span no area (zero or parallel)")
    return np.array([[o, o + u, o + u + v], [o, o + u + v, o + v]])


def polygon_triangles(points, where: str = "polygon") -> np.ndarray:
    """(m, 3, 3) triangles of a planar polygon given by its (n, 3) vertices.

    The polygon may be non-convex and may have holes joined to its outline by keyhole
    seams, wound either way: it is read by the even–odd rule, as Radiance reads
    polygons (:func:`lbl_illum.scene.polygons.triangulate_face`).  Triangles are wound like the
    polygon (normal by the right-hand rule over its outline).  Fewer than 3 vertices,
    zero area, vertices off the plane by more than ``PLANAR_TOLERANCE`` of the diameter,
    and edges that cross (triangles whose area differs from the polygon's by more than
    :data:`~lbl_illum.scene.polygons.AREA_TOLERANCE`) are refused.  Units are those of ``points``.
    """
    from .polygons import AREA_TOLERANCE, face_frame, triangulate_face

    p = check_coordinates(points, where, "vertex coordinate").reshape(-1, 3)
    if len(p) < 3:
        raise InputError(f"{where}: a polygon needs at least 3 vertices, got {len(p)}")
    diameter = float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))
    area_vector = 0.5 * np.sum(np.cross(p, np.roll(p, -1, axis=0)), axis=0)     # Newell
    if float(np.linalg.norm(area_vector)) <= _EPS * diameter * diameter:
        raise InputError(f"{where}: the polygon has zero area")
    normal = face_frame(p)[0]
    off = np.abs((p - p.mean(axis=0)) @ normal)
    if off.max() > PLANAR_TOLERANCE * diameter:
        k = int(off.argmax())
        raise InputError(f"{where}: the polygon is not planar (vertex {k} is {off[k]:.3g} off its plane)")
    index, area = triangulate_face(p)
    tri = p[index]
    tri_area = float(0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
    if area <= 0.0 or abs(tri_area - area) > AREA_TOLERANCE * area:
        raise InputError(f"{where}: the polygon cannot be triangulated as drawn (do its edges cross?): its "
                         f"triangles cover {tri_area:.6g}, the polygon {area:.6g} square units")
    return tri


# ---------------------------------------------------------------------------
# Clean-up of the assembled triangles
# ---------------------------------------------------------------------------

def degenerate_mask(vertices: np.ndarray) -> np.ndarray:
    """(T,) bool: triangles of zero area (|cross| ≤ 1e-12 · longest edge², any length unit).

    Computed on coordinate columns, with the operations of ``np.cross`` and
    ``np.linalg.norm`` in their order (the same bits, in a third of the time)."""
    v = np.asarray(vertices, dtype=np.float64)

    def edge(k: int, j: int):
        return tuple(v[:, j, c] - v[:, k, c] for c in range(3))

    ax, ay, az = edge(0, 1)
    bx, by, bz = edge(0, 2)
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    cross = np.sqrt(cx * cx + cy * cy + cz * cz)
    longest = np.zeros(len(v))
    for k in range(3):
        dx, dy, dz = edge(k, (k + 1) % 3)
        longest = np.maximum(longest, np.sqrt(dx * dx + dy * dy + dz * dz))
    return cross <= _EPS * longest ** 2


def duplicate_mask(vertices: np.ndarray) -> np.ndarray:
    """(T,) bool: triangles whose three corners (in any order) equal an earlier triangle's.

    A 64-bit hash independent of the corner order picks the candidates (equal hashes);
    only those are compared exactly, corners in lexicographic order.
    """
    v = np.ascontiguousarray(np.asarray(vertices, dtype=np.float64) + 0.0)     # -0.0 → 0.0
    mask = np.zeros(len(v), dtype=bool)
    if len(v) < 2:
        return mask
    bits = v.view(np.uint64)
    with np.errstate(over="ignore"):
        hashed = np.zeros(len(v), np.uint64)                                    # wraps mod 2**64
        for k in range(3):                                                      # symmetric in the corners
            corner = bits[:, k, 0] * _HASH_MULTIPLIERS[0]
            corner += bits[:, k, 1] * _HASH_MULTIPLIERS[1]
            corner += bits[:, k, 2] * _HASH_MULTIPLIERS[2]
            corner ^= corner >> np.uint64(31)
            corner *= _HASH_MIX
            corner ^= corner >> np.uint64(29)
            hashed += corner
    order = np.argsort(hashed, kind="stable")
    same = hashed[order[1:]] == hashed[order[:-1]]
    candidate = np.zeros(len(v), dtype=bool)
    candidate[order[1:][same]] = candidate[order[:-1][same]] = True
    index = np.flatnonzero(candidate)
    if len(index):
        c = v[index]
        for axis in (2, 1, 0):                                  # lexicographic order of the corners
            c = np.take_along_axis(c, np.argsort(c[:, :, axis], axis=1, kind="stable")[:, :, None], axis=1)
        _, first = np.unique(c.reshape(len(c), 9), axis=0, return_index=True)
        mask[index] = True
        mask[index[first]] = False
    return mask


#: Odd 64-bit constants of the triangle hash in :func:`duplicate_mask`.
_HASH_MULTIPLIERS = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], dtype=np.uint64)
_HASH_MIX = np.uint64(0xFF51AFD7ED558CCD)


class TriangleSampler:
    """Points on a set of triangles, each chosen with probability ∝ ``weight`` (default:
    area) and uniform on it: the area density at a sampled point is ``prob / area``.

    Used for light surfaces (direct light) and window portals (indirect light).

    Reference: Pharr, Jakob & Humphreys, *Physically Based Rendering*, 4th ed., §6.5.4.
    """

    def __init__(self, triangles: Triangles, ids: np.ndarray, weight: np.ndarray | None = None):
        self.ids = np.asarray(ids, np.int64)
        self.vertices = triangles.vertices[self.ids]
        self.normals = triangles.normals[self.ids]
        self.area = triangles.areas[self.ids]
        w = self.area if weight is None or np.sum(weight) <= 0 else np.asarray(weight, np.float64)
        self.prob = w / w.sum()
        self.cdf = np.cumsum(self.prob)
        self.cdf[-1] = 1.0

    def __len__(self) -> int:
        return len(self.ids)

    def sample(self, rng: np.random.Generator, n: int):
        """``(index, points, pdf_area)``: (n,) index into ``ids``, (n, 3) points [m], (n,) [1/m²]."""
        return self._place(rng.random(n), rng.random(n))

    def sample_stratified(self, rng: np.random.Generator, groups: int, per: int):
        """Like :meth:`sample`, ``groups`` sets of ``gx · gy ≈ per`` points, each set a
        jittered gx × gy grid over the unit square mapped onto the triangles (the area
        CDF along one axis, the square-to-triangle map within a triangle), so every set
        covers the triangles evenly.  Returns ``(index, points, pdf_area, count)`` with
        ``count = gx · gy`` points per set, sets one after another.
        """
        gx, gy = self.grid(per)
        i = np.repeat(np.arange(gx), gy)[None, :]
        j = np.tile(np.arange(gy), gx)[None, :]
        a = ((i + rng.random((groups, gx * gy))) / gx).ravel()
        b = ((j + rng.random((groups, gx * gy))) / gy).ravel()
        k, x, pdf = self._place(a, b, square=True)
        return k, x, pdf, gx * gy

    @staticmethod
    def grid(per: int) -> tuple[int, int]:
        """(gx, gy) of the stratified sets of :meth:`sample_stratified`."""
        gx = max(1, int(round(np.sqrt(per))))
        return gx, max(1, int(round(per / gx)))

    def pdf_area(self, k: np.ndarray) -> np.ndarray:
        """Area density [1/m²] of points on sampled triangle(s) ``k`` (index into ``ids``)."""
        return self.prob[k] / self.area[k]

    def _place(self, a, b, square=False):
        k = np.minimum(np.searchsorted(self.cdf, a, side="right"), len(self.ids) - 1)
        V = np.take(self.vertices, k, axis=0)          # as vertices[k], a third of the time
        if square:
            # position of a within triangle k's stretch of the CDF, then the
            # continuous square-to-triangle map (1 - √a', √a' (1 - b), √a' b)
            start = self.cdf[k] - self.prob[k]
            s = np.sqrt(np.clip((a - start) / self.prob[k], 0.0, 1.0))
            u, v = s * (1.0 - b), s * b
        else:
            flip = a + b > 1.0
            u = np.where(flip, 1.0 - a, a)
            v = np.where(flip, 1.0 - b, b)
        x = V[:, 0] + u[:, None] * (V[:, 1] - V[:, 0]) + v[:, None] * (V[:, 2] - V[:, 0])
        return k, x, self.pdf_area(k)


def orthonormal_basis(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two (n, 3) unit tangents completing (n, 3) unit ``normals`` to a right-handed frame.

    Branch-free construction of Duff et al., "Building an Orthonormal Basis,
    Revisited", JCGT 6(1), 2017.
    """
    n = np.asarray(normals, dtype=np.float64)
    x, y, z = n[:, 0], n[:, 1], n[:, 2]
    sign = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + z)
    b = x * y * a
    t = np.stack([1.0 + sign * x * x * a, sign * b, -sign * x], axis=1)
    s = np.stack([b, sign + y * y * a, -y], axis=1)
    return t, s
