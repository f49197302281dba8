"""Every threshold of the verdict (``replication.rig.quality.THRESHOLDS``) at its boundary, through ``judge(Evidence)``.

For each check and each of its bounds (warning, fail): a value just below and just above the bound, and the bound
itself. A check is either a "below" check (a value under the bound reaches its level) or an "above" check; all are
strict except the offset at the search bound ("within 2 resolutions" includes 2). :data:`DRIVERS` says how each
check's measured value enters :class:`Evidence`; a threshold added to ``THRESHOLDS`` without a driver fails
:func:`test_every_threshold_has_a_boundary_test`.
"""
import dataclasses
import math

import numpy as np
import pytest

from replication.rig.changepoint import ChangeTest
from replication.rig.quality import THRESHOLDS, Evidence, judge

#: Evidence that passes every check by a wide margin (asserted in test_the_good_evidence_is_ok).
GOOD = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.1,
                axis_spread_deg=20.0, offset_s=0.001, offset_correlation=0.99, max_offset_s=0.2,
                offset_resolution_s=5e-4, blocks=100.0, overlap_s=1000.0, interval_s=1.0, gyro_rate_hz=200.0,
                reference_error_deg=0.1, excitation_deg=20.0, offset_peak_margin=0.5, second_peak_offset_s=0.4)

#: Relative step from a bound for "just below" / "just above" (a bound of 0 moves by this absolute amount).
EPS = 1e-9


def _change(angle_deg, significant=True):
    return ChangeTest(significant=significant, statistic=50.0 if significant else 1.0, threshold=20.0,
                      p_value=1e-6 if significant else 0.9, level=0.01, split_index=500, split_time=45.0,
                      R_before=np.eye(3), R_after=np.eye(3), angle_deg=angle_deg, difference_radius_deg=0.05,
                      n_before=500, n_after=500, inflation=1.3, effective_blocks=100.0, split_times=np.zeros(1),
                      statistics=np.zeros(1))


def _gap_share(share):
    before = 10**9
    return dict(pairs_before_gaps=before, pairs_dropped_at_gaps=int(round(share * before)))


def _outlying_station(ratio):
    medians = np.full(9, 0.5)
    medians[6] = ratio * 0.5  # the stations' median stays 0.5 (exact in binary, as is 3 x 0.5)
    return dict(pose_residual_medians_deg=tuple(medians))


#: check -> (direction, reason's check name, value -> Evidence changes). Other values of GOOD stay as they are, and
#: are chosen so that only the driven check can fire (e.g. a small residual where the motion is driven).
DRIVERS = {
    "offset_correlation": ("below", "offset_correlation", lambda v: dict(offset_correlation=v)),
    # the value is the distance of |offset| from the search bound, in resolutions; "within" includes the bound
    "offset_at_bound_resolutions": ("within", "offset_at_bound",
                                    lambda v: dict(offset_s=GOOD.max_offset_s - v * GOOD.offset_resolution_s)),
    "offset_peak_margin": ("below", "offset_peak_margin", lambda v: dict(offset_peak_margin=v)),
    "blocks": ("below", "blocks", lambda v: dict(blocks=v)),
    "overlap_intervals": ("below", "overlap_intervals", lambda v: dict(overlap_s=v * 2.0, interval_s=2.0)),
    "residual_to_motion": ("above", "residual_to_motion",
                           lambda v: dict(residual_median_deg=v * 4.0, motion_median_deg=4.0)),
    "residual_median_deg": ("above", "residual_median_deg",
                            lambda v: dict(residual_median_deg=v, motion_median_deg=170.0)),
    "bootstrap_deg": ("above", "bootstrap_deg", lambda v: dict(bootstrap_deg=v)),
    "axis_spread_deg": ("below", "axis_spread_deg", lambda v: dict(axis_spread_deg=v)),
    "excitation_deg": ("below", "excitation_deg", lambda v: dict(excitation_deg=v)),
    "motion_median_deg": ("below", "motion_median_deg",
                          lambda v: dict(motion_median_deg=v, residual_median_deg=0.001)),
    "pose_residual_ratio": ("above", "pose_outliers", _outlying_station),
    "gap_share_dropped": ("above", "gap_share_dropped", _gap_share),
    "gyro_rate_hz": ("below", "gyro_rate_hz", lambda v: dict(gyro_rate_hz=v)),
    "gyro_samples_per_interval": ("below", "gyro_samples_per_interval",
                                  lambda v: dict(gyro_rate_hz=128.0, interval_s=v / 128.0)),
    "n_pairs": ("below", "n_pairs", lambda v: dict(n_pairs=v)),
    "reference_error_deg": ("above", "reference_error_deg", lambda v: dict(reference_error_deg=v)),
    "remount_deg": ("above", "remount_deg", lambda v: dict(change=_change(v))),
    "offset_left_ms": ("above", "offset_left_ms", lambda v: dict(offset_s=v / 1e3, offset_applied=False)),
    "mirror_fit_ratio": ("below", "mirror_fit_ratio", lambda v: dict(mirror_fit_ratio=v)),
}

