"""The pure parts of validation/bench/compare_radiance.py: Pareto fronts, time at equal
error (log-log interpolation), the ratio verdicts, parsing of ``rad``, ``lookamb`` and
worker output, the ladders and the run table; for the accuracy corpus the case names,
its ladders, the report, and one cheap whole command (and one cheap Radiance run, when
Radiance is installed) on a tiny scene.  Nothing here runs a benchmark."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
PATH = ROOT / "validation" / "bench" / "compare_radiance.py"


def _load():
    spec = importlib.util.spec_from_file_location("compare_radiance", PATH)
    module = importlib.util.module_from_spec(spec)
    sys.modules["compare_radiance"] = module
    spec.loader.exec_module(module)
    return module


cr = _load()


# -- Pareto front ---------------------------------------------------------------------
def test_pareto_front_keeps_runs_no_faster_run_beats():
    seconds = [1.0, 2.0, 3.0, 4.0, 5.0, 2.5]
    errors = [0.10, 0.12, 0.05, 0.06, 0.01, 0.05]
    # 2.0 s is beaten by 1.0 s; 3.0 s ties the error of 2.5 s, which is faster; 4.0 s is beaten
    assert cr.pareto_front(seconds, errors) == [0, 5, 4]


def test_pareto_front_drops_missing_and_non_finite():
    seconds = [1.0, None, 2.0, math.nan, 3.0]
    errors = [0.1, 0.01, math.inf, 0.001, 0.05]
    assert cr.pareto_front(seconds, errors) == [0, 4]
    assert cr.pareto_front([], []) == []


# -- time at equal error ----------------------------------------------------------------
def test_time_at_error_is_exact_for_a_power_law():
    """On a front lying on t = c e^-2 the log-log interpolation returns c e^-2 exactly."""
    c = 0.5
    errs = [0.08, 0.03, 0.011, 0.004]
    front = [(c * e ** -2, e) for e in errs]
    for level in (0.05, 0.02, 0.01, 0.005, 0.03):
        seconds, kind = cr.time_at_error(front, level)
        assert kind == "interpolated"
        assert seconds == pytest.approx(c * level ** -2, rel=1e-12)


def test_time_at_error_linear_in_log_log_between_two_runs():
    front = [(1.0, 0.04), (16.0, 0.01)]       # log t rises by log 16 over log e falling by log 4
    seconds, kind = cr.time_at_error(front, 0.02)
    assert kind == "interpolated"
    assert seconds == pytest.approx(4.0, rel=1e-12)   # halfway in log e -> halfway in log t


def test_time_at_error_bounds_and_not_reached():
    front = [(2.0, 0.03), (10.0, 0.012)]
    assert cr.time_at_error(front, 0.05) == (2.0, "at most")
    assert cr.time_at_error(front, 0.01) == (None, "not reached")
    assert cr.time_at_error(front, 0.012) == (10.0, "interpolated")
    assert cr.time_at_error(front, 0.03) == (2.0, "interpolated")
    assert cr.time_at_error([], 0.02) == (None, "no runs")
    assert cr.time_at_error([(3.0, 0.02)], 0.02) == (3.0, "interpolated")


# -- ratio at equal error ----------------------------------------------------------------
def test_compare_at_interpolated_ratio_and_verdict():
    ours = [(1.0, 0.04), (16.0, 0.01)]
    theirs = [(10.0, 0.04), (160.0, 0.01)]
    c = cr.compare_at(ours, theirs, 0.02)
    assert c["ratio"] == pytest.approx(0.1) and c["relation"] == "=" and c["verdict"] == "met"
    c = cr.compare_at(theirs, ours, 0.02)
    assert c["ratio"] == pytest.approx(10.0) and c["verdict"] == "missed"


def test_compare_at_bounds_not_reached_and_undetermined():
    fast_and_good = [(1.0, 0.004)]                   # already within every level
    radiance = [(10.0, 0.06), (100.0, 0.015)]
    c = cr.compare_at(fast_and_good, radiance, 0.02)
    assert c["relation"] == "≤" and c["ratio"] < 0.5 and c["verdict"] == "met"
    assert cr.ratio_text(c).startswith("≤ ")
    c = cr.compare_at(fast_and_good, radiance, 0.01)          # Radiance never gets to 1 %
    assert c["verdict"] == "n/a" and c["ratio"] is None
    assert cr.ratio_text(c) == "Radiance not reached"
    c = cr.compare_at([(1.0, 0.05)], radiance, 0.02)          # we never get to 2 %
    assert c["verdict"] == "missed" and cr.ratio_text(c) == "lbl_illum not reached"
    c = cr.compare_at(radiance, [(1.0, 0.004)], 0.02)         # Radiance's time an upper bound
    assert c["relation"] == "≥" and c["verdict"] == "missed"
    c = cr.compare_at([(1.0, 0.004)], [(5.0, 0.003)], 0.02)   # both bounds: nothing decided
    assert c["relation"] is None and c["verdict"] == "undetermined"
    assert cr.short_ratio(c) == "?"


# -- parsing ----------------------------------------------------------------------------
RAD_OUTPUT = """\
DETAIL=medium
QUALITY=MEDIUM
ZONE= I 0 4 0 6 0 3
\toconv materials.rad sky.rad geometry.rad > scene.oct
\trpict -vtv -vp 3.8 3 1.5 -vd -4 0 0 -vu 0 0 1 -vh 45 -vv 45 -x 1024 -y 1024 -dp 512 -ar 44 -ms 0.11 \
-ds .3 -dt .07 -dc .7 -dr 1 -ss 1 -st .1 -ab 2 -aa .1 -ad 1536 -as 392 -av 0.01 0.01 0.01 -lr 8 -lw 1e-4 \
-ps 6 -pt .08 scene.oct > scene_X.unf
\tpfilt -r .6 -x /2 -y /2 scene_X.unf > scene_X.hdr
"""


def test_rad_rtrace_options_keeps_rendering_options_only():
    args = cr.rad_rtrace_options(RAD_OUTPUT)
    assert args == ["-dp", "512", "-ar", "44", "-ms", "0.11", "-ds", ".3", "-dt", ".07", "-dc", ".7", "-dr", "1",
                    "-ss", "1", "-st", ".1", "-ab", "2", "-aa", ".1", "-ad", "1536", "-as", "392",
                    "-av", "0.01", "0.01", "0.01", "-lr", "8", "-lw", "1e-4"]


def test_rad_rtrace_options_errors():
    with pytest.raises(ValueError, match="no rpict"):
        cr.rad_rtrace_options("QUALITY=LOW\n\toconv a.rad > a.oct\n")
    with pytest.raises(ValueError, match="unknown rpict option '-zz'"):
        cr.rad_rtrace_options("\trpict -zz 3 -ab 1 scene.oct > x.unf\n")
    with pytest.raises(ValueError, match="lacks"):
        cr.rad_rtrace_options("\trpict -ab 1 -av 0.1 0.1 scene.oct\n")


def test_rif_text_names_zone_and_quality():
    text = cr.rif_text((0, 4, 0, 6, 0, 3), ["a.rad", "b.rad"], "scene.oct", "HIGH", 5)
    assert "ZONE= I 0 4 0 6 0 3\n" in text and "scene= a.rad b.rad\n" in text
    assert "QUALITY= HIGH\n" in text and "INDIRECT= 5\n" in text and "OCTREE= scene.oct\n" in text


def test_count_ambient_records_and_worker_output():
    assert cr.count_ambient_records("1 2 3\n\n4 5 6\n   \n7 8 9\n") == 3
    assert cr.count_ambient_records("") == 0
    doc = cr.parse_worker_output('warning: x\n{"seconds": 1.5, "rays": 10, "records": [3, 4]}\n\n')
    assert doc["seconds"] == 1.5 and doc["records"] == [3, 4]
    with pytest.raises(ValueError, match="lacks rays"):
        cr.parse_worker_output('{"seconds": 1, "records": []}')
    with pytest.raises(ValueError, match="nothing"):
        cr.parse_worker_output("\n")


def test_parse_scenes():
    assert cr.parse_scenes("office, furnished,office") == ["office", "furnished"]
    with pytest.raises(ValueError, match="unknown scene 'kitchen'"):
        cr.parse_scenes("office,kitchen")
    with pytest.raises(ValueError, match="no scene"):
        cr.parse_scenes(" , ")


# -- ladders and settings -----------------------------------------------------------------
def test_ambient_resolution_matches_rads_rule():
    # rad (DETAIL=medium, QUALITY=MEDIUM): ar = 32 * cube / mean zone side
    assert cr.ambient_resolution(32, cube=6.0, zone_size=(4 + 6 + 3) / 3) == 44
    assert cr.ambient_resolution(8, cube=1.0, zone_size=1000.0) == 1


def test_sphere_plane_ladders_follow_one_reflection():
    ours = cr.engine_ladder("sphere-plane")
    assert ours and all(s.options["bounces"] == 1 for s in ours)
    theirs = cr.radiance_ladder("sphere-plane", cube=10000.0, zone_size=2.0)
    assert theirs and all(cr._arg(s.args, "-ab") == "1" for s in theirs)
    assert len({s.key for s in ours + theirs}) == len(ours + theirs)


def test_office_ladders_include_presets_and_monte_carlo():
    ours = cr.engine_ladder("office")
    families = {s.family for s in ours}
    assert {"preset", "a × samples", "Monte Carlo", "paper interpolation"} <= families
    assert len({s.key for s in ours}) == len(ours)
    theirs = cr.radiance_ladder("office", cube=200.0, zone_size=13 / 3)
    pure = [s for s in theirs if cr._arg(s.args, "-aa") == "0"]
    assert pure and all("-as" not in s.args and "-af" not in s.args for s in pure)
    assert all(cr._arg(s.args, "-lw") == cr.LIMIT_WEIGHT for s in theirs)


def test_quick_ladders_are_tiny():
    for kind in ("office", "furnished", "sphere-plane"):
        assert 2 <= len(cr.engine_ladder(kind, quick=True)) <= 3
        assert 2 <= len(cr.radiance_ladder(kind, cube=200.0, zone_size=4.0, quick=True)) + \
            len(cr.QUICK_RAD_PRESETS if cr.RAD_PRESETS[kind] else []) <= 3


def test_run_order_alternates_the_programs():
    settings = cr.engine_ladder("office", quick=True) + cr.radiance_ladder("office", 200.0, 4.0, quick=True)
    order = cr.run_order(settings)
    assert sorted(order) == list(range(len(settings)))
    programs = [settings[k].program for k in order]
    assert programs[:4] == ["lbl_illum", "radiance", "lbl_illum", "radiance"]


def test_warmup_options_are_cheap_and_of_the_same_kind():
    full = cr.engine_options("medium")
    warm = cr.warmup_options(full)
    assert warm["samples"] <= 64 and warm["bounces"] <= 2 and warm["point_samples"] <= 64
    assert warm["accuracy"] >= 0.3 and warm["interpolation"] == full["interpolation"]
    pure = cr.warmup_options(cr.engine_options(accuracy=0.0, samples=4096))
    assert pure["accuracy"] == 0.0 and pure["samples"] == 64


def test_room_zone_leaves_out_the_ground():
    room = np.array([[[0, 0, 0], [4, 0, 0], [4, 6, 3]], [[0, 6, 3], [4, 6, 0], [0, 0, 3]]], float)
    ground = np.array([[[-100, -100, 0], [100, -100, 0], [100, 100, 0]]], float)
    tri = SimpleNamespace(vertices=np.concatenate([room, ground]))
    points = np.array([[0.5, 0.5, 0.8], [3.5, 5.5, 0.8]])
    assert cr.room_zone(tri, points) == (0.0, 4.0, 0.0, 6.0, 0.0, 3.0)


# -- the run table ------------------------------------------------------------------------------
def test_run_table_rows_and_front_marks():
    runs = [
        {"program": "lbl_illum", "family": "preset", "label": "preset draft", "seconds": 1.0, "process_seconds": 3.0,
         "maxrss_kib": 2048, "mean_error": 0.02, "max_error": 0.05, "bias": 0.01, "records": 4710, "rays": 403139},
        {"program": "lbl_illum", "family": "preset", "label": "preset high", "seconds": 5.0, "process_seconds": 7.0,
         "maxrss_kib": 4096, "mean_error": 0.03, "max_error": 0.05, "bias": 0.01, "records": 1, "rays": 2},
        {"program": "radiance", "family": "-aa × -ad", "label": "-ab 8", "seconds": 2.0, "process_seconds": 2.0,
         "maxrss_kib": 1024, "mean_error": 0.01, "max_error": 0.04, "bias": -0.002, "records": 99, "rays": None},
        {"program": "radiance", "family": "-ab", "label": "-ab 5", "failed": True},
    ]
    assert cr.front_pairs(runs, "lbl_illum") == [(1.0, 0.02)]
    assert cr.front_pairs(runs, "radiance") == [(2.0, 0.01)]
    header, rows = cr.run_table(runs)
    assert len(rows) == 4 and all(len(r) == len(header) for r in rows)
    assert rows[0][header.index("mean error")] == "2.00 %"
    assert rows[0][header.index("peak MiB")] == "2"
    assert rows[0][header.index("front")] == "★" and rows[1][header.index("front")] == ""
    assert rows[2][header.index("rays")] == "—" and rows[2][header.index("bias")] == "-0.20 %"
    assert rows[3][header.index("seconds")] == "failed"


# -- measuring a child --------------------------------------------------------------------------
def test_run_measured_reads_the_childs_peak_memory():
    """A child that touches 64 MiB reports a peak resident set of at least that."""
    code = "import sys; b = bytearray(64 * 1024 * 1024); b[::4096] = b'x' * len(b[::4096]); print('ok')"
    m = cr.run_measured([sys.executable, "-c", code], timeout=60)
    assert m.returncode == 0 and m.stdout.strip() == b"ok"
    assert m.maxrss_kib >= 64 * 1024
    assert m.seconds > 0
    bad = cr.run_measured([sys.executable, "-c", "import sys; sys.exit(3)"], timeout=60)
    assert bad.returncode == 3


def test_run_measured_does_not_count_this_process_memory(tmp_path):
    """Linux adds the memory of the image an exec replaces to the child's ru_maxrss: a
    small child of a process holding 256 MiB must still report a small peak."""
    ballast = bytearray(256 * 1024 * 1024)
    ballast[::4096] = b"x" * len(ballast[::4096])
    out = tmp_path / "out.txt"
    m = cr.run_measured([sys.executable, "-S", "-c", "print(6 * 7)"], cwd=tmp_path, stdout_path=out, timeout=60)
    assert m.returncode == 0 and out.read_text().strip() == "42" and m.stdout == b""
    assert m.maxrss_kib < 64 * 1024
    del ballast


def test_run_measured_stops_a_run_past_its_limits():
    m = cr.run_measured([sys.executable, "-S", "-c", "import time; time.sleep(30)"], timeout=0.3)
    assert m.returncode < 0 and m.seconds < 10 and m.stopped == "timeout"
    assert cr.failure(m) == "stopped: over the time limit"
    hog = "import time; b = bytearray(200 * 1024 * 1024); b[::4096] = b'x' * len(b[::4096]); time.sleep(30)"
    m = cr.run_measured([sys.executable, "-S", "-c", hog], timeout=20, memory_gib=0.1)
    assert m.returncode < 0 and m.seconds < 10 and m.stopped == "memory"


@pytest.mark.skipif(importlib.util.find_spec("pyradiance") is None, reason="needs pyradiance (Radiance programs)")
def test_rad_presets_on_the_office(tmp_path):
    """rad's MEDIUM options for the office: -ab INDIRECT, its -aa/-ad, and an -ar
    from the zone and the octree's cube (32 · cube / zone for DETAIL=medium)."""
    import subprocess

    from lbl_illum import load_scene, read_points
    from lbl_illum.io.radiance import export_radiance, radiance_programs

    scene = load_scene(ROOT / "examples" / "office" / "scene.toml")
    points, normals = read_points(ROOT / "examples" / "office" / "grid.pts", scene.unit_scale)
    ex = export_radiance(scene, tmp_path / "office", points, normals, glass="brtdfunc")
    programs = radiance_programs(ex.directory)
    with open(ex.directory / ex.octree, "wb") as out:
        subprocess.run(cr._program(ex.oconv_command(), programs), cwd=ex.directory, env=programs["env"],
                       stdout=out, check=True)
    zone = cr.room_zone(scene.triangles, points)
    (medium,) = cr.rad_settings(programs, ex, zone, [("MEDIUM", 3)])
    assert cr._arg(medium.args, "-ab") == "3"
    assert cr._arg(medium.args, "-aa") is not None and cr._arg(medium.args, "-ad") is not None
    info = subprocess.run([str(programs["bin"]["getinfo"]), "-d", ex.octree], cwd=ex.directory,
                          env=programs["env"], capture_output=True, text=True, check=True).stdout
    cube = float(info.split()[-1])
    assert int(cr._arg(medium.args, "-ar")) == cr.ambient_resolution(32, cube, 13 / 3)


