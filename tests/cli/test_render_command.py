"""``lbl-illum render``: views by name, string or file; the image written with its view, the
previews, the cache and the stats; bad input refused before anything is written."""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest

from lbl_illum import Integrator
from lbl_illum.cli.render import render_command, resolve_view
from lbl_illum.errors import InputError
from lbl_illum.io.images import read_hdr_header, read_image
from lbl_illum.scene.scenefile import load_scene
from lbl_illum.scene.views import view_from_string

from conftest import make_scene

ROOM_VIEW = "-vtv -vp -1.2 -1.2 1.6 -vd 1 1 0.3 -vh 70 -vv 70"
#: Sensors on the room's floor plan at 0.8 m, facing up.
FLOOR = np.column_stack([np.repeat(np.linspace(-1.2, 1.2, 5), 5), np.tile(np.linspace(-1.2, 1.2, 5), 5),
                         np.full(25, 0.8)])
UP = np.tile([0.0, 0.0, 1.0], (25, 1))


def one_room():
    """A closed 3 m room with a lamp in the ceiling."""
    return make_scene([{"shape": "box", "center": [0, 0, 1.5], "size": [3, 3, 3], "material": "wall"}],
                      {"wall": {"type": "diffuse", "reflectance": 0.5}}, {"type": "none"})


def test_named_views(tmp_path):
    scene = one_room()
    toml = tmp_path / "scene.toml"
    toml.write_text('[views.corner]\nposition = [-1.2, -1.2, 1.6]\ntarget = [0, 0, 1]\nhorizontal = 70\n'
                    '[views.desk]\nradiance = "-vta -vp 0 0 1.2 -vd 0 1 0"\n')
    scene.path = toml
    assert resolve_view(scene, "desk").type == "a"
    assert resolve_view(scene, "corner").horizontal == 70.0
    with pytest.raises(InputError, match="did you mean 'desk'"):
        resolve_view(scene, "dsk")
    scene.views = {"north": view_from_string("-vtv -vd 0 1 0")}      # a loader that keeps the views
    assert resolve_view(scene, "north").direction == (0.0, 1.0, 0.0)
    vf = tmp_path / "v.vf"
    vf.write_text("rvu -vtv -vp 1 2 3 -vd 0 1 0 -vh 50 -vv 40\n")
    assert resolve_view(scene, None, str(vf)).position == (1.0, 2.0, 3.0)
    changed = resolve_view(scene, "-vh 30", str(vf))
    assert changed.horizontal == 30.0 and changed.position == (1.0, 2.0, 3.0)
    with pytest.raises(InputError, match="give a view"):
        resolve_view(scene)


ROOM_TOML = """units = "m"
[[geometry]]
shape = "box"
center = [0, 0, 1.5]
size = [3, 3, 3]
material = "wall"
[[geometry]]
shape = "rectangle"
origin = [-0.3, -0.3, 2.99]
u = [0.6, 0, 0]
v = [0, 0.6, 0]
material = "lamp"
[materials.wall]
type = "diffuse"
reflectance = 0.5
[materials.lamp]
type = "light"
luminance = 2000
[sky]
type = "none"
[settings]
accuracy = 0.2
samples = 64
bounces = 2
"""


def command_args(tmp_path, **changes):
    values = dict(scene=str(tmp_path / "room.toml"), view=ROOM_VIEW, view_file=None, x=32, y=32,
                  output=str(tmp_path / "out.hdr"), pixel_samples=1, preview=None, falsecolor=None,
                  falsecolor_max=None, falsecolor_scale="linear", falsecolor_style="bands", falsecolor_title=None,
                  cache=None, stats=None, quiet=True)
    values.update(changes)
    return argparse.Namespace(**values)


def test_render_command_writes_the_image_with_its_view(tmp_path, capsys):
    (tmp_path / "room.toml").write_text(ROOM_TOML)
    args = command_args(tmp_path, preview=str(tmp_path / "p.png"), falsecolor=str(tmp_path / "f.png"),
                        cache=str(tmp_path / "c.npz"), stats=str(tmp_path / "s.json"), quiet=False)
    assert render_command(args) == 0
    header = read_hdr_header(tmp_path / "out.hdr")
    view = view_from_string(ROOM_VIEW)
    assert header.view == view
    assert (header.width, header.height) == view.resolution(32, 32)
    image = read_image(tmp_path / "out.hdr")
    assert image.rgb.shape == (header.height, header.width, 3)
    assert image.luminance.max() == pytest.approx(2000.0, rel=1 / 256)
    for name in ("p.png", "f.png", "c.npz", "s.json"):
        assert (tmp_path / name).stat().st_size > 0
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("lbl-illum: render") and "records per level" in line and "rays" in line
    # the second run reads the cache and adds nothing
    assert render_command(command_args(tmp_path, cache=str(tmp_path / "c.npz"), stats=str(tmp_path / "t.json"))) == 0
    assert json.loads((tmp_path / "t.json").read_text())["records_made"] == 0


