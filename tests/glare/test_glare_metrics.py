"""Glare figures of fisheye images (lbl_illum.glare.metrics): the pixels' solid angles, a
source evaluated by hand, the position index, the indices and their classes, the grouping
of glare sources, evalglare on a small rendered image, and bad input."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.glare.metrics import (DGP_CONSTANTS, EVALGLARE_DGP_CONSTANTS, check_fisheye,
                                     daylight_glare_probability, dgp_category, en17037_class, evaluate_glare,
                                     fisheye_geometry, glare_from_image, low_light_factor, position_index)
from lbl_illum.io.images import hdr_bytes, write_hdr
from lbl_illum.scene.views import view_from_string

from conftest import make_scene, radiance_tool


def fisheye(kind="a", direction="0 1 0"):
    return view_from_string(f"-vt{kind} -vp 0 0 1.2 -vd {direction} -vu 0 0 1 -vh 180 -vv 180")


def disc_image(view, side, sigma, tau, gamma, lb, ls):
    """A uniform background lb with a disc of ls, angular radius gamma, at sigma from the
    line of sight and tau from the image's up direction (degrees)."""
    g = fisheye_geometry(view, side, side)
    s, t = math.radians(sigma), math.radians(tau)
    centre = math.cos(s) * view.unit_direction + math.sin(s) * (math.sin(t) * view.right + math.cos(t) * view.image_up)
    L = np.full((side, side), float(lb))
    disc = g.directions @ centre >= math.cos(math.radians(gamma))
    L[disc] = ls
    return L, g, disc


# -- solid angles ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["a", "h"])
@pytest.mark.parametrize("side", [31, 64, 200])
def test_every_pixel_together_is_the_hemisphere_exactly(kind, side):
    """The contour integrals of shared edges telescope: Σ ω = 2π, Σ ω_⊥ = π to round-off."""
    g = fisheye_geometry(fisheye(kind), side, side)
    assert g.square_solid_angle.sum() == pytest.approx(2 * math.pi, abs=1e-12)
    assert g.square_projected.sum() == pytest.approx(math.pi, abs=1e-12)
    assert np.all(g.square_solid_angle >= 0) and np.all(g.square_projected <= g.square_solid_angle + 1e-15)


@pytest.mark.parametrize("kind, omega_share, projected_share", [("a", 0.0018, 1.2e-5), ("h", 0.030, 0.0024)])
def test_the_valid_pixels_miss_only_the_rim_measured(kind, omega_share, projected_share):
    """Pixels count when their centre is in front (evalglare's rule); the parts in front of
    the rim pixels whose centres are not are what is lost: at 200 × 200 measured 0.17 % of
    2π and 9e-6 of π (-vta), 2.9 % and 0.22 % (-vth, where ω grows as 1/cos θ at the rim)."""
    g = fisheye_geometry(fisheye(kind), 200, 200)
    lost = 1 - g.solid_angle.sum() / (2 * math.pi)
    lost_projected = 1 - g.projected.sum() / math.pi
    assert 0 < lost < omega_share and 0 < lost_projected < projected_share
    # a uniform hemisphere: E_v = π L less that share
    L = np.full((200, 200), 1000.0)
    assert evaluate_glare(L, g.view, geometry=g).ev == pytest.approx(1000 * math.pi * (1 - lost_projected), rel=1e-12)


@pytest.mark.parametrize("kind", ["a", "h"])
def test_pixel_integrals_are_converged(kind):
    """Each pixel's ω equals the sum over its 16 × 16 sub-pixels (another set of edges)."""
    view = fisheye(kind)
    coarse = fisheye_geometry(view, 24, 24)
    fine = fisheye_geometry(view, 24 * 16, 24 * 16)
    blocks = fine.square_solid_angle.reshape(24, 16, 24, 16).sum(axis=(1, 3))
    assert coarse.square_solid_angle == pytest.approx(blocks, rel=1e-6, abs=1e-12)
    blocks = fine.square_projected.reshape(24, 16, 24, 16).sum(axis=(1, 3))
    assert coarse.square_projected == pytest.approx(blocks, rel=1e-6, abs=1e-12)


def test_interior_pixels_agree_with_evalglares_corner_quadrilaterals():
    """Away from the rim the quadrilateral of the corners' directions is the pixel to second order."""
    view = fisheye("a")
    exact = fisheye_geometry(view, 100, 100)
    corners = fisheye_geometry(view, 100, 100, method="corners")
    inner = exact.valid & (exact.cos_theta > math.cos(math.radians(80)))
    assert corners.solid_angle[inner] == pytest.approx(exact.solid_angle[inner], rel=2e-4)


