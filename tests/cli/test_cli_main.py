"""The command line: outputs, summaries, cache reuse, and bad input (one line, exit 2, no output)."""

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.cli.main import main
from lbl_illum.options import PRESETS, Options
from lbl_illum.io.points import read_points

from conftest import EXAMPLES

SPHERE = EXAMPLES / "sphere_on_plane"
FAST = ["--samples", "64", "--bounces", "1"]


def run(argv, capsys):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def sphere_job(tmp_path):
    pts = tmp_path / "p.pts"
    pts.write_text("# two points\n0 0 2 0 0 1\n\n1 0 1 1 0 0  # equator\n")
    return tmp_path, pts


def test_csv_and_txt_outputs(sphere_job, capsys):
    tmp, pts = sphere_job
    code, _, err = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.csv"] + FAST, capsys)
    assert code == 0
    assert "illuminance at 2 points" in err and "rays" in err and "records per level" in err
    lines = (tmp / "r.csv").read_text().splitlines()
    assert lines[0].startswith("x,y,z,nx,ny,nz,illuminance")
    values = np.array([float(l.split(",")[6]) for l in lines[1:]])
    # top of the sphere: E0 = 1000 lux direct, nothing reflected to it
    assert values[0] == pytest.approx(1000.0, rel=1e-4)
    code, _, _ = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.txt", "-q"] + FAST, capsys)
    txt = np.array([float(l) for l in (tmp / "r.txt").read_text().split()])
    assert np.allclose(txt, values, rtol=1e-5)


def test_cache_file_second_run_identical_and_stats(tmp_path, capsys):
    office = EXAMPLES / "office"
    pts = tmp_path / "g.pts"
    pts.write_text("\n".join((office / "grid.pts").read_text().splitlines()[::8]))
    # --point-samples 0: the cache starts at the points, so a rerun from the file computes nothing
    args = ["illuminance", office / "scene.toml", "--points", pts, "--samples", "128", "--bounces", "2",
            "--point-samples", "0", "--cache", tmp_path / "c.lblcache"]
    assert run(args + ["-o", tmp_path / "a.csv", "--stats", tmp_path / "a.json"], capsys)[0] == 0
    assert run(args + ["-o", tmp_path / "b.csv", "--stats", tmp_path / "b.json"], capsys)[0] == 0
    a, b = (json.loads((tmp_path / f"{n}.json").read_text()) for n in "ab")
    assert a["primary_evaluations"] > 0 and b["primary_evaluations"] == 0
    assert b["records"] == a["records"]
    for key in ("records", "primary_evaluations", "cache_hits", "rays", "seconds", "settings"):
        assert key in a
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()
    # the same cache with other settings is refused, and no output is written
    code, _, err = run(args[:-2] + ["--samples", "256", "--cache", tmp_path / "c.lblcache",
                                   "-o", tmp_path / "c.csv"], capsys)
    assert code == 2 and "c.lblcache" in err and "other settings" in err
    assert not (tmp_path / "c.csv").exists()


def _bad_scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


GOOD = """
units = "m"
[[geometry]]
shape = "rectangle"
origin = [0, 0, 0]
u = [1, 0, 0]
v = [0, 1, 0]
material = "floor"
[materials.floor]
type = "diffuse"
reflectance = 0.5
[sky]
type = "uniform"
"""


@pytest.mark.parametrize("case, scene_text, pts_text, expect", [
    ("missing geometry file", GOOD.replace('shape = "rectangle"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]',
                                           'file = "nowhere.obj"'), None, "nowhere.obj"),
    ("toml syntax", GOOD.replace("reflectance = 0.5", "reflectance = = 0.5"), None, "line 11, column"),
    ("unknown material", GOOD.replace('material = "floor"', 'material = "flor"'), None, "did you mean 'floor'"),
    ("malformed pts line", GOOD, "0 0 1 0 0 1\n0 0 x 0 0 1\n", "p.pts: line 2"),
    ("zero normal", GOOD, "0 0 1 0 0 0\n", "zero-length normal"),
    ("no points", GOOD, "# nothing\n", "no points"),
])
def test_bad_input_one_line_exit_2_no_output(tmp_path, capsys, case, scene_text, pts_text, expect):
    scene = _bad_scene(tmp_path, scene_text)
    pts = tmp_path / "p.pts"
    pts.write_text(pts_text or "0.5 0.5 0 0 0 1\n")
    out = tmp_path / "out.csv"
    code, stdout, err = run(["illuminance", scene, "--points", pts, "-o", out], capsys)
    assert code == 2, case
    lines = [l for l in err.splitlines() if l.strip()]
    assert len(lines) == 1 and expect in lines[0], err
    assert "Traceback" not in err
    assert not out.exists()


