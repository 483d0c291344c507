"""Model only what the scene requires: records and rays go where the queries need them.

Ward, Rubinstein & Clear (1988), abstract and §6: "Illuminance calculations are made
only for those areas participating in the selected view, and the results are stored so
that subsequent views can reuse common values."  In this tool the "view" is the set of
sensor points.  A record of diffuse level 0 is made only at a sensor point that no
existing record covers (Eqs. 5 and 6); a record of level k + 1 only at a diffuse hit
of a level-k record's hemisphere rays (Eq. 2, §3.4) that no level-(k + 1) record
covers.  Hits on surfaces of reflectance 0 reflect nothing and are not queries
(``Integrator.trace_paths``); levels that could only hold zero are never made
(``Integrator._level_active``).

The study measures this on the bundled office (``examples/office``, 4 × 6 × 3 m, one
south window, CIE overcast sky, 77 workplane sensors at 0.8 m):

1. a grid over the west half of the workplane against the full grid — level-0
   records lie only at the half's points, deeper records per level and region;
2. a floor of reflectance 0 — no record of level ≥ 1 on it;
3. no sky, no sun and no light surface — no record and no ray at all;
   and the sun without a sky — the bounce-limit level is not made;
4. a second grid B overlapping a first grid A, run on A's cache — B's new records
   against B alone, each one where A's records do not reach;
5. grids of increasing density over the same workplane — records per level against
   points, and the local growth exponent d ln(records) / d ln(points).

Every office run uses the same record-spacing limits (the defaults the 77-point grid
gets, ``Integrator.default_spacing``), so that record counts differ only by where the
queries are.
"""

from __future__ import annotations

import copy
import math

import numpy as np

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

from lbl_illum import Integrator, Options, read_points
from lbl_illum.engine import LevelRecords, Tracer
from lbl_illum.errors import InputError
from lbl_illum.scene import scene_from_dict

from . import repository_root
from .report import Report, StudyContext, fmt, new_figure, pct

TITLE = "Records and rays go only where the queries need them"

# -- the office (examples/office/make_office.py) ------------------------------------
ROOM_LO = np.array([0.0, 0.0, 0.0])     # [m] interior box
ROOM_HI = np.array([4.0, 6.0, 3.0])
WINDOW_X = (0.5, 3.5)                    # [m] window opening in the south wall (y = 0)
WORKPLANE_X = (0.5, 3.5)                 # [m] box of the example's sensor grid
WORKPLANE_Y = (0.5, 5.5)
WORKPLANE_Z = 0.8
#: the half grid: sensors with x below this [m] (the room's middle)
HALF_X = 2.0
#: overlapping grids: A holds the rows y ≤ A_MAX_Y, B the rows y ≥ B_MIN_Y [m]
A_MAX_Y = 3.5
B_MIN_Y = 2.5
#: a position within this of a plane lies on it [m] (hit points are projected onto
#: their triangle's plane in float64, see raycast.Tracer.surface)
ON_PLANE = 1e-6
#: the sun of the "sun without sky" case: due south, through the window
SUN = {"altitude": 35.0, "azimuth": 180.0, "direct_normal_illuminance": 60000.0}
#: The example's glazing without surface reflection.
CLEAR_PORTAL = {"type": "glass", "model": "constant", "transmittance": 0.6, "reflectance": 0.0, "portal": True}

QUICK = {"accuracy": 0.2, "bounces": 2, "samples": 64}
FULL = {"accuracy": 0.1, "bounces": 3, "samples": 512}
#: grid spacings [m] of the density series (3 and 5 m are whole multiples of each)
DENSITY_QUICK = (1.0, 0.5, 0.25, 0.125)
DENSITY_FULL = (1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125)

# bounds the report states and the test asserts
#: growth exponent d ln(records)/d ln(points) allowed between the two densest grids
DENSE_EXPONENT_MAX = 0.3
#: ... and expected at least at level 0 between the two coarsest (about a record per point)
COARSE_EXPONENT_MIN = 0.8

LEVEL_COLOURS = ("black", "tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple",
                 "tab:brown", "tab:pink", "tab:olive")


# -- scene and points ------------------------------------------------------------------
def office_folder():
    """``examples/office`` of the source checkout; InputError when there is none."""
    root = repository_root()
    if root is None:
        raise InputError("scene-requires: needs the examples/ folder of a source checkout "
                         "(examples/office/scene.toml); run it from the repository")
    return root / "examples" / "office"


def office_scene(folder, materials=None, sky=None, sun=None):
    """The office scene file with ``materials`` entries replaced, and ``sky`` / ``sun``
    tables replacing (``False`` removes) the file's."""
    with open(folder / "scene.toml", "rb") as f:
        data = tomllib.load(f)
    data = copy.deepcopy(data)
    for name, table in (materials or {}).items():
        data["materials"][name] = dict(table)
    for key, table in (("sky", sky), ("sun", sun)):
        if table is False:
            data.pop(key, None)
        elif table is not None:
            data[key] = dict(table)
    return scene_from_dict(data, folder, "scene.toml")


