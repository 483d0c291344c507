"""Annual metrics against values worked out by hand on tiny arrays: the occupied rows, DA, cDA,
UDI and ASE at their boundaries, the shade rule's choice, LEED points, EN 17037 levels,
the per-area figures and the files."""

import csv
import datetime as dt
import json

import numpy as np
import pytest

from lbl_illum.errors import InputError
from lbl_illum.workplane import annual as A
from lbl_illum.workplane.annual import (WindowGroup, annual_metrics, annual_summary, ase_percent, dst_days,
                                        en17037_daylight_hours, en17037_provision, leed_points, lm83_occupancy,
                                        operate_shades, point_metrics, read_schedule, row_times, spatial_da,
                                        sun_hours, write_point_table)


# ---------------------------------------------------------------------------
# Rows and occupancy
# ---------------------------------------------------------------------------

def day_index(month, day):
    """0-based day of a 365-day year."""
    return (dt.date(2001, month, day) - dt.date(2001, 1, 1)).days


def test_rows_are_hour_ending_of_a_365_day_year():
    t = row_times()
    assert t.shape == (8760, 3)
    assert t[0].tolist() == [1, 1, 1] and t[23].tolist() == [1, 1, 24] and t[24].tolist() == [1, 2, 1]
    assert t[24 * 59].tolist() == [3, 1, 1]                 # no 29 February
    assert t[-1].tolist() == [12, 31, 24]


def test_lm83_default_is_3650_hours_ending_9_to_18_standard_time():
    occ = lm83_occupancy()
    assert occ.sum() == 3650
    day = occ.reshape(365, 24)
    # row index i = hour-ending i + 1: occupied 8 < H <= 18, i.e. rows 8..17 (8:00-18:00)
    assert (day == day[0]).all()
    assert np.flatnonzero(day[0]).tolist() == list(range(8, 18))
    assert set(np.unique(occ)) == {0.0, 1.0}


def test_other_hours():
    occ = lm83_occupancy(9, 17)
    assert occ.sum() == 8 * 365 and np.flatnonzero(occ[:24]).tolist() == list(range(9, 17))
    for bad in [(18, 8), (8, 25), (-1, 5), (8.5, 18)]:
        with pytest.raises(ValueError, match="whole hours"):
            lm83_occupancy(*bad)


@pytest.mark.parametrize("rule, year, first, end", [
    ("us", 2023, (3, 12), (11, 5)), ("us", 2024, (3, 10), (11, 3)),
    ("eu", 2023, (3, 26), (10, 29)), ("eu", 2024, (3, 31), (10, 27)),
])
def test_dst_days(rule, year, first, end):
    a, b = dst_days(rule, year)
    assert (a.month, a.day) == first and (b.month, b.day) == end
    assert a.weekday() == 6 and b.weekday() == 6


def test_dst_moves_the_office_hours_an_hour_earlier_in_standard_time():
    occ = lm83_occupancy(dst="us", year=2023).reshape(365, 24)
    assert occ.sum() == 3650                                # still 10 hours a day
    standard = list(range(8, 18))
    summer = list(range(7, 17))                             # hour-ending 8..17: 7:00-17:00 standard
    assert np.flatnonzero(occ[day_index(3, 11)]).tolist() == standard      # Saturday before
    assert np.flatnonzero(occ[day_index(3, 12)]).tolist() == summer        # change-over Sunday
    assert np.flatnonzero(occ[day_index(7, 1)]).tolist() == summer
    assert np.flatnonzero(occ[day_index(11, 4)]).tolist() == summer
    assert np.flatnonzero(occ[day_index(11, 5)]).tolist() == standard      # back on Sunday 5 November
    assert sum((occ[d] != occ[0]).any() for d in range(365)) == day_index(11, 5) - day_index(3, 12)


def test_dst_needs_a_year_and_a_known_rule():
    with pytest.raises(ValueError, match="year"):
        lm83_occupancy(dst="us")
    with pytest.raises(ValueError, match="us, eu"):
        lm83_occupancy(dst="mars", year=2023)


