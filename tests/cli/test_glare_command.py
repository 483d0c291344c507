"""``lbl-illum glare`` and ``render --glare``: one line on the terminal, the JSON written
whole, bad input refused in one line (exit 2) before anything is written."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from lbl_illum.cli.main import main
from lbl_illum.io.images import hdr_bytes, write_hdr
from lbl_illum.scene.views import view_from_string

from test_render_command import ROOM_TOML

FISHEYE = "-vta -vp 0 0 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180"


@pytest.fixture
def image(tmp_path):
    """A 120-pixel fisheye: 200 cd/m² everywhere and a 10,000 cd/m² disc 30° up and to the right."""
    from lbl_illum.glare.metrics import fisheye_geometry

    view = view_from_string(FISHEYE)
    g = fisheye_geometry(view, 120, 120)
    centre = math.cos(math.radians(30)) * view.unit_direction + math.sin(math.radians(30)) * (
        math.sqrt(0.5) * view.right + math.sqrt(0.5) * view.image_up)
    L = np.full((120, 120), 200.0)
    L[g.directions @ centre >= math.cos(math.radians(6))] = 10000.0
    path = tmp_path / "eye.hdr"
    write_hdr(path, np.repeat(L[..., None], 3, axis=-1), view=view)
    return path


def test_glare_prints_one_line_and_writes_the_json_whole(image, tmp_path, capsys):
    out = tmp_path / "glare.json"
    assert main(["glare", str(image), "--json", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 1
    line = lines[0]
    assert line.startswith("lbl-illum: glare eye.hdr: DGP 0.") and "Ev " in line and "1 glare source" in line
    assert "EN 17037 high" in line and line.endswith(f"-> {out}")
    doc = json.loads(out.read_text())
    assert doc["command"] == "glare" and doc["image"] == str(image)
    assert 0 < doc["dgp"] < 1 and doc["ev"] > 200 * math.pi * 0.99
    assert doc["en17037"]["class"] == "high" and doc["en17037"]["limits"] == {"high": 0.35, "medium": 0.4,
                                                                                "minimum": 0.45}
    [source] = doc["sources"]
    assert source["luminance"] == pytest.approx(10000.0, rel=0.005)
    assert source["solid_angle"] == pytest.approx(2 * math.pi * (1 - math.cos(math.radians(6))), rel=0.05)
    assert np.linalg.norm(source["direction"]) == pytest.approx(1.0)
    assert source["position_index"] > 1 and source["above_line_of_sight"]
    assert doc["threshold"]["luminance"] == 2000.0 and doc["view"].startswith("-vta")
    for key in ("dgp_uncorrected", "low_light_factor", "dgi", "ugr", "background_luminance", "ev_sources"):
        assert key in doc
    # quiet: the JSON alone; options reach the evaluation
    assert main(["glare", str(image), "-q", "--factor", "3", "--no-low-light", "--json", str(out)]) == 0
    assert capsys.readouterr().out == ""
    doc = json.loads(out.read_text())
    assert doc["dgp"] == doc["dgp_uncorrected"] and doc["threshold"]["rule"].startswith("3 x the average")


def test_glare_view_option_replaces_a_missing_header(tmp_path, capsys):
    path = tmp_path / "bare.hdr"
    write_hdr(path, np.full((40, 40, 3), 100.0))
    assert main(["glare", str(path)]) == 2
    assert "no VIEW= line" in capsys.readouterr().err
    assert main(["glare", str(path), f"--view={FISHEYE}"]) == 0
    line = capsys.readouterr().out      # 100 cd/m² over the hemisphere, within RGBE's rounding
    assert "Ev 315 lux, no glare source above 2,000 cd/m2, DGI -, UGR -" in line


def test_glare_refuses_bad_input_in_one_line_without_writing(image, tmp_path, capsys):
    out = tmp_path / "x.json"
    raw = image.read_bytes()
    (tmp_path / "zero.hdr").write_bytes(raw.replace(b"EXPOSURE=1.000000e+00", b"EXPOSURE=0"))
    write_hdr(tmp_path / "persp.hdr", np.ones((20, 20, 3)), view=view_from_string("-vtv -vd 0 1 0"))
    bad = [[str(tmp_path / "zero.hdr")], [str(tmp_path / "persp.hdr")], [str(tmp_path / "none.hdr")],
           [str(image), "--threshold", "-1"], [str(image), "--threshold", "5", "--factor", "2"],
           [str(image), "--view=-vtv -vh 40"], [str(image), "--task", "0", "0", "10"]]
    for args in bad:
        assert main(["glare", *args, "--json", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("lbl-illum: error:") and "\n" not in err and "Traceback" not in err
    for target in (str(tmp_path / "no" / "x.json"), str(tmp_path / "x.txt")):
        assert main(["glare", str(image), "--json", target]) == 2
    assert not out.exists() and not (tmp_path / "x.txt").exists()


#: The render tests' room with its ceiling lamp at 20,000 cd/m², a glare source from the eye below.
ROOM = ROOM_TOML.replace("luminance = 2000\n", "luminance = 20000\n")


def test_render_glare_reports_in_one_step(tmp_path, capsys):
    (tmp_path / "room.toml").write_text(ROOM)
    out = tmp_path / "eye.hdr"
    report = tmp_path / "eye.json"
    assert main(["render", str(tmp_path / "room.toml"), "--view=-vta -vp 0 -1 1.2 -vd 0 1 0 -vh 180 -vv 180",
                 "-x", "48", "-y", "48", "-o", str(out), "--glare", "--glare-json", str(report), "-q"]) == 0
    assert capsys.readouterr().out == ""                   # -q: the JSON only
    doc = json.loads(report.read_text())
    assert doc["command"] == "render --glare" and len(doc["sources"]) == 1 and doc["dgp"] > 0.16
    assert main(["render", str(tmp_path / "room.toml"), "--view=-vta -vp 0 -1 1.2 -vd 0 1 0 -vh 180 -vv 180",
                 "-x", "48", "-y", "48", "-o", str(out), "--glare"]) == 0
    [line] = capsys.readouterr().out.strip().splitlines()
    assert line.startswith("lbl-illum: glare eye.hdr: DGP ") and "1 glare source" in line
    # the same figures from the file (RGBE rounds each pixel by at most 0.4 %)
    assert main(["glare", str(out), "--json", str(tmp_path / "file.json"), "-q"]) == 0
    again = json.loads((tmp_path / "file.json").read_text())
    assert again["dgp"] == pytest.approx(doc["dgp"], abs=0.005) and again["ev"] == pytest.approx(doc["ev"], rel=0.005)


def test_render_glare_refuses_a_view_that_is_not_a_fisheye_before_rendering(tmp_path, capsys):
    (tmp_path / "room.toml").write_text(ROOM)
    for extra in (["--glare"], ["--glare-json", str(tmp_path / "g.json")]):
        assert main(["render", str(tmp_path / "room.toml"), "--view=-vtv -vp 0 -1 1.2 -vd 0 1 0", "-x", "16",
                     "-y", "16", "-o", str(tmp_path / "v.hdr"), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert "not a fisheye" in err and "\n" not in err
    assert main(["render", str(tmp_path / "room.toml"), "--view=-vta -vd 0 1 0", "-o", str(tmp_path / "v.hdr"),
                 "--glare-json", str(tmp_path / "no" / "g.json")]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["room.toml"]


def test_glare_help_imports_neither_numba_nor_the_engine():
    """The glare command's parser (built for every command) leaves numba to the first grouping."""
    import subprocess
    import sys

    code = ("import sys\nfrom lbl_illum.cli.main import main\n"
            "try:\n    main(['glare', '--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numba', 'embreex', 'trimesh')"
            " or m.startswith('lbl_illum.engine')), file=sys.stderr)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stderr.strip() == "[]" and "--threshold" in proc.stdout