def workplane_grid(step: float):
    """Sensors every ``step`` metres over the example's workplane box (x 0.5–3.5 m,
    y 0.5–5.5 m, z 0.8 m), facing up: ((n, 3) points [m], (n, 3) normals).  Rows run
    along x, from the window (y = 0.5) back, as in ``grid.pts``."""
    nx = int(round((WORKPLANE_X[1] - WORKPLANE_X[0]) / step)) + 1
    ny = int(round((WORKPLANE_Y[1] - WORKPLANE_Y[0]) / step)) + 1
    x, y = np.meshgrid(np.linspace(*WORKPLANE_X, nx), np.linspace(*WORKPLANE_Y, ny))
    points = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, WORKPLANE_Z)])
    return points, np.tile([0.0, 0.0, 1.0], (len(points), 1))


# -- where records are -----------------------------------------------------------------
def interior(P, N):
    """(n,) bool: records inside the room facing into it.  Room surfaces are
    zero-thickness sheets, so a record on the outside face of a wall or the roof lies on
    the box too; its normal (turned towards the ray that made it) faces away from the
    room's centre."""
    P = np.asarray(P, np.float64).reshape(-1, 3)
    N = np.asarray(N, np.float64).reshape(-1, 3)
    inside = np.all((P >= ROOM_LO - ON_PLANE) & (P <= ROOM_HI + ON_PLANE), axis=1)
    centre = 0.5 * (ROOM_LO + ROOM_HI)
    return inside & (np.einsum("ij,ij->i", N, centre - P) > 0.0)


def regions(P, N, split_x: float = HALF_X) -> dict:
    """Records per region: ``west`` (inside, x < split_x), ``east`` (inside, x ≥ split_x)
    and ``outside`` (ground, outer faces of the room)."""
    inner = interior(P, N)
    x = np.asarray(P, np.float64).reshape(-1, 3)[:, 0]
    return {"west": int(np.sum(inner & (x < split_x))), "east": int(np.sum(inner & (x >= split_x))),
            "outside": int(np.sum(~inner))}


def on_floor(P, N):
    """(n,) bool: records on the room's floor (z = 0 inside the footprint, facing up)."""
    P = np.asarray(P, np.float64).reshape(-1, 3)
    return interior(P, N) & (np.abs(P[:, 2] - ROOM_LO[2]) <= ON_PLANE)


def growth_exponents(points, records) -> list[float]:
    """Local exponent d ln(records) / d ln(points) between successive grids (NaN where a
    count is zero): 1 means one more record per point, 0 means no more records."""
    n = np.asarray(points, np.float64)
    r = np.asarray(records, np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.log(r[1:] / r[:-1]) / np.log(n[1:] / n[:-1])
    return [float(v) if np.isfinite(v) else math.nan for v in e]


def uncovered_by(level: LevelRecords, count: int, P, N, zone=None) -> np.ndarray:
    """(n,) bool: positions no record among the first ``count`` of ``level`` covers
    (Eqs. 5 and 6 with the level's a, and the records' zones against ``zone``, default 0),
    looked up in a fresh octree of those records."""
    P = np.asarray(P, np.float64).reshape(-1, 3)
    if count == 0 or len(P) == 0:
        return np.ones(len(P), bool)
    fresh = LevelRecords(level.accuracy, level.node_center[0], level.node_half[0], capacity=count)
    fresh.add(level.P[:count], level.N[:count], level.R[:count], zone=level.zone[:count])
    _, _, hits = fresh.lookup(P, np.asarray(N, np.float64).reshape(-1, 3), zone=zone)
    return hits == 0


# -- runs --------------------------------------------------------------------------------
class _Run:
    """One calculation: its stats, illuminance and the records of every level."""

    def __init__(self, scene, options, points, normals, cache=None):
        integ = Integrator(scene, options, cache=cache)
        self.integ = integ
        before = [0] * (options.bounces + 1) if cache is None else cache.record_counts
        result = integ.compute(points, normals)
        self.stats = result.stats
        self.illuminance = result.illuminance
        self.points = points
        self.cache = integ.cache
        self.before = list(before)
        levels = integ.cache.levels
        self.P = [lv.P[:lv.count].copy() for lv in levels]
        self.N = [lv.N[:lv.count].astype(np.float64) for lv in levels]

    @property
    def records(self) -> list[int]:
        return [int(v) for v in self.stats.records]

    @property
    def new(self) -> list[int]:
        return [int(v) for v in self.stats.new_records]

    def new_positions(self, k):
        """(P, N) of the records of level k this run made."""
        return self.P[k][self.before[k]:], self.N[k][self.before[k]:]

    def regions(self) -> dict:
        """Records per level in each region (see :func:`regions`)."""
        per = [regions(P, N) for P, N in zip(self.P, self.N)]
        return {key: [r[key] for r in per] for key in ("west", "east", "outside")}

    def summary(self) -> dict:
        return {"points": len(self.points), "records": self.records, "new_records": self.new,
                "total_records": int(sum(self.records)), "rays": int(self.stats.rays),
                "seconds": float(self.stats.seconds)}


def _plan(ax, run, k, title):
    """Plan view (x, y) of a run's level-k records inside the room (all heights projected)."""
    ax.add_patch(_rect(ROOM_LO[:2], ROOM_HI[:2]))
    ax.plot(WINDOW_X, [0.0, 0.0], color="tab:cyan", lw=4, solid_capstyle="butt")
    P, N = run.P[k], run.N[k]
    P = P[interior(P, N)]
    if len(P):
        ax.scatter(P[:, 0], P[:, 1], s=10.0 if k == 0 else 2.0, lw=0, alpha=1.0 if k == 0 else 0.6,
                   color=LEVEL_COLOURS[k % len(LEVEL_COLOURS)])
    ax.set_title(f"{title}\nlevel {k}: {len(P):,} inside", fontsize=9)
    ax.axvline(HALF_X, color="0.5", ls=":", lw=1)
    ax.set_xlim(-0.3, 4.3)
    ax.set_ylim(-0.3, 6.3)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)