# -- the accuracy corpus --------------------------------------------------------------------------
def test_parse_scenes_corpus_cases():
    from lbl_illum_studies import corpus_scenes

    every = cr.parse_scenes("corpus")
    assert len(every) == len(corpus_scenes.SCENES) * len(corpus_scenes.SKIES)
    assert every[0] == "corpus:office-overcast" and all(cr.is_corpus(n) for n in every)
    assert cr.parse_scenes("corpus:lbnl-open-office-overcast, corpus:cabin-sunny") == \
        ["corpus:lbnl-open-office-overcast", "corpus:cabin-sunny"]
    # a scene name gives both skies; names with hyphens are told apart from NAME-SKY
    assert cr.parse_scenes("corpus:deep-room-opening") == ["corpus:deep-room-opening-overcast",
                                                            "corpus:deep-room-opening-sunny"]
    assert cr.parse_scenes("office,corpus:cabin-sunny,corpus:cabin,office") == \
        ["office", "corpus:cabin-sunny", "corpus:cabin-overcast"]
    assert not cr.is_corpus("office")
    scene, sky = cr.corpus_case("deep-room-overcast")
    assert scene.name == "deep-room" and sky == "overcast"
    with pytest.raises(ValueError, match="unknown corpus case 'cabin-rainy'"):
        cr.parse_scenes("corpus:cabin-rainy")
    with pytest.raises(ValueError, match="unknown scene 'corpus-cabin'"):
        cr.parse_scenes("corpus-cabin")


