"""The lighting context (lbl_illum.engine.context): built once per scene, shared by
integrators of several option sets, never changed by a run."""

import numpy as np
import pytest

from lbl_illum import Integrator, Options, load_scene, read_points
from lbl_illum.engine.context import LightingContext

from conftest import EXAMPLES

OPTS = Options(accuracy=0.3, bounces=1, samples=64)


@pytest.fixture(scope="module")
def office():
    scene = load_scene(EXAMPLES / "office" / "scene.toml")
    points, normals = read_points(EXAMPLES / "office" / "grid.pts", scene.unit_scale)
    return scene, points[::6], normals[::6]


def test_a_shared_context_gives_what_a_context_of_its_own_does(office):
    """Two option sets on one context, each run after the other has run, bit for bit as
    integrators that built their own context: a run leaves nothing on the context."""
    scene, P, N = office
    shared = LightingContext.of(scene)
    other = Options(accuracy=0.5, bounces=2, samples=32, seed=3)
    first = Integrator(scene, OPTS, context=shared).compute(P, N).illuminance
    second = Integrator(scene, other, context=shared).compute(P, N).illuminance
    again = Integrator(scene, OPTS, context=shared).compute(P, N).illuminance
    np.testing.assert_array_equal(first, Integrator(scene, OPTS).compute(P, N).illuminance)
    np.testing.assert_array_equal(second, Integrator(scene, other).compute(P, N).illuminance)
    np.testing.assert_array_equal(first, again)


def test_the_context_is_read_only_and_bound_to_its_scene(office):
    scene, _, _ = office
    context = LightingContext.of(scene)
    with pytest.raises(AttributeError):
        context.reflects = True                                   # frozen
    with pytest.raises(ValueError):
        context.portal_index[0] = 5                               # its arrays too
    with pytest.raises(ValueError, match="another scene"):
        Integrator(load_scene(EXAMPLES / "office" / "scene.toml"), OPTS, context=context)


def test_a_run_keeps_its_plan_off_the_integrator(office):
    """Spacing limits of one run (given by the caller, as the renderer does) do not reach the next."""
    scene, P, N = office
    integ = Integrator(scene, OPTS)
    given = integ.compute(P, N, spacing=(0.05, 0.4)).stats
    assert (given.min_spacing, given.max_spacing) == (0.05, 0.4)
    fresh = Integrator(scene, OPTS).compute(P, N).stats
    later = integ.compute(P, N).stats
    assert (later.min_spacing, later.max_spacing) == (fresh.min_spacing, fresh.max_spacing) != (0.05, 0.4)
    assert not any(hasattr(integ, name) for name in ("min_spacing", "max_spacing", "_roi", "_open"))
