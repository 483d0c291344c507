"""Write the furnished office: the side-lit office of ``examples/office`` with desks, chairs,
bookcases and a coffered ceiling, at a chosen number of triangles.

Run:  python examples/furnished_office/make_furnished_office.py [--triangles N] [--out DIR]

The room shell (4 × 6 × 3 m, south window 3 × 1.5 m with its glass, ground outside) is
taken unchanged from ``examples/office/make_office.py``.  Added, all diffuse:

* 4 desks (top 1.4 × 0.7 m, work surface at 0.72 m; four legs; a drawer pedestal);
* 4 office chairs (seat, back, back support, gas column; at higher detail a five-star base
  with a hub and, higher still, castors);
* 3 bookcases 2 m tall (two on the north wall, one on the east wall), five compartments
  each, filled with books and archive boxes (at the lowest detail, one block per
  compartment);
* a coffered ceiling: a grid of square coffers of pitch p, each a flat soffit frame and
  four bevelled sides rising to the ceiling plane, with a small cylinder (a sprinkler head
  or downlight trim; not a light source) in every coffer from the second detail tier on.

``--triangles N`` sets the size.  The detail tier (cylinder sections, castors, single
books) follows N, and the coffer pitch p = 2 m / n is chosen with the integer n that
brings the total closest to N; the ceiling carries most of the triangles of large
scenes.  The coarsest scene, the bare room with box furniture, has about 1,000.
Everything is deterministic (no random numbers): the same N gives the same files.

Output in ``--out`` (default ``build/`` beside this script), each file written to a
temporary name and renamed:

* one binary PLY per material group (``floor.ply``, ``walls.ply``, ``ceiling.ply``,
  ``glazing.ply``, ``ground.ply``, ``desks.ply``, ``chairs.ply``, ``shelves.ply``,
  ``books.ply``), float64 vertices shared within each file;
* ``scene.toml`` mapping each file to its material (one ``[[geometry]]`` entry per file)
  with the office's sky and glazing;
* ``grid.pts``: the office's 77 workplane sensors (0.5 m grid at z = 0.8 m, 0.5 m from
  the walls), unchanged.  The desk work surfaces are at 0.72 m, so the sensors above a
  desk lie 8 cm above its surface; no sensor lies inside furniture (checked when writing).

Axes: +x east, +y north, +z up; lengths in metres.  Reflectances: desks 0.4, chairs 0.15
(dark fabric), bookcases 0.5, books 0.3 (a mix of covers), ceiling 0.8, floor 0.2,
walls 0.5, ground 0.2; glazing transmittance 0.6 (a window portal), as in the office.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DEFAULT_OUT = HERE / "build"
DEFAULT_TRIANGLES = 1_000_000
MIN_TRIANGLES = 1_000
MAX_TRIANGLES = 20_000_000


def _office_module():
    """``examples/office/make_office.py`` as a module (the room shell and the grid)."""
    path = HERE.parent / "office" / "make_office.py"
    spec = importlib.util.spec_from_file_location("make_office", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


office = _office_module()
W, D, H = office.W, office.D, office.H          # room interior [m]

# -- furniture dimensions [m] ------------------------------------------------------------
DESK_SIZE = (1.4, 0.7)          # top, x by y
DESK_TOP = 0.72                 # work surface height
DESK_THICK = 0.025
DESK_LEG_R = 0.025
DESK_CENTRES = ((1.0, 1.5), (3.0, 1.5), (1.0, 3.3), (3.0, 3.3))
CHAIR_OFFSET = 0.6              # chair centre north of its desk's centre
SEAT = (0.46, 0.46, 0.42, 0.48)     # width, depth, bottom, top
CHAIR_BACK = (0.44, 0.21, 0.25, 0.55, 0.97)  # width, y from .. to (behind the seat centre), z from .. to
STAR_RADIUS = 0.30              # reach of the five-star base's arms
CASTOR_R = 0.025
CASE_DEPTH = 0.35
CASE_HEIGHT = 2.0
CASE_PANEL = 0.02
CASE_PLINTH = 0.08
CASE_LEVELS = 5
#: bookcases: (width, rotation about z [deg], translation); local frame: x along the
#: width, front at y = 0 facing -y, back at y = CASE_DEPTH, 1 cm off the wall behind.
CASES = ((1.6, 0.0, (0.2, D - 0.01 - CASE_DEPTH)),
         (1.6, 0.0, (2.2, D - 0.01 - CASE_DEPTH)),
         (1.2, -90.0, (W - 0.01 - CASE_DEPTH, 5.4)))
#: coffer proportions as fractions of the pitch p: soffit frame width, bevel run, depth
COFFER_FRAME, COFFER_BEVEL, COFFER_DEPTH = 0.1, 0.1, 0.08
#: ceiling cylinder: radius and drop as fractions of the pitch and of the coffer depth
FIXTURE_RADIUS, FIXTURE_DROP = 0.12, 0.5
#: a sensor closer than this to the inside of a furniture box counts as inside it
SENSOR_CLEARANCE = 0.01

MATERIALS = {   # group -> (material, type, value, comment)
    "floor": ("floor", "reflectance", 0.2, "Floor: dark carpet."),
    "walls": ("wall", "reflectance", 0.5, "Walls: mid-grey matte finish."),
    "ceiling": ("ceiling", "reflectance", 0.8, "Ceiling, coffers and ceiling fittings: white matte."),
    "glazing": ("glazing", "transmittance", 0.6, "Window: clear double glazing, a portal for the "
                "indirect calculation (as in examples/office)."),
    "ground": ("ground", "reflectance", 0.2, "Ground outside the window."),
    "desks": ("desk", "reflectance", 0.4, "Desks: mid-tone wood laminate."),
    "chairs": ("chair", "reflectance", 0.15, "Chairs: dark fabric and black plastic."),
    "shelves": ("shelf", "reflectance", 0.5, "Bookcases: light-grey melamine."),
    "books": ("books", "reflectance", 0.3, "Books and archive boxes: a mix of covers, 30 % on average."),
}
OFFICE_GROUPS = {"Floor": "floor", "Walls": "walls", "Ceiling": "ceiling", "Glass": "glazing", "Ground": "ground"}


# ---------------------------------------------------------------------------------------
# Level of detail
# ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Detail:
    """What the generator tessellates and how finely.

    sections : sides of every cylinder (0: square legs and columns, no five-star base)
    books : single books (else one block per compartment)
    castors : castors on the five-star bases
    fixtures : a cylinder in every coffer
    divisions : coffers per 2 m (pitch p = 2 m / divisions; 4 and 6 m are multiples of 2 m)
    """

    sections: int
    books: bool
    castors: bool
    fixtures: bool
    divisions: int = 1

    @property
    def pitch(self) -> float:
        return 2.0 / self.divisions


def tier_for(target: int) -> Detail:
    """The furniture's detail for a total of about ``target`` triangles (divisions = 1)."""
    if target < 3_000:
        return Detail(sections=0, books=False, castors=False, fixtures=False)
    if target < 30_000:
        return Detail(sections=8, books=True, castors=False, fixtures=True)
    sections = int(np.clip(2 * round(4.0 * math.sqrt(target / 30_000)), 8, 96))
    return Detail(sections=sections, books=True, castors=True, fixtures=True)


