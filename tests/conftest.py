"""Shared fixtures: small scenes built from plain dicts, as a scene file would give them."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from lbl_illum.scene import scene_from_dict

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

GROUND = {"shape": "polygon", "material": "ground",
          "vertices": [[-50, -50, 0], [50, -50, 0], [50, 50, 0], [-50, 50, 0]]}


def make_scene(geometry, materials, sky=None, sun=None, settings=None, units="m", base_dir=ROOT):
    """A scene from the pieces of a scene file."""
    data = {"units": units, "geometry": copy.deepcopy(geometry), "materials": copy.deepcopy(materials)}
    if sky is not None:
        data["sky"] = dict(sky)
    if sun is not None:
        data["sun"] = dict(sun)
    if settings is not None:
        data["settings"] = dict(settings)
    return scene_from_dict(data, base_dir, "test.toml")


@pytest.fixture
def open_ground():
    """A 100 m ground plane of reflectance 0.2 under nothing else."""
    def build(sky=None, sun=None, reflectance=0.2):
        return make_scene([GROUND], {"ground": {"type": "diffuse", "reflectance": reflectance}}, sky, sun)
    return build


def horizontal(n=1, z=0.0):
    """n sensors on the ground plane facing up, spread over a few metres."""
    x = np.linspace(-2, 2, n)
    points = np.column_stack([x, np.zeros(n), np.full(n, z)])
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return points, normals