def test_parse_args_takes_corpus_cases():
    args = cr.parse_args(["--scenes", "corpus:deep-room-overcast", "--quick", "--run-timeout", "60"])
    assert args.scene_list == ["corpus:deep-room-overcast"] and args.run_timeout == 60.0
    with pytest.raises(SystemExit):
        cr.parse_args(["--scenes", "corpus:nowhere-sunny"])


def test_corpus_ladders():
    ours = cr.corpus_engine_ladder()
    assert [s.label for s in ours if s.family == "preset"] == [f"preset {p}" for p in ("draft", "low", "medium",
                                                                                       "high")]
    assert all(s.program == "lbl_illum" and s.args and not s.options for s in ours)
    assert 8 <= len(ours) <= 10 and len({s.key for s in ours}) == len(ours)
    pure = [s for s in ours if s.family == "Monte Carlo"]
    assert pure[0].args == ["--accuracy", "0", "--samples", "1024", "--point-samples", "0", "--bounces", "10"]
    # Monte Carlo at the samples of Radiance's -aa 0 runs (checked below: 1024, 4096, 16384)
    assert [cr._arg(s.args, "--samples") for s in pure] == ["1024", "4096", "16384"]
    assert 1 <= len(cr.corpus_engine_ladder(quick=True)) <= 2
    from lbl_illum.options import PRESETS

    assert {p["bounces"] for p in PRESETS.values()} == {cr.CORPUS_BOUNCES}
    cube, zone = 120.0, (4 + 12 + 3) / 3
    theirs = cr.radiance_ladder(cr.CORPUS, cube=cube, zone_size=zone)
    assert all(cr._arg(s.args, "-ab") == "11" and cr._arg(s.args, "-lw") == cr.LIMIT_WEIGHT for s in theirs)
    cached = [s for s in theirs if cr._arg(s.args, "-aa") != "0"]
    assert [(float(cr._arg(s.args, "-aa")), int(cr._arg(s.args, "-ad"))) for s in cached] == \
        [(0.2, 512), (0.1, 1024), (0.1, 2048), (0.05, 2048), (0.05, 4096)]
    assert all(int(cr._arg(s.args, "-as")) == int(cr._arg(s.args, "-ad")) // 2 for s in cached)
    assert all(int(cr._arg(s.args, "-ar")) == cr.ambient_resolution(cr.AR_FACTOR, cube, zone) for s in cached)
    pure = [s for s in theirs if cr._arg(s.args, "-aa") == "0"]
    assert [(cr._arg(s.args, "-ad"), cr._arg(s.args, "-as")) for s in pure] == \
        [("1024", None), ("4096", None), ("16384", None), ("1024", "0"), ("4096", "0"), ("16384", "0")]
    assert all("-ar" not in s.args for s in pure)
    assert 1 <= len(cr.radiance_ladder(cr.CORPUS, cube=cube, zone_size=zone, quick=True)) <= 2


def test_engine_command_is_what_a_user_types(tmp_path):
    cmd = cr.engine_command(Path("s.toml"), Path("g.pts"), Path("o.csv"), Path("st.json"), ["--preset", "low"])
    assert cmd[:3] == [sys.executable, "-m", "lbl_illum"]
    assert cmd[3:] == ["illuminance", "s.toml", "--points", "g.pts", "-o", "o.csv", "--preset", "low",
                       "--stats", "st.json", "-q"]
    path = tmp_path / "out.csv"
    path.write_text("x,y,z,nx,ny,nz,illuminance,direct,indirect,area\n1,1,0.8,0,0,1,101.5,1,100.5,floor\n"
                    "2,1,0.8,0,0,1,7.25,0,7.25,\n")
    assert cr.read_illuminance_csv(path).tolist() == [101.5, 7.25]
    path.write_text("x,y,z,nx,ny,nz,illuminance,direct,indirect\n1,1,0.8,0,0,1,3,1,2\n")
    assert cr.read_illuminance_csv(path).tolist() == [3.0]
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="no 'illuminance' column"):
        cr.read_illuminance_csv(path)