def detail_for(target: int) -> Detail:
    """:func:`tier_for` with the coffer divisions n whose total is closest to ``target``."""
    base = tier_for(target)
    rest = sum(len(t) for name, t in build_groups(base).items() if name != "ceiling") + len(office_ceiling())
    per_cell = len(coffer_cell(base))
    # 4 × 6 m at pitch 2/n holds (2n)(3n) = 6n² coffers
    n0 = max(1, int(math.sqrt(max(target - rest, 0) / (6.0 * per_cell))))
    best = min(range(max(1, n0 - 1), n0 + 3), key=lambda n: abs(rest + 6 * n * n * per_cell - target))
    return Detail(base.sections, base.books, base.castors, base.fixtures, best)


# ---------------------------------------------------------------------------------------
# Triangle helpers: every part is a (T, 3, 3) float64 array of corners [m]
# ---------------------------------------------------------------------------------------

_AXES = {"-x": (-1, 0, 0), "+x": (1, 0, 0), "-y": (0, -1, 0), "+y": (0, 1, 0), "-z": (0, 0, -1), "+z": (0, 0, 1)}


def _corners(mesh) -> np.ndarray:
    return np.asarray(mesh.vertices, dtype=np.float64)[np.asarray(mesh.faces, dtype=np.int64)]