# -- one source by hand -----------------------------------------------------------------------------------------
def test_a_disc_source_against_the_formulas_by_hand():
    """L_b = 100, a disc of L_s = 20000 cd/m², γ = 5°, at σ = 30°, τ = 45° (above the line of
    sight): ω_s = 2π(1 − cos γ) = 0.02391 sr, E_v = πL_b + (L_s − L_b) π sin²γ cos σ = 725.4 lux,
    Guth's P = 2.3833, DGP = 5.87e-5 E_v + 0.0918 log10(1 + L_s² ω_s/(E_v^1.87 P²)) + 0.16 = 0.28806."""
    view = fisheye("a")
    L, g, disc = disc_image(view, 400, 30.0, 45.0, 5.0, 100.0, 20000.0)
    result = evaluate_glare(L, view, geometry=g)
    omega = 2 * math.pi * (1 - math.cos(math.radians(5)))
    ev = math.pi * 100 + 19900 * math.pi * math.sin(math.radians(5)) ** 2 * math.cos(math.radians(30))
    p = 2.383327244698465       # exp[(35.2 − 0.31889·45 − 1.22 e^(−10))·30e-3 + (21 + 0.26667·45 − 0.002963·45²)·900e-5]
    dgp = 5.87e-5 * ev + 0.0918 * math.log10(1 + 20000 ** 2 * omega / (ev ** 1.87 * p ** 2)) + 0.16
    assert (omega, ev, dgp) == pytest.approx((0.023909417, 725.4279, 0.288056), rel=1e-5)
    [source] = result.sources
    # the image holds the disc as whole pixels: its outline costs 1 % here
    assert source.solid_angle == pytest.approx(omega, rel=0.015)
    assert source.solid_angle == pytest.approx(g.solid_angle[disc].sum(), rel=1e-12)
    assert source.luminance == pytest.approx(20000.0) and source.pixels == disc.sum()
    assert result.ev == pytest.approx(ev, rel=0.01)
    assert (source.sigma, source.tau, source.above) == pytest.approx((30.0, 45.0, True), abs=0.1)
    assert source.position_index == pytest.approx(p, rel=0.003)
    assert result.dgp_uncorrected == pytest.approx(dgp, abs=0.001)
    assert result.dgp == pytest.approx(dgp * low_light_factor(result.ev), abs=0.001)
    # the same formula on the image's own ω_s, E_v and P: to round-off
    exact = DGP_CONSTANTS[0] * result.ev + DGP_CONSTANTS[2] + DGP_CONSTANTS[1] * math.log10(
        1 + 20000 ** 2 * source.solid_angle / (result.ev ** 1.87 * source.position_index ** 2))
    assert result.dgp_uncorrected == pytest.approx(exact, rel=1e-12)
    # background, DGI and UGR by their formulas
    lb = (result.ev - source.illuminance) / math.pi
    assert result.background_luminance == pytest.approx(lb) and lb == pytest.approx(100.0, rel=0.01)
    w, P = source.solid_angle, source.position_index
    assert result.dgi == pytest.approx(10 * math.log10(0.478 * 20000 ** 1.6 * (w / P ** 2) ** 0.8
                                                       / (lb + 0.07 * math.sqrt(w) * 20000)))
    assert result.ugr == pytest.approx(8 * math.log10(0.25 / lb * 20000 ** 2 * w / P ** 2))
    assert result.en17037 == "high" and result.category == "imperceptible"


def test_a_source_below_the_line_of_sight_takes_iwatas_index():
    view = fisheye("h")
    L, g, _ = disc_image(view, 200, 25.0, 150.0, 4.0, 150.0, 30000.0)
    [source] = evaluate_glare(L, view, geometry=g).sources
    assert not source.above and source.tau == pytest.approx(150.0, abs=0.2)
    assert source.position_index == pytest.approx(1.4000981526464695, rel=0.005)


def test_tau_of_a_tilted_view_is_measured_from_the_images_up_direction():
    """A source straight above the line of sight in the image of a view tilted 30° up has
    τ = 0: Guth's τ is the angle from the vertical plane through the line of sight.  (evalglare
    measures it from -vu itself, not made normal to -vd, and would give 30°.)"""
    view = view_from_string("-vta -vp 0 0 1.2 -vd 0 1 0.57735 -vu 0 0 1 -vh 180 -vv 180")
    L, g, _ = disc_image(view, 200, 20.0, 0.0, 3.0, 50.0, 10000.0)
    [source] = evaluate_glare(L, view, geometry=g).sources
    assert source.tau == pytest.approx(0.0, abs=0.5) and source.above
    assert source.position_index == pytest.approx(position_index(source.sigma, 0.0, True), rel=1e-3)


def test_position_index_formulas():
    """Guth above (IES handbook form, capped at 16), Iwata & Osterhaus below, 1 on the axis."""
    p = position_index([0, 30, 20, 60, 25, 40], [0, 45, 90, 0, 150, 180], [True, True, True, True, False, False])
    assert p == pytest.approx([1.0, 2.383327244698465, 1.2386201774883272, 16.0, 1.4000981526464695,
                               1.9968756345483443], rel=1e-12)