def test_case_verdict():
    def c(verdict):
        return {"verdict": verdict}

    assert cr.case_verdict([c("met"), c("met"), c("n/a")]) == "met"
    assert cr.case_verdict([c("met"), c("missed"), c("undetermined")]) == "missed"
    assert cr.case_verdict([c("met"), c("undetermined"), c("n/a")]) == "undetermined"
    assert cr.case_verdict([c("n/a"), c("n/a")]) == "n/a"


def test_corpus_run_table_shows_both_parts_of_radiances_time():
    runs = [
        {"program": "lbl_illum", "family": "preset", "label": "preset draft", "seconds": 3.0, "process_seconds": 3.0,
         "compute_seconds": 1.5, "maxrss_kib": 204800, "mean_error": 0.02, "max_error": 0.05, "bias": 0.01,
         "records": 9047, "rays": 491342},
        {"program": "radiance", "family": "-aa × -ad", "label": "-ab 9 -aa 0.2", "seconds": 2.5,
         "process_seconds": 2.5, "oconv_seconds": 0.5, "rtrace_seconds": 2.0, "maxrss_kib": 10240,
         "mean_error": 0.07, "max_error": 0.2, "bias": 0.01, "records": 2224, "rays": None},
        {"program": "radiance", "family": "-aa 0 (Monte Carlo)", "label": "-aa 0", "failed": True,
         "error": "stopped: over the time limit", "elapsed": 60.2},
    ]
    cr.front_pairs(runs, "lbl_illum")
    cr.front_pairs(runs, "radiance")
    header, rows = cr.corpus_run_table(runs)
    assert all(len(r) == len(header) for r in rows)
    assert rows[0][header.index("of which")] == "compute 1.5" and rows[0][header.index("front")] == "★"
    assert rows[1][header.index("of which")] == "oconv 0.5 + rtrace 2"
    assert rows[2][header.index("seconds")] == "stopped (time)" and rows[2][header.index("of which")] == "after 60.2 s"