def _drop(tri: np.ndarray, faces: tuple[str, ...]) -> np.ndarray:
    """``tri`` without the triangles whose normal points along one of ``faces``
    (hidden faces: a box's bottom on the floor, a leg's ends inside the parts it joins)."""
    if not faces or len(tri) == 0:
        return tri
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    keep = np.ones(len(tri), dtype=bool)
    for face in faces:
        keep &= n @ np.array(_AXES[face], dtype=np.float64) < 0.999
    return tri[keep]


def box(lo, hi, drop: tuple[str, ...] = ()) -> np.ndarray:
    """Axis-aligned box from corner ``lo`` to ``hi``, outward normals, minus ``drop`` faces."""
    import trimesh

    return _drop(_corners(trimesh.creation.box(bounds=np.array([lo, hi], dtype=np.float64))), drop)


def cylinder(radius: float, z0: float, z1: float, sections: int, drop: tuple[str, ...] = ()) -> np.ndarray:
    """Vertical cylinder about the z axis from z0 to z1; ``drop`` '-z'/'+z' removes a cap."""
    import trimesh

    mesh = trimesh.creation.cylinder(radius=radius, segment=[[0, 0, z0], [0, 0, z1]], sections=sections)
    return _drop(_corners(mesh), drop)


def transform(tri: np.ndarray, angle_deg: float = 0.0, offset=(0.0, 0.0, 0.0), axis=(0, 0, 1)) -> np.ndarray:
    """``tri`` rotated by ``angle_deg`` about ``axis`` through the origin, then moved by ``offset``."""
    import trimesh

    m = trimesh.transformations.rotation_matrix(math.radians(angle_deg), axis)
    return tri @ m[:3, :3].T + np.asarray(offset, dtype=np.float64)


def instances(template: np.ndarray, offsets) -> np.ndarray:
    """Copies of ``template`` moved by each of the (k, 3) ``offsets``, in order."""
    offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 1, 1, 3)
    return (template[None] + offsets).reshape(-1, 3, 3)


def _cat(parts) -> np.ndarray:
    parts = [p for p in parts if len(p)]
    return np.concatenate(parts) if parts else np.zeros((0, 3, 3))


# ---------------------------------------------------------------------------------------
# Furniture (local frames, then placed)
# ---------------------------------------------------------------------------------------

def desk(detail: Detail) -> np.ndarray:
    """A desk centred on the origin: top, four legs, a drawer pedestal (floor at z = 0)."""
    wx, wy = DESK_SIZE[0] / 2, DESK_SIZE[1] / 2
    under = DESK_TOP - DESK_THICK
    parts = [box((-wx, -wy, under), (wx, wy, DESK_TOP))]
    legs = [(sx * (wx - 0.06), sy * (wy - 0.06), 0.0) for sx in (-1, 1) for sy in (-1, 1)]
    if detail.sections:
        leg = cylinder(DESK_LEG_R, 0.0, under, detail.sections, drop=("-z", "+z"))
    else:
        r = DESK_LEG_R
        leg = box((-r, -r, 0.0), (r, r, under), drop=("-z", "+z"))
    parts.append(instances(leg, legs))
    parts.append(box((0.15, -wy + 0.05, 0.0), (0.55, wy - 0.05, 0.6), drop=("-z",)))   # pedestal
    return _cat(parts)


