"""``lbl-illum batch``: studies and variants from one TOML file, one table at the end; every
study checked before any runs."""

import json
import shutil
from pathlib import Path

import pytest

from lbl_illum.cli.main import main

OFFICE = Path(__file__).resolve().parents[2] / "examples" / "office"


@pytest.fixture
def batch(tmp_path):
    """Two variants of the office (wall reflectance 0.5 and 0.6) and an output folder."""
    variants = tmp_path / "variants"
    variants.mkdir()
    shutil.copy(OFFICE / "office.obj", variants)
    text = (OFFICE / "scene.toml").read_text()
    (variants / "base.toml").write_text(text)
    (variants / "bright.toml").write_text(text.replace("reflectance = 0.5", "reflectance = 0.6", 1))
    (tmp_path / "out").mkdir()
    return tmp_path


def write(folder, studies):
    (folder / "studies.toml").write_text(
        '[defaults]\npreset = "draft"\nbounces = 1\nsamples = 16\npoint_samples = 16\n\n' + studies)
    return folder / "studies.toml"


GRID = f'points = "{OFFICE / "grid.pts"}"\n'


def test_batch_runs_every_study_and_prints_one_table(batch, capsys):
    path = write(batch, '[[study]]\nname = "grid"\ncommand = "illuminance"\nscene = "variants/base.toml"\n' + GRID +
                 'output = "out/grid.csv"\noptions = { cache = "out/base.cache" }\n\n'
                 '[[study]]\ncommand = "daylight-factor"\nscene = "variants/*.toml"\n' + GRID +
                 'output = "out/{stem}-df.csv"\n')
    code = main(["batch", str(path), "--workers", "0", "--chunk-size", "40", "--table", str(batch / "out" / "t.json")])
    err = capsys.readouterr().err
    assert code == 0
    assert sorted(p.name for p in (batch / "out").iterdir()) == ["base-df.csv", "base.cache", "bright-df.csv",
                                                                  "grid.csv", "t.json"]
    table = json.loads((batch / "out" / "t.json").read_text())["studies"]
    assert [r["study"] for r in table] == ["grid", "daylight-factor base", "daylight-factor bright"]
    assert all(r["status"] == "ok" and "on one process (--workers 0) (2 rounds)" in r["summary"] for r in table)
    assert err.splitlines()[-1].startswith("lbl-illum: batch of 3 studies in ")
    assert err.splitlines()[-1].endswith("on one process (--workers 0): 3 done, 0 failed")
    assert not any(line.startswith("lbl-illum: illuminance at") for line in err.splitlines())   # in the table


def test_a_study_s_progress_is_its_share_of_the_batch():
    from lbl_illum.cli.batch import _StudyProgress

    class Bar:
        def __init__(self):
            self.seen = []

        def fraction(self, f):
            self.seen.append(("fraction", f))

        def describe(self, text):
            self.seen.append(("describe", text))

        def update(self, rays):
            self.seen.append(("update", rays))

    bar = Bar()
    study = _StudyProgress(bar, 2, 4, "grid")
    study.fraction(0.5)
    study.describe("round 1 of 3")
    study.update(10)
    assert bar.seen == [("fraction", 0.625), ("describe", "study 3 of 4 (grid): round 1 of 3"), ("update", 10)]


@pytest.mark.parametrize("studies, message", [
    ('[[study]]\ncommand = "illuminance"\nscene = "variants/base.toml"\n' + GRID + 'output = "out/a.csv"\n'
     'options = { colour = "red" }\n', "study 'illuminance base': unrecognized arguments: --colour red"),
    ('[[study]]\ncommand = "illuminance"\nscene = "variants/nothing*.toml"\n' + GRID + 'output = "out/a.csv"\n',
     "studies.toml: study 1: no scene file matches variants/nothing*.toml"),
    ('[[study]]\ncommand = "glare"\nscene = "variants/base.toml"\noutput = "out/a.csv"\n',
     "studies.toml: study 1: command must be one of illuminance, daylight-factor, render, annual, got 'glare'"),
    ('[[study]]\ncommand = "illuminance"\nscene = "variants/*.toml"\n' + GRID + 'output = "out/same.csv"\n',
     "studies.toml: studies 'illuminance base' and 'illuminance bright' both write"),
    ('[[study]]\ncommand = "illuminance"\nscene = "variants/base.toml"\n' + GRID + 'output = "out/a.csv"\n'
     'options = { workers = 2 }\n', "option 'workers' is the batch's own"),
])
def test_a_bad_study_stops_the_batch_before_any_work(batch, capsys, studies, message):
    code = main(["batch", str(write(batch, studies)), "--workers", "0"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1
    assert list((batch / "out").iterdir()) == []
