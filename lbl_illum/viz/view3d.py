"""A 3-D view of a scene with its sensor points coloured by result (pyvista / VTK).

The view is built from *layers*, each an object with ``add_to(plotter, view)``: the
scene's geometry (:class:`GeometryLayer`), the sensor points (:class:`PointLayer`) and
the records of an irradiance cache (:class:`CacheLayer`); :func:`render` takes any list
of them.

**Records** are drawn as the paper draws them in its Figure 5b (Ward, Rubinstein &
Clear, "A Ray Tracing Solution for Diffuse Interreflection", SIGGRAPH 1988): each record
i of level k is a flat disc at its position P_i [m], perpendicular to its normal N_i,
whose radius is the reach of its valid domain, a_k · R_i [m].  A query at distance d
from P_i (with the same normal) may use the record while d / R_i < a_k (Eq. 5 with
the normal term 0), so the disc is the set of same-plane points the record serves.
A level with elliptical domains (``interpolation = "hessian"``) holds a shape vector W_i
per record: the domain is (d² + (d·W_i)²) / R_i² < a_k², an ellipse whose short radius
a_k R_i / sqrt(1 + |W_i|²) lies along W_i and whose long radius a_k R_i lies across it
(:attr:`lbl_illum.engine.cache.LevelRecords.W`); it is drawn as that ellipse.  Discs are
coloured by level, with a legend giving each level's ``a`` and record count.

Geometry near the points is drawn semi-transparent, grey by reflectance, glass pale
blue, light sources yellow; horizontal surfaces above the highest point (ceilings,
roofs) are left out so that the grid is seen from above.  The camera looks down from
the south-east at the region of interest (the points, or without points the
non-horizontal geometry, which leaves out a large ground plane).

Off-screen rendering (screenshots) needs an OpenGL that works without a display.
VTK's wheels (9.4 and later) for Linux try an X11 window, then EGL (``libEGL`` with
Mesa's drivers, e.g. the ``libegl1`` and ``libgl1-mesa-dri`` packages), then OSMesa;
without ``DISPLAY`` or ``WAYLAND_DISPLAY`` the failed X11 attempt only prints a warning,
which :func:`render` silences (VTK messages below errors are not shown).
:func:`offscreen_available` tries a render in a child process, so a missing library
cannot crash the caller.

pyvista is an optional extra (``pip install 'lbl_illum[view]'``); importing this module
does not need it, using it does.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..optional import available, require

__all__ = ["GeometryLayer", "PointLayer", "CacheLayer", "ViewFrame", "record_outlines", "read_cache_layer", "render",
           "check_view_path", "offscreen_available", "require_pyvista", "SCREENSHOT_FORMATS"]

SCREENSHOT_FORMATS = (".png",)
#: Opacity of the scene's surfaces.
SURFACE_OPACITY = 0.35
#: The region of interest grows by this fraction of its size (at least 1 m) on each side;
#: geometry wholly outside is not drawn.
ROI_GROWTH = 0.3


def require_pyvista():
    """The pyvista module, or an :class:`InputError` saying how to install it."""
    return require("pyvista")


def check_view_path(path: str | os.PathLike) -> Path:
    """Refuse a screenshot whose extension is not .png or whose folder does not exist, and
    a missing pyvista."""
    path = Path(path)
    if path.suffix.lower() not in SCREENSHOT_FORMATS:
        raise InputError(f"{path.name}: a screenshot must end in {', '.join(SCREENSHOT_FORMATS)}")
    if str(path.parent) and not path.parent.is_dir():
        raise InputError(f"{path}: folder {path.parent} does not exist")
    require_pyvista()
    return path


def _headless() -> bool:
    return sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _quiet_vtk() -> None:
    """Without a display, hide VTK's warnings (the X11 window it tries before EGL)."""
    if _headless():
        from vtkmodules.vtkCommonCore import vtkLogger

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)