def chair(detail: Detail) -> np.ndarray:
    """An office chair centred on the origin, facing -y (its back towards +y)."""
    sw, sd, s0, s1 = SEAT
    bw, by0, by1, bz0, bz1 = CHAIR_BACK
    parts = [box((-sw / 2, -sd / 2, s0), (sw / 2, sd / 2, s1)),
             box((-bw / 2, by0, bz0), (bw / 2, by1, bz1)),
             box((-0.03, 0.15, 0.45), (0.03, by0, 0.60), drop=("+y",))]            # back support
    hub_top = 0.12
    if detail.sections:
        s = detail.sections
        parts.append(cylinder(0.025, hub_top, s0, s, drop=("-z", "+z")))            # gas column
        parts.append(cylinder(0.045, 0.05, hub_top, s))                             # hub
        arm = box((0.0, -0.02, 0.05), (STAR_RADIUS, 0.02, 0.08), drop=("-x",))
        parts += [transform(arm, 90.0 + 72.0 * k) for k in range(5)]
        if detail.castors:
            import trimesh

            wheel = _corners(trimesh.creation.cylinder(radius=CASTOR_R, height=0.02, sections=s))
            wheel = transform(wheel, 90.0, axis=(1, 0, 0))          # axle along y, across an arm along x
            wheel = transform(wheel, 0.0, (STAR_RADIUS - 0.02, 0.0, CASTOR_R + 0.002))
            parts += [transform(wheel, 90.0 + 72.0 * k) for k in range(5)]
    else:
        parts.append(box((-0.025, -0.025, 0.05), (0.025, 0.025, s0), drop=("-z", "+z")))
        parts.append(box((-0.28, -0.28, 0.0), (0.28, 0.28, 0.05), drop=("-z",)))    # base plate
    return _cat(parts)


def _golden(k: int, shift: float) -> float:
    """Fractional part of k·φ⁻¹ + shift: a deterministic, evenly spread sequence in [0, 1)."""
    return math.modf(k * 0.6180339887498949 + shift)[0]


def bookcase(width: float, detail: Detail) -> tuple[np.ndarray, np.ndarray]:
    """(carcass, books) of a bookcase in its local frame (front y = 0, facing -y)."""
    t, dep, top = CASE_PANEL, CASE_DEPTH, CASE_HEIGHT
    carcass = [box((0, 0, 0), (t, dep, top), drop=("-z",)),
               box((width - t, 0, 0), (width, dep, top), drop=("-z",)),
               box((t, 0, top - t), (width - t, dep, top), drop=("-x", "+x")),
               box((t, 0, 0), (width - t, dep, CASE_PLINTH), drop=("-x", "+x", "-z")),
               box((t, dep - 0.01, CASE_PLINTH), (width - t, dep, top - t), drop=("-x", "+x", "-z", "+z"))]
    step = (top - t - CASE_PLINTH) / CASE_LEVELS
    floors = [CASE_PLINTH + k * step for k in range(CASE_LEVELS)]      # top of each compartment's floor
    for z in floors[1:]:
        carcass.append(box((t, 0, z - t), (width - t, dep - 0.01, z), drop=("-x", "+x", "+y")))
    clear = step - t                                                   # compartment height
    books = []
    for c, z in enumerate(floors):
        x0, x1 = t + 0.01, width - t - 0.01
        if not detail.books:
            books.append(box((x0 + 0.01, 0.03, z), (x1 - 0.01, 0.27, z + 0.7 * clear), drop=("-z",)))
            continue
        x, k = x0, 0
        archive = c % 4 == 2                     # one compartment in four holds archive boxes
        while True:
            key = 37 * c + k
            if archive:
                w, h, d = 0.10, min(0.30, clear - 0.03), 0.30
            else:
                w = 0.018 + 0.030 * _golden(key, 0.0)
                h = min(0.17 + 0.12 * _golden(key, 0.31), clear - 0.03)
                d = 0.16 + 0.08 * _golden(key, 0.67)
            if x + w > x1:
                break
            books.append(box((x, 0.02, z), (x + w, 0.02 + d, z + h), drop=("-z",)))
            x += w + 0.003
            k += 1
    return _cat(carcass), _cat(books)


