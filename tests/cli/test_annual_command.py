"""``lbl-illum annual``: a year at the office's sensors into OUTDIR, one summary line, and
bad input refused in one line (exit 2) before anything is written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from lbl_illum.cli.main import main

from conftest import EXAMPLES

WEATHER = EXAMPLES / "weather"
EPW = WEATHER / "USA_CA_Oakland.Intl.AP.724930_TMY3.epw"
WEA = WEATHER / "oakland_tmy3.wea"
SCENE = EXAMPLES / "office" / "scene.toml"
POINTS = EXAMPLES / "office" / "grid.pts"
#: Enough for the files and figures to be checked, in a few seconds.
QUICK = ["--samples", "32", "--point-samples", "256", "--bounces", "2"]



@pytest.fixture(scope="module")
def outdir(tmp_path_factory):
    out = tmp_path_factory.mktemp("annual") / "year"
    code = main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(EPW), "-o", str(out), *QUICK])
    assert code == 0
    return out


def test_writes_every_file(outdir):
    for name in ("illuminance.npy", "direct_sun.npy", "points.csv", "summary.json", "da.png", "sda.png", "ase.png",
                 "day_hour.png"):
        assert (outdir / name).is_file(), name
    E = np.load(outdir / "illuminance.npy")
    D = np.load(outdir / "direct_sun.npy")
    assert E.shape == D.shape == (77, 8760) and E.dtype == D.dtype == np.float32
    assert (E >= D).all() and E.max() > 10_000 and (D > 1000).any()
    rows = (outdir / "points.csv").read_text().splitlines()
    assert rows[0].startswith("x,y,z,DA300,cDA300") and len(rows) == 78


def test_summary_holds_the_metrics_of_the_files(outdir):
    doc = json.loads((outdir / "summary.json").read_text())
    E = np.load(outdir / "illuminance.npy")
    D = np.load(outdir / "direct_sun.npy")
    from lbl_illum.workplane.annual import lm83_occupancy

    occupied = lm83_occupancy() > 0
    da = 100.0 * (E[:, occupied] >= 300.0).mean(axis=1)
    assert doc["overall"]["sda"] == pytest.approx(100.0 * (da >= 50.0).mean())
    ase = ((D[:, occupied] >= 1000.0).sum(axis=1) > 250).mean() * 100.0
    assert doc["overall"]["ase"] == pytest.approx(ase)
    assert doc["occupied_hours"] == 3650
    assert doc["settings"]["samples"] == 32 and doc["settings"]["accuracy"] == 0.12      # draft, then the options
    assert doc["bytes_per_record"] > 0 and doc["sun_positions"] > 40
    assert doc["leed"]["points"] in (0, 1, 2, 3) and "en17037" in doc["overall"]


def test_summary_line(tmp_path, capsys):
    out = tmp_path / "wea"
    assert main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(WEA), "-o", str(out), "--no-plots",
                 *QUICK]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("lbl-illum: a year at 77 points") and "sDA300" in err[-1] and str(out) in err[-1]
    assert not (out / "da.png").exists()


def test_wea_and_epw_agree(outdir, tmp_path):
    """The .wea is the EPW's irradiance (epw2wea): the same year but for the dew point the
    Perez efficacies take (the .wea has none: 11 degrees C)."""
    out = tmp_path / "wea"
    assert main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(WEA), "-o", str(out), "--no-plots",
                 "-q", *QUICK]) == 0
    a, b = np.load(outdir / "illuminance.npy"), np.load(out / "illuminance.npy")
    assert b.sum() == pytest.approx(a.sum(), rel=0.03)


def test_reinhart_sky(tmp_path, outdir):
    """MF 2: 577 sky patches; the year is the Tregenza one's within the finer patches' difference."""
    out = tmp_path / "mf2"
    assert main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(EPW), "-o", str(out), "--no-plots",
                 "-q", "--sky-subdivision", "2", *QUICK]) == 0
    doc = json.loads((out / "summary.json").read_text())
    assert doc["sky_subdivision"] == 2 and doc["bytes_per_record"] > 4 * 577
    E = np.load(out / "illuminance.npy")
    assert E.shape == (77, 8760)
    assert E.sum() == pytest.approx(np.load(outdir / "illuminance.npy").sum(), rel=0.03)


def test_help_names_the_annual_preset(capsys):
    with pytest.raises(SystemExit):
        main(["annual", "--help"])
    text = capsys.readouterr().out
    assert "default draft" in text and "--weather-values" in text


def test_operable_shades(tmp_path, outdir):
    """A window group with shades: the operated year, the shaded columns and the shade
    hours; sDA with the shades operated, ASE with them open (LM-83)."""
    out = tmp_path / "shades"
    assert main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(EPW), "-o", str(out), "--no-plots",
                 "-q", "--shade", "south=glazing", "--shade-transmittance", "0.1", *QUICK]) == 0
    doc = json.loads((out / "summary.json").read_text())
    assert doc["shade_groups"] == {"south": ["glazing"]} and doc["shade_transmittance"] == 0.1
    assert 0 < doc["shades"]["groups"]["south"] < 3650
    E = np.load(out / "illuminance.npy")
    operated = np.load(out / "illuminance_shades_operated.npy")
    assert operated.shape == E.shape and (operated <= E * 1.0001 + 1e-3).mean() > 0.99
    assert doc["overall"]["sda"] <= doc["overall"]["sda_shades_open"]
    assert doc["overall"]["ase"] == json.loads((outdir / "summary.json").read_text())["overall"]["ase"]
    assert "DA300_shaded" in (out / "points.csv").read_text().splitlines()[0]


def test_views_give_annual_glare(tmp_path):
    out = tmp_path / "glare"
    assert main(["annual", str(SCENE), "--points", str(POINTS), "--weather", str(EPW), "-o", str(out), "--no-plots",
                 "-q", "--views", "all", *QUICK]) == 0
    dgp, ev = np.load(out / "glare_dgp.npy"), np.load(out / "glare_ev.npy")
    assert dgp.shape == ev.shape == (2, 8760) and dgp.dtype == np.float32
    assert (dgp >= 0).all() and (dgp <= 1).all() and ev.max() > 2000
    doc = json.loads((out / "glare.json").read_text())
    assert doc["order"] == ["desk", "side"]
    side = doc["views"]["side"]
    assert side["sun_in_view_hours"] > 0 and doc["views"]["desk"]["sun_in_view_hours"] < side["sun_in_view_hours"]
    shares = side["dgp"]["classes"]
    assert sum(shares.values()) == pytest.approx(100.0)
    assert side["dgp"]["glare_autonomy"] == pytest.approx(shares["imperceptible"] + shares["perceptible"])
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["glare"]) == {"desk", "side"}
    # the grid's own results are those of a run without views
    assert np.load(out / "illuminance.npy").shape == (77, 8760)


@pytest.mark.parametrize("change, expect", [
    (lambda t: ["--weather", str(t / "year.txt")], "year.txt"),
    (lambda t: ["--weather", str(t / "missing.epw")], "missing.epw"),
    (lambda t: ["--schedule", str(t / "empty.csv")], "occupies no hour"),
    (lambda t: ["-o", str(t / "file.txt")], "is a file"),
    (lambda t: ["--area", "kitchen"], "kitchen"),
    (lambda t: ["--dst", "us", "--schedule", str(t / "empty.csv")], "--dst"),
    (lambda t: ["--weather", str(t / "short.wea")], "8760"),
    (lambda t: ["--shade", "south"], "GROUP=MATERIAL"),
    (lambda t: ["--shade", "south=wall"], "'wall' is not a glass"),
    (lambda t: ["--shade", "a=glazing", "--shade", "a=glazing"], "given twice"),
    (lambda t: ["--shade-transmittance", "2"], "--shade-transmittance"),
    (lambda t: ["--views", "nowhere"], "no [views.nowhere]"),
    (lambda t: ["--ill"], "--ill writes Honeybee's results"),
    (lambda t: ["--weather", str(t / "dark.wea")], "no occupied hour has daylight"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, change, expect):
    (tmp_path / "year.txt").write_text("1 2 3\n")
    (tmp_path / "empty.csv").write_text("0\n" * 8760)
    (tmp_path / "file.txt").write_text("")
    lines = WEA.read_text().splitlines()
    (tmp_path / "short.wea").write_text("\n".join(lines[:6 + 48]) + "\n")
    dark = [" ".join(line.split()[:3] + ["0", "0"]) for line in lines[6:]]       # a polar night all year
    (tmp_path / "dark.wea").write_text("\n".join(lines[:6] + dark) + "\n")
    args = {"--weather": str(EPW), "-o": str(tmp_path / "out")}
    extra = change(tmp_path)
    for key in ("--weather", "-o"):
        if key in extra:
            args[key] = extra[extra.index(key) + 1]
            del extra[extra.index(key):extra.index(key) + 2]
    argv = ["annual", str(SCENE), "--points", str(POINTS), *[x for kv in args.items() for x in kv], *extra, *QUICK]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expect in err[0], err
    assert not (tmp_path / "out").exists()