#: Checks whose value is a count: "just below / above" is one less / more.
COUNTS = {"n_pairs"}

BOUNDS = [(check, level, bound) for check, (warn, fail) in THRESHOLDS.items()
          for level, bound in (("warning", warn), ("fail", fail)) if bound is not None]


def _found(check, value):
    direction, name, drive = DRIVERS[check]
    return {r.check: r.level for r in judge(dataclasses.replace(GOOD, **drive(value))).reasons}


def _below_the(level, check):
    """The level one step milder than ``level`` for ``check`` (a fail bound falls back to the warning if any)."""
    return "warning" if level == "fail" and THRESHOLDS[check][0] is not None else None


#: The bounds the module notes of replication/rig/quality.py state and argue for (warning, fail). The tests below read
#: THRESHOLDS, so they follow any change of it; this pins the values so that a change must also update the notes.
DOCUMENTED = {
    "offset_correlation": (0.9, 0.5), "offset_at_bound_resolutions": (None, 2), "offset_peak_margin": (0.1, 0.01),
    "blocks": (10, 3), "overlap_intervals": (10, 2), "residual_to_motion": (0.1, 0.3),
    "residual_median_deg": (2.0, 10.0), "bootstrap_deg": (1.0, 5.0), "axis_spread_deg": (1.0, None),
    "excitation_deg": (1.0, None), "motion_median_deg": (1.0, 0.5), "pose_residual_ratio": (3.0, None),
    "gap_share_dropped": (0.0, 0.5), "gyro_rate_hz": (50.0, None), "gyro_samples_per_interval": (None, 5.0),
    "n_pairs": (30, 10), "reference_error_deg": (1.0, 5.0), "remount_deg": (0.5, 0.75), "offset_left_ms": (5.0, None),
    "mirror_fit_ratio": (3.0, None),
}


def test_the_thresholds_are_the_documented_ones():
    assert THRESHOLDS == DOCUMENTED


def test_the_good_evidence_is_ok():
    assert judge(GOOD).level == "ok" and judge(GOOD).reasons == ()


def test_every_threshold_has_a_boundary_test():
    assert set(DRIVERS) == set(THRESHOLDS)
    assert all(d in ("below", "above", "within") for d, _, _ in DRIVERS.values())


@pytest.mark.parametrize("check, level, bound", BOUNDS, ids=[f"{c}-{lv}" for c, lv, _ in BOUNDS])
def test_each_bound_just_below_at_and_just_above(check, level, bound):
    direction, name, _ = DRIVERS[check]
    step = 1 if check in COUNTS else (EPS * abs(bound) if bound else EPS)
    lower, upper = bound - step, bound + step
    milder = _below_the(level, check)
    if direction == "above":  # strict: the bound itself is not above it
        expected = {lower: milder, bound: milder, upper: level}
    else:  # "below" strict, "within" includes the bound
        expected = {lower: level, bound: level if direction == "within" else milder, upper: milder}
    for value, want in expected.items():
        found = _found(check, value)
        assert found == ({name: want} if want else {}), (check, value, found)


def test_the_offset_bound_is_checked_on_both_sides_and_without_a_resolution():
    at = dataclasses.replace(GOOD, offset_s=-(GOOD.max_offset_s - 2 * GOOD.offset_resolution_s))
    assert {r.check: r.level for r in judge(at).reasons} == {"offset_at_bound": "fail"}
    inside = dataclasses.replace(GOOD, offset_s=-(GOOD.max_offset_s - 2.01 * GOOD.offset_resolution_s))
    assert judge(inside).reasons == ()
    # no resolution given: only the bound itself counts
    no_res = dataclasses.replace(GOOD, offset_resolution_s=None, offset_s=GOOD.max_offset_s * (1 - EPS))
    assert judge(no_res).reasons == ()
    assert judge(dataclasses.replace(no_res, offset_s=GOOD.max_offset_s)).level == "fail"


