"""The verdict rules of :func:`replication.rig.quality.judge` at their boundaries, one check at a time: mutation testing
(scripts/mutation) found loosened thresholds, flipped comparisons and removed branches that no test saw."""
import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from replication.rig.quality import LEVELS, THRESHOLDS, Evidence, Reason, Verdict, judge

#: Evidence that every check passes: no reason at all.
GOOD = Evidence(n_pairs=100, residual_median_deg=0.2, motion_median_deg=30.0, bootstrap_deg=0.1, axis_spread_deg=20.0)
EPS = 1e-9


def _reasons(e, extra=()):
    return {r.check: r for r in judge(e, extra).reasons}


def test_good_evidence_gives_ok_and_no_reason():
    v = judge(GOOD)
    assert v.level == "ok" and v.reasons == ()


#: check, the Evidence field(s) a value sets, "below" or "above", the unit printed, the name printed.
CHECKS = [
    ("n_pairs", lambda v: dict(n_pairs=v), "below", "", "motion pairs"),
    ("offset_correlation", lambda v: dict(offset_correlation=v), "below", "", "time-offset correlation"),
    ("offset_peak_margin", lambda v: dict(offset_peak_margin=v, second_peak_offset_s=0.25), "below", "",
     "margin of the time-offset correlation peak over the next one"),
    ("blocks", lambda v: dict(blocks=v), "below", "", "independent bootstrap blocks"),
    ("overlap_intervals", lambda v: dict(overlap_s=v * 0.5, interval_s=0.5), "below", "",
     "overlap of the streams in pairing intervals"),
    ("motion_median_deg", lambda v: dict(motion_median_deg=v, residual_median_deg=v * 0.01), "below", " deg",
     "median motion per pair"),
    ("residual_to_motion", lambda v: dict(residual_median_deg=v * 10.0, motion_median_deg=10.0), "above", "",
     "median pair residual / median motion"),
    ("residual_median_deg", lambda v: dict(residual_median_deg=v, motion_median_deg=1000.0), "above", " deg",
     "median pair residual"),
    ("bootstrap_deg", lambda v: dict(bootstrap_deg=v), "above", " deg", "bootstrap 95 % radius"),
    ("axis_spread_deg", lambda v: dict(axis_spread_deg=v), "below", " deg", "camera axis spread"),
    ("excitation_deg", lambda v: dict(excitation_deg=v), "below", " deg", "RMS rotation about the least-excited axes"),
    ("gyro_rate_hz", lambda v: dict(gyro_rate_hz=v), "below", " Hz", "gyro rate"),
    ("gyro_samples_per_interval", lambda v: dict(gyro_rate_hz=100.0, interval_s=v / 100.0), "below", "",
     "gyro samples per pairing interval"),
    ("reference_error_deg", lambda v: dict(reference_error_deg=v), "above", " deg", "angle to the given reference"),
    ("offset_left_ms", lambda v: dict(offset_s=-v / 1e3, offset_applied=False), "above", " ms",
     "clock offset measured but not removed"),
    ("gap_share_dropped", lambda v: dict(pairs_dropped_at_gaps=round(v * 1000), pairs_before_gaps=1000), "above", "",
     "share of pairs dropped across stream gaps"),
]


def _cases():
    for check, make, side, unit, name in CHECKS:
        warn, fail = THRESHOLDS[check]
        for level, bound in (("warning", warn), ("fail", fail)):
            if bound is not None:
                yield pytest.param(check, make, side, unit, name, level, bound, id=f"{check}-{level}")


@pytest.mark.parametrize("check, make, side, unit, name, level, bound", list(_cases()))
def test_each_threshold_at_its_boundary(check, make, side, unit, name, level, bound):
    warn, fail = THRESHOLDS[check]
    integer = check in ("n_pairs",)
    step = 1 if integer else (1e-3 if check == "gap_share_dropped" else EPS * max(1.0, abs(bound)))
    beyond = bound - step if side == "below" else bound + step
    at = _reasons(dataclasses.replace(GOOD, **make(bound)))
    # exactly at the bound: not this level (the comparisons are strict)
    if check in at:
        assert at[check].level != level
        assert level == "fail" and at[check].level == "warning"  # at the fail bound, still beyond the warning one
    else:
        assert level == "warning" or warn is None
    got = _reasons(dataclasses.replace(GOOD, **make(beyond)))
    r = got[check]
    assert r.level == level
    assert r.threshold == pytest.approx(bound) and isinstance(r.threshold, float)
    assert r.measured == pytest.approx(beyond, rel=1e-6) and isinstance(r.measured, float)
    sign = "<" if side == "below" else ">"
    assert r.message.startswith(f"{name} {beyond:.3g}{unit} {sign} {bound:g}{unit}: ")
    assert judge(dataclasses.replace(GOOD, **make(beyond))).level == level
    if level == "warning" and fail is not None:
        # between the warning and fail bounds: a warning
        mid = (warn + fail) / 2 if not integer else (warn + fail) // 2
        assert _reasons(dataclasses.replace(GOOD, **make(mid)))[check].level == "warning"