def _rect(lo, hi, **kw):
    from matplotlib.patches import Rectangle

    style = {"fill": False, "ec": "0.3", "lw": 1.0}
    style.update(kw)
    return Rectangle(lo, hi[0] - lo[0], hi[1] - lo[1], **style)


def _room_axes(ax):
    ax.set_xlim(-0.3, 4.3)
    ax.set_ylim(-0.3, 6.3)
    ax.set_aspect("equal")
    ax.set_xlabel("x (east) [m]")
    ax.set_ylabel("y (north) [m]")
    ax.legend(fontsize=7, loc="upper right", markerscale=2.0, framealpha=0.9)


def _levels_header(B):
    return [f"level {k}" for k in range(B + 1)]


# -- the study ---------------------------------------------------------------------------
def run(ctx: StudyContext) -> Report:
    folder = office_folder()
    setting = QUICK if ctx.quick else FULL
    steps = DENSITY_QUICK if ctx.quick else DENSITY_FULL
    B = setting["bounces"]
    report = Report("scene-requires", TITLE, "")
    res = report.results
    res["settings"] = dict(setting)
    scene = office_scene(folder)
    points, normals = read_points(folder / "grid.pts", scene.unit_scale)
    grids = [workplane_grid(step) for step in steps]
    # the example grid itself (same points, same limits) is not run twice
    same = [len(p) == len(points) and np.array_equal(p, points) and np.array_equal(n, normals) for p, n in grids]
    ctx.plan(9 + len(steps) - sum(same))

    # 1. the full grid with default spacing; its limits serve every other office run
    full = _Run(scene, Options(**setting), points, normals)
    ctx.step("full grid", full.stats)
    spacing = {"min_spacing": float(full.stats.min_spacing), "max_spacing": float(full.stats.max_spacing)}
    res["spacing"] = dict(spacing)
    opts = Options(**setting, **spacing)

    # 2. the west half
    west = points[:, 0] < HALF_X
    half = _Run(scene, opts, points[west], normals[west])
    ctx.step("half grid", half.stats)

    # 3. a black floor
    black_scene = office_scene(folder, materials={"floor": {"type": "diffuse", "reflectance": 0.0}})
    black = _Run(black_scene, opts, points, normals)
    ctx.step("black floor", black.stats)

    # 4. no light at all (default options: the spacing probe would be the only work)
    dark_scene = office_scene(folder, sky={"type": "none"}, sun=False)
    dark = _Run(dark_scene, Options(**setting), points, normals)
    ctx.step("no sky, no sun", dark.stats)
    # glass that reflects nothing: a reflecting pane can show the sun to a record outside
    # (on the ground), and then the bounce-limit level is made (Integrator._level_active)
    sun_scene = office_scene(folder, materials={"glazing": CLEAR_PORTAL}, sky={"type": "none"}, sun=SUN)
    sun = _Run(sun_scene, opts, points, normals)
    ctx.step("sun, no sky", sun.stats)

    # 5. overlapping grids
    in_a = points[:, 1] <= A_MAX_Y + 1e-9
    in_b = points[:, 1] >= B_MIN_Y - 1e-9
    run_a = _Run(scene, opts, points[in_a], normals[in_a])
    ctx.step("grid A", run_a.stats)
    counts_a = run_a.records
    b_after_a = _Run(scene, opts, points[in_b], normals[in_b], cache=run_a.cache)
    ctx.step("grid B on A's cache", b_after_a.stats)
    b_alone = _Run(scene, opts, points[in_b], normals[in_b])
    ctx.step("grid B alone", b_alone.stats)
    b_seed = _Run(scene, opts.replace(seed=1), points[in_b], normals[in_b])
    ctx.step("grid B alone, seed 1", b_seed.stats)

    # 6. density series
    density = []
    for step, (p, n), is_full in zip(steps, grids, same):
        if is_full:
            density.append(full)
            continue
        r = _Run(scene, opts, p, n)
        density.append(r)
        ctx.step(f"density {step:g} m", r.stats)

    _section_intro(report, res, setting, spacing, full, ctx.quick)
    _section_half(report, res, full, half, B)
    _section_black(report, res, full, black, B)
    _section_dark(report, res, dark, sun, points, B)
    _section_overlap(report, res, full, run_a, b_after_a, b_alone, b_seed, counts_a, in_a, in_b, B)
    _section_density(report, res, steps, density, B)
    _section_checks(report, res)
    return report