# -- indices and classes ------------------------------------------------------------------------------------------
def test_dgp_without_sources_and_the_low_light_correction():
    assert daylight_glare_probability(2000.0, [], [], [], low_light=False) == pytest.approx(5.87e-5 * 2000 + 0.16)
    assert low_light_factor(1000.0) == 1.0 and low_light_factor(999.999) == pytest.approx(1.0, abs=1e-8)
    assert low_light_factor(300.0) == pytest.approx(math.exp(0.024 * 300 - 4) / (1 + math.exp(0.024 * 300 - 4)))
    assert daylight_glare_probability(300.0, [], [], []) == pytest.approx((5.87e-5 * 300 + 0.16) * low_light_factor(300))
    assert daylight_glare_probability(40000.0, [1e9], [6.8e-5], [1.0]) == 1.0
    c1, c2, c3 = EVALGLARE_DGP_CONSTANTS
    assert daylight_glare_probability(2000.0, [], [], [], EVALGLARE_DGP_CONSTANTS, False) == pytest.approx(c1 * 2000 + c3)


def test_en17037_classes_and_dgp_categories():
    """EN 17037:2018 Table A.7: high ≤ 0.35, medium ≤ 0.40, minimum ≤ 0.45."""
    assert [en17037_class(d) for d in (0.2, 0.35, 0.3501, 0.40, 0.45, 0.4501, 1.0)] == \
        ["high", "high", "medium", "medium", "minimum", "none", "none"]
    assert [dgp_category(d) for d in (0.34, 0.35, 0.39, 0.40, 0.45)] == \
        ["imperceptible", "perceptible", "perceptible", "disturbing", "intolerable"]


# -- glare sources -----------------------------------------------------------------------------------------------
def test_sources_within_the_search_angle_merge_and_peaks_split_off():
    view = fisheye("a")
    g = fisheye_geometry(view, 200, 200)
    L = np.full((200, 200), 50.0)
    d, r, u = view.unit_direction, view.right, view.image_up

    def spot(sigma_deg, tau_deg, radius_deg, value):
        s, t = math.radians(sigma_deg), math.radians(tau_deg)
        c = math.cos(s) * d + math.sin(s) * (math.sin(t) * r + math.cos(t) * u)
        L[g.directions @ c >= math.cos(math.radians(radius_deg))] = value

    spot(20, 90, 2, 5000)         # two spots 8° apart with a 4° gap: merged within 5.7°...
    spot(20, 66, 2, 5000)
    spot(50, 270, 3, 5000)        # ...one far away on its own
    assert len(evaluate_glare(L, view, geometry=g).sources) == 2
    assert len(evaluate_glare(L, view, geometry=g, search_angle=math.radians(2)).sources) == 3
    spot(50, 270, 0.5, 1e8)       # a sun in the far spot: split off as its own source
    result = evaluate_glare(L, view, geometry=g)
    assert len(result.sources) == 3 and result.sources[0].luminance == pytest.approx(1e8)
    assert len(evaluate_glare(L, view, geometry=g, peak=None).sources) == 2
    # the threshold rules
    assert evaluate_glare(L, view, geometry=g, threshold=1e7).threshold == 1e7
    assert evaluate_glare(L, view, geometry=g, factor=5).threshold == pytest.approx(5 * result.average_luminance)
    task = evaluate_glare(L, view, geometry=g, task=(100, 100, 10))
    assert task.task_luminance == pytest.approx(50.0) and task.threshold == pytest.approx(250.0)
    none = evaluate_glare(np.full((200, 200), 50.0), view, geometry=g)
    assert none.sources == () and none.dgi is None and none.ugr is None


# -- evalglare ---------------------------------------------------------------------------------------------------
LAMP_ROOM = {"geometry": [{"shape": "box", "center": [0, 0, 1.5], "size": [3, 3, 3], "material": "wall"},
                          {"shape": "rectangle", "origin": [-0.3, 0.6, 2.99], "u": [0.6, 0, 0], "v": [0, 0.6, 0],
                           "material": "lamp"}],
             "materials": {"wall": {"type": "diffuse", "reflectance": 0.5},
                           "lamp": {"type": "light", "luminance": 20000}}}


def evalglare_figures(program, path, *options):
    out = subprocess.run([program, "-d", *options, str(path)], capture_output=True, text=True, check=True).stdout
    names, values = next(line for line in out.splitlines() if line.startswith("dgp,")).split(":")
    return dict(zip(names.split(","), map(float, values.split())))