# ---------------------------------------------------------------------------------------
# Ceiling
# ---------------------------------------------------------------------------------------

def coffer_cell(detail: Detail) -> np.ndarray:
    """One coffer over the square [0, p]² below the ceiling plane z = H, facing down.

    A soffit frame (the square minus an inset square) at z = H - depth, four bevelled
    sides from the inset square up to a smaller square in the ceiling plane, and, with
    ``fixtures``, a cylinder hanging from the ceiling at the centre (its top cap dropped).
    """
    p = detail.pitch
    f, b, h = COFFER_FRAME * p, COFFER_BEVEL * p, COFFER_DEPTH * p
    z0 = H - h

    def square(inset, z):   # counter-clockwise seen from above
        return np.array([(inset, inset, z), (p - inset, inset, z), (p - inset, p - inset, z), (inset, p - inset, z)])

    outer, inner, top = square(0.0, z0), square(f, z0), square(f + b, H)
    tris = []
    for i in range(4):
        j = (i + 1) % 4
        # frame trapezoid and bevel, wound clockwise seen from above: normals face down
        tris += [(outer[i], inner[j], outer[j]), (outer[i], inner[i], inner[j])]
        tris += [(inner[i], top[j], inner[j]), (inner[i], top[i], top[j])]
    cell = np.array(tris, dtype=np.float64)
    if detail.fixtures and detail.sections:
        fixture = cylinder(FIXTURE_RADIUS * p, H - FIXTURE_DROP * h, H, detail.sections, drop=("+z",))
        cell = _cat([cell, transform(fixture, 0.0, (p / 2, p / 2, 0.0))])
    return cell


def office_ceiling() -> np.ndarray:
    return _office_group("Ceiling")


def coffers(detail: Detail) -> np.ndarray:
    p, n = detail.pitch, detail.divisions
    ii, jj = np.meshgrid(np.arange(2 * n), np.arange(3 * n), indexing="ij")
    offsets = np.column_stack([ii.ravel() * p, jj.ravel() * p, np.zeros(ii.size)])
    return instances(coffer_cell(detail), offsets)


# ---------------------------------------------------------------------------------------
# The whole scene
# ---------------------------------------------------------------------------------------

def _office_group(name: str) -> np.ndarray:
    parts = office.build_groups()[name]
    return _cat([np.array(tris, dtype=np.float64) for tris, _ in parts])


def furniture_boxes() -> list[tuple[np.ndarray, np.ndarray]]:
    """(lo, hi) of the solid parts a sensor must stay out of [m] (a superset is fine)."""
    out = []
    for cx, cy in DESK_CENTRES:
        wx, wy = DESK_SIZE[0] / 2, DESK_SIZE[1] / 2
        out.append(((cx - wx, cy - wy, 0.0), (cx + wx, cy + wy, DESK_TOP)))
        chair_y = cy + CHAIR_OFFSET
        sw, sd, s0, s1 = SEAT
        bw, by0, by1, bz0, bz1 = CHAIR_BACK
        out.append(((cx - STAR_RADIUS, chair_y - STAR_RADIUS, 0.0), (cx + STAR_RADIUS, chair_y + STAR_RADIUS, s1)))
        out.append(((cx - bw / 2, chair_y + 0.15, 0.45), (cx + bw / 2, chair_y + by1, bz1)))
    for width, angle, (tx, ty) in CASES:
        corners = transform(np.array([[[0, 0, 0], [width, CASE_DEPTH, CASE_HEIGHT], [0, 0, 0]]], float),
                            angle, (tx, ty, 0.0))[0, :2]
        out.append((corners.min(axis=0), corners.max(axis=0)))
    return [(np.asarray(lo, float), np.asarray(hi, float)) for lo, hi in out]