def _section_intro(report, res, setting, spacing, full, quick):
    report.text(
        "The paper computes indirect illuminance \"only for those areas participating in the selected "
        "view\" (Ward, Rubinstein & Clear 1988, abstract). Here the view is the set of sensor points: a "
        "level-0 record is made only at a sensor point that no record covers, and a record of level k + 1 "
        "only at a diffuse surface that a level-k record's hemisphere rays hit and that no level-(k + 1) "
        "record covers. This report counts records and rays on the office example "
        "(`examples/office`: 4 × 6 × 3 m, a 3 × 1.5 m south window, CIE overcast sky, 77 sensors at "
        "0.8 m on a 0.5 m grid) when the sensors, the materials or the light change.")
    report.text(
        f"Settings of every run: accuracy a = {fmt(setting['accuracy'])}, {setting['bounces']} bounces, "
        f"{setting['samples']} hemisphere samples at level 0 (§3.4 scaling: a × 1.4 and samples × 0.5 per "
        f"level, a capped at 2×), seed 0{' (the reduced version of the study)' if quick else ''}. The record "
        f"spacing limits depend on the extent of the queries (`Integrator.default_spacing`), so a smaller "
        f"grid would get smaller records. To compare grids by where their points are and nothing else, every "
        f"office run except the first uses the limits the full 77-point grid gets by default, given "
        f"explicitly: min_spacing = {fmt(spacing['min_spacing'])} m, max_spacing = "
        f"{fmt(spacing['max_spacing'])} m (`--min-spacing`, `--max-spacing` on the command line).")
    report.text(
        "*Regions.* A record is *inside* when it lies in the room's box and its normal faces the room; the "
        "others are on the ground outside or on the outer faces of the walls and roof (the room's surfaces "
        "are single sheets, seen from both sides). Inside records are split at x = 2 m into a west and an "
        "east half.")


def _section_half(report, res, full, half, B):
    report.heading("A grid over one half of the room")
    lo = half.points.min(axis=0)
    hi = half.points.max(axis=0)
    P0 = half.P[0]
    level0_max_x = float(P0[:, 0].max()) if len(P0) else math.nan
    level0_outside_box = int(np.sum(np.any((P0 < lo - 1e-9) | (P0 > hi + 1e-9), axis=1)))
    rf, rh = full.regions(), half.regions()
    res["full"] = {**full.summary(), "regions": rf, "floor_records": [int(np.sum(on_floor(P, N)))
                                                                       for P, N in zip(full.P, full.N)]}
    res["half"] = {**half.summary(), "regions": rh, "half_boundary_x": HALF_X,
                   "level0_max_x": level0_max_x, "level0_outside_sensor_box": level0_outside_box}
    report.text(
        f"The half grid keeps the {len(half.points)} of the 77 sensors with x < {fmt(HALF_X)} m (x = 0.5, 1 and "
        f"1.5 m). Its level-0 records are made at its own points: the easternmost lies at x = "
        f"{fmt(level0_max_x)} m, and {level0_outside_box} lie outside the box of its sensors. Records of "
        "deeper levels sit where the rays of the level above hit diffuse surfaces, so they spread through "
        "the whole room and out of the window to the ground.")
    rows = []
    for label, run, reg in (("full grid", full, rf), ("half grid", half, rh)):
        for key in ("west", "east", "outside"):
            rows.append([f"{label}, {key}", *reg[key]])
        rows.append([f"{label}, all", *run.records])
    report.table(["records", *_levels_header(B)], rows,
                 caption="Records per level and region (west: inside, x < 2 m; east: inside, x ≥ 2 m; "
                         "outside: ground and outer faces).")
    report.table(["run", "points", "records", "rays", "seconds"],
                 [["full grid", len(full.points), sum(full.records), full.stats.rays, full.stats.seconds],
                  ["half grid", len(half.points), sum(half.records), half.stats.rays, half.stats.seconds]],
                 caption="Work of the two runs.")
    ratios = []
    for k in range(B + 1):
        east_full, east_half = rf["east"][k], rh["east"][k]
        west_full, west_half = rf["west"][k], rh["west"][k]
        ratios.append({"west": west_half / west_full if west_full else math.nan,
                       "east": east_half / east_full if east_full else math.nan})
    res["half"]["fraction_of_full"] = ratios
    res["half"]["records_fraction"] = sum(half.records) / sum(full.records)
    res["half"]["rays_fraction"] = half.stats.rays / full.stats.rays
    deeper = "; ".join(f"level {k}: {fmt(r['west'])} in the west half and {fmt(r['east'])} in the east half"
                       for k, r in enumerate(ratios) if k > 0)
    report.text(
        f"The half grid made {fmt(res['half']['records_fraction'])} of the full grid's records with "
        f"{fmt(res['half']['rays_fraction'])} of its rays. Its deeper records, as a fraction of the full "
        f"grid's in the same region: {deeper}. Level-1 records lie where the hemisphere rays of the level-0 "
        "records land; from the west sensors these reach the east wall and the ceiling above the east half "
        "too, but fewer of them, so the east half holds fewer level-1 records than with the east sensors. "
        "Each deeper level starts from more records spread over more of the room, so by the deepest level "
        "the two runs differ less.")
    fig, axes = new_figure(2.3 * (B + 1), 7.4, nrows=2, ncols=B + 1, sharex=True, sharey=True)
    for row, (run, name) in enumerate(((full, "full grid"), (half, "half grid"))):
        for k in range(B + 1):
            _plan(axes[row, k], run, k, name)
        axes[row, 0].set_ylabel("y (north) [m]", fontsize=8)
    for k in range(B + 1):
        axes[1, k].set_xlabel("x (east) [m]", fontsize=8)
    report.figure("plan_full_half", fig,
                  "Plan of the records inside the room by level (columns), full grid (top) and half grid "
                  "(bottom); all heights projected, so records on the walls form the outline and records on "
                  "the ceiling and floor fill the inside. The window is the cyan bar at y = 0; the dotted "
                  "line is x = 2 m.")