def test_bad_option_values_are_refused(sphere_job, capsys):
    tmp, pts = sphere_job
    for args, expect in ((["--samples", "0"], "samples"), (["--accuracy", "-1"], "accuracy"),
                         (["--bounces", "x"], "whole number")):
        code, _, err = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "o.csv"] + args, capsys)
        assert code == 2 and expect in err and len(err.strip().splitlines()) == 1
    assert not (tmp / "o.csv").exists()


def test_unknown_output_format(sphere_job, capsys):
    tmp, pts = sphere_job
    code, _, err = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "o.xlsx"], capsys)
    assert code == 2 and ".csv or .txt" in err


def test_module_entry_point_and_help():
    for argv in (["-m", "lbl_illum", "--help"], ["-m", "lbl_illum", "illuminance", "--help"]):
        proc = subprocess.run([sys.executable] + argv, capture_output=True, text=True, timeout=60)
        assert proc.returncode == 0 and "usage: lbl-illum" in proc.stdout
    assert "--accuracy" in proc.stdout and "--cache" in proc.stdout


def test_outputs_get_ordinary_permissions(sphere_job, capsys):
    import os
    import stat

    tmp, pts = sphere_job
    assert run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.csv", "-q",
                "--cache", tmp / "c.lblcache"] + FAST, capsys)[0] == 0
    mask = os.umask(0)
    os.umask(mask)
    for name in ("r.csv", "c.lblcache"):
        assert stat.S_IMODE((tmp / name).stat().st_mode) == 0o666 & ~mask
    assert not [p for p in tmp.iterdir() if p.name.endswith(".tmp")]


def test_cache_in_missing_folder_is_refused_before_any_output(sphere_job, capsys):
    tmp, pts = sphere_job
    code, _, err = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.csv",
                        "--cache", tmp / "nowhere" / "c.lblcache"] + FAST, capsys)
    assert code == 2 and "does not exist" in err and len(err.strip().splitlines()) == 1
    assert not (tmp / "r.csv").exists()


def test_preset_and_explicit_option(sphere_job, capsys):
    tmp, pts = sphere_job
    args = ["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.csv", "--preset", "draft",
            "--bounces", "1", "--samples", "32", "--stats", tmp / "s.json"]
    assert run(args, capsys)[0] == 0
    settings = json.loads((tmp / "s.json").read_text())["settings"]
    assert settings["accuracy"] == PRESETS["draft"]["accuracy"] and settings["samples"] == 32
    assert settings["bounces"] == 1


def test_unknown_preset_and_study_one_line(sphere_job, capsys):
    tmp, pts = sphere_job
    code, _, err = run(["illuminance", SPHERE / "scene.toml", "--points", pts, "-o", tmp / "r.csv",
                        "--preset", "ultra"], capsys)
    assert code == 2 and "invalid choice: 'ultra'" in err and len(err.strip().splitlines()) == 1
    assert not (tmp / "r.csv").exists()
    code, _, err = run(["validate", "nonsense", "--report", tmp], capsys)
    assert code == 2 and "invalid choice: 'nonsense'" in err and len(err.strip().splitlines()) == 1


@pytest.fixture
def no_radiance(monkeypatch):
    """Radiance made unavailable as on a machine without it: no pyradiance package and no
    Radiance program on the PATH."""
    import importlib.util

    from lbl_illum.io.radiance import radiance_programs

    real_find_spec, real_which = importlib.util.find_spec, shutil.which
    programs = {"oconv", "rtrace", "rad", "obj2mesh", "gensky", "getinfo", "lookamb", "rcalc", "rpict"}
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a, **k: None if name == "pyradiance" else real_find_spec(name, *a, **k))
    monkeypatch.setattr(shutil, "which",
                        lambda name, *a, **k: None if name in programs else real_which(name, *a, **k))
    assert radiance_programs() is None