def test_nonfinite_offset_correlation_fails_without_a_number():
    r = _reasons(dataclasses.replace(GOOD, offset_correlation=math.nan))["offset_correlation"]
    assert (r.level, r.measured, r.threshold) == ("fail", None, THRESHOLDS["offset_correlation"][1])
    assert r.message.startswith("no time-offset correlation: ")


def test_nonfinite_peak_margin_is_no_reason_and_the_second_peak_is_named():
    assert "offset_peak_margin" not in _reasons(dataclasses.replace(GOOD, offset_peak_margin=math.nan))
    r = _reasons(dataclasses.replace(GOOD, offset_peak_margin=0.0, second_peak_offset_s=-0.0123))["offset_peak_margin"]
    assert "another clock offset (-12.3 ms) matches" in r.message


@pytest.mark.parametrize("sign", [1, -1])
def test_offset_at_the_search_bound_fails_within_two_resolutions(sign):
    res, bound = 0.01, 0.2
    margin = THRESHOLDS["offset_at_bound_resolutions"][1] * res
    base = dataclasses.replace(GOOD, max_offset_s=bound, offset_resolution_s=res)
    at = _reasons(dataclasses.replace(base, offset_s=sign * (bound - margin)))["offset_at_bound"]
    assert (at.level, at.measured, at.threshold) == ("fail", sign * (bound - margin), bound)
    assert at.message.startswith(f"the clock offset {1e3 * sign * (bound - margin):+.1f} ms lies at the search bound "
                                 f"+-200 ms")
    assert "offset_at_bound" not in _reasons(dataclasses.replace(base, offset_s=sign * (bound - margin - 1e-6)))
    # without a resolution, only the bound itself
    no_res = dataclasses.replace(base, offset_resolution_s=None)
    assert "offset_at_bound" in _reasons(dataclasses.replace(no_res, offset_s=sign * bound))
    assert "offset_at_bound" not in _reasons(dataclasses.replace(no_res, offset_s=sign * (bound - 1e-6)))
    assert "offset_at_bound" not in _reasons(dataclasses.replace(base, offset_s=sign * bound, max_offset_s=None))


def test_offset_left_in_is_said_only_when_not_applied():
    assert "offset_left_ms" not in _reasons(dataclasses.replace(GOOD, offset_s=0.05, offset_applied=True))
    assert _reasons(dataclasses.replace(GOOD, offset_s=0.05, offset_applied=False))["offset_left_ms"].measured == 50.0


def test_residual_to_motion_needs_a_positive_motion():
    e = dataclasses.replace(GOOD, motion_median_deg=0.0, residual_median_deg=0.5)
    assert "residual_to_motion" not in _reasons(e)
    assert "residual_to_motion" not in _reasons(dataclasses.replace(GOOD, motion_median_deg=None))
    assert "residual_to_motion" not in _reasons(dataclasses.replace(GOOD, residual_median_deg=None))


def test_overlap_needs_an_interval_and_gyro_samples_need_one_too():
    assert "overlap_intervals" not in _reasons(dataclasses.replace(GOOD, overlap_s=0.1, interval_s=None))
    assert "overlap_intervals" not in _reasons(dataclasses.replace(GOOD, overlap_s=None, interval_s=1.0))
    found = _reasons(dataclasses.replace(GOOD, gyro_rate_hz=1.0, interval_s=None))
    assert "gyro_rate_hz" in found and "gyro_samples_per_interval" not in found


def test_the_radius_is_named_by_its_kind():
    boot = _reasons(dataclasses.replace(GOOD, bootstrap_deg=2.0))["bootstrap_deg"]
    curv = _reasons(dataclasses.replace(GOOD, bootstrap_deg=2.0, radius_kind="curvature"))["bootstrap_deg"]
    assert boot.message.startswith("bootstrap 95 % radius 2 deg > 1 deg: the pairs disagree on R0")
    assert curv.message.startswith("95 % radius (curvature of eq. (8)) 2 deg > 1 deg")