def _section_black(report, res, full, black, B):
    report.heading("A floor of reflectance 0")
    floor_full = res["full"]["floor_records"]
    floor_black = [int(np.sum(on_floor(P, N))) for P, N in zip(black.P, black.N)]
    res["black_floor"] = {**black.summary(), "floor_records": floor_black}
    report.text(
        "A hemisphere ray that hits a diffuse surface of reflectance ρ = 0 ends there with nothing: the "
        "surface reflects no light, so the engine does not keep the hit as a query of the next level "
        "(`Integrator.trace_paths` keeps only diffuse hits with ρ > 0). A record can therefore sit on "
        "the black floor only at level 0, and only if a sensor lies on it (none does here).")
    report.table(["run", *_levels_header(B), "rays"],
                 [["floor ρ = 0.2: records", *full.records, full.stats.rays],
                  ["floor ρ = 0.2: on the floor", *floor_full, ""],
                  ["floor ρ = 0: records", *black.records, black.stats.rays],
                  ["floor ρ = 0: on the floor", *floor_black, ""]],
                 caption="Records per level, all and on the floor (z = 0 inside the room).")
    res["black_floor"]["deeper_on_floor"] = int(sum(floor_black[1:]))
    res["black_floor"]["records_fraction"] = sum(black.records) / sum(full.records)
    res["black_floor"]["rays_fraction"] = black.stats.rays / full.stats.rays
    report.text(
        f"With the floor at ρ = 0.2, {sum(floor_full[1:]):,} records of levels 1–{B} lie on the floor; with "
        f"ρ = 0, {res['black_floor']['deeper_on_floor']}. The black-floor run made "
        f"{fmt(res['black_floor']['records_fraction'])} of the records and traced "
        f"{fmt(res['black_floor']['rays_fraction'])} of the rays of the ρ = 0.2 run.")
    fig, axes = new_figure(9.0, 3.4, ncols=2, sharey=True)
    for ax, run, title in ((axes[0], full, "floor ρ = 0.2"), (axes[1], black, "floor ρ = 0")):
        ax.add_patch(_rect(ROOM_LO[1:], ROOM_HI[1:]))
        for k in range(len(run.P) - 1, 0, -1):
            P, N = run.P[k], run.N[k]
            P = P[interior(P, N)]
            if len(P):
                ax.scatter(P[:, 1], P[:, 2], s=3, lw=0, alpha=0.5, color=LEVEL_COLOURS[k % len(LEVEL_COLOURS)],
                           label=f"level {k}: {len(P):,}")
        ax.set_title(title, fontsize=10)
        ax.set_xlim(-0.3, 6.3)
        ax.set_ylim(-0.3, 3.3)
        ax.set_aspect("equal")
        ax.set_xlabel("y (north) [m]")
        ax.legend(fontsize=7, loc="upper right", markerscale=2.0, framealpha=0.9)
    axes[0].set_ylabel("z [m]")
    report.figure("section_black_floor", fig,
                  "Section (y, z; all x projected) of the records of levels ≥ 1 inside the room. "
                  "The row at z = 0 is the floor.")


def _section_dark(report, res, dark, sun, points, B):
    report.heading("No light: nothing to compute")
    max_E = float(np.max(np.abs(dark.illuminance))) if len(dark.illuminance) else 0.0
    # what the automatic spacing probe alone traces for these points (skipped in the dark run)
    traced = dark.integ.tracer.rays_traced
    dark.integ.default_spacing(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)))
    probe_rays = int(dark.integ.tracer.rays_traced - traced)
    res["dark"] = {**dark.summary(), "max_illuminance": max_E, "spacing_probe_rays": probe_rays}
    res["sun_only"] = {**sun.summary(), "bounce_limit_records": int(sun.records[B]), "sun": dict(SUN)}
    report.text(
        f"Without sky, sun or light surface no surface receives light, so no level can hold anything but "
        f"zero and none is made (`Integrator._level_active`). The run on the 77 sensors, with the default "
        f"(automatic) spacing limits, made {sum(dark.records)} records and traced {dark.stats.rays:,} rays; "
        f"the largest illuminance it returned is {fmt(max_E)} lux. The rays an office run can trace are: "
        f"the spacing probe (16 per point for up to 256 points, when a spacing limit is automatic), the "
        f"hemisphere rays and portal samples of new records with their specular continuations, one sun or "
        f"light-surface shadow ray per diffuse hit, "
        + ("16 per sensor point for the sun and light surfaces, and a few probe rays per sensor point that "
           "keep the origins of its rays clear of nearby surfaces (`Tracer.sensor_origins`, traced for the "
           "direct step and for level-0 records)"
           if hasattr(Tracer, "sensor_origins") else "and 16 per sensor point for the sun and light surfaces")
        + ". With no light every one of these is skipped: the direct step returns zero without tracing "
        "(`DirectLight.is_dark`), and no record is made.")
    report.text(
        f"(Before this study the spacing probe still ran in a dark scene: called on its own for these 77 "
        f"points it traces {probe_rays:,} rays. `Integrator.compute` now skips it when no level can hold "
        f"light, and when both limits are given.)")
    report.text(
        f"The sun without a sky shows the other half of the rule. Records at the bounce limit (level {B}) "
        f"hold only what their rays find in the sky and the ground glow (the deeper levels are cut off) and "
        f"the sun or a light surface seen in a mirror or a pane. With no sky and the window's glass set to "
        f"reflect nothing that is dark, so the level is not made: levels 0–{B - 1} hold records, level {B} "
        f"holds {res['sun_only']['bounce_limit_records']}. (With the example's reflecting glass it is made: "
        f"from the ground outside, the sun can be seen in the pane.)")
    report.table(["light", *_levels_header(B), "rays"],
                 [["no sky, no sun, no light surface", *dark.records, dark.stats.rays],
                  [f"sun only (altitude {fmt(SUN['altitude'])}°, due south), no sky, glass reflecting nothing",
                   *sun.records, sun.stats.rays]],
                 caption="Records per level and rays.")


