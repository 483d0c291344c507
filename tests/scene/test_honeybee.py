"""Honeybee models (.hbjson) as scenes, sensor grids and views, and results written the
way Ladybug Tools reads them (lbl_illum.scene.honeybee, lbl_illum.io.honeybee_results)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from lbl_illum.cli.main import main
from lbl_illum.errors import InputError
from lbl_illum.io.points import read_points
from lbl_illum.scene.scenefile import load_scene

from conftest import EXAMPLES, ROOT

MODEL = ROOT / "tests" / "data" / "honeybee" / "model_radiance_grid_views.hbjson"
EPW = EXAMPLES / "weather" / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
QUICK = ["--samples", "32", "--point-samples", "128", "--bounces", "2"]

honeybee = pytest.importorskip("honeybee_radiance", reason="the optional extra 'honeybee' is not installed")


@pytest.fixture
def job(tmp_path):
    shutil.copy(MODEL, tmp_path / "model.hbjson")
    (tmp_path / "scene.toml").write_text('[[geometry]]\nfile = "model.hbjson"\n[sky]\ntype = "cie-overcast"\n'
                                         'horizontal_illuminance = 10000\n')
    return tmp_path


def test_the_model_is_the_scene(job):
    from honeybee.model import Model

    scene = load_scene(job / "scene.toml")
    model = Model.from_hbjson(str(MODEL))
    faces = [f for room in model.rooms for f in room.faces]
    # the faces less their openings, the apertures and doors, and every shade (Model.shades
    # holds those assigned to rooms, faces and apertures too); the wall between the two
    # rooms twice, once for each room
    expected = sum(f.punched_geometry.area for f in faces) + sum(a.area for f in faces for a in f.apertures) \
        + sum(d.area for f in faces for d in f.doors) + sum(s.area for s in model.shades)
    tri = scene.triangles.vertices
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
    assert area == pytest.approx(expected, rel=1e-6)
    kinds = {m.name: m.kind for m in scene.materials}
    assert kinds["generic_exterior_window_vis_0.64"] == "glass" and kinds["generic_wall_0.50"] == "diffuse"
    assert set(scene.views) == {"Tiny_House_Zone", "Tiny_Garage"}
    v = scene.views["Tiny_House_Zone"]
    assert v.position == pytest.approx((2.5, 5.0, 1.5)) and v.type == "v"


def test_sensor_grids_are_points_with_their_grid_as_area():
    points, normals, areas = read_points(MODEL, 123.0, with_areas=True)        # unit_scale does not apply
    assert points.shape == (400, 3) and (normals[:, 2] == 1.0).all()
    assert list(dict.fromkeys(areas.tolist())) == ["Tiny_House_Zone", "Tiny_Garage"]
    assert points[0] == pytest.approx([4.75, 0.25, 1.0])


def test_results_go_out_as_res_files(job, capsys):
    assert main(["illuminance", str(job / "scene.toml"), "--points", str(job / "model.hbjson"), "-o",
                 str(job / "res"), "-q", *QUICK]) == 0
    info = json.loads((job / "res" / "grids_info.json").read_text())
    assert [g["identifier"] for g in info] == ["Tiny_House_Zone", "Tiny_Garage"]
    for g in info:
        values = np.loadtxt(job / "res" / f"{g['identifier']}.res")
        assert len(values) == g["count"] == 200 and (values > 0).all()


def test_annual_results_in_honeybees_layout(job):
    out = job / "year"
    assert main(["annual", str(job / "scene.toml"), "--points", str(job / "model.hbjson"), "--weather", str(EPW),
                 "-o", str(out), "-q", "--no-plots", "--ill", *QUICK]) == 0
    results = out / "results"
    sun_up = np.loadtxt(results / "sun-up-hours.txt")
    total = np.load(results / "__static_apertures__" / "default" / "total" / "Tiny_Garage.npy")
    assert total.shape == (200, len(sun_up)) and total.dtype == np.float32
    E = np.load(out / "illuminance.npy")
    np.testing.assert_array_equal(total, E[200:, (sun_up - 0.5).astype(int)])
    summary = json.loads((out / "summary.json").read_text())
    # the text .ill of the earlier recipes: the same values to 0.01 lux, and the DA that
    # honeybee-radiance's own post-processing computes from it equals ours (it rounds each
    # point's DA to 0.01 %: measured within 2.3e-4 % in the mean)
    ill = np.loadtxt(results / "Tiny_Garage.ill", delimiter="\t")
    np.testing.assert_allclose(ill, total, atol=0.005 + 1e-6 * total.max())
    from honeybee_radiance.postprocess.annualdaylight import metrics_from_folder

    da = metrics_from_folder(str(results), threshold=300)[0]
    for d, g in zip(da, json.loads((results / "grids_info.json").read_text())):
        assert np.mean(d) == pytest.approx(summary["areas"][g["identifier"]]["da"], abs=0.005)
    try:
        from honeybee_radiance_postprocess.results.annual_daylight import AnnualDaylight
    except ImportError:
        return
    da, info = AnnualDaylight(str(results)).daylight_autonomy(threshold=300)
    theirs = {i["identifier"]: float(np.mean(d)) for d, i in zip(da, info)}
    for name in theirs:
        assert theirs[name] == pytest.approx(summary["areas"][name]["da"], rel=1e-9)


def test_without_the_extra_one_line(job, monkeypatch):
    import importlib

    import lbl_illum.optional as optional

    real = importlib.import_module

    def refuse(name, *args):
        if name == "honeybee_radiance":
            raise ImportError(name)
        return real(name, *args)

    monkeypatch.setattr(optional.importlib, "import_module", refuse)
    from lbl_illum.scene import honeybee as hb

    hb._read.cache_clear()
    with pytest.raises(InputError, match=r"Honeybee models \(\.hbjson\) needs honeybee_radiance; install it with "
                                         r"pip install 'lbl_illum\[honeybee\]'"):
        load_scene(job / "scene.toml")
    hb._read.cache_clear()


def test_a_file_that_is_no_model(job):
    (job / "model.hbjson").write_text('{"type": "Model"}')
    from lbl_illum.scene import honeybee as hb

    hb._read.cache_clear()
    with pytest.raises(InputError, match=r"geometry\[0\] model.hbjson: not a Honeybee model"):
        load_scene(job / "scene.toml")