def test_the_offset_left_in_counts_either_sign_and_only_when_not_applied():
    left = dataclasses.replace(GOOD, offset_s=-0.0051, offset_applied=False)
    assert {r.check: r.level for r in judge(left).reasons} == {"offset_left_ms": "warning"}
    assert judge(dataclasses.replace(left, offset_s=-0.0049)).reasons == ()
    assert judge(dataclasses.replace(left, offset_applied=True)).reasons == ()  # removed: nothing left in


def test_a_nan_offset_correlation_fails():
    """A stream whose speed does not vary leaves no correlation: a fail, with no measured number."""
    reasons = judge(dataclasses.replace(GOOD, offset_correlation=float("nan"))).reasons
    assert [(r.check, r.level, r.measured, r.threshold) for r in reasons] == [("offset_correlation", "fail", None, 0.5)]
    assert "no time-offset correlation" in reasons[0].message


def test_a_peak_margin_without_the_second_peak_offset_is_judged():
    """``second_peak_offset_s`` defaults to None: judge used to format it into the message before comparing, and
    raised TypeError for any margin, even one far above the bound."""
    assert judge(dataclasses.replace(GOOD, second_peak_offset_s=None)).reasons == ()
    reason, = judge(dataclasses.replace(GOOD, offset_peak_margin=0.005, second_peak_offset_s=None)).reasons
    assert (reason.check, reason.level) == ("offset_peak_margin", "fail") and "another clock offset" in reason.message
    reason, = judge(dataclasses.replace(GOOD, offset_peak_margin=0.005)).reasons
    assert "another clock offset (+400.0 ms)" in reason.message


def test_a_nan_peak_margin_is_no_reason():
    assert judge(dataclasses.replace(GOOD, offset_peak_margin=float("nan"), second_peak_offset_s=float("nan"))
                 ).reasons == ()


def test_a_remount_counts_only_when_the_change_test_is_significant():
    e = dataclasses.replace(GOOD, change=_change(5.0, significant=False))
    assert judge(e).reasons == ()
    reason, = judge(dataclasses.replace(GOOD, change=_change(5.0))).reasons
    assert (reason.check, reason.level, reason.measured, reason.threshold) == ("remount_deg", "fail", 5.0, 0.75)
    assert "after 45.0 s" in reason.message and "500 pairs before" in reason.message


def test_no_pair_dropped_at_a_gap_is_no_reason():
    assert judge(dataclasses.replace(GOOD, **_gap_share(0.0))).reasons == ()
    one = judge(dataclasses.replace(GOOD, pairs_dropped_at_gaps=1, pairs_before_gaps=None)).reasons
    assert [(r.check, r.level, r.measured) for r in one] == [("gap_share_dropped", "fail", 1.0)]  # 1 of "1"


def test_gyro_samples_are_judged_only_with_an_interval():
    assert judge(dataclasses.replace(GOOD, gyro_rate_hz=100.0, interval_s=None, overlap_s=None)).reasons == ()


@pytest.mark.parametrize("medians, flagged", [
    ((0.5, 0.5, 0.5, 0.5, 1.5 * (1 + EPS)), [4]),      # just above 3 x the median of the stations' medians
    ((0.5, 0.5, 0.5, 0.5, 1.5 * (1 - EPS)), []),       # just below
    ((0.1, 0.4, 0.4, 1.0, 5.0, np.nan), [4]),          # median of the finite ones (0.4): 1.0 is 2.5 x, 5.0 is 12.5 x
    ((0.0, 0.0, 0.0, 1.0), []),                        # a median of 0: no ratio
    ((0.4, 0.4, 0.4, 2.0, 2.0, 2.0, 2.0), []),         # the median is 2.0: nothing stands out
])
def test_pose_outliers_are_ratios_to_the_stations_median(medians, flagged):
    reasons = {r.check: r for r in judge(dataclasses.replace(GOOD, pose_residual_medians_deg=medians)).reasons}
    if not flagged:
        assert "pose_outliers" not in reasons
        return
    r = reasons["pose_outliers"]
    assert r.level == "warning" and r.threshold == 3.0
    assert r.measured == pytest.approx(medians[flagged[0]] / np.nanmedian(medians))
    assert f"{flagged[0]} (" in r.message


