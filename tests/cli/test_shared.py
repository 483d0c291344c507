"""The options every command shares (cli/shared.run_options): units at the edge."""

import argparse

import pytest

from lbl_illum.cli.shared import run_options
from lbl_illum.errors import InputError

from conftest import make_scene

FOOT = 0.3048


def feet_scene(settings):
    geo = [{"shape": "rectangle", "origin": [0, 0, 0], "u": [10, 0, 0], "v": [0, 10, 0], "material": "floor"}]
    return make_scene(geo, {"floor": {"type": "diffuse", "reflectance": 0.5}}, units="ft", settings=settings)


def args(**given):
    return argparse.Namespace(scene="scene.toml", **given)


def test_spacings_typed_in_feet_reach_the_engine_in_metres():
    scene = feet_scene({"max_spacing": 3.0})
    assert scene.options.max_spacing == pytest.approx(3.0 * FOOT)      # [settings], converted on loading
    options = run_options(scene, args(min_spacing=0.5))
    assert options.min_spacing == pytest.approx(0.5 * FOOT) and options.max_spacing == pytest.approx(3.0 * FOOT)
    options = run_options(scene, args(max_spacing=6.0))
    assert options.max_spacing == pytest.approx(6.0 * FOOT) and options.min_spacing is None


def test_min_above_max_spacing_is_named_in_the_units_typed():
    scene = feet_scene({"max_spacing": 1.0})
    with pytest.raises(InputError, match=r"^the command line with scene.toml \[settings\]: 'min_spacing' \(2\) "
                                         r"must not exceed max_spacing \(1\)$"):
        run_options(scene, args(min_spacing=2.0))