def test_bootstrap_failure_and_repeated_pairs_are_warnings():
    r = _reasons(dataclasses.replace(GOOD, bootstrap_failed="singular"))["bootstrap_failed"]
    assert (r.level, r.measured, r.threshold) == ("warning", None, None) and "(singular)" in r.message
    r = _reasons(dataclasses.replace(GOOD, repeated_pairs=3))["repeated_pairs"]
    assert (r.level, r.measured, r.threshold) == ("warning", 3.0, 0.0)
    assert r.message.startswith("3 pairs repeated earlier ones")
    assert "repeated_pairs" not in _reasons(dataclasses.replace(GOOD, repeated_pairs=0))


def test_gap_share_uses_the_pairs_before_the_gaps():
    # 1 of 3 dropped: a third, below the fail bound; without the count before, the share is over at least one pair
    r = _reasons(dataclasses.replace(GOOD, pairs_dropped_at_gaps=1, pairs_before_gaps=3))["gap_share_dropped"]
    assert (r.level, r.measured) == ("warning", pytest.approx(1 / 3))
    assert r.message.endswith("1 pairs spanned a gap in a stream and were dropped")
    r = _reasons(dataclasses.replace(GOOD, pairs_dropped_at_gaps=2, pairs_before_gaps=None))["gap_share_dropped"]
    assert (r.level, r.measured) == ("fail", 2.0)
    r = _reasons(dataclasses.replace(GOOD, pairs_dropped_at_gaps=1, pairs_before_gaps=0))["gap_share_dropped"]
    assert r.measured == 1.0


@pytest.mark.parametrize("name, level", [("LocalMinimumWarning", "fail"), ("AccuracyWarning", "fail"),
                                         ("ConvergenceWarning", "warning"), ("IterationCapWarning", "warning")])
def test_solver_warnings_fail_only_for_a_wrong_answer(name, level):
    r = _reasons(dataclasses.replace(GOOD, warnings=(name, name)))["solver_warning"]
    assert (r.level, r.measured, r.threshold) == (level, None, None)
    assert name not in r.message and "use the default method chordal_optimal" in r.message
    assert [x.check for x in judge(dataclasses.replace(GOOD, warnings=(name, name))).reasons] == ["solver_warning"]


def test_solver_warnings_are_listed_in_name_order():
    v = judge(dataclasses.replace(GOOD, warnings=("LocalMinimumWarning", "ConvergenceWarning")))
    assert [r.message.split()[0] for r in v.reasons] == ["the", "the"]
    assert "stopped before converging" in v.reasons[0].message and "certified optimum" in v.reasons[1].message
    assert v.level == "fail"


def test_observability_warning_is_said_once_with_the_spread_when_low():
    spread = THRESHOLDS["axis_spread_deg"][0]
    low = judge(dataclasses.replace(GOOD, axis_spread_deg=spread - 0.01, warnings=("ObservabilityWarning",)))
    assert [r.check for r in low.reasons] == ["axis_spread_deg"]
    at = judge(dataclasses.replace(GOOD, axis_spread_deg=spread, warnings=("ObservabilityWarning",)))
    assert [(r.check, r.level) for r in at.reasons] == [("observability", "warning")]
    assert at.reasons[0].measured is None and at.reasons[0].threshold is None
    assert at.reasons[0].message.startswith(f"the motions barely determine R0 (camera axis spread {spread:g} deg")
    msg = at.reasons[0].message
    assert "ObservabilityWarning" not in msg and "add motion about other axes" in msg
    assert "another rotation fits eq. (8) almost as well" in at.reasons[0].message
    none = judge(dataclasses.replace(GOOD, axis_spread_deg=None, warnings=("ObservabilityWarning",)))
    assert [r.check for r in none.reasons] == ["observability"]


def _change(angle, significant=True):
    return SimpleNamespace(significant=significant, angle_deg=angle, split_time=12.34, n_before=40, n_after=60,
                           p_value=1e-4, level=0.01, difference_radius_deg=0.3, R_before=np.eye(3),
                           R_after=np.eye(3))


def test_a_change_counts_only_when_significant_and_beyond_the_bounds():
    warn, fail = THRESHOLDS["remount_deg"]
    assert "remount_deg" not in _reasons(dataclasses.replace(GOOD, change=_change(10.0, significant=False)))
    assert "remount_deg" not in _reasons(dataclasses.replace(GOOD, change=_change(warn)))
    r = _reasons(dataclasses.replace(GOOD, change=_change(warn + EPS)))["remount_deg"]
    assert r.level == "warning"
    assert r.message.startswith(f"angle between R0 before and after 12.3 s {warn + EPS:.3g} deg > {warn:g} deg: "
                                f"the 40 pairs before and the 60 after agree on different R0")
    assert "(change test p = 0.0001 < the test's level 0.01, 95 % noise radius 0.3 deg)" in r.message
    assert ("R0 before (1.0000, 0.0000, 0.0000, 0.0000), after (1.0000, 0.0000, 0.0000, 0.0000) (w, x, y, z)"
            in r.message)
    assert _reasons(dataclasses.replace(GOOD, change=_change(fail)))["remount_deg"].level == "warning"
    assert _reasons(dataclasses.replace(GOOD, change=_change(fail + EPS)))["remount_deg"].level == "fail"