_PROBE = """
import sys
from vtkmodules.vtkCommonCore import vtkLogger
vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
import pyvista as pv
p = pv.Plotter(off_screen=True, window_size=(64, 48))
p.add_mesh(pv.Sphere())
img = p.screenshot(return_img=True)
p.close()
sys.exit(0 if img is not None and img.size > 0 else 3)
"""


@lru_cache(maxsize=1)
def offscreen_available() -> tuple[bool, str]:
    """(True, "") when pyvista can render off screen here, else (False, reason).

    The trial runs in a child process (a missing OpenGL library can abort the process
    that tries), with a 120 s limit.
    """
    if not available("pyvista"):
        return False, "pyvista is not installed (pip install 'lbl_illum[view]')"
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120)
    except subprocess.TimeoutExpired:
        return False, "off-screen rendering did not finish within 120 s"
    if proc.returncode == 0:
        return True, ""
    last = [l for l in proc.stderr.splitlines() if l.strip()]
    return False, f"VTK cannot render off screen here ({last[-1].strip() if last else f'exit {proc.returncode}'})"


# ---------------------------------------------------------------------------
# Layers
# ---------------------------------------------------------------------------

@dataclass
class ViewFrame:
    """What the layers share: the region of interest [m] and the height above which
    horizontal surfaces are left out (None: keep them)."""

    lo: np.ndarray
    hi: np.ndarray
    cut_above: float | None = None


@dataclass
class GeometryLayer:
    """The scene's triangles, clipped to the region of interest."""

    scene: object
    opacity: float = SURFACE_OPACITY

    def add_to(self, plotter, frame: ViewFrame) -> None:
        import pyvista as pv

        from ..scene.materials import GLASS, LIGHT
        from ..photometry import luminance

        tri = self.scene.triangles
        table = self.scene.material_table
        v = tri.vertices
        keep = np.all((v.max(axis=1) >= frame.lo) & (v.min(axis=1) <= frame.hi), axis=1)
        if frame.cut_above is not None:
            flat = np.abs(tri.normals[:, 2]) > 0.99
            keep &= ~(flat & (v[:, :, 2].min(axis=1) > frame.cut_above))
        kind = table.kind[tri.material]
        grey = np.clip(luminance(table.reflectance)[tri.material], 0.0, 1.0)
        colour = np.repeat(0.25 + 0.7 * grey[:, None], 3, axis=1)
        colour[kind == GLASS] = (0.55, 0.8, 1.0)
        colour[kind == LIGHT] = (1.0, 0.9, 0.3)
        for glass in (False, True):
            sel = np.flatnonzero(keep & ((kind == GLASS) == glass))
            if len(sel) == 0:
                continue
            faces = np.column_stack([np.full(len(sel), 3), np.arange(3 * len(sel)).reshape(-1, 3)])
            mesh = pv.PolyData(v[sel].reshape(-1, 3), faces.ravel())
            mesh.cell_data["rgb"] = (255 * colour[sel]).astype(np.uint8)
            bounds = (frame.lo[0], frame.hi[0], frame.lo[1], frame.hi[1], frame.lo[2], frame.hi[2])
            mesh = mesh.clean().clip_box(bounds, invert=False).extract_surface(algorithm=None)
            if mesh.n_cells == 0:
                continue
            plotter.add_mesh(mesh, scalars="rgb", rgb=True, opacity=self.opacity * (0.6 if glass else 1.0),
                             show_edges=False, lighting=True)
            edges = mesh.extract_feature_edges(boundary_edges=True, feature_edges=True, manifold_edges=False,
                                               non_manifold_edges=False, feature_angle=30)
            if edges.n_points:
                plotter.add_mesh(edges, color="black", line_width=1, opacity=0.6)