def test_validate_all_skips_the_studies_that_need_radiance_when_it_is_missing(tmp_path, capsys, monkeypatch,
                                                                               no_radiance):
    """Each study with an ``unavailable()`` reason is skipped with a line saying why; the
    others run (here a stand-in writes their report); the summary counts both."""
    pytest.importorskip("matplotlib")
    from lbl_illum.cli.main import _studies

    studies = _studies()
    ran = []

    def fake_run(name, ctx, report_dir, command_dir=None):
        ran.append(name)
        folder = Path(report_dir) / name
        folder.mkdir(parents=True)
        (folder / "report.md").write_text("# stand-in\n")
        return folder

    monkeypatch.setattr(studies, "run_study", fake_run)
    skipped = [name for name in studies.STUDIES if studies.unavailable(name) is not None]
    assert "office-daylight" in skipped and "sphere-plane" not in skipped     # sphere-plane runs without it
    code, _, err = run(["validate", "all", "--quick", "--report", tmp_path], capsys)
    assert code == 0, err
    assert ran == [name for name in studies.STUDIES if name not in skipped]
    lines = err.splitlines()
    assert "lbl-illum: validate office-daylight: skipped: needs Radiance's oconv and rtrace (pip install pyradiance)" \
        in lines
    assert not (tmp_path / "office-daylight").exists()
    assert lines[-1].startswith(f"lbl-illum: validate all (quick): {len(ran)} reports written, {len(skipped)} "
                                f"skipped ({', '.join(skipped)}) in ")
    # one study asked for by name cannot run: one line, exit 2, nothing written
    code, _, err = run(["validate", "office-daylight", "--quick", "--report", tmp_path / "one"], capsys)
    assert code == 2 and err.strip() == ("lbl-illum: error: validate office-daylight: cannot run here: needs "
                                         "Radiance's oconv and rtrace (pip install pyradiance)")
    assert not (tmp_path / "one").exists() and ran.count("office-daylight") == 0


def test_help_lists_presets_and_studies(capsys):
    with pytest.raises(SystemExit):
        main(["illuminance", "--help"])
    out = capsys.readouterr().out
    assert "presets (accuracy / samples / bounces" in out and "medium" in out
    with pytest.raises(SystemExit):
        main(["validate", "--help"])
    out = capsys.readouterr().out
    assert "sphere-plane" in out and "--quick" in out


# ---------------------------------------------------------------------------
# grid, daylight-factor, summaries, plans and views
# ---------------------------------------------------------------------------

from conftest import L_ROOM, MATERIALS, room_geometry  # noqa: E402


def _toml(value):
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(float(value)) if isinstance(value, float) else repr(value)