def test_outlying_poses_beyond_three_times_the_median():
    factor = THRESHOLDS["pose_residual_ratio"][0]
    base = [1.0] * 9
    assert "pose_outliers" not in _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(base + [factor])))
    r = _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(base + [factor + 1e-6])))["pose_outliers"]
    assert (r.level, r.threshold) == ("warning", factor) and r.measured == pytest.approx(factor + 1e-6)
    assert r.message.startswith("outlying pose (0-based index, median residual of its pairs): 9 (3 deg) > 3 x the "
                                "stations' median 1 deg = 3 deg")
    # the worst first, five named, the rest counted; the measured ratio is the worst one's
    medians = [1.0] * 20 + [4.0, 9.0, 5.0, 6.0, 7.0, 8.0, 4.5]
    r = _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(medians)))["pose_outliers"]
    assert r.measured == 9.0
    assert "outlying poses (0-based index" in r.message
    assert "21 (9 deg), 25 (8 deg), 24 (7 deg), 23 (6 deg), 22 (5 deg) and 2 more > 3 x" in r.message
    five = [1.0] * 10 + [4.0] * 5
    assert "and" not in _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(five)))[
        "pose_outliers"].message.split(" > ")[0]
    six = [2.0] * 20 + [7.0, 8.0, 9.0, 10.0, 11.0, 12.0]  # the stations' median 2 deg: the bound 6 deg
    r = _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(six)))["pose_outliers"]
    assert "25 (12 deg), 24 (11 deg), 23 (10 deg), 22 (9 deg), 21 (8 deg) and 1 more > 3 x the stations' median " \
           "2 deg = 6 deg: a bad measurement" in r.message
    two = [2.0] * 20 + [7.0, 8.0]
    assert _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=tuple(two)))["pose_outliers"].message\
        .startswith("outlying poses (0-based index, median residual of its pairs): 21 (8 deg), 20 (7 deg) > 3 x")
    # a zero or undefined median of the stations: nothing to compare with
    assert "pose_outliers" not in _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=(0.0, 0.0, 5.0)))
    assert "pose_outliers" not in _reasons(dataclasses.replace(GOOD, pose_residual_medians_deg=(math.nan,) * 3))


def test_extra_reasons_join_and_the_worst_level_wins():
    extra = [Reason("input_mistake", "fail", 1.0, 2.0, "x")]
    v = judge(dataclasses.replace(GOOD, n_pairs=20), extra)
    assert [r.check for r in v.reasons] == ["n_pairs", "input_mistake"] and v.level == "fail"
    assert judge(GOOD, [None]).reasons == ()


def test_verdict_of_lines_and_dicts():
    w = Reason("a", "warning", 1.0, 2.0, "m1")
    f = Reason("b", "fail", None, None, "m2")
    assert Verdict.of([]).level == "ok" and LEVELS == ("ok", "warning", "fail")
    assert (Verdict.of([w]).level == "warning" and Verdict.of([f, w]).level == "fail"
            and Verdict.of([w, f]).level == "fail")
    v = Verdict.of(iter([w, f]))
    assert v.reasons == (w, f)
    assert v.lines() == ["verdict: FAIL", "  warning: m1", "  fail: m2"]
    assert v.to_dict() == {"level": "fail", "reasons": [
        {"check": "a", "level": "warning", "measured": 1.0, "threshold": 2.0, "message": "m1"},
        {"check": "b", "level": "fail", "measured": None, "threshold": None, "message": "m2"}]}


@pytest.mark.parametrize("p, level, significant, words", [
    (0.049, 0.01, False, "p = 0.049 >= the test's level 0.01"),   # "within their noise (p = 0.049)" read as a paradox
    (0.00999, 0.01, True, "p = 0.00999 < the test's level 0.01"),  # just below: digits enough to tell it from 0.01
    (0.01001, 0.01, False, "p = 0.01001 >= the test's level 0.01"),  # just above
    (1e-4, 0.01, True, "p = 0.0001 < the test's level 0.01"),
    (0.25, None, False, "p = 0.25"),                                # an old report without the level
    (0.0100001, 0.01, True, "p = 0.0100001, at the test's level 0.01 (its threshold decided)"),  # never "p > level"
])
def test_a_p_value_is_printed_with_the_tests_level(p, level, significant, words):
    from replication.rig.quality import p_with_level

    assert p_with_level(p, level, significant) == words