def test_render_command_refuses_bad_input_before_writing(tmp_path):
    (tmp_path / "room.toml").write_text(ROOM_TOML)
    bad = [dict(output=str(tmp_path / "out.jpg")), dict(view="nowhere"), dict(view=None),
           dict(view="-vtv -vh 200"), dict(preview=str(tmp_path / "p.jpg")), dict(x=0),
           dict(point_samples=64), dict(cache=str(tmp_path / "no" / "c.npz")),
           dict(falsecolor_style="contours"), dict(falsecolor_title="Level 2"), dict(falsecolor_max=100.0),
           dict(falsecolor=str(tmp_path / "f.png"), falsecolor_max=-1.0)]
    for change in bad:
        with pytest.raises(InputError) as info:
            render_command(command_args(tmp_path, **change))
        assert "\n" not in str(info.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["room.toml"]
    # a cache made with point_samples is refused with the reason
    scene_cache = tmp_path / "c.npz"
    scene = load_scene(tmp_path / "room.toml")
    integ = Integrator(scene, scene.options.replace(point_samples=64))
    integ.compute(FLOOR[:5], UP[:5])
    integ.cache.save(scene_cache)
    with pytest.raises(InputError, match="point_samples"):
        render_command(command_args(tmp_path, cache=str(scene_cache)))


def test_view_options_and_files_are_in_the_scene_units(tmp_path):
    """A scene in millimetres: --view -vp 1200 ... is 1.2 m, not 1.2 km (it was metres)."""
    import dataclasses

    scene = dataclasses.replace(one_room(), unit_scale=0.001, units="mm")
    view = resolve_view(scene, "-vtv -vp -1200 -1200 1600 -vd 1 1 0.3")
    assert np.allclose(view.position, [-1.2, -1.2, 1.6])
    vf = tmp_path / "v.vf"
    vf.write_text("rvu -vtv -vp 1000 2000 3000 -vd 0 1 0\n")
    assert np.allclose(resolve_view(scene, None, str(vf)).position, [1.0, 2.0, 3.0])


def test_falsecolor_gets_the_source_pixels_the_style_and_the_title(tmp_path, monkeypatch):
    """The lamp seen in the ceiling (2,000 cd/m²) is the only source: the false colour gets
    the render's source pixels (its default scale is the walls'), the style and the title
    asked for; without --falsecolor-title the scene file names the picture."""
    pytest.importorskip("matplotlib")
    from lbl_illum.viz import falsecolor

    calls = []
    real = falsecolor.write_falsecolor

    def spy(path, image, **kwargs):
        calls.append(kwargs)
        return real(path, image, **kwargs)

    monkeypatch.setattr(falsecolor, "write_falsecolor", spy)
    (tmp_path / "room.toml").write_text(ROOM_TOML)
    title = "Room 1, lamp on, no daylight: luminance seen from the door"
    args = command_args(tmp_path, falsecolor=str(tmp_path / "f.png"), falsecolor_style="contours",
                        falsecolor_title=title)
    assert render_command(args) == 0
    lum = read_image(tmp_path / "out.hdr").luminance
    (kwargs,) = calls
    assert kwargs["style"] == "contours" and kwargs["title"] == title and kwargs["maximum"] is None
    lamp = lum > 1000.0                  # pixels wholly on the lamp
    beside = lamp.copy()                 # ... and those next to them, where edge rays may meet it
    beside[1:] |= lamp[:-1]
    beside[:-1] |= lamp[1:]
    beside[:, 1:] |= beside[:, :-1].copy() | lamp[:, :-1]
    beside[:, :-1] |= lamp[:, 1:]
    source = kwargs["source"]
    assert lamp.any() and not (lamp & ~source).any() and not (source & ~beside).any()
    assert falsecolor.default_maximum(lum, kwargs["valid"], kwargs["source"]) < 1000.0
    assert (tmp_path / "f.png").stat().st_size > 0
    assert render_command(command_args(tmp_path, falsecolor=str(tmp_path / "g.png"))) == 0
    assert calls[-1]["title"] == "room.toml: luminance" and calls[-1]["style"] == "bands"