def write_scene(path, geometry, materials, sky=None):
    """A scene file from the pieces the test_grid builders make."""
    lines = ['units = "m"']
    for entry in geometry:
        lines.append("[[geometry]]")
        lines += [f"{k} = {_toml(v)}" for k, v in entry.items()]
    for name, table in materials.items():
        lines.append(f"[materials.{name}]")
        lines += [f"{k} = {_toml(v)}" for k, v in table.items()]
    if sky is not None:
        lines.append("[sky]")
        lines += [f"{k} = {_toml(v)}" for k, v in sky.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def l_scene(tmp_path):
    used = {k: MATERIALS[k] for k in ("floor", "wall", "ceiling")}
    return write_scene(tmp_path / "l.toml", room_geometry(L_ROOM), used, {"type": "cie-overcast"})


def test_grid_command_writes_named_points_and_a_plan(tmp_path, l_scene, capsys):
    pytest.importorskip("matplotlib")
    out, plan = tmp_path / "g.pts", tmp_path / "g.png"
    code, _, err = run(["grid", l_scene, "-o", out, "--plot", plan], capsys)
    assert code == 0 and plan.stat().st_size > 10000
    assert "grid: 56 points in 1 area (floor: 56 on 9 x 9 cells of 0.556 x 0.556 m)" in err
    assert len(err.strip().splitlines()) == 1
    text = out.read_text()
    assert "EN 12464-1" in text and "columns: x y z nx ny nz area" in text
    points, normals, areas = read_points(out, with_areas=True)
    assert len(points) == 56 and set(areas) == {"floor"} and np.allclose(points[:, 2], 0.8)
    # the same in centimetres: lengths on the command line and in the file are in the scene's units
    cm = write_scene(tmp_path / "cm.toml", [dict(g, vertices=[[100 * c for c in v] for v in g["vertices"]])
                                          for g in room_geometry(L_ROOM)],
                     {k: MATERIALS[k] for k in ("floor", "wall", "ceiling")})
    cm_text = cm.read_text().replace('units = "m"', 'units = "cm"')
    cm.write_text(cm_text)
    assert run(["grid", cm, "-o", tmp_path / "cm.pts", "--height", "75", "--no-names", "-q"], capsys)[0] == 0
    cm_points = np.loadtxt(tmp_path / "cm.pts")
    assert cm_points.shape == (56, 6) and np.allclose(cm_points[:, 2], 75)
    assert np.allclose(np.sort(cm_points[:, 0]), np.sort(100 * points[:, 0]))


@pytest.mark.parametrize("args, expect", [
    (["--surface", "flor"], "did you mean 'floor'"),
    (["--margin", "3"], "smaller --margin"),
    (["--spacing", "-1"], "--spacing"),
    (["--plot", "x.bmp"], "must end in"),
])
def test_grid_bad_input_one_line_exit_2_no_output(tmp_path, l_scene, capsys, args, expect):
    out = tmp_path / "g.pts"
    code, _, err = run(["grid", l_scene, "-o", out] + args, capsys)
    assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists() and not (tmp_path / "x.bmp").exists()
    code, _, err = run(["grid", l_scene, "-o", tmp_path / "g.txt"], capsys)
    assert code == 2 and "must end in .pts" in err


def test_daylight_factor_of_an_unobstructed_point_is_100(tmp_path, capsys):
    ground = write_scene(tmp_path / "ground.toml", [{"shape": "polygon", "material": "ground",
                                                     "vertices": [[-50, -50, 0], [50, -50, 0], [50, 50, 0],
                                                                  [-50, 50, 0]]}],
                         {"ground": {"type": "diffuse", "reflectance": 0.2}},
                         {"type": "uniform", "horizontal_illuminance": 3000})
    pts = tmp_path / "p.pts"
    pts.write_text("0 0 0 0 0 1 open\n5 5 0 0 0 1 open\n")
    out = tmp_path / "df.csv"
    code, _, err = run(["daylight-factor", ground, "--points", pts, "-o", out, "--sky-illuminance", "20000",
                        "--bounces", "1", "--summary", tmp_path / "df.summary.json"], capsys)
    assert code == 0 and "daylight factor at 2 points" in err and ">=2% 100%" in err
    lines = out.read_text().splitlines()
    assert lines[0] == "x,y,z,nx,ny,nz,daylight_factor,illuminance,direct,indirect,area"
    df = np.array([float(l.split(",")[6]) for l in lines[1:]])
    E = np.array([float(l.split(",")[7]) for l in lines[1:]])
    # the scene's uniform sky is replaced by a CIE overcast sky of 20 000 lux: E = E_h, DF = 100 %
    assert np.allclose(df, 100.0, rtol=0.005) and np.allclose(E, 20000.0, rtol=0.005)
    summary = json.loads((tmp_path / "df.summary.json").read_text())
    assert summary["sky"]["unobstructed_horizontal_illuminance"] == pytest.approx(20000.0, rel=1e-12)
    assert summary["unit"] == "%" and summary["areas"]["open"]["points"] == 2
    assert summary["overall"]["at_or_above"] == {"2": 1.0}


def _sky_component_under_a_roof_opening(H, half, x, y, n=600, uniform=False):
    """DF [%] under a CIE overcast sky at a floor point (x, y) below a square opening of half
    side ``half`` centred over (0, 0) at height H: the integral of L cos²θ / r² over the
    opening (cos θ = H / r, L ∝ 1 + 2 cos θ, L_z = 1) divided by E_h = 7π / 9 (midpoint rule
    on n x n cells).  ``uniform``: L = 1 and E_h = π instead."""
    s = (np.arange(n) + 0.5) / n * 2 * half - half
    X, Y = np.meshgrid(s - x, s - y)
    r2 = X ** 2 + Y ** 2 + H ** 2
    cos = H / np.sqrt(r2)
    L = np.ones_like(cos) if uniform else (1 + 2 * cos) / 3
    E = np.sum(L * cos ** 2 / r2) * (2 * half / n) ** 2
    return 100 * E / (np.pi if uniform else 7 * np.pi / 9)


def test_the_reference_sky_integral_gives_the_view_factor_of_a_square():
    # uniform sky: DF = 100 x the view factor from a horizontal element to a parallel square centred
    # above it, 4 x (1/2π)·2·A/√(1+A²)·atan(A/√(1+A²)), A = half / H
    A = 1.5 / 3.0
    F = 4 * (1 / (2 * np.pi)) * 2 * A / np.sqrt(1 + A * A) * np.arctan(A / np.sqrt(1 + A * A))
    assert _sky_component_under_a_roof_opening(3.0, 1.5, 0, 0, uniform=True) == pytest.approx(100 * F, rel=1e-5)


def test_daylight_factor_under_a_roof_opening_matches_the_sky_integral(tmp_path, capsys):
    # a black 6 x 6 x 3 m room (nothing reflects) with a 3 x 3 m opening in the roof
    H, half = 3.0, 1.5
    geo = [g for g in room_geometry([(-3, -3), (3, -3), (3, 3), (-3, 3)]) if g["material"] != "ceiling"]
    ring = [((-3, -3), (3, -half)), ((-3, half), (3, 3)), ((-3, -half), (-half, half)), ((half, -half), (3, half))]
    for (x0, y0), (x1, y1) in ring:
        geo.append({"shape": "polygon", "material": "ceiling",
                    "vertices": [[x0, y0, H], [x0, y1, H], [x1, y1, H], [x1, y0, H]]})
    black = {name: {"type": "diffuse", "reflectance": 0.0} for name in ("floor", "wall", "ceiling")}
    scene = write_scene(tmp_path / "roof.toml", geo, black)
    where = [(0.0, 0.0), (1.5, 0.0), (2.5, 2.5)]
    pts = tmp_path / "p.pts"
    pts.write_text("".join(f"{x} {y} 0 0 0 1\n" for x, y in where))
    out = tmp_path / "df.txt"
    assert run(["daylight-factor", scene, "--points", pts, "-o", out, "--point-samples", "4096", "-q"], capsys)[0] == 0
    df = np.array([float(v) for v in out.read_text().split()])
    expect = np.array([_sky_component_under_a_roof_opening(H, half, x, y) for x, y in where])
    assert expect[2] < expect[1] < expect[0]
    assert np.allclose(df, expect, rtol=0.015), (df, expect)       # measured: within 0.4 %


def test_illuminance_run_writes_summary_plan_and_keeps_its_columns(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    office = EXAMPLES / "office"
    pts = tmp_path / "g.pts"
    assert run(["grid", office / "scene.toml", "-o", pts, "-q"], capsys)[0] == 0
    out, plan = tmp_path / "e.csv", tmp_path / "plan.png"
    code, _, err = run(["illuminance", office / "scene.toml", "--points", pts, "-o", out, "--plot", plan,
                        "--preset", "draft", "--thresholds", "100", "1000", "--summary", tmp_path / "e.summary.json"],
                       capsys)
    assert code == 0 and len(err.strip().splitlines()) == 1
    assert ">=100 lux" in err and ">=1000 lux" in err and "U0" in err
    header = out.read_text().splitlines()[0]
    assert header == "x,y,z,nx,ny,nz,illuminance,direct,indirect,area"
    summary = json.loads((tmp_path / "e.summary.json").read_text())
    assert summary["quantity"] == "illuminance" and summary["unit"] == "lux"
    assert set(summary["overall"]["at_or_above"]) == {"100", "1000"} and "floor" in summary["areas"]
    E = np.array([float(l.split(",")[6]) for l in out.read_text().splitlines()[1:]])
    assert summary["overall"]["mean"] == pytest.approx(E.mean(), rel=1e-6)
    assert summary["overall"]["uniformity"] == pytest.approx(E.min() / E.mean(), rel=1e-6)
    assert plan.stat().st_size > 10000


@pytest.mark.parametrize("args, expect", [
    (["--sky-illuminance", "0"], "--sky-illuminance"),
    (["--ground-reflectance", "1.5"], "--ground-reflectance"),
    (["--plot", "plan.jpg"], "must end in"),
    (["--view3d", "nowhere/shot.png"], "does not exist"),
    (["--thresholds"], "expected at least one argument"),
    (["--summary", "nowhere/df.summary.json"], "does not exist"),
])
def test_daylight_factor_bad_input_one_line_exit_2_no_output(sphere_job, capsys, args, expect):
    tmp, pts = sphere_job
    out = tmp / "df.csv"
    code, _, err = run(["daylight-factor", SPHERE / "scene.toml", "--points", pts, "-o", out] + FAST + args, capsys)
    assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists() and not (tmp / "df.summary.json").exists() and not (tmp / "plan.jpg").exists()


def test_view3d_and_view_command(tmp_path, capsys):
    pytest.importorskip("pyvista")
    from lbl_illum.viz.view3d import offscreen_available

    ok, reason = offscreen_available()
    if not ok:
        pytest.skip(reason)
    office = EXAMPLES / "office"
    pts = tmp_path / "g.pts"
    pts.write_text("\n".join((office / "grid.pts").read_text().splitlines()[1::6]) + "\n")
    out, shot = tmp_path / "df.csv", tmp_path / "df.png"
    assert run(["daylight-factor", office / "scene.toml", "--points", pts, "-o", out, "--view3d", shot, "-q",
                "--preset", "draft", "--bounces", "2"], capsys)[0] == 0
    assert shot.stat().st_size > 10000
    view = tmp_path / "view.png"
    code, _, err = run(["view", office / "scene.toml", "--results", out, "--screenshot", view], capsys)
    assert code == 0 and "view: 13 points" in err and view.stat().st_size > 10000
    code, _, err = run(["view", office / "scene.toml", "--results", tmp_path / "r.txt", "--screenshot", view], capsys)
    assert code == 2 and "no positions" in err


def test_help_of_the_new_commands(capsys):
    for command, words in (("grid", ("--height", "--spacing", "--margin", "--surface", "EN 12464-1")),
                           ("daylight-factor", ("--sky-illuminance", "--accuracy", "--thresholds", "--plot",
                                                "--view3d", "presets")),
                           ("view", ("--results", "--screenshot"))):
        with pytest.raises(SystemExit) as exit_:
            main([command, "--help"])
        out = capsys.readouterr().out
        assert exit_.value.code == 0 and all(w in out for w in words), (command, out)


def test_validate_help_names_every_study():
    from lbl_illum.cli.main import _STUDY_HELP
    from lbl_illum_studies import STUDIES

    listed = [line.split()[0] for line in _STUDY_HELP.splitlines()[1:] if line.strip()]
    assert listed == list(STUDIES)


def test_help_imports_neither_numba_nor_the_engine():
    """``lbl-illum --help`` and every command's ``--help`` build the parser without
    importing numba, Embree or the engine (they cost most of a second): checked in a
    fresh interpreter, whose modules are its own."""
    import subprocess
    import sys

    code = ("import sys\nfrom lbl_illum.cli.main import main\n"
            "for argv in (['--help'], ['illuminance', '--help'], ['render', '--help'], ['validate', '--help']):\n"
            "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
            "heavy = sorted(m for m in sys.modules if m.split('.')[0] in ('numba', 'embreex', 'trimesh', 'colour')"
            " or m.startswith('lbl_illum.engine'))\n"
            "print(heavy, file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stderr.strip() == "[]"


def test_no_summary_file_unless_asked(sphere_job, capsys):
    """A run writes OUT and nothing beside it unless --summary (or --stats, --plot ...) asks."""
    tmp, pts = sphere_job
    out = tmp / "alone" / "df.csv"
    out.parent.mkdir()
    code, _, err = run(["daylight-factor", SPHERE / "scene.toml", "--points", pts, "-o", out] + FAST, capsys)
    assert code == 0, err
    assert sorted(p.name for p in out.parent.iterdir()) == ["df.csv"]


def test_defaults_in_help_and_user_guide_are_the_code_s(capsys):
    """The defaults --help prints and the user guide's option table states are what a run
    without settings uses: the default preset's values (options.PRESETS), the rest
    Options()'s."""
    import re

    from lbl_illum.options import DEFAULT_PRESET, PRESETS

    d = Options().with_preset(DEFAULT_PRESET)
    expected = {"--preset": DEFAULT_PRESET, "--accuracy": f"{d.accuracy:g}", "--bounces": str(d.bounces),
                "--samples": str(d.samples), "--point-samples": str(d.point_samples), "--ambient": f"{d.ambient:g}",
                "--seed": str(d.seed), "--interpolation": d.interpolation}
    assert {k: PRESETS[DEFAULT_PRESET][k] for k in ("accuracy", "samples", "bounces", "point_samples",
                                                     "interpolation")} == {
        "accuracy": d.accuracy, "samples": d.samples, "bounces": d.bounces, "point_samples": d.point_samples,
        "interpolation": d.interpolation}
    with pytest.raises(SystemExit):
        main(["illuminance", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    entries = {chunk.split()[0]: chunk for chunk in re.split(r" (?=--[a-z])", text.split("quality:", 1)[1])}
    for option, value in expected.items():
        assert re.search(r"default " + re.escape(value) + r"\b", entries[option]), (option, value, entries[option])
    guide = (Path(__file__).resolve().parents[2] / "docs" / "user-guide.md").read_text()
    for option, value in expected.items():
        row = re.search(r"^\| `" + re.escape(option) + r"[ `][^|]*\| ([^|]+) \|", guide, flags=re.M)
        assert row and row.group(1).strip() == value, (option, row and row.group(1))


def test_validate_never_replaces_a_report_without_force(tmp_path, capsys, monkeypatch, no_radiance):
    """An existing DIR/NAME/report.md is refused before any work (one line, exit 2,
    nothing changed); --force replaces it; without --report the reports go to
    ./lbl-illum-reports."""
    pytest.importorskip("matplotlib")
    from lbl_illum.cli.main import _studies

    studies = _studies()
    ran = []

    def fake_run(name, ctx, report_dir, command_dir=None):
        ran.append((name, str(report_dir)))
        folder = Path(report_dir) / name
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "report.md").write_text("# new\n")
        return folder

    monkeypatch.setattr(studies, "run_study", fake_run)
    kept = tmp_path / "reports" / "extremes" / "report.md"
    kept.parent.mkdir(parents=True)
    kept.write_text("# committed\n")
    code, _, err = run(["validate", "extremes", "--quick", "--report", tmp_path / "reports"], capsys)
    assert code == 2 and err.strip() == (f"lbl-illum: error: {kept.parent}: a report is there already; "
                                         "give --force to replace it, or another --report folder")
    assert kept.read_text() == "# committed\n" and ran == []
    code, _, err = run(["validate", "extremes", "--quick", "--report", tmp_path / "reports", "--force"], capsys)
    assert code == 0 and kept.read_text() == "# new\n"
    monkeypatch.chdir(tmp_path)
    code, _, err = run(["validate", "extremes", "--quick"], capsys)
    assert code == 0 and ran[-1] == ("extremes", "lbl-illum-reports")
    assert (tmp_path / "lbl-illum-reports" / "extremes" / "report.md").is_file()


@pytest.mark.parametrize("args, expect", [
    (["--plot-title", "Level 2"], "--plot-title, --plot-scale and --plot-range go with --plot PLAN"),
    (["--plot", "plan.png", "--plot-range", "500", "100"], "--plot-range: MIN must be below MAX"),
    (["--plot", "plan.png", "--plot-scale", "log", "--plot-range", "0", "100"], "a log scale needs MIN above 0"),
])
def test_plan_options_checked_before_any_work(sphere_job, capsys, args, expect):
    tmp, pts = sphere_job
    out = tmp / "df.csv"
    code, _, err = run(["daylight-factor", SPHERE / "scene.toml", "--points", pts, "-o", out] + FAST + args, capsys)
    assert code == 2 and expect in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def _sub_help(parser, command: str) -> str:
    """The help text of ``command``'s sub-parser (and of its own sub-commands)."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    texts = [sub.format_help()]
    for action in sub._actions:
        if isinstance(action, argparse._SubParsersAction):
            texts += [p.format_help() for p in action.choices.values()]
    return "\n".join(texts)


def test_a_command_line_builds_only_its_commands_parser_and_the_same_one():
    """main() builds the parser of the command it is given alone (the others' modules are
    not imported); its options and help are those of the whole parser's."""
    from lbl_illum.cli.main import COMMANDS, _build_parser

    whole = _build_parser()
    choices = next(a for a in whole._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert tuple(choices) == COMMANDS
    for command in COMMANDS:
        alone = _build_parser(command)
        assert list(next(a for a in alone._actions if isinstance(a, argparse._SubParsersAction)).choices) == [command]
        assert _sub_help(alone, command) == _sub_help(whole, command)
    code = ("import sys; from lbl_illum.cli.main import _build_parser; _build_parser('illuminance'); "
            "print(sorted(m for m in ('lbl_illum.cli.render', 'lbl_illum.cli.glare', 'lbl_illum.cli.batch', "
            "'lbl_illum_studies') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
