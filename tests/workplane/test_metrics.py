"""Grid figures against values worked out by hand, and the sky integral against closed forms."""

import json
import math

import numpy as np
import pytest

from lbl_illum.workplane.metrics import (area_figures, daylight_factor, grid_summary, readable, summary_line,
                               unobstructed_horizontal_illuminance)

VALUES = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0]
AREAS = ["a", "a", "a", "b", "b", "b"]


def test_figures_by_hand():
    doc = grid_summary(VALUES, [300, 500], AREAS)
    o = doc["overall"]
    # mean 2100/6 = 350; U0 = 100/350; min/max = 100/600; 4 of 6 at or above 300, 2 of 6 at or above 500
    assert o == {"points": 6, "mean": 350.0, "min": 100.0, "max": 600.0, "uniformity": pytest.approx(2 / 7),
                 "min_max": pytest.approx(1 / 6), "at_or_above": {"300": pytest.approx(4 / 6),
                                                                  "500": pytest.approx(2 / 6)}}
    a, b = doc["areas"]["a"], doc["areas"]["b"]
    assert (a["mean"], a["uniformity"], a["min_max"]) == (200.0, 0.5, pytest.approx(1 / 3))
    assert a["at_or_above"] == {"300": pytest.approx(1 / 3), "500": 0.0}        # 300 counts: "at or above"
    assert (b["mean"], b["uniformity"], b["min_max"]) == (500.0, 0.8, pytest.approx(2 / 3))
    assert b["at_or_above"] == {"300": 1.0, "500": pytest.approx(2 / 3)}
    assert doc["unit"] == "lux" and doc["thresholds"] == [300.0, 500.0]
    json.dumps(doc)                                     # JSON-ready


def test_unnamed_points_belong_to_no_area_and_order_is_kept():
    doc = grid_summary(VALUES, [], ["", "z", "z", "", "y", "y"])
    assert list(doc["areas"]) == ["z", "y"] and doc["areas"]["z"]["mean"] == 250.0
    assert grid_summary(VALUES)["areas"] == {}


def test_scale_and_shape():
    # ratios and shares do not change with the unit; any shape is flattened
    lux = area_figures(np.array(VALUES).reshape(2, 3), [300])
    klux = area_figures(np.array(VALUES) / 1000, [0.3])
    assert klux["uniformity"] == pytest.approx(lux["uniformity"]) and klux["at_or_above"]["0.3"] == lux["at_or_above"]["300"]
    assert lux["points"] == 6


def test_zero_and_single_values():
    zero = area_figures([0.0, 0.0], [1])
    assert zero["uniformity"] is None and zero["min_max"] is None and zero["at_or_above"] == {"1": 0.0}
    one = area_figures([42.0], [42])
    assert one["uniformity"] == 1.0 and one["at_or_above"] == {"42": 1.0}


@pytest.mark.parametrize("values", [[], [1.0, float("nan")], [float("inf")]])
def test_bad_values_are_refused(values):
    with pytest.raises(ValueError):
        area_figures(values)


def test_mismatched_areas_and_bad_thresholds():
    with pytest.raises(ValueError, match="area names"):
        grid_summary(VALUES, [], ["a"])
    with pytest.raises(ValueError, match="thresholds"):
        grid_summary(VALUES, [float("nan")])


def test_summary_line():
    line = summary_line(grid_summary(VALUES, [300, 500], AREAS))
    assert line == "mean 350 lux, min 100, max 600, U0 0.286, min/max 0.167, >=300 lux 67%, >=500 lux 33%"
    df = summary_line(grid_summary([1.0, 3.0], [2], quantity="daylight_factor", unit="%"))
    assert df == "mean 2%, min 1, max 3, U0 0.5, min/max 0.333, >=2% 50%"
    assert summary_line(grid_summary([1.0, 3.0], [2], unit="%"), extremes=False) == "U0 0.5, min/max 0.333, >=2% 50%"


@pytest.mark.parametrize("x, text", [(10930.4, "10,930"), (1234567.0, "1,234,567"), (999.6, "1,000"),
                                     (999.4, "999.4"), (424.24, "424.2"), (81.82, "81.82"), (0.04234, "0.04234"),
                                     (0.0, "0"), (-1500.0, "-1,500")])
def test_readable_numbers(x, text):
    assert readable(x) == text


def test_summary_line_of_a_sunlit_room_reads_without_exponents():
    line = summary_line(grid_summary([120.0, 10930.0, 47012.3], [300]))
    assert line.startswith("mean 19,354 lux, min 120, max 47,012, ") and "e+" not in line


@pytest.mark.parametrize("luminance, expect", [
    (lambda d: np.ones(len(d)), math.pi),                                   # uniform L = 1: E = π
    (lambda d: (1 + 2 * d[:, 2]) / 3, 7 * math.pi / 9),                     # CIE overcast, L_z = 1
    (lambda d: d[:, 2] ** 3, 2 * math.pi / 5),                              # ∫ μ^3 μ dμ dφ = 2π/5
    (lambda d: 1 + d[:, 0] / np.sqrt(1 - d[:, 2] ** 2 + 1e-300), math.pi),  # 1 + cos φ: the cosine cancels
])
def test_horizontal_illuminance_of_closed_forms(luminance, expect):
    assert unobstructed_horizontal_illuminance(luminance) == pytest.approx(expect, rel=1e-12)


def test_horizontal_illuminance_of_a_sun_sized_peak_converges():
    # a narrow peak (a circumsolar glow of 10° half width at 40° altitude) is resolved by the quadrature
    sun = np.array([0.0, math.cos(math.radians(40)), math.sin(math.radians(40))])

    def glow(d):
        return np.exp(-(np.arccos(np.clip(d @ sun, -1, 1)) / math.radians(10)) ** 2)

    fine = unobstructed_horizontal_illuminance(glow, nodes=(256, 512))
    assert unobstructed_horizontal_illuminance(glow) == pytest.approx(fine, rel=1e-4)


def test_daylight_factor():
    assert np.allclose(daylight_factor([100.0, 250.0], 10000.0), [1.0, 2.5])
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError):
            daylight_factor([1.0], bad)
