"""A 3-D view of a scene with its sensor points coloured by result (pyvista / VTK).

The view is built from *layers*, each an object with ``add_to(plotter, view)``: the
scene's geometry (:class:`GeometryLayer`) and the sensor points (:class:`PointLayer`).
Further layers (e.g. irradiance-cache records drawn as spheres) only need the same
method; :func:`render` takes any list of them.

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
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import InputError
from .files import atomic_write_bytes

__all__ = ["GeometryLayer", "PointLayer", "ViewFrame", "render", "check_view_path", "offscreen_available",
           "require_pyvista", "SCREENSHOT_FORMATS"]

SCREENSHOT_FORMATS = (".png",)
#: Opacity of the scene's surfaces.
SURFACE_OPACITY = 0.35
#: The region of interest grows by this fraction of its size (at least 1 m) on each side;
#: geometry wholly outside is not drawn.
ROI_GROWTH = 0.3


def require_pyvista():
    """The pyvista module, or an :class:`InputError` saying how to install it."""
    try:
        import pyvista
    except ImportError:
        raise InputError("3-D views need pyvista; install it with pip install 'lbl_illum[view]'") from None
    return pyvista


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
    try:
        import pyvista  # noqa: F401
    except ImportError:
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

        from .materials import GLASS, LIGHT
        from .photometry import luminance

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

    scene : the :class:`~lbl_illum.scene.Scene`;  layers : objects with ``add_to``
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
    _write_png(screenshot, image)


def _write_png(path: Path, image: np.ndarray) -> None:
    """Write an (h, w, 3 or 4) uint8 image as PNG, atomically."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(buf, format="PNG")
    atomic_write_bytes(path, buf.getvalue())