def _section_overlap(report, res, full, run_a, b_after_a, b_alone, b_seed, counts_a, in_a, in_b, B):
    report.heading("A second, overlapping grid")
    n_a, n_b = int(in_a.sum()), int(in_b.sum())
    n_overlap = int((in_a & in_b).sum())
    new = b_after_a.new
    alone = b_alone.records
    covered = []
    for k in range(B + 1):
        P, N = b_after_a.new_positions(k)
        lv = b_after_a.cache.levels[k]
        zone = lv.zone[counts_a[k]:lv.count]          # each new record's own zone
        covered.append(int(np.sum(~uncovered_by(lv, counts_a[k], P, N, zone))))
    P0, _ = b_after_a.new_positions(0)
    new0_min_y = float(P0[:, 1].min()) if len(P0) else math.nan
    after = b_after_a.illuminance / b_alone.illuminance - 1.0
    seed = b_seed.illuminance / b_alone.illuminance - 1.0
    auto_a = run_a.integ.default_spacing(run_a.points, np.tile([0.0, 0.0, 1.0], (len(run_a.points), 1)))
    auto_b = b_alone.integ.default_spacing(b_alone.points, np.tile([0.0, 0.0, 1.0], (len(b_alone.points), 1)))
    res["overlap"] = {
        "A": {**run_a.summary(), "rows_y_max": A_MAX_Y}, "B_alone": {**b_alone.summary(), "rows_y_min": B_MIN_Y},
        "B_after_A": b_after_a.summary(), "points_A": n_a, "points_B": n_b, "points_shared": n_overlap,
        "shared_fraction_of_B": n_overlap / n_b,
        "new_records_covered_by_A": covered, "new_level0_min_y": new0_min_y,
        "new_fraction_of_alone": (sum(new) / sum(alone)) if sum(alone) else math.nan,
        "rays_fraction_of_alone": b_after_a.stats.rays / b_alone.stats.rays,
        "two_runs_total": int(sum(run_a.records) + sum(new)), "union_one_run_total": int(sum(full.records)),
        "automatic_spacing": {"A": list(auto_a), "B": list(auto_b)},
        "illuminance_after_A_vs_alone": {"mean_abs": float(np.mean(np.abs(after))),
                                         "max_abs": float(np.max(np.abs(after))), "mean": float(np.mean(after))},
        "illuminance_seed1_vs_seed0": {"mean_abs": float(np.mean(np.abs(seed))),
                                       "max_abs": float(np.max(np.abs(seed))), "mean": float(np.mean(seed))},
    }
    o = res["overlap"]
    oa, os_ = o["illuminance_after_A_vs_alone"], o["illuminance_seed1_vs_seed0"]
    report.text(
        f"Grid A holds the {n_a} sensors of the rows y ≤ {fmt(A_MAX_Y)} m, grid B the {n_b} of the rows "
        f"y ≥ {fmt(B_MIN_Y)} m; {n_overlap} sensors ({pct(n_overlap / n_b, 1)} of B) belong to both. A runs "
        "first; B then runs on A's cache (`Integrator(scene, options, cache=run_a.cache)` in Python; "
        "`--cache FILE` on the command line reads the records before the run and writes all of them back "
        "after it). Records stay valid for other points and other spacing limits: the cache's fingerprint "
        "covers the scene, a, bounces, samples, ambient and the bounce scaling, not the points or the limits. "
        f"But automatic limits follow each grid's extent: A alone would get min_spacing = {fmt(auto_a[0])} m "
        f"and max_spacing = {fmt(auto_a[1])} m, B alone {fmt(auto_b[0])} m and {fmt(auto_b[1])} m, against "
        f"{fmt(res['spacing']['min_spacing'])} m and {fmt(res['spacing']['max_spacing'])} m for the whole grid. "
        "Grids that are to share a cache should therefore be given the same limits explicitly "
        "(`min_spacing`/`max_spacing` in `Options` or `[settings]`, `--min-spacing`/`--max-spacing`); here all "
        "three runs use the whole grid's.")
    report.table(["run", *_levels_header(B), "all", "rays"],
                 [["A alone", *run_a.records, sum(run_a.records), run_a.stats.rays],
                  ["B alone", *alone, sum(alone), b_alone.stats.rays],
                  ["B on A's cache: new records", *new, sum(new), b_after_a.stats.rays],
                  ["… of which A's records cover", *covered, sum(covered), ""],
                  ["A ∪ B in one run (the full grid)", *full.records, sum(full.records), full.stats.rays]],
                 caption="Records per level and rays.")
    report.text(
        f"On A's cache, B made {fmt(o['new_fraction_of_alone'])} of the records it makes alone and traced "
        f"{fmt(o['rays_fraction_of_alone'])} of the rays. Each new record was looked up against A's records "
        f"of its level (Eqs. 5 and 6, in a fresh octree of A's records only): {sum(covered)} of "
        f"{sum(new):,} are covered by one, so every new record lies where A's records do not reach. "
        f"The new level-0 records start at y = {fmt(new0_min_y)} m, beyond A's last row at "
        f"{fmt(A_MAX_Y)} m: the shared sensors are answered by A's records. A then B made "
        f"{o['two_runs_total']:,} records in all, against {o['union_one_run_total']:,} for the union in one run.")
    report.text(
        f"At B's points the illuminance after A differs from B alone by {pct(oa['mean_abs'])} on average "
        f"({pct(oa['max_abs'])} at most, mean signed difference {pct(oa['mean'])}). B alone with another "
        f"seed differs from B alone by {pct(os_['mean_abs'])} on average ({pct(os_['max_abs'])} at most, "
        f"mean signed {pct(os_['mean'])}). "
        + ("The difference after A is no larger than the seed-to-seed difference: it is the records' "
           "sampling noise at these settings, drawn anew when B answers from A's records."
           if oa["mean_abs"] <= os_["mean_abs"] else
           "The difference after A is larger than the seed-to-seed difference: answering from A's records "
           "changes B's values by more than the records' sampling noise."))
    fig, axes = new_figure(9.0, 6.6, ncols=2)
    for ax, k in zip(axes, (0, 1)):
        ax.add_patch(_rect(ROOM_LO[:2], ROOM_HI[:2]))
        ax.axhspan(B_MIN_Y, A_MAX_Y, color="0.9", zorder=0, label="rows in A and B")
        PA, NA = b_after_a.P[k][:counts_a[k]], b_after_a.N[k][:counts_a[k]]
        PA = PA[interior(PA, NA)]
        Pn, Nn = b_after_a.new_positions(k)
        Pn = Pn[interior(Pn, Nn)]
        size = 14 if k == 0 else 3
        ax.scatter(PA[:, 0], PA[:, 1], s=size, lw=0, color="0.45", label=f"A's records: {len(PA):,}")
        ax.scatter(Pn[:, 0], Pn[:, 1], s=size, lw=0, color="tab:red", label=f"B's new records: {len(Pn):,}")
        ax.set_title(f"level {k}", fontsize=10)
        _room_axes(ax)
    report.figure("plan_overlap", fig,
                  "Plan of the records inside the room after A then B, at levels 0 and 1: A's records grey, "
                  "the records B added red. The grey band holds the rows of both grids.")