def build_groups(detail: Detail) -> dict[str, np.ndarray]:
    """{file group: (T, 3, 3) corners [m]} of the whole scene at ``detail``."""
    groups = {OFFICE_GROUPS[name]: _office_group(name) for name in OFFICE_GROUPS}
    groups["ceiling"] = _cat([groups["ceiling"], coffers(detail)])
    d, c = desk(detail), chair(detail)
    groups["desks"] = _cat([transform(d, 0.0, (x, y, 0.0)) for x, y in DESK_CENTRES])
    groups["chairs"] = _cat([transform(c, 0.0, (x, y + CHAIR_OFFSET, 0.0)) for x, y in DESK_CENTRES])
    shelves, books = [], []
    for width, angle, (tx, ty) in CASES:
        carcass, content = bookcase(width, detail)
        shelves.append(transform(carcass, angle, (tx, ty, 0.0)))
        books.append(transform(content, angle, (tx, ty, 0.0)))
    groups["shelves"], groups["books"] = _cat(shelves), _cat(books)
    return groups


def grid_points() -> np.ndarray:
    """(n, 3) the office's workplane sensors [m], rows from the window to the back wall."""
    xs = np.arange(office.GRID_MARGIN, W - office.GRID_MARGIN + 1e-9, office.GRID_STEP)
    ys = np.arange(office.GRID_MARGIN, D - office.GRID_MARGIN + 1e-9, office.GRID_STEP)
    yy, xx = np.meshgrid(ys, xs, indexing="ij")
    return np.column_stack([xx.ravel(), yy.ravel(), np.full(xx.size, office.GRID_Z)])


def sensors_in_furniture(points: np.ndarray) -> np.ndarray:
    """(n,) bool: sensors inside (or within SENSOR_CLEARANCE of) a furniture box."""
    inside = np.zeros(len(points), dtype=bool)
    for lo, hi in furniture_boxes():
        inside |= np.all((points > lo - SENSOR_CLEARANCE) & (points < hi + SENSOR_CLEARANCE), axis=1)
    return inside


# ---------------------------------------------------------------------------------------
# Files
# ---------------------------------------------------------------------------------------