@pytest.mark.parametrize("kind", ["a", "h"])
def test_a_small_rendered_fisheye_against_evalglare(tmp_path, kind):
    """A lamp 20,000 cd/m² above and ahead of the eye in a grey room, 96 × 96 pixels: DGP
    within 0.02 (measured 0.002), E_v within 1 % (-vta, measured 0.0 %; -vth 0.5 %: evalglare
    drops the pixels with a corner outside the circle), DGI and UGR within 1 (measured 0.5:
    evalglare takes P at the pixel its truncated centre coordinates name, here 1.6° nearer the
    line of sight, where P changes by 8 % a degree)."""
    program = radiance_tool("evalglare")
    if program is None:
        pytest.skip("Radiance's evalglare is not installed (pip install pyradiance)")
    from lbl_illum import Options
    from lbl_illum.engine import render_image

    scene = make_scene(LAMP_ROOM["geometry"], LAMP_ROOM["materials"], {"type": "none"})
    view = view_from_string(f"-vt{kind} -vp 0 -1 1.2 -vd 0 1 0 -vu 0 0 1 -vh 180 -vv 180")
    image = render_image(scene, view, 96, 96, Options(accuracy=0.3, samples=32, bounces=1))
    path = tmp_path / "lamp.hdr"
    write_hdr(path, image.rgb, view=view)
    ours = glare_from_image(path)
    theirs = evalglare_figures(program, path, "-C", "l+")
    assert len(ours.sources) == 1
    assert ours.dgp == pytest.approx(theirs["dgp"], abs=0.02)
    assert ours.ev == pytest.approx(theirs["E_v"], rel=0.01 if kind == "a" else 0.05)
    assert ours.dgi == pytest.approx(theirs["dgi"], abs=1.0) and ours.ugr == pytest.approx(theirs["ugr"], abs=1.0)


# -- bad input -------------------------------------------------------------------------------------------------
def _one_line(exc_info) -> str:
    text = str(exc_info.value)
    assert "\n" not in text and text
    return text


def test_bad_images_give_one_line(tmp_path):
    L = np.full((48, 48, 3), 10.0)
    cases = {}
    write_hdr(tmp_path / "noview.hdr", L)
    cases["noview.hdr"] = "no VIEW= line"
    write_hdr(tmp_path / "persp.hdr", L, view=view_from_string("-vtv -vd 0 1 0 -vh 60 -vv 60"))
    cases["persp.hdr"] = "not a fisheye"
    i, j = np.mgrid[0:48, 0:48]
    black = L.copy()
    black[np.hypot(j + 0.5 - 24, i + 0.5 - 24) > 24] = 0.0
    write_hdr(tmp_path / "corners.hdr", black, view=view_from_string("-vtv -vd 0 1 0 -vh 60 -vv 60"))
    cases["corners.hdr"] = "corners outside the inscribed circle are black"
    raw = hdr_bytes(L, view=fisheye("a"))
    for name, value in (("zero.hdr", b"EXPOSURE=0"), ("negative.hdr", b"EXPOSURE=-1.5")):
        (tmp_path / name).write_bytes(raw.replace(b"EXPOSURE=1.000000e+00", value))
        cases[name] = "exposure must be a positive number"
    write_hdr(tmp_path / "narrow.hdr", L, view=view_from_string("-vta -vd 0 1 0 -vh 120 -vv 120"))
    cases["narrow.hdr"] = "whole hemisphere"
    write_hdr(tmp_path / "shifted.hdr", L, view=view_from_string("-vta -vd 0 1 0 -vh 180 -vv 180 -vs 0.1"))
    cases["shifted.hdr"] = "shifted"
    (tmp_path / "text.hdr").write_text("not a picture\n")
    cases["text.hdr"] = "text.hdr"
    cases["missing.hdr"] = "no such file"
    for name, words in cases.items():
        with pytest.raises(InputError) as info:
            glare_from_image(tmp_path / name)
        assert words in _one_line(info) and name in _one_line(info)
    # a wrong header is overridden by a view given
    assert glare_from_image(tmp_path / "corners.hdr", view=fisheye("h")).ev > 0


def test_bad_arrays_and_options_give_one_line():
    view = fisheye("a")
    good = np.full((40, 40), 10.0)
    for L in (np.full((40, 40), -1.0), np.full((40, 40), np.nan), np.ones(5)):
        with pytest.raises(InputError) as info:
            evaluate_glare(L, view)
        _one_line(info)
    for options in ({"threshold": 0.0}, {"factor": -2.0}, {"threshold": 100.0, "factor": 5.0},
                    {"task": (0, 0, 10)}, {"task": (20, 20, 0)}, {"search_angle": 0.0}):
        with pytest.raises(InputError) as info:
            evaluate_glare(good, view, **options)
        _one_line(info)
    for text in ("-vtl -vh 3 -vv 3", "-vtc -vh 180 -vv 60"):
        with pytest.raises(InputError, match="not a fisheye"):
            check_fisheye(view_from_string(text))