# ---------------------------------------------------------------------------
# Schedule files
# ---------------------------------------------------------------------------

def write(tmp_path, lines, name="sched.csv"):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_schedule_file_with_header_comments_and_fractions(tmp_path):
    values = ["0"] * 8760
    values[10], values[11] = "1", "0.5"
    path = write(tmp_path, ["occupancy", "# from the office", ""] + values)
    occ = read_schedule(path)
    assert occ.shape == (8760,) and occ.sum() == 1.5 and occ[10] == 1.0 and occ[11] == 0.5


@pytest.mark.parametrize("lines, message", [
    (["0"] * 8760, "sched.csv: the schedule occupies no hour (all 8760 values are 0)"),
    (["1"] * 8759, "sched.csv: 8759 values, expected 8760"),
    (["1"] * 8761, "sched.csv: 8761 values, expected 8760"),
    (["1"] * 5 + ["abc"] + ["1"] * 8754, "sched.csv: line 6: expected one number per line"),
    (["1"] * 5 + ["1.5"] + ["1"] * 8754, "sched.csv: line 6: occupancy must be within 0 and 1, got '1.5'"),
    (["1"] * 5 + ["-0.1"] + ["1"] * 8754, "sched.csv: line 6: occupancy must be within 0 and 1"),
    (["1"] * 5 + ["nan"] + ["1"] * 8754, "sched.csv: line 6: occupancy must be within 0 and 1"),
    (["1,1"] + ["1"] * 8759, "sched.csv: 8759 values"),           # '1,1' is taken for a header ...
    (["value", "1,1"] + ["1"] * 8759, "sched.csv: line 2: expected one number per line"),  # ... once only
])
def test_bad_schedule_files_are_one_line_errors_naming_the_file(tmp_path, lines, message):
    with pytest.raises(InputError) as err:
        read_schedule(write(tmp_path, lines))
    assert str(err.value).startswith(message) and "\n" not in str(err.value)


def test_missing_schedule_file(tmp_path):
    with pytest.raises(InputError, match="nothere.csv: no such file"):
        read_schedule(tmp_path / "nothere.csv")


# ---------------------------------------------------------------------------
# Per-point metrics
# ---------------------------------------------------------------------------

# 3 points x 5 hours, the last hour empty (its values must not count)
E3 = np.array([[300.0, 299.0, 100.0, 3000.0, 5000.0],
               [99.9, 3000.1, 0.0, 1000.0, 5000.0],
               [0.0, 0.0, 0.0, 0.0, 5000.0]], dtype=np.float32)
OCC = np.array([1.0, 1.0, 1.0, 1.0, 0.0])


def test_da_cda_udi_by_hand_at_the_boundaries():
    m = point_metrics(E3, OCC)
    assert m.occupied_hours == 4.0
    # p0: 300 >= 300 and 3000 count, 299 does not
    assert m.da.tolist() == [50.0, 50.0, 0.0]
    # p0: (1 + 299/300 + 100/300 + 1) / 4;  p1: (99.9/300 + 1 + 0 + 1) / 4
    assert m.cda == pytest.approx([100 * (2 + 399 / 300) / 4, 100 * (2 + 99.9 / 300) / 4, 0.0], rel=1e-6)
    # 100 is not "fell short" (< 100), 3000 is not "exceeded" (> 3000), 300 is autonomous
    assert m.udi_fell_short.tolist() == [0.0, 50.0, 100.0]
    assert m.udi_supplementary.tolist() == [50.0, 0.0, 0.0]          # 299 and 100
    assert m.udi_autonomous.tolist() == [50.0, 25.0, 0.0]            # 300, 3000 | 1000
    assert m.udi_exceeded.tolist() == [0.0, 25.0, 0.0]               # 3000.1
    assert m.udi_useful.tolist() == [100.0, 25.0, 0.0]
    total = m.udi_fell_short + m.udi_useful + m.udi_exceeded
    assert total.tolist() == [100.0, 100.0, 100.0]