def _section_density(report, res, steps, density, B):
    report.heading("Records against the number of sensor points")
    pts = [len(r.points) for r in density]
    per_level = [[r.records[k] for r in density] for k in range(B + 1)]
    total = [sum(r.records) for r in density]
    rays = [int(r.stats.rays) for r in density]
    exps = {f"level {k}": growth_exponents(pts, per_level[k]) for k in range(B + 1)}
    exps["all"] = growth_exponents(pts, total)
    exps["rays"] = growth_exponents(pts, rays)
    res["density"] = {"spacing": list(steps), "points": pts, "records": per_level, "total": total,
                      "rays": rays, "seconds": [float(r.stats.seconds) for r in density], "exponents": exps,
                      "dense_exponent_max": DENSE_EXPONENT_MAX, "coarse_exponent_min": COARSE_EXPONENT_MIN}
    report.text(
        "Grids of spacing " + ", ".join(f"{s:g}" for s in steps) + " m over the same workplane box "
        "(x 0.5–3.5 m, y 0.5–5.5 m, z 0.8 m; the 0.5 m grid is the example's, and its row is the full-grid run above). The paper's records "
        "follow the accuracy a and the geometry, not the resolution: once the points are closer than "
        "the records' valid domains (a R_i, Eqs. 5 and 6), further points fall inside existing domains "
        "and add no record. The local exponent d ln(records) / d ln(points) between successive grids "
        "measures this: 1 means a record per added point, 0 no record at all.")
    rows = [[f"{s:g}", n, *[per_level[k][i] for k in range(B + 1)], total[i], rays[i]]
            for i, (s, n) in enumerate(zip(steps, pts))]
    report.table(["spacing [m]", "points", *_levels_header(B), "all", "rays"], rows,
                 caption="Records per level and rays for each grid.")
    erows = [[f"{steps[i]:g} → {steps[i + 1]:g} m", *[exps[f'level {k}'][i] for k in range(B + 1)],
              exps["all"][i], exps["rays"][i]] for i in range(len(steps) - 1)]
    report.table(["grids", *_levels_header(B), "all", "rays"], erows,
                 caption="Local growth exponent d ln(records) / d ln(points) (and of the rays).")
    last = {key: v[-1] for key, v in exps.items()}
    first0 = exps["level 0"][0]
    res["density"]["dense_end"] = last
    report.text(
        f"From the coarsest grid to the next, level 0 grows with exponent {fmt(first0)} (1 is a record per "
        f"added point). Between the two densest grids ({pts[-2]:,} and {pts[-1]:,} points) the exponent is "
        f"{fmt(last['level 0'])} at level 0 and {fmt(last['all'])} for all records; the rays grow with "
        f"exponent {fmt(last['rays'])}. The densest grid has {fmt(pts[-1] / per_level[0][-1])} points per "
        f"level-0 record. The count levels off but does not stop entirely. Two things can still add records "
        f"as points get denser: the valid domains are discs that leave gaps between them, and a denser grid "
        f"puts points into smaller gaps, each of which then gets a record; and records placed in the same "
        f"pass do not see each other (architecture, departure 1). This study does not separate the two.")
    fig, axes = new_figure(9.0, 3.8, ncols=2)
    ax = axes[0]
    n = np.array(pts, float)
    ax.plot(n, n, ls="--", color="0.6", lw=1, label="one per point")
    for k in range(B + 1):
        ax.plot(n, per_level[k], marker="o", ms=3, color=LEVEL_COLOURS[k % len(LEVEL_COLOURS)], label=f"level {k}")
    ax.plot(n, total, marker="s", ms=3, color="0.2", lw=2, label="all levels")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("sensor points")
    ax.set_ylabel("records")
    ax.legend(fontsize=7)
    ax.set_title("records", fontsize=10)
    ax = axes[1]
    ax.plot(n, rays, marker="o", ms=3, color="0.2")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("sensor points")
    ax.set_ylabel("rays")
    ax.set_title("rays", fontsize=10)
    report.figure("records_vs_points", fig, "Records per level and rays against the number of sensor points "
                                            "(log–log) over the same workplane.")


