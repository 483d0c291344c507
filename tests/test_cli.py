"""The command line: outputs, summaries, cache reuse, and bad input (one line, exit 2, no output)."""

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from lbl_illum.cli import main
from lbl_illum.options import PRESETS

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
    args = ["illuminance", office / "scene.toml", "--points", pts, "--samples", "128", "--bounces", "2",
            "--cache", tmp_path / "c.lblcache"]
    assert run(args + ["-o", tmp_path / "a.csv", "--stats", tmp_path / "a.json"], capsys)[0] == 0
    assert run(args + ["-o", tmp_path / "b.csv", "--stats", tmp_path / "b.json"], capsys)[0] == 0
    a, b = (json.loads((tmp_path / f"{n}.json").read_text()) for n in "ab")
    assert a["primary_evaluations"] > 0 and b["primary_evaluations"] == 0
    assert b["records"] == a["records"]
    for key in ("records", "primary_evaluations", "cache_hits", "rays", "seconds", "settings"):
        assert key in a
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()
    # the same cache with other settings is refused, and no output is written
    code, _, err = run(args[:-4] + ["--samples", "256", "--bounces", "2", "--cache", tmp_path / "c.lblcache",
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


def test_help_lists_presets_and_studies(capsys):
    with pytest.raises(SystemExit):
        main(["illuminance", "--help"])
    out = capsys.readouterr().out
    assert "presets (accuracy / samples / bounces" in out and "medium" in out
    with pytest.raises(SystemExit):
        main(["validate", "--help"])
    out = capsys.readouterr().out
    assert "sphere-plane" in out and "--quick" in out