@dataclass
class PointLayer:
    """Sensor points [m], coloured by ``values`` (or plain when None), with area names."""

    points: np.ndarray
    values: np.ndarray | None = None
    label: str = "Illuminance [lux]"
    areas: np.ndarray | None = None
    point_size: float = 14.0
    cmap: str = "viridis"

    def add_to(self, plotter, frame: ViewFrame) -> None:
        import pyvista as pv

        cloud = pv.PolyData(np.asarray(self.points, dtype=np.float64))
        if self.values is None:
            plotter.add_mesh(cloud, color="black", point_size=self.point_size * 0.6, render_points_as_spheres=True)
        else:
            cloud.point_data[self.label] = np.asarray(self.values, dtype=np.float64)
            plotter.add_mesh(cloud, scalars=self.label, cmap=self.cmap, point_size=self.point_size,
                             render_points_as_spheres=True,
                             scalar_bar_args=dict(title=self.label, vertical=True, position_x=0.86,
                                                  position_y=0.2, height=0.6, width=0.06, fmt="%.4g"))
        if self.areas is not None:
            names = np.asarray(self.areas, dtype=object)
            labelled = [n for n in dict.fromkeys(names.tolist()) if n]
            if labelled:
                centres = np.array([np.median(self.points[names == n], axis=0) for n in labelled])
                centres[:, 2] = np.asarray(self.points)[:, 2].max() + 0.3
                plotter.add_point_labels(centres, labelled, font_size=14, point_size=1, shape_opacity=0.6,
                                         always_visible=True)


#: Corners of the polygon drawn for each record's domain.
RECORD_SIDES = 24
#: Discs float this fraction of the region of interest's size above their surface,
#: so that the surface does not hide them.
RECORD_LIFT = 2e-3
#: Opacity of the record discs (their outlines are drawn opaque).
RECORD_OPACITY = 0.45