def _section_checks(report, res):
    """The properties the test suite asserts, stated with their bounds."""
    B = len(res["full"]["records"]) - 1
    half, ov, den = res["half"], res["overlap"], res["density"]
    checks = {
        "half_level0_in_half": half["level0_outside_sensor_box"] == 0 and half["level0_max_x"] < HALF_X,
        "half_fewer_records_and_rays": half["records_fraction"] < 1.0 and half["rays_fraction"] < 1.0,
        "black_floor_no_deeper_records": res["black_floor"]["deeper_on_floor"] == 0,
        "baseline_floor_has_deeper_records": sum(res["full"]["floor_records"][1:]) > 0,
        "dark_no_records_no_rays": res["dark"]["total_records"] == 0 and res["dark"]["rays"] == 0
        and res["dark"]["max_illuminance"] == 0.0,
        "sun_only_no_bounce_limit_level": res["sun_only"]["bounce_limit_records"] == 0
        and all(c > 0 for c in res["sun_only"]["records"][:B]),
        "overlap_new_not_above_alone": all(n <= a for n, a in zip(ov["B_after_A"]["new_records"],
                                                                   ov["B_alone"]["records"])),
        "overlap_new_uncovered_by_A": sum(ov["new_records_covered_by_A"]) == 0,
        "overlap_new_level0_beyond_A": ov["new_level0_min_y"] > A_MAX_Y,
        "density_linear_at_coarse_end": den["exponents"]["level 0"][0] >= COARSE_EXPONENT_MIN,
        "density_sublinear_at_dense_end": den["dense_end"]["level 0"] <= DENSE_EXPONENT_MAX
        and den["dense_end"]["all"] <= DENSE_EXPONENT_MAX,
    }
    res["checks"] = checks
    report.heading("What held")
    words = {True: "held", False: "did NOT hold"}
    report.bullets([
        f"Half grid: every level-0 record lies at one of the half's sensors, x < {fmt(HALF_X)} m — "
        f"{words[checks['half_level0_in_half']]}; it made fewer records and traced fewer rays than the full "
        f"grid — {words[checks['half_fewer_records_and_rays']]}.",
        f"Floor of ρ = 0: no record of level ≥ 1 on it (0 of the run's {res['black_floor']['total_records']:,} "
        f"records) — "
        f"{words[checks['black_floor_no_deeper_records']]}; with ρ = 0.2 the floor has such records — "
        f"{words[checks['baseline_floor_has_deeper_records']]}.",
        f"No sky, no sun, no light surface: 0 records, 0 rays, 0 lux — {words[checks['dark_no_records_no_rays']]}.",
        f"Sun without sky: no record at the bounce limit, records at every shallower level — "
        f"{words[checks['sun_only_no_bounce_limit_level']]}.",
        f"Second grid on the first's cache: new records ≤ its records alone at every level — "
        f"{words[checks['overlap_new_not_above_alone']]}; none covered by the first grid's records — "
        f"{words[checks['overlap_new_uncovered_by_A']]}; new level-0 records only beyond the first grid's rows "
        f"(y > {fmt(A_MAX_Y)} m) — {words[checks['overlap_new_level0_beyond_A']]}.",
        f"Density: level-0 growth exponent between the two coarsest grids ≥ {fmt(COARSE_EXPONENT_MIN)} (a record "
        f"per point) — {words[checks['density_linear_at_coarse_end']]}; growth exponent between the two densest "
        f"grids ≤ {fmt(DENSE_EXPONENT_MAX)} at level 0 and for all records — "
        f"{words[checks['density_sublinear_at_dense_end']]}.",
    ])
