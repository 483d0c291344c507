"""Quality options: presets, their precedence, and the measured numbers the help prints."""

import json

import pytest

from lbl_illum.errors import InputError
from lbl_illum.options import PRESET_MEASURED, PRESETS, Options, preset_table

from conftest import ROOT


def test_preset_sets_its_four_options():
    for name, values in PRESETS.items():
        opts = Options(seed=7).with_preset(name)
        assert {k: getattr(opts, k) for k in values} == values
        assert opts.seed == 7            # other options untouched


def test_settings_table_preset_then_explicit_keys_win():
    opts = Options.from_table({"preset": "draft", "samples": 999}, "scene.toml: [settings]")
    assert opts.samples == 999
    assert opts.accuracy == PRESETS["draft"]["accuracy"] and opts.bounces == PRESETS["draft"]["bounces"]


def test_unknown_preset_is_one_line_naming_the_choices():
    with pytest.raises(InputError, match=r"scene.toml: \[settings\]: 'preset' must be one of draft, low"):
        Options.from_table({"preset": "ultra"}, "scene.toml: [settings]")


def test_presets_are_ordered_by_cost():
    names = list(PRESETS)
    samples = [PRESETS[n]["samples"] for n in names]
    accuracy = [PRESETS[n]["accuracy"] for n in names]
    assert samples == sorted(samples) and accuracy == sorted(accuracy, reverse=True)


def test_help_numbers_are_the_committed_measurements():
    """The numbers the help prints are those of the committed office-tradeoff report."""
    path = ROOT / "docs" / "validation" / "office-tradeoff" / "results.json"
    if not path.exists():
        pytest.skip("no committed office-tradeoff report")
    measured = json.loads(path.read_text())["results"]["presets"]
    assert set(PRESET_MEASURED) == set(PRESETS) == set(measured)
    for name, (seconds, mean, worst) in PRESET_MEASURED.items():
        row = measured[name]
        assert row["options"]["accuracy"] == PRESETS[name]["accuracy"]
        assert row["options"]["samples"] == PRESETS[name]["samples"]
        assert row["options"]["bounces"] == PRESETS[name]["bounces"]
        assert row["options"]["point_samples"] == PRESETS[name]["point_samples"]
        assert row["options"]["interpolation"] == PRESETS[name]["interpolation"]
        assert seconds == pytest.approx(row["seconds"], abs=0.05)
        assert mean == pytest.approx(row["mean_error"], abs=5e-5)
        assert worst == pytest.approx(row["max_error"], abs=5e-5)
        assert f"{name:7s}" in preset_table()