@pytest.mark.parametrize("name, check, level", [
    ("LocalMinimumWarning", "solver_warning", "fail"),
    ("AccuracyWarning", "solver_warning", "fail"),
    ("ConvergenceWarning", "solver_warning", "warning"),
    ("CertificateWarning", "solver_warning", "warning"),
    ("IterationCapWarning", "solver_warning", "warning"),
    ("ObservabilityWarning", "observability", "warning"),
])
def test_solver_warnings_fail_or_warn_by_name(name, check, level):
    reasons = judge(dataclasses.replace(GOOD, warnings=(name, name))).reasons  # repeated: named once
    assert [(r.check, r.level) for r in reasons] == [(check, level)]
    if check == "solver_warning":  # the cause and what to do, not the warning's class
        assert name not in reasons[0].message
    else:
        assert "the motions barely determine R0" in reasons[0].message


CAP_RATIO = math.exp(math.log(1e-12) / 2000)  # sigma_2 / sigma_1 of K above which 1000 iterations do not reach 1e-12


@pytest.mark.parametrize("ratio, slow", [(CAP_RATIO * (1 + EPS), True), (0.9975, True),
                                         (CAP_RATIO * (1 - EPS), False), (None, False)])
def test_the_iteration_cap_is_named_by_its_measured_cause_and_what_to_do(ratio, slow):
    """EuRoC with two_step_left: sigma_2 / sigma_1 0.9975 at axis spread 3.2 deg; the verdict names that, with the
    threshold, and the default method, never the class IterationCapWarning."""
    e = dataclasses.replace(GOOD, warnings=("IterationCapWarning",), spectral_ratio=ratio, axis_spread_deg=3.2,
                            method="two_step_left")
    (r,) = judge(e).reasons
    assert r.level == "warning" and "IterationCapWarning" not in r.message
    assert "camera axis spread 3.2 deg" in r.message and "use the default method chordal_optimal" in r.message
    assert "add motion about other axes" in r.message and "'two_step_left'" in r.message
    if slow:
        assert (r.measured, r.threshold) == (pytest.approx(ratio), pytest.approx(CAP_RATIO))
        assert f"sigma_2 / sigma_1 of K {ratio:.4f} > {CAP_RATIO:.4f}" in r.message
        assert "motions too close to one axis (or too small) for the two-step iteration" in r.message
        assert "(> its cap of 1000)" in r.message
    else:  # not slow by the ratio: the start, or a cap the caller set; no claim that the ratio is over the bound
        assert "> 0.9863" not in r.message and "did not reach its limit within its iterations" in r.message
        assert "its start was orthogonal to the limit" in r.message


def test_a_solver_warning_with_the_default_method_says_to_check_the_pairs():
    e = dataclasses.replace(GOOD, warnings=("LocalMinimumWarning",), method="chordal_optimal")
    (r,) = judge(e).reasons
    assert r.level == "fail" and "use the default method" not in r.message and "check the pairs" in r.message
    assert "away from the certified optimum of eq. (8)" in r.message


def test_an_observability_warning_is_not_repeated_when_the_axis_spread_says_it():
    e = dataclasses.replace(GOOD, warnings=("ObservabilityWarning",), axis_spread_deg=0.5)
    assert {r.check: r.level for r in judge(e).reasons} == {"axis_spread_deg": "warning"}


def test_the_verdict_is_the_worst_reason():
    e = dataclasses.replace(GOOD, n_pairs=20, bootstrap_deg=6.0)
    verdict = judge(e)
    assert verdict.level == "fail" and {r.check: r.level for r in verdict.reasons} == {"n_pairs": "warning",
                                                                                      "bootstrap_deg": "fail"}


@pytest.mark.parametrize("poses", [False, True])
def test_the_remedies_are_for_static_poses_or_for_streams(poses):
    """Static pose sets are told to add stations, streams to record longer (a red-team case: a pose set was told to
    use a shorter interval)."""
    e = dataclasses.replace(GOOD, n_pairs=2, blocks=1.0, pose_residual_medians_deg=(0.1, 0.1, 0.1) if poses else None)
    reasons = {r.check: r.message for r in judge(e).reasons}
    stream_words = ("stride", "recording", "overlap", "interval")
    if poses:
        assert "more static poses" in reasons["n_pairs"] and "more distinct stations" in reasons["blocks"]
        assert not any(w in reasons["n_pairs"] + reasons["blocks"] for w in stream_words)
    else:
        assert "a longer recording" in reasons["n_pairs"] and "a shorter interval" in reasons["blocks"]