def test_prepare_corpus_skips_a_case_without_reference(tmp_path, monkeypatch):
    corpus = cr.corpus_module()
    monkeypatch.setattr(corpus, "reference_path", lambda scene, sky: tmp_path / f"{scene.name}-{sky}.json")
    why = cr.prepare_corpus("cabin-sunny")
    assert isinstance(why, str) and "no reference" in why and "cabin-sunny.json" in why


TINY_SCENE = """\
units = "m"

[[geometry]]
shape = "polygon"
vertices = [[-10, -10, 0], [10, -10, 0], [10, 10, 0], [-10, 10, 0]]
material = "ground"

[[geometry]]
shape = "box"
center = [0, 0, 1]
size = [2, 2, 2]
material = "wall"

[materials.ground]
type = "diffuse"
reflectance = 0.2

[materials.wall]
type = "diffuse"
reflectance = 0.5

[sky]
type = "cie-overcast"
horizontal_illuminance = 10000
ground_reflectance = 0.2
"""
TINY_POINTS = "1.5 0 0.5 0 0 1 east\n-1.5 0 0.5 0 0 1 west\n0 1.5 0.5 0 0 1\n0 -1.5 0.5 0 0 1\n"


@pytest.fixture
def tiny_case(tmp_path):
    """A corpus-like case on a 2 m box standing on a ground plane under an overcast sky:
    four sensors beside it, and a made-up reference of 8000 lux each."""
    import json

    (tmp_path / "scene.toml").write_text(TINY_SCENE)
    (tmp_path / "grid.pts").write_text(TINY_POINTS)
    ref = tmp_path / "tiny-overcast.json"
    ref.write_text(json.dumps({"illuminance": [8000.0] * 4, "standard_error": [8.0] * 4,
                               "relative_standard_error": {"mean": 0.001, "max": 0.001}, "seeds": 4,
                               "method": "made up", "estimator": {"point_samples": 16}}))
    bench = cr.corpus_bench("tiny-overcast", "tiny", tmp_path / "scene.toml", tmp_path / "grid.pts", ref,
                            {"role": "choose"})
    return bench, tmp_path