def ply_bytes(tri: np.ndarray, comment: str) -> bytes:
    """Binary little-endian PLY of triangles: shared float64 vertices, int32 faces."""
    flat = np.ascontiguousarray(tri.reshape(-1, 3) + 0.0)            # -0.0 -> 0.0
    vertices, faces = np.unique(flat, axis=0, return_inverse=True)
    faces = faces.reshape(-1, 3).astype("<i4")
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"comment {comment}\n"
              f"element vertex {len(vertices)}\n"
              "property double x\nproperty double y\nproperty double z\n"
              f"element face {len(faces)}\n"
              "property list uchar int vertex_indices\nend_header\n").encode("ascii")
    face_rec = np.empty(len(faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    face_rec["n"], face_rec["v"] = 3, faces
    return header + vertices.astype("<f8").tobytes() + face_rec.tobytes()


def scene_toml(files: dict[str, int], detail: Detail, total: int, command: str) -> str:
    lines = [
        "# Furnished side-lit office, 4 x 6 x 3 m, one south window (3 x 1.5 m), CIE overcast sky.",
        f"# Generated by make_furnished_office.py ({command}) -- edit that script, not this file.",
        f"# {total:,} triangles; coffer pitch {detail.pitch:.4g} m, "
        + (f"cylinders of {detail.sections} sides." if detail.sections else "box legs, no cylinders."),
        "# Axes: +x east, +y north, +z up.  All lengths in metres.",
        'units = "m"', "",
        "# One binary PLY per material group; each file's triangles get the entry's material.",
    ]
    for group, count in files.items():
        lines += ["[[geometry]]", f'file = "{group}.ply"  # {count:,} triangles',
                  f'material = "{MATERIALS[group][0]}"', ""]
    for group, (name, key, value, comment) in MATERIALS.items():
        lines += [f"# {comment}", f"[materials.{name}]", f'type = "{"glass" if key == "transmittance" else "diffuse"}"',
                  f"{key} = {value}"]
        if key == "transmittance":
            # the same transmittance at every angle, as the committed reference was computed
            lines += ['model = "constant"', "portal = true"]
        lines.append("")
    lines += ["# CIE overcast sky, 10 000 lux on an unobstructed horizontal surface outside (as examples/office).",
              "[sky]", 'type = "cie-overcast"', "horizontal_illuminance = 10000", "ground_reflectance = 0.2", ""]
    return "\n".join(lines)


def grid_text(points: np.ndarray) -> str:
    lines = [f"# Workplane grid of examples/office: {len(points)} sensors at z = {office.GRID_Z:g} m facing up, "
             f"{office.GRID_STEP:g} m spacing, {office.GRID_MARGIN:g} m from the walls; desk tops at "
             f"{DESK_TOP:g} m. Columns: x y z nx ny nz"]
    lines += [" ".join(office.fmt(v) for v in (*p, 0, 0, 1)) for p in points]
    return "\n".join(lines) + "\n"


def write(out: Path, target: int) -> dict:
    """Generate the scene for about ``target`` triangles into ``out``; return a summary."""
    from lbl_illum.io.files import atomic_write_bytes, atomic_write_text

    t0 = time.perf_counter()
    detail = detail_for(target)
    groups = build_groups(detail)
    points = grid_points()
    bad = sensors_in_furniture(points)
    if bad.any():
        raise RuntimeError(f"{int(bad.sum())} sensors lie inside furniture, e.g. {points[bad][0]}")
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    for group, tri in groups.items():
        atomic_write_bytes(out / f"{group}.ply", ply_bytes(tri, f"furnished office: {group}"))
        files[group] = len(tri)
    total = sum(files.values())
    atomic_write_text(out / "grid.pts", grid_text(points))
    atomic_write_text(out / "scene.toml", scene_toml(files, detail, total, f"--triangles {target}"))
    return {"triangles": total, "files": len(files) + 2, "detail": detail, "sensors": len(points),
            "per_group": files, "seconds": time.perf_counter() - t0}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        description="Write the furnished office (examples/office with desks, chairs, bookcases and a coffered "
                    "ceiling) as binary PLY files, scene.toml and grid.pts.")
    parser.add_argument("--triangles", type=int, default=DEFAULT_TRIANGLES, metavar="N",
                        help=f"about how many triangles ({MIN_TRIANGLES:,} to {MAX_TRIANGLES:,}; "
                             f"default {DEFAULT_TRIANGLES:,})")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, metavar="DIR",
                        help="output folder (default: build/ beside this script)")
    args = parser.parse_args(argv)
    if not MIN_TRIANGLES <= args.triangles <= MAX_TRIANGLES:
        print(f"make_furnished_office: --triangles must be between {MIN_TRIANGLES:,} and {MAX_TRIANGLES:,}, "
              f"got {args.triangles:,}", file=sys.stderr)
        return 2
    try:
        s = write(args.out, args.triangles)
    except OSError as exc:
        print(f"make_furnished_office: {args.out}: cannot write ({exc.strerror or exc})", file=sys.stderr)
        return 1
    d = s["detail"]
    legs = f"{d.sections}-sided cylinders" if d.sections else "box legs"
    print(f"furnished office: {s['triangles']:,} triangles (coffer pitch {d.pitch:.3g} m, {legs}), "
          f"{s['files']} files, {s['sensors']} sensors -> {args.out} in {s['seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