def _tangent_frame(N: np.ndarray, W: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals n and two unit tangents (e1, e2) with e1 × e2 = n, each (n, 3).

    Without W (or where W has no tangential part) e1 is any tangent; otherwise e1 is
    the direction of W's tangential part (the short axis of an elliptical domain).
    """
    n = np.asarray(N, np.float64)
    n = n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    helper = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(helper, n)
    if W is not None:
        w = np.asarray(W, np.float64)
        w = w - np.einsum("ij,ij->i", w, n)[:, None] * n
        shaped = np.linalg.norm(w, axis=1) > 1e-9
        e1[shaped] = w[shaped]
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(n, e1)
    return n, e1, e2


def record_outlines(P, N, R, accuracy: float, W=None, sides: int = RECORD_SIDES, lift: float = 0.0) -> np.ndarray:
    """Corners (n, sides, 3) [m] of the polygons that outline n records' valid domains.

    P (n, 3) [m], N (n, 3) unit normals, R (n,) [m] the records' R_i, ``accuracy`` the
    level's a; W (n, 3) the shape vectors of elliptical domains (None: round).  A round
    domain is a circle of radius a R_i in the record's tangent plane; an elliptical one
    has radius a R_i / sqrt(1 + |W_i|²) along W_i and a R_i across it.  ``lift`` [m]
    moves the polygons along N.
    """
    P = np.asarray(P, np.float64).reshape(-1, 3)
    R = np.asarray(R, np.float64).reshape(-1)
    n, e1, e2 = _tangent_frame(N, W)
    long = accuracy * R
    short = long if W is None else long / np.sqrt(1.0 + np.sum(np.asarray(W, np.float64) ** 2, axis=1))
    t = 2.0 * np.pi * np.arange(sides) / sides
    c, s = np.cos(t), np.sin(t)
    return ((P + lift * n)[:, None, :] + (short[:, None] * c)[:, :, None] * e1[:, None, :]
            + (long[:, None] * s)[:, :, None] * e2[:, None, :])


def _level_colours(k: int) -> tuple[float, float, float]:
    from matplotlib import colormaps

    return tuple(float(x) for x in colormaps["tab10"](k % 10)[:3])


@dataclass
class CacheLayer:
    """The records of an irradiance cache, drawn as their valid domains (module text).

    levels : one dict per diffuse level with ``accuracy`` (a), ``P`` (n, 3) [m], ``N``
    (n, 3), ``R`` (n,) [m] and optionally ``W`` (n, 3) (elliptical domains);
    show : the level numbers to draw (None: every level); the first level drawn is the
    most opaque (``opacity``), the n-th drawn after it ``opacity / (1 + n/2)``.  After :meth:`add_to`,
    ``drawn`` holds the records drawn per level (those inside the region of interest,
    and not on a horizontal surface above the ceiling cut).
    """

    levels: list
    show: list | None = None
    opacity: float = RECORD_OPACITY
    drawn: dict = field(default_factory=dict)

    @classmethod
    def from_cache(cls, cache, show=None) -> "CacheLayer":
        """From an :class:`~lbl_illum.engine.cache.IrradianceCache` or a
        :class:`~lbl_illum.engine.cache.CacheData` (a file's contents)."""
        levels = []
        if hasattr(cache, "levels") and not hasattr(cache, "header"):
            for lv in cache.levels:
                n = lv.count
                levels.append({"accuracy": lv.accuracy, "P": lv.P[:n], "N": lv.N[:n], "R": lv.R[:n],
                               "W": lv.W[:n] if lv.anisotropic else None})
        else:
            for k, info in enumerate(cache.header["levels"]):
                a = cache.level(k)
                levels.append({"accuracy": float(info["accuracy"]), "P": a["P"], "N": a["N"], "R": a["R"],
                               "W": a.get("W") if cache.anisotropic else None})
        return cls(levels, show)

    def add_to(self, plotter, frame: ViewFrame) -> None:
        import pyvista as pv

        size = float(np.max(frame.hi - frame.lo))
        entries, shaped = [], False
        for k, lv in enumerate(self.levels):
            if self.show is not None and k not in self.show:
                continue
            P = np.asarray(lv["P"], np.float64).reshape(-1, 3)
            N = np.asarray(lv["N"], np.float64).reshape(-1, 3)
            keep = np.all((P >= frame.lo) & (P <= frame.hi), axis=1)
            if frame.cut_above is not None:
                keep &= ~((np.abs(N[:, 2]) > 0.99) & (P[:, 2] > frame.cut_above))
            idx = np.flatnonzero(keep) if lv["accuracy"] > 0.0 else np.zeros(0, np.int64)   # a = 0: no domain
            self.drawn[k] = int(len(idx))
            if len(idx) == 0:
                continue
            W = None if lv.get("W") is None else np.asarray(lv["W"])[idx]
            corners = record_outlines(P[idx], N[idx], np.asarray(lv["R"])[idx], lv["accuracy"], W,
                                      lift=RECORD_LIFT * size)
            m, sides = corners.shape[:2]
            faces = np.column_stack([np.full(m, sides), np.arange(m * sides).reshape(m, sides)])
            discs = pv.PolyData(corners.reshape(-1, 3), faces.ravel())
            colour = _level_colours(k)
            # the first level drawn most opaque: deeper levels' larger discs would hide it
            plotter.add_mesh(discs, color=colour, opacity=self.opacity / (1.0 + 0.5 * (len(entries))),
                             lighting=False, show_edges=True,
                             edge_color=tuple(0.6 * c for c in colour), line_width=1)
            shaped |= W is not None
            entries.append([f"level {k}: {len(idx):,}, a = {lv['accuracy']:.3g}", colour, "circle"])
        if entries:
            head = "records (" + ("ellipses" if shaped else "discs") + " of radius a R_i)"
            entries.insert(0, [head, "black", "none"])
            # rows of about 3 % of the window's height; the width fits the longest label
            w_px, h_px = plotter.window_size
            rows = min(0.032 * len(entries), 0.32)
            chars = max(len(e[0]) for e in entries) + 3
            width = min(0.6, 0.45 * chars * (rows / len(entries)) * h_px / w_px + 0.02)
            legend = plotter.add_legend(entries, bcolor="white", border=True, loc="lower right", size=(width, rows))
            legend.SetPosition(1.0 - width - 0.01, 0.02)     # (pyvista places "right" by the height)


def read_cache_layer(path: str | os.PathLike, show=None) -> CacheLayer:
    """A :class:`CacheLayer` of the cache file ``path``.  Any lbl_illum cache file is
    drawn, whatever scene and settings it was made for; anything else is refused with
    one line (:class:`InputError`, from :func:`lbl_illum.io.cachefile.read_cache_file`)."""
    from ..io.cachefile import read_cache_file

    layer = CacheLayer.from_cache(read_cache_file(path), show)
    if show is not None:
        missing = [k for k in show if not 0 <= k < len(layer.levels)]
        if missing:
            raise InputError(f"{Path(path).name}: no level {missing[0]} (the file has levels 0 to "
                             f"{len(layer.levels) - 1})")
    return layer


# ---------------------------------------------------------------------------
# Rendering
# ---------------------------------------------------------------------------

def _region(scene, points: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The region of interest [m]: the points, else the non-horizontal geometry, grown."""
    tri = scene.triangles
    if points is not None and len(points):
        lo, hi = np.min(points, axis=0), np.max(points, axis=0)
    else:
        upright = np.abs(tri.normals[:, 2]) < 0.99
        v = tri.vertices[upright] if upright.any() else tri.vertices
        lo, hi = v.reshape(-1, 3).min(axis=0), v.reshape(-1, 3).max(axis=0)
    grow = np.maximum(1.0, ROI_GROWTH * (hi - lo).max())
    lo, hi = lo - grow, hi + grow
    lo[2], hi[2] = tri.bounds[0, 2] - 1e-6, tri.bounds[1, 2] + 1e-6    # every height
    return lo, hi


def render(scene, layers: list | None = None, points: np.ndarray | None = None,
           screenshot: str | os.PathLike | None = None, window_size=(1280, 960), title: str | None = None,
           cut_ceiling: bool = True) -> None:
    """Show the view in a window, or write it to ``screenshot`` (.png) off screen.

    scene : the :class:`~lbl_illum.scene.scenefile.Scene`;  layers : objects with ``add_to``
    (default: the geometry only);  points : (n, 3) [m] that set the region of interest
    and the ceiling cut (usually those of a :class:`PointLayer`).
    """
    pv = require_pyvista()
    if screenshot is None and _headless():
        raise InputError("no display to open a window on: give --screenshot FILE.png")
    if screenshot is not None:
        screenshot = check_view_path(screenshot)
        _quiet_vtk()
    lo, hi = _region(scene, points)
    cut = float(np.max(points[:, 2])) + 0.05 if (cut_ceiling and points is not None and len(points)) else None
    if cut is None and cut_ceiling and points is None:
        cut = float(0.5 * (lo[2] + hi[2]))
    frame = ViewFrame(lo, hi, cut)
    plotter = pv.Plotter(off_screen=screenshot is not None, window_size=list(window_size), title=title)
    try:
        plotter.set_background("white")
        for layer in layers if layers is not None else [GeometryLayer(scene)]:
            layer.add_to(plotter, frame)
        if title:
            plotter.add_text(title, font_size=11, color="black")
        centre = 0.5 * (lo + hi)
        if points is not None and len(points):
            centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        plotter.camera.focal_point = tuple(centre)
        plotter.camera.position = tuple(centre + np.array([0.55, -0.9, 1.1]))
        plotter.camera.up = (0.0, 0.0, 1.0)
        plotter.reset_camera(bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        plotter.add_axes(color="black")
        if screenshot is None:
            plotter.show()
            return
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    from ..io.images import write_png

    write_png(screenshot, np.ascontiguousarray(image), "lbl_illum 3-D view")