def test_corpus_bench_reads_the_reference(tiny_case, tmp_path):
    bench, folder = tiny_case
    assert bench.kind == cr.CORPUS and bench.reference.tolist() == [8000.0] * 4
    assert bench.reference_info["standard_error_mean"] == 0.001 and bench.reference_info["role"] == "choose"
    assert "made up" in bench.reference_info["method"] and "4 seeds" in bench.reference_info["method"]
    assert bench.zone == (-1.0, 1.0, -1.0, 1.0, 0.0, 2.0)          # the box, not the ground
    bad = folder / "bad.json"
    bad.write_text('{"illuminance": [1, 2]}')
    with pytest.raises(ValueError, match="2 reference values for 4 points"):
        cr.corpus_bench("x", "x", folder / "scene.toml", folder / "grid.pts", bad)
    bad.write_text('{"illuminance": [1, 2')                       # still being written
    with pytest.raises(ValueError, match="unreadable reference"):
        cr.corpus_bench("x", "x", folder / "scene.toml", folder / "grid.pts", bad)


def test_run_command_times_the_whole_command(tiny_case):
    """One cheap preset through the real command: values from its CSV, records and rays
    from its stats, wall time from start to exit (more than the compute time)."""
    bench, folder = tiny_case
    runner = cr.Runner(bench, folder / "build", None, processes=2, timeout=120, memory_gib=4)
    (setting,) = [s for s in cr.corpus_engine_ladder(quick=True) if s.label == "preset draft"]
    row = runner.run_command(setting)
    assert not row.get("failed"), row.get("error")
    assert row["flags"] == ["--preset", "draft"] and "--preset draft" in row["command"]
    assert len(row["illuminance"]) == 4 and all(1000 < v < 10000 for v in row["illuminance"])
    err = np.array(row["illuminance"]) / 8000.0 - 1.0
    assert row["mean_error"] == pytest.approx(np.mean(np.abs(err)), rel=1e-4)
    assert row["bias"] == pytest.approx(np.mean(err), rel=1e-4, abs=1e-6)
    assert row["records"] == sum(row["records_per_level"]) > 0 and row["rays"] > 0
    assert row["settings"]["interpolation"] == "gradients" and row["settings"]["samples"] == 64
    assert row["seconds"] == row["process_seconds"] > row["compute_seconds"] > 0
    assert row["maxrss_kib"] > 10 * 1024
    # a command that fails is a failed row, not an exception
    broken = cr.Setting("lbl_illum", "options", "bad", args=["--accuracy", "-1"])
    bad = runner.run_command(broken)
    assert bad["failed"] and "exit code" in bad["error"]