def test_fractional_occupancy_weights_the_hours():
    m = point_metrics(E3, [0.5, 1.0, 1.0, 0.5, 0.0])
    assert m.occupied_hours == 3.0
    assert m.da[0] == pytest.approx(100 * (0.5 + 0.5) / 3)           # 300 and 3000 at half weight
    assert m.udi_supplementary[0] == pytest.approx(100 * 2 / 3)


def test_threshold_and_udi_limits_are_parameters():
    m = point_metrics(E3, OCC, threshold=100.0, udi_limits=(100.0, 300.0, 2000.0))
    assert m.da.tolist() == [100.0, 50.0, 0.0]
    assert m.udi_exceeded.tolist() == [25.0, 25.0, 0.0]              # 3000 > 2000 now


def test_bad_inputs_are_refused():
    with pytest.raises(ValueError, match="not finite"):
        point_metrics(np.array([[1.0, np.nan]]), [1, 1])
    with pytest.raises(ValueError, match="below 0"):
        point_metrics(np.array([[1.0, -1.0]]), [1, 1])
    with pytest.raises(ValueError, match="covers no hour"):
        point_metrics(E3, np.zeros(5))
    with pytest.raises(ValueError, match="5 values for 4 hours"):
        point_metrics(E3[:, :4], OCC)
    with pytest.raises(ValueError, match="within 0 and 1"):
        point_metrics(E3, [2, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="shape"):
        point_metrics(E3[0], OCC)


def test_sun_hours_count_1000_lux_and_ase_needs_more_than_250():
    D = np.array([[1000.0, 999.9, 2000.0, 0.0]])
    assert sun_hours(D, [1, 1, 1, 1]).tolist() == [2.0]
    assert sun_hours(D, [1, 1, 0, 1]).tolist() == [1.0]              # empty hours do not count
    assert ase_percent([250.0, 250.5, 251.0, 0.0]) == 50.0
    # by arrays: 251, 250 and 0 occupied hours of sun
    D = np.zeros((3, 300), np.float32)
    D[0, :251] = 1000.0
    D[1, :250] = 5000.0
    D[1, 250] = 999.0
    hours = sun_hours(D, np.ones(300))
    assert hours.tolist() == [251.0, 250.0, 0.0]
    assert ase_percent(hours) == pytest.approx(100 / 3)


def test_sda_counts_points_at_50_percent_and_is_exact_at_55():
    assert spatial_da([50.0, 49.99, 100.0, 0.0]) == 50.0
    assert spatial_da([50.0] * 11 + [10.0] * 9) == 55.0              # 11 of 20, not 55.000000000000007
    assert leed_points(spatial_da([50.0] * 11 + [10.0] * 9), [55.0, 60.0])["points"] == 3


# ---------------------------------------------------------------------------
# Shades
# ---------------------------------------------------------------------------

P, HOURS = 50, 8        # 50 points: 1 sunlit point is 2 % (stays open), 2 are more


def shade_case():
    """Sun and diffuse light through groups A and B and through static glazing, by hour."""
    sun = {k: np.zeros((P, HOURS)) for k in ("A", "B", "static")}
    diffuse = {k: np.full((P, HOURS), 100.0) for k in ("A", "B")}
    sun["A"][0, 1] = 2000.0                          # h1: one point (2 %): open
    sun["A"][:2, 2] = 2000.0                         # h2: two points through A: close A
    sun["A"][:5, 3] = 2000.0                         # h3: 5 + 5 points: close both
    sun["B"][5:10, 3] = 2000.0
    sun["A"][:5, 4] = 2000.0                         # h4: 5 through A, 1 through B: close A only
    sun["B"][5, 4] = 2000.0
    sun["static"][:3, 5] = 2000.0                    # h5: no shade helps: all closed, unresolved
    sun["A"][:3, 6] = 600.0                          # h6: 600 + 600 on 3 points: either closes it;
    sun["B"][:3, 6] = 600.0                          #     B brings more diffuse light: close A
    diffuse["B"][:, 6] = 300.0
    sun["A"][:3, 7] = 600.0                          # h7: the same with equal light: the first (A)
    sun["B"][:3, 7] = 600.0
    D = sun["A"] + sun["B"] + sun["static"]
    E = D + diffuse["A"] + diffuse["B"] + 50.0
    groups = [WindowGroup(g, E - sun[g] - 0.9 * diffuse[g], D - sun[g]) for g in ("A", "B")]
    return E, D, groups


def test_the_least_shaded_combination_is_chosen_each_hour():
    E, D, groups = shade_case()
    op = operate_shades(E.astype(np.float32), D.astype(np.float32), groups)
    assert op.names == ["A", "B"]
    assert op.closed[0].tolist() == [False, False, True, True, True, True, True, True]
    assert op.closed[1].tolist() == [False, False, False, True, False, True, False, False]
    assert op.unresolved.tolist() == [False] * 5 + [True] + [False] * 2
    # the shaded illuminance is the open one less what the closed groups take away
    expected = E.copy()
    for g, grp in enumerate(groups):
        expected[:, op.closed[g]] += (grp.illuminance - E)[:, op.closed[g]]
    assert np.allclose(op.illuminance, expected)
    assert op.illuminance.dtype == np.float32
    assert op.closed_hours(np.ones(HOURS)) == {"A": 6.0, "B": 2.0}


def test_each_area_is_judged_on_its_own_points():
    areas = np.array(["a"] * 40 + ["b"] * 10, dtype=object)
    sun_a, sun_b = np.zeros((P, 3)), np.zeros((P, 3))
    sun_b[45, 0] = 2000.0                   # h0: 1 point: 2 % of all, 10 % of area b
    sun_a[:2, 1] = 2000.0                   # h1: 2 points of a (5 %) and 1 of b (10 %)
    sun_b[46, 1] = 2000.0                   # h2: no sun
    D = sun_a + sun_b
    E = 300.0 + D
    # closed, A takes 1 lux of sky light, B 100 lux: only the sun rule closes B
    groups = [WindowGroup("A", E - sun_a - 1.0, D - sun_a), WindowGroup("B", E - sun_b - 100.0, D - sun_b)]
    together = operate_shades(E, D, groups)
    apart = operate_shades(E, D, groups, areas)
    assert together.closed.tolist() == [[False, True, False], [False, False, False]]   # 1 of 50 left in h1
    assert apart.closed.tolist() == [[False, True, False], [True, True, False]]


def greedy_case(groups=5):
    """Hour 0: group 3 lights 10 points, group 1 lights 1; hour 1: groups 0 and 4 light 5 each;
    hours 2 and 3: groups 1 and 2 give 600 lux each to 3 points, so that closing either
    one is enough; in hour 2 group 1 brings more diffuse light, in hour 3 both the same."""
    E = np.full((P, 4), 500.0)
    D = np.zeros((P, 4))
    sun = np.zeros((groups, P, 4))
    sky = np.zeros((groups, P, 4))
    sun[3, :10, 0] = 3000.0
    sun[1, 20, 0] = 3000.0
    sun[0, :5, 1] = 3000.0
    sun[4, 5:10, 1] = 3000.0
    sun[1:3, :3, 2:] = 600.0
    sky[1, :, 2] = 200.0
    D += sun.sum(axis=0)
    E += D + sky.sum(axis=0)
    return E, D, [WindowGroup(f"g{g}", E - sun[g] - sky[g], D - sun[g]) for g in range(groups)]


def test_more_groups_than_tried_exhaustively_are_closed_one_by_one():
    assert A.EXHAUSTIVE_GROUPS == 4
    E, D, groups = greedy_case(5)
    op = operate_shades(E, D, groups)
    assert np.flatnonzero(op.closed[:, 0]).tolist() == [3]           # 1 point left: 2 %, enough
    assert np.flatnonzero(op.closed[:, 1]).tolist() == [0, 4]
    assert np.flatnonzero(op.closed[:, 2]).tolist() == [2]              # keeps group 1's light
    assert np.flatnonzero(op.closed[:, 3]).tolist() == [1]              # a tie: the first
    assert not op.unresolved.any()
    # four groups (exhaustive) choose the same
    E4, D4, groups4 = greedy_case(5)
    op4 = operate_shades(E4, D4, groups4[:4])
    assert np.flatnonzero(op4.closed[:, 0]).tolist() == [3]


def test_shade_inputs_are_checked():
    E, D, groups = shade_case()
    with pytest.raises(ValueError, match="no window group"):
        operate_shades(E, D, [])
    with pytest.raises(ValueError, match="names must differ"):
        operate_shades(E, D, [groups[0], groups[0]])
    with pytest.raises(ValueError, match="'B': direct_sun has shape"):
        operate_shades(E, D, [groups[0], WindowGroup("B", groups[1].illuminance, D[:, :3])])
    with pytest.raises(ValueError, match="direct sun"):
        annual_metrics(E, np.ones(HOURS), groups=groups)


# ---------------------------------------------------------------------------
# LEED v4.1
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("sda, spaces, points, exemplary", [
    (39.99, [39.99], 0, False), (40.0, [40.0], 1, False), (54.99, [54.99], 1, False),
    (55.0, [54.99, 60.0], 2, False), (74.99, [74.99, 50.0], 2, False), (75.0, [75.0, 50.0], 3, False),
    (57.0, [55.0, 60.0], 3, False),          # every space at 55 %: one more point on 2 ...
    (45.0, [55.0, 60.0], 1, False),          # ... not on 1 (inconsistent input, but the rule)
    (80.0, [55.0, 90.0], 3, True),           # ... exemplary performance on 3
    (55.0, None, 3, False),                  # no spaces named: the floor is one space at 55 %
    (0.0, [], 0, False),
])
def test_leed_points_at_the_boundaries(sda, spaces, points, exemplary):
    got = leed_points(sda, spaces)
    assert (got["points"], got["exemplary_performance"]) == (points, exemplary)


@pytest.mark.parametrize("sda, spaces, points, exemplary", [
    (39.99, [30.0], 0, False), (40.0, [30.0], 1, False), (55.0, [54.0, 56.0], 2, False),
    (74.99, [54.0, 80.0], 2, False), (75.0, [54.0, 80.0], 2, True), (60.0, [55.0, 65.0], 2, True),
])
def test_leed_healthcare_stops_at_2_points(sda, spaces, points, exemplary):
    got = leed_points(sda, spaces, healthcare=True)
    assert (got["points"], got["exemplary_performance"]) == (points, exemplary)


# ---------------------------------------------------------------------------
# EN 17037
# ---------------------------------------------------------------------------

def provision(target, minimum, n_target=10, n_minimum=9, passing_hours=2, hours=4, points=20):
    """``n_target`` points at ``target`` and ``n_minimum`` more at ``minimum`` (the rest 0)
    for the first ``passing_hours`` of ``hours``, dark after."""
    E = np.zeros((points, hours))
    E[:n_target, :passing_hours] = target
    E[n_target:n_target + n_minimum, :passing_hours] = minimum
    return E


@pytest.mark.parametrize("E, level", [
    (provision(300, 100), "minimum"),                         # 10/20 = 50 %, 19/20 = 95 %, 2/4 hours
    (provision(299.9, 100), "none"),                          # E_T missed
    (provision(300, 99.9), "none"),                           # E_TM on 18 of 20 only
    (provision(300, 100, n_target=9, n_minimum=10), "none"),  # E_T on 45 %
    (provision(300, 100, n_minimum=8), "none"),               # E_TM on 90 %
    (provision(300, 100, passing_hours=1), "none"),           # 25 % of the daylight hours
    (provision(500, 300), "medium"),
    (provision(750, 499.9), "medium"),
    (provision(750, 500), "high"),
    (provision(750, 500, passing_hours=3), "high"),
])
def test_en17037_levels_at_their_boundaries(E, level):
    got = en17037_provision(E, np.ones(E.shape[1], bool))
    assert got["level"] == level
    assert got["daylight_hours"] == 4


def test_en17037_reports_the_hours_of_each_criterion_and_counts_only_daylight_hours():
    E = provision(300, 100, passing_hours=2, hours=4)
    got = en17037_provision(E, np.ones(4, bool))["levels"]["minimum"]
    assert got == {"target_lux": 300.0, "target_hours": 50.0, "minimum_lux": 100.0, "minimum_hours": 50.0,
                   "met": True}
    # the same two bright hours out of 3 daylight hours (one dark hour is not a daylight hour)
    assert en17037_provision(E, np.array([1, 1, 1, 0], bool))["levels"]["minimum"]["target_hours"] == \
        pytest.approx(200 / 3)
    # roof openings: E_T over 95 % of the plane
    assert en17037_provision(E, np.ones(4, bool), target_percent=95.0)["level"] == "none"
    assert en17037_provision(provision(300, 100, n_target=19, n_minimum=0), np.ones(4, bool),
                             target_percent=95.0)["level"] == "minimum"


def test_daylight_hours_are_the_brightest_half():
    mask = en17037_daylight_hours([5.0, 3.0, 1.0, 3.0, 3.0, np.nan])
    assert mask.tolist() == [True, True, False, True, False, False]   # ties: the earlier rows
    year = np.sin(np.linspace(0, 40, 8760)) + 1.0
    assert en17037_daylight_hours(year).sum() == 4380
    # a year of nights (0) and ten bright hours: those and then the earliest dark rows
    dark = np.zeros(8760)
    dark[5000:5010] = 1.0
    assert np.flatnonzero(en17037_daylight_hours(dark)).tolist() == list(range(4370)) + list(range(5000, 5010))
    assert en17037_daylight_hours(sun_up=[0, 1, 1, 0]).tolist() == [False, True, True, False]
    with pytest.raises(ValueError, match="diffuse horizontal illuminance or the sun-up hours"):
        en17037_daylight_hours()
    with pytest.raises(ValueError, match="missing at every hour"):
        en17037_daylight_hours(np.full(8760, np.nan))


# ---------------------------------------------------------------------------
# All together: areas, summary, table
# ---------------------------------------------------------------------------

def test_area_aggregation_and_summary():
    D = np.zeros_like(E3)
    D[0, :3] = 1000.0
    areas = ["a", "a", "b"]
    m = annual_metrics(E3, OCC, direct_sun=D, areas=areas, daylight_hours=np.array([1, 1, 1, 1, 0], bool))
    doc = annual_summary(m)
    json.dumps(doc)
    a, b, o = doc["areas"]["a"], doc["areas"]["b"], doc["overall"]
    assert list(doc["areas"]) == ["a", "b"]
    assert (a["points"], a["da"], a["sda"]) == (2, 50.0, 100.0)
    assert a["udi"]["useful"] == pytest.approx(62.5) and a["udi"]["exceeded"] == 12.5
    assert (b["da"], b["sda"], b["udi"]["fell_short"]) == (0.0, 0.0, 100.0)
    assert o["da"] == pytest.approx(100 / 3) and o["sda"] == pytest.approx(200 / 3)
    assert (a["ase"], a["ase_hours_mean"], b["ase"]) == (0.0, 1.5, 0.0)      # 3 hours: far below 250
    assert (a["leed_points"], b["leed_points"], o["leed_points"]) == (3, 0, 2)
    # the credit: 66.7 % on average, but area b is below 55 %: 2 points
    assert (doc["leed"]["points"], doc["leed"]["every_space_55"], doc["leed"]["glare_review"]) == (2, False, False)
    assert doc["occupied_hours"] == 4.0 and "shades" not in doc and "shaded" not in o
    # area a by hour (2 points): 300 lux on one of them in hours 0, 1, 3 (3 of 4); 100 lux on
    # both in hours 1 and 3 (2 of 4, 50 %): minimum.  500 lux on one: hours 1, 3; 300 on both:
    # hour 3 only (25 %): not medium.  Area b is dark.
    assert a["en17037"]["level"] == "minimum" and b["en17037"]["level"] == "none"
    assert a["en17037"]["levels"]["medium"]["minimum_hours"] == 25.0
    assert doc["en17037_every_area"] == "none"


def test_summary_with_shades_uses_the_operated_shades_for_sda():
    E, D, groups = shade_case()
    # point 0 reaches 300 lux open in most hours but not with A closed
    occ = np.ones(HOURS)
    m = annual_metrics(E, occ, direct_sun=D, groups=groups)
    doc = annual_summary(m)
    assert doc["shades"] == {"groups": {"A": 6.0, "B": 2.0}, "unresolved_hours": 1}
    assert doc["overall"]["sda"] == spatial_da(m.shaded.da)
    assert doc["overall"]["sda_shades_open"] == spatial_da(m.open.da)
    assert doc["overall"]["sda"] < doc["overall"]["sda_shades_open"]
    assert doc["leed"]["shades_operated"] is True


def test_unnamed_points_count_overall_only():
    m = annual_metrics(E3, OCC, areas=["", "a", ""])
    doc = annual_summary(m)
    assert list(doc["areas"]) == ["a"] and doc["overall"]["points"] == 3
    assert "ase" not in doc["overall"] and "ase" not in doc["leed"]


def test_point_table(tmp_path):
    E, D, groups = shade_case()
    areas = np.array(["a"] * 25 + ["b"] * 25, dtype=object)
    m = annual_metrics(E, np.ones(HOURS), direct_sun=D, groups=groups, areas=areas)
    xyz = np.column_stack([np.arange(P), np.zeros(P), np.full(P, 0.8)])
    path = tmp_path / "annual.csv"
    write_point_table(path, xyz, m)
    rows = list(csv.reader(path.open()))
    assert rows[0] == ["x", "y", "z", "DA300", "cDA300", "UDI<100", "UDI100-300", "UDI300-3000", "UDI100-3000",
                       "UDI>3000", "ASE1000_hours", "DA300_shaded", "cDA300_shaded", "UDI<100_shaded",
                       "UDI100-3000_shaded", "UDI>3000_shaded", "area"]
    assert len(rows) == P + 1 and rows[1][-1] == "a" and rows[-1][-1] == "b"
    first = [float(v) for v in rows[1][:-1]]
    assert first[:3] == [0.0, 0.0, 0.8]
    assert first[3] == pytest.approx(m.open.da[0]) and first[10] == m.ase_hours[0]
    assert first[11] == pytest.approx(m.shaded.da[0], rel=1e-5)
    assert not [p for p in tmp_path.iterdir() if p.suffix == ".tmp"]
    with pytest.raises(ValueError, match="points"):
        write_point_table(path, xyz[:3], m)


def test_point_table_without_names_sun_or_shades(tmp_path):
    m = annual_metrics(E3, OCC)
    path = tmp_path / "annual.csv"
    write_point_table(path, np.zeros((3, 3)), m)
    lines = path.read_text().splitlines()
    assert lines[0] == "x,y,z,DA300,cDA300,UDI<100,UDI100-300,UDI300-3000,UDI100-3000,UDI>3000"
    assert lines[1] == "0,0,0,50,83.25,0,50,50,100,0"     # cDA (2 + 299/300 + 100/300) / 4