def test_radiance_time_on_a_corpus_case_adds_oconv(tiny_case):
    from lbl_illum.io.radiance import radiance_programs

    programs = radiance_programs()
    if programs is None:
        pytest.skip("needs Radiance's programs (pyradiance or oconv/rtrace on the PATH)")
    bench, folder = tiny_case
    runner = cr.Runner(bench, folder / "build", programs, processes=1, timeout=120, memory_gib=4)
    setup = runner.prepare_radiance()
    assert setup["oconv_seconds"] > 0 and setup["cube"] > 0
    setting = cr.Setting("radiance", "-aa × -ad", "cheap", args=cr.rtrace_args(0.3, 64, 32, 2, 8))
    row = runner.run_radiance(setting)
    assert not row.get("failed"), row.get("error")
    assert row["oconv_seconds"] == setup["oconv_seconds"] and row["rtrace_seconds"] > 0
    assert row["seconds"] == pytest.approx(row["oconv_seconds"] + row["rtrace_seconds"])
    assert len(row["illuminance"]) == 4 and all(1000 < v < 10000 for v in row["illuminance"])
    assert row["records"] is None or row["records"] > 0


def test_corpus_report_has_a_section_and_a_summary(tiny_case, tmp_path):
    import json

    bench, folder = tiny_case
    runs = [
        {"program": "lbl_illum", "family": "preset", "label": "preset draft", "seconds": 2.0, "process_seconds": 2.0,
         "compute_seconds": 0.5, "maxrss_kib": 204800, "mean_error": 0.015, "max_error": 0.03, "bias": 0.01,
         "records": 100, "rays": 1000},
        {"program": "lbl_illum", "family": "preset", "label": "preset high", "seconds": 8.0, "process_seconds": 8.0,
         "compute_seconds": 6.0, "maxrss_kib": 204800, "mean_error": 0.004, "max_error": 0.01, "bias": 0.001,
         "records": 900, "rays": 9000},
        {"program": "radiance", "family": "-aa × -ad", "label": "-aa 0.2", "seconds": 5.0, "process_seconds": 5.0,
         "oconv_seconds": 0.1, "rtrace_seconds": 4.9, "maxrss_kib": 10240, "mean_error": 0.06, "max_error": 0.1,
         "bias": 0.0, "records": 50, "rays": None},
        {"program": "radiance", "family": "-aa × -ad", "label": "-aa 0.05", "seconds": 50.0,
         "process_seconds": 50.0, "oconv_seconds": 0.1, "rtrace_seconds": 49.9, "maxrss_kib": 10240,
         "mean_error": 0.008, "max_error": 0.03, "bias": 0.0, "records": 500, "rays": None},
    ]
    ours, theirs = cr.front_pairs(runs, "lbl_illum"), cr.front_pairs(runs, "radiance")
    comparison = [cr.compare_at(ours, theirs, e) for e in cr.CORPUS_ERROR_LEVELS]
    res = {"runs": runs, "comparison": {"command": comparison}, "verdict": cr.case_verdict(comparison),
           "radiance_setup": {"version": "RADIANCE test", "export_seconds": 0.1, "oconv_seconds": 0.1, "cube": 20.0,
                              "mesh": False, "ar": 80}}
    assert res["verdict"] == "met"               # 5 %, 2 %: ours ≤ 2 s; 1 %: both interpolated; 0.5 %: n/a
    args = SimpleNamespace(out_display="OUT", scenes_given=True, scenes="corpus:tiny-overcast", quick=False,
                           run_timeout=cr.RUN_TIMEOUT, processes=2, memory_limit=6.0)
    folder_out = cr.write_report(tmp_path / "out", [bench], {bench.name: res}, args, {"bin": {}}, 1.0,
                                 skipped={"cabin-sunny": "no reference yet"})
    assert folder_out.name == cr.CORPUS_NAME
    md = (folder_out / "report.md").read_text()
    assert "| tiny-overcast | choose | 0.10 % |" in md and "| met |" in md
    assert "skipped: no reference yet" in md and "Radiance not reached" in md
    assert "oconv 0.1 + rtrace 4.9" in md and (folder_out / "tiny-overcast-front.png").is_file()
    doc = json.loads((folder_out / "results.json").read_text())["results"]
    assert doc["corpus_verdicts"] == {"tiny-overcast": "met"} and doc["corpus_skipped"] == {"cabin-sunny":
                                                                                              "no reference yet"}
    assert doc["corpus"]["tiny-overcast"]["runs"][0]["compute_seconds"] == 0.5
    assert doc["corpus"]["tiny-overcast"]["scene_file"] == "scene.toml"      # no machine's folders
    assert cr.shown_path(cr.ROOT / "validation" / "corpus") == "validation/corpus"


def test_merge_keeps_the_cases_a_run_does_not_measure(tiny_case, tmp_path, monkeypatch):
    """--merge: a case of the earlier report comes back with its runs and the date it was
    measured; a case measured now replaces the stored one; a changed reference or other
    processes refuse the stored case."""
    import json

    bench, folder = tiny_case
    runs = [{"program": "lbl_illum", "family": "preset", "label": "preset draft", "seconds": 2.0,
             "process_seconds": 2.0, "compute_seconds": 1.0, "maxrss_kib": 1024, "mean_error": 0.015,
             "max_error": 0.03, "bias": 0.01, "records": 1, "rays": 1}]
    res = {"runs": runs, "fronts": {}, "measured": "2026-11-30"}
    args = SimpleNamespace(out_display="OUT", scenes_given=True, scenes="corpus:tiny-overcast", quick=False,
                           run_timeout=cr.RUN_TIMEOUT, processes=2, memory_limit=6.0, merge=False)
    out = cr.write_report(tmp_path / "out", [bench], {bench.name: res}, args, None, 1.0)
    path = out / "results.json"
    monkeypatch.setattr(cr, "prepare_corpus", lambda case: bench if case == "tiny-overcast" else "gone")
    (kept_bench, kept), = cr.merge_corpus_cases(path, args, {}, {})
    assert kept_bench is bench and kept["runs"] == runs and kept["measured"] == "2026-11-30"
    assert "reference_illuminance" not in kept and "title" not in kept
    assert cr.merge_corpus_cases(path, args, {"tiny-overcast": {}}, {}) == []       # measured again now
    assert cr.merge_corpus_cases(tmp_path / "none.json", args, {}, {}) == []
    with pytest.raises(RuntimeError, match="--processes 2 .* this run uses 1"):
        cr.merge_corpus_cases(path, SimpleNamespace(processes=1, run_timeout=cr.RUN_TIMEOUT), {}, {})
    doc = json.loads(path.read_text())
    doc["results"]["corpus"]["tiny-overcast"]["reference_illuminance"][0] = 7999.0
    path.write_text(json.dumps(doc))
    assert cr.merge_corpus_cases(path, args, {}, {}) == []                          # reference changed
    with pytest.raises(SystemExit):
        cr.parse_args(["--scenes", "office", "--merge"])


def test_the_report_command_shows_no_machine_folders(tmp_path):
    """An absolute --out inside a repository shows relative to its root in the report's
    command; other paths show as given."""
    repo = tmp_path / "clone"
    (repo / "docs" / "performance").mkdir(parents=True)
    (repo / "pyproject.toml").write_text("[project]\nname = 'x'\n")
    assert cr.display_path(repo / "docs" / "performance") == Path("docs/performance")
    assert cr.display_path(Path("docs/performance")) == Path("docs/performance")
    outside = tmp_path / "elsewhere"
    assert cr.display_path(outside) == outside
