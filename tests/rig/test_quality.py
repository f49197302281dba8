"""Every threshold of the verdict (``replication.rig.quality.THRESHOLDS``) at its boundary, through
``judge(Evidence)``.

For each check and each of its bounds (warning, fail): a value just below and just above the bound,
and the bound itself. A check is either a "below" check (a value under the bound reaches its level)
or an "above" check; all are strict except the offset at the search bound ("within 2 resolutions"
includes 2). :data:`DRIVERS` says how each check's measured value enters :class:`Evidence`; a
threshold added to ``THRESHOLDS`` without a driver fails
:func:`test_every_threshold_has_a_boundary_test`.
"""
import dataclasses
import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest

from replication.rig.changepoint import ChangeTest
from replication.rig.quality import LEVELS, THRESHOLDS, Evidence, Reason, Verdict, judge

#: Evidence that passes every check by a wide margin (asserted in test_the_good_evidence_is_ok).
GOOD = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.1,
                axis_spread_deg=20.0, offset_s=0.001, offset_correlation=0.99, max_offset_s=0.2,
                offset_resolution_s=5e-4, blocks=100.0, overlap_s=1000.0, interval_s=1.0, gyro_rate_hz=200.0,
                reference_error_deg=0.1, excitation_deg=20.0, offset_peak_margin=0.5, second_peak_offset_s=0.4)

#: Relative step from a bound for "just below" / "just above" (a bound of 0 moves by this absolute
#: amount).
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


#: check -> (direction, reason's check name, value -> Evidence changes). Other values of GOOD stay
#: as they are, and are chosen so that only the driven check can fire (e.g. a small residual where
#: the motion is driven).
DRIVERS = {
    "offset_correlation": ("below", "offset_correlation", lambda v: dict(offset_correlation=v)),
    # the value is the distance of |offset| from the search bound, in resolutions; "within" includes
    # the bound
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
    """The level one step milder than ``level`` for ``check`` (a fail bound falls back to the
    warning if any)."""
    return "warning" if level == "fail" and THRESHOLDS[check][0] is not None else None


#: The bounds the module notes of replication/rig/quality.py state and argue for (warning, fail).
#: The tests below read THRESHOLDS, so they follow any change of it; this pins the values so that a
#: change must also update the notes.
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
    """``second_peak_offset_s`` defaults to None: judge used to format it into the message before
    comparing, and raised TypeError for any margin, even one far above the bound."""
    assert judge(dataclasses.replace(GOOD, second_peak_offset_s=None)).reasons == ()
    reason, = judge(dataclasses.replace(GOOD, offset_peak_margin=0.005, second_peak_offset_s=None)).reasons
    assert (reason.check, reason.level) == ("offset_peak_margin", "fail")
    assert "another clock offset matches the angular speeds" in reason.message
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
    """EuRoC with two_step_left: sigma_2 / sigma_1 0.9975 at axis spread 3.2 deg; the verdict names
    that, with the threshold, and the default method, never the class IterationCapWarning."""
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


@pytest.mark.parametrize("ratio, slow", [(CAP_RATIO, False), (CAP_RATIO * (1 + EPS), True), (1 - EPS, True),
                                         (1.0, False), (1 + EPS, False), (0.5, False)])
def test_the_iteration_cap_ratio_rule_at_its_bounds(ratio, slow):
    """The ratio says "too slow" strictly between the cap's ratio and 1: at the cap's ratio 1000
    iterations just reach the precision, at 1 and above the iteration does not converge at all (no
    count to name); otherwise the measured ratio is still given, against the same threshold."""
    e = dataclasses.replace(CLEAN, warnings=("IterationCapWarning",), spectral_ratio=ratio, method="two_step_left")
    (r,) = judge(e).reasons
    assert (r.check, r.level, r.measured, r.threshold) == ("solver_warning", "warning", ratio, CAP_RATIO)
    assert ("for the two-step iteration" in r.message) is slow
    if not slow:
        assert r.message.startswith(f"solver 'two_step_left' did not reach its limit within its iterations (sigma_2 "
                                    f"/ sigma_1 of K {ratio:.4f}, camera axis spread 20 deg, median motion per pair "
                                    f"30 deg; or its start was orthogonal")


@pytest.mark.parametrize("ratio", [CAP_RATIO * (1 + EPS), 0.9975, 0.99999])
def test_the_iterations_needed_reach_the_precision_and_no_fewer(ratio):
    """The count named is the n with ratio ** (2 n) = 1e-12 (the two-step error shrinks by the
    ratio squared per iteration), rounded: n - 1 iterations leave more than 1e-12, n + 1 less."""
    e = dataclasses.replace(CLEAN, warnings=("IterationCapWarning",), spectral_ratio=ratio, method="two_step_left")
    (r,) = judge(e).reasons
    n = int(r.message.split("would need about ")[1].split(" iterations")[0])
    assert n >= 1000 and ratio ** (2 * (n - 1)) > 1e-12 > ratio ** (2 * (n + 1))


def test_an_unmeasured_iteration_cap_names_the_motion_alone():
    e = dataclasses.replace(CLEAN, warnings=("IterationCapWarning",), spectral_ratio=None)
    (r,) = judge(e).reasons
    assert (r.check, r.measured, r.threshold) == ("solver_warning", None, None)
    assert ("did not reach its limit within its iterations (camera axis spread 20 deg, median motion per pair 30 "
            "deg; or its start" in r.message)


def test_the_default_methods_remedy_is_checking_the_pairs():
    e = dataclasses.replace(CLEAN, warnings=("LocalMinimumWarning",), method="chordal_optimal")
    (r,) = judge(e).reasons
    assert r.message.endswith("(it stopped early or on another stationary point): check the pairs (outliers, "
                              "mismatched streams)")


def test_an_unknown_solver_warning_is_named_with_its_solver():
    e = dataclasses.replace(CLEAN, warnings=("NewSolverWarning",), method="svd")
    (r,) = judge(e).reasons
    assert (r.check, r.level, r.measured, r.threshold) == ("solver_warning", "warning", None, None)
    assert r.message == "solver 'svd' warned (NewSolverWarning; its words in the result's warnings)"


@pytest.mark.parametrize("spread, motion, words", [
    (20.0, 30.0, "camera axis spread 20 deg, median motion per pair 30 deg"),
    (None, 30.0, "median motion per pair 30 deg"),
    (20.0, None, "camera axis spread 20 deg"),
    (None, None, "no motion measure"),
])
def test_the_motion_words_are_those_measured(spread, motion, words):
    """A certificate warning names the motions' measured shape: each measure that is known, and
    "no motion measure" when neither is."""
    e = dataclasses.replace(CLEAN, warnings=("CertificateWarning",), axis_spread_deg=spread, motion_median_deg=motion)
    (r,) = judge(e).reasons
    assert f"close to one axis cause ({words}): add motion" in r.message


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
    """Static pose sets are told to add stations, streams to record longer (a case once found: a
    pose set was told to use a shorter interval)."""
    e = dataclasses.replace(GOOD, n_pairs=2, blocks=1.0, pose_residual_medians_deg=(0.1, 0.1, 0.1) if poses else None)
    reasons = {r.check: r.message for r in judge(e).reasons}
    stream_words = ("stride", "recording", "overlap", "interval")
    if poses:
        assert reasons["n_pairs"].endswith("(3 unknowns; more static poses, each turned from the others by more than "
                                           "min_motion_deg)")
        assert reasons["blocks"].endswith("bootstrap radius (more distinct stations)")
        assert not any(w in reasons["n_pairs"] + reasons["blocks"] for w in stream_words)
    else:
        assert "a longer recording" in reasons["n_pairs"] and "a shorter interval" in reasons["blocks"]

# --------------------------------------------------------------------------------------------------
# The verdict rules of :func:`replication.rig.quality.judge` at their boundaries, one check at a
# time: mutation testing (scripts/mutation) found loosened thresholds, flipped comparisons and
# removed branches that no test saw.


#: Evidence that every check passes: no reason at all.
CLEAN = Evidence(n_pairs=100, residual_median_deg=0.2, motion_median_deg=30.0, bootstrap_deg=0.1, axis_spread_deg=20.0)


def _reasons(e, extra=()):
    return {r.check: r for r in judge(e, extra).reasons}


def test_good_evidence_gives_ok_and_no_reason():
    v = judge(CLEAN)
    assert v.level == "ok" and v.reasons == ()


#: check, the Evidence field(s) a value sets, "below" or "above", the unit printed, the name
#: printed, and what the reason says of its cause: the words right after ": " and the words it
#: ends with (each across the joins of the message's pieces).
CHECKS = [
    ("n_pairs", lambda v: dict(n_pairs=v), "below", "", "motion pairs",
     ("too few for R0 and a check of it (3 unknowns; a smaller stride", "or interval, or a longer recording)")),
    ("offset_correlation", lambda v: dict(offset_correlation=v), "below", "", "time-offset correlation",
     ("the two streams' angular speeds do not match", "wrong units or columns, or a clock offset beyond the search)")),
    ("offset_peak_margin", lambda v: dict(offset_peak_margin=v, second_peak_offset_s=0.25), "below", "",
     "margin of the time-offset correlation peak over the next one",
     ("another clock offset (+250.0 ms) matches the angular speeds", "record motion that is not periodic")),
    ("blocks", lambda v: dict(blocks=v), "below", "", "independent bootstrap blocks",
     ("too few for a meaningful bootstrap radius (a longer", "(a longer overlap or a shorter interval)")),
    ("overlap_intervals", lambda v: dict(overlap_s=v * 0.5, interval_s=0.5), "below", "",
     "overlap of the streams in pairing intervals", ("the streams overlap ", " s only")),
    ("motion_median_deg", lambda v: dict(motion_median_deg=v, residual_median_deg=v * 0.01), "below", " deg",
     "median motion per pair", ("the rig barely moves over a pairing interval", "too short): the pairs carry noise, "
                                                                                 "not motion")),
    ("residual_to_motion", lambda v: dict(residual_median_deg=v * 10.0, motion_median_deg=10.0), "above", "",
     "median pair residual / median motion", ("R0 does not map", "one stream's motions onto the other's")),
    ("residual_median_deg", lambda v: dict(residual_median_deg=v, motion_median_deg=1000.0), "above", " deg",
     "median pair residual", ("far above what stream noise", "leaves with the right R0")),
    ("bootstrap_deg", lambda v: dict(bootstrap_deg=v), "above", " deg", "bootstrap 95 % radius",
     ("the pairs disagree", "on R0")),
    ("axis_spread_deg", lambda v: dict(axis_spread_deg=v), "below", " deg", "camera axis spread",
     ("nearly single-axis motion", "the rotation about that axis is poorly determined")),
    ("excitation_deg", lambda v: dict(excitation_deg=v), "below", " deg", "RMS rotation about the least-excited axes",
     ("the motion so far does not determine R0", "(rotate about other axes)")),
    ("gyro_rate_hz", lambda v: dict(gyro_rate_hz=v), "below", " Hz", "gyro rate",
     ("integrating a slow gyro", "leaves an error in every pair")),
    ("gyro_samples_per_interval", lambda v: dict(gyro_rate_hz=100.0, interval_s=v / 100.0), "below", "",
     "gyro samples per pairing interval", ("too few to integrate", "the motion of one pair")),
    ("reference_error_deg", lambda v: dict(reference_error_deg=v), "above", " deg", "angle to the given reference",
     ("the data agree with another R0 than the reference: gyro axes permuted or sign-flipped (a fixed rotation",
      "cannot show), or a reference for another rig or camera")),
    ("offset_left_ms", lambda v: dict(offset_s=-v / 1e3, offset_applied=False), "above", " ms",
     "clock offset measured but not removed", ("the pairs were formed", "with the clocks as recorded (keep-clock)")),
    ("gap_share_dropped", lambda v: dict(pairs_dropped_at_gaps=round(v * 1000), pairs_before_gaps=1000), "above", "",
     "share of pairs dropped across stream gaps", ("", " pairs spanned a gap in a stream and were dropped")),
    ("mirror_fit_ratio", lambda v: dict(mirror_fit_ratio=v), "below", "",
     "median residual with the sensor's frame mirrored / this fit's",
     ("a sensor with one axis's sign flipped", "and little about its normal; rotate about that axis too, or check the "
                                               "sensor's axes")),  # no normal given: none named
]


def _cases():
    for check, make, side, unit, name, why in CHECKS:
        warn, fail = THRESHOLDS[check]
        for level, bound in (("warning", warn), ("fail", fail)):
            if bound is not None:
                yield pytest.param(check, make, side, unit, name, why, level, bound, id=f"{check}-{level}")


@pytest.mark.parametrize("check, make, side, unit, name, why, level, bound", list(_cases()))
def test_each_threshold_at_its_boundary(check, make, side, unit, name, why, level, bound):
    warn, fail = THRESHOLDS[check]
    integer = check in ("n_pairs",)
    step = 1 if integer else (1e-3 if check == "gap_share_dropped" else EPS * max(1.0, abs(bound)))
    beyond = bound - step if side == "below" else bound + step
    at = _reasons(dataclasses.replace(CLEAN, **make(bound)))
    # exactly at the bound: not this level (the comparisons are strict)
    if check in at:
        assert at[check].level != level
        assert level == "fail" and at[check].level == "warning"  # at the fail bound, still beyond the warning one
    else:
        assert level == "warning" or warn is None
    got = _reasons(dataclasses.replace(CLEAN, **make(beyond)))
    r = got[check]
    assert r.level == level
    assert r.threshold == pytest.approx(bound) and isinstance(r.threshold, float)
    assert r.measured == pytest.approx(beyond, rel=1e-6) and isinstance(r.measured, float)
    sign = "<" if side == "below" else ">"
    first, last = why
    assert r.message.startswith(f"{name} {beyond:.3g}{unit} {sign} {bound:g}{unit}: {first}")
    assert r.message.endswith(last)
    assert judge(dataclasses.replace(CLEAN, **make(beyond))).level == level
    if level == "warning" and fail is not None:
        # between the warning and fail bounds: a warning
        mid = (warn + fail) / 2 if not integer else (warn + fail) // 2
        assert _reasons(dataclasses.replace(CLEAN, **make(mid)))[check].level == "warning"


def test_nonfinite_offset_correlation_fails_without_a_number():
    r = _reasons(dataclasses.replace(CLEAN, offset_correlation=math.nan))["offset_correlation"]
    assert (r.level, r.measured, r.threshold) == ("fail", None, THRESHOLDS["offset_correlation"][1])
    assert r.message.startswith("no time-offset correlation: ")
    assert r.message.endswith("(a rig at rest, or a constant stream), so no clock offset could be estimated")


def test_nonfinite_peak_margin_is_no_reason_and_the_second_peak_is_named():
    assert "offset_peak_margin" not in _reasons(dataclasses.replace(CLEAN, offset_peak_margin=math.nan))
    r = _reasons(dataclasses.replace(CLEAN, offset_peak_margin=0.0, second_peak_offset_s=-0.0123))["offset_peak_margin"]
    assert "another clock offset (-12.3 ms) matches" in r.message


@pytest.mark.parametrize("sign", [1, -1])
def test_offset_at_the_search_bound_fails_within_two_resolutions(sign):
    res, bound = 0.01, 0.2
    margin = THRESHOLDS["offset_at_bound_resolutions"][1] * res
    base = dataclasses.replace(CLEAN, max_offset_s=bound, offset_resolution_s=res)
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
    assert "offset_left_ms" not in _reasons(dataclasses.replace(CLEAN, offset_s=0.05, offset_applied=True))
    assert _reasons(dataclasses.replace(CLEAN, offset_s=0.05, offset_applied=False))["offset_left_ms"].measured == 50.0


@pytest.mark.parametrize("motion, residual, level", [
    (0.0, 0.5, None),         # no motion: no ratio
    (None, 0.5, None), (30.0, None, None),
    (EPS, 0.5 * EPS, "fail"),  # any positive motion, however small, gives the ratio (here 0.5)
    (1.0, 0.5, "fail"),
])
def test_residual_to_motion_needs_a_positive_motion(motion, residual, level):
    found = _reasons(dataclasses.replace(CLEAN, motion_median_deg=motion, residual_median_deg=residual))
    assert (found["residual_to_motion"].level if "residual_to_motion" in found else None) == level
    if level:
        assert found["residual_to_motion"].measured == pytest.approx(residual / motion)


def test_overlap_needs_an_interval_and_gyro_samples_need_one_too():
    assert "overlap_intervals" not in _reasons(dataclasses.replace(CLEAN, overlap_s=0.1, interval_s=None))
    assert "overlap_intervals" not in _reasons(dataclasses.replace(CLEAN, overlap_s=None, interval_s=1.0))
    found = _reasons(dataclasses.replace(CLEAN, gyro_rate_hz=1.0, interval_s=None))
    assert "gyro_rate_hz" in found and "gyro_samples_per_interval" not in found


def test_the_radius_is_named_by_its_kind():
    boot = _reasons(dataclasses.replace(CLEAN, bootstrap_deg=2.0))["bootstrap_deg"]
    curv = _reasons(dataclasses.replace(CLEAN, bootstrap_deg=2.0, radius_kind="curvature"))["bootstrap_deg"]
    assert boot.message.startswith("bootstrap 95 % radius 2 deg > 1 deg: the pairs disagree on R0")
    assert curv.message.startswith("95 % radius (curvature of eq. (8)) 2 deg > 1 deg")


def test_bootstrap_failure_and_repeated_pairs_are_warnings():
    r = _reasons(dataclasses.replace(CLEAN, bootstrap_failed="singular"))["bootstrap_failed"]
    assert (r.level, r.measured, r.threshold) == ("warning", None, None) and "(singular)" in r.message
    r = _reasons(dataclasses.replace(CLEAN, repeated_pairs=3))["repeated_pairs"]
    assert (r.level, r.measured, r.threshold) == ("warning", 3.0, 0.0)
    assert r.message.startswith("3 pairs repeated earlier ones")
    assert "repeated_pairs" not in _reasons(dataclasses.replace(CLEAN, repeated_pairs=0))


def test_gap_share_uses_the_pairs_before_the_gaps():
    # 1 of 3 dropped: a third, below the fail bound; without the count before, the share is over at
    # least one pair
    r = _reasons(dataclasses.replace(CLEAN, pairs_dropped_at_gaps=1, pairs_before_gaps=3))["gap_share_dropped"]
    assert (r.level, r.measured) == ("warning", pytest.approx(1 / 3))
    assert r.message.endswith("1 pairs spanned a gap in a stream and were dropped")
    r = _reasons(dataclasses.replace(CLEAN, pairs_dropped_at_gaps=2, pairs_before_gaps=None))["gap_share_dropped"]
    assert (r.level, r.measured) == ("fail", 2.0)
    r = _reasons(dataclasses.replace(CLEAN, pairs_dropped_at_gaps=1, pairs_before_gaps=0))["gap_share_dropped"]
    assert r.measured == 1.0


@pytest.mark.parametrize("name, level", [("LocalMinimumWarning", "fail"), ("AccuracyWarning", "fail"),
                                         ("ConvergenceWarning", "warning"), ("IterationCapWarning", "warning")])
def test_solver_warnings_fail_only_for_a_wrong_answer(name, level):
    r = _reasons(dataclasses.replace(CLEAN, warnings=(name, name)))["solver_warning"]
    assert (r.level, r.measured, r.threshold) == (level, None, None)
    assert name not in r.message and "use the default method chordal_optimal" in r.message
    assert [x.check for x in judge(dataclasses.replace(CLEAN, warnings=(name, name))).reasons] == ["solver_warning"]


def test_solver_warnings_are_listed_in_name_order():
    v = judge(dataclasses.replace(CLEAN, warnings=("LocalMinimumWarning", "ConvergenceWarning")))
    assert [r.message.split()[0] for r in v.reasons] == ["the", "the"]
    assert "stopped before converging" in v.reasons[0].message and "certified optimum" in v.reasons[1].message
    assert v.level == "fail"


def test_observability_warning_is_said_once_with_the_spread_when_low():
    spread = THRESHOLDS["axis_spread_deg"][0]
    low = judge(dataclasses.replace(CLEAN, axis_spread_deg=spread - 0.01, warnings=("ObservabilityWarning",)))
    assert [r.check for r in low.reasons] == ["axis_spread_deg"]
    at = judge(dataclasses.replace(CLEAN, axis_spread_deg=spread, warnings=("ObservabilityWarning",)))
    assert [(r.check, r.level) for r in at.reasons] == [("observability", "warning")]
    assert at.reasons[0].measured is None and at.reasons[0].threshold is None
    assert at.reasons[0].message.startswith(f"the motions barely determine R0 (camera axis spread {spread:g} deg")
    msg = at.reasons[0].message
    assert "ObservabilityWarning" not in msg and "add motion about other axes" in msg
    assert "another rotation fits eq. (8) almost as well" in at.reasons[0].message
    none = judge(dataclasses.replace(CLEAN, axis_spread_deg=None, warnings=("ObservabilityWarning",)))
    assert [r.check for r in none.reasons] == ["observability"]
    unmeasured = dataclasses.replace(CLEAN, axis_spread_deg=None, motion_median_deg=None,
                                     warnings=("ObservabilityWarning",))
    assert judge(unmeasured).reasons[0].message.startswith("the motions barely determine R0 (no motion measure; the ")
    # the warnings after it (in name order) are still judged, whether it or the spread says it
    later = ("ObservabilityWarning", "TranslationNotEstimatedWarning")
    for value, first in ((spread - 0.01, "axis_spread_deg"), (spread, "observability")):
        v = judge(dataclasses.replace(CLEAN, axis_spread_deg=value, warnings=later))
        assert [r.check for r in v.reasons] == [first, "solver_warning"]
        assert "(TranslationNotEstimatedWarning; its words" in v.reasons[1].message


def _change_mq(angle, significant=True):
    return SimpleNamespace(significant=significant, angle_deg=angle, split_time=12.34, n_before=40, n_after=60,
                           p_value=1e-4, level=0.01, difference_radius_deg=0.3, R_before=np.eye(3),
                           R_after=np.eye(3))


def test_a_change_counts_only_when_significant_and_beyond_the_bounds():
    warn, fail = THRESHOLDS["remount_deg"]
    assert "remount_deg" not in _reasons(dataclasses.replace(CLEAN, change=_change_mq(10.0, significant=False)))
    assert "remount_deg" not in _reasons(dataclasses.replace(CLEAN, change=_change_mq(warn)))
    r = _reasons(dataclasses.replace(CLEAN, change=_change_mq(warn + EPS)))["remount_deg"]
    assert r.level == "warning"
    assert r.message.startswith(f"angle between R0 before and after 12.3 s {warn + EPS:.3g} deg > {warn:g} deg: "
                                f"the 40 pairs before and the 60 after agree on different R0")
    assert "(change test p = 0.0001 < the test's level 0.01, 95 % noise radius 0.3 deg)" in r.message
    assert ("R0 before (1.0000, 0.0000, 0.0000, 0.0000), after (1.0000, 0.0000, 0.0000, 0.0000) (w, x, y, z)"
            in r.message)
    assert _reasons(dataclasses.replace(CLEAN, change=_change_mq(fail)))["remount_deg"].level == "warning"
    assert _reasons(dataclasses.replace(CLEAN, change=_change_mq(fail + EPS)))["remount_deg"].level == "fail"


def test_outlying_poses_beyond_three_times_the_median():
    factor = THRESHOLDS["pose_residual_ratio"][0]
    base = [1.0] * 9
    assert "pose_outliers" not in _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(base + [factor])))
    r = _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(base + [factor + 1e-6])))["pose_outliers"]
    assert (r.level, r.threshold) == ("warning", factor) and r.measured == pytest.approx(factor + 1e-6)
    assert r.message.startswith("outlying pose (0-based index, median residual of its pairs): 9 (3 deg) > 3 x the "
                                "stations' median 1 deg = 3 deg")
    # the worst first, five named, the rest counted; the measured ratio is the worst one's
    medians = [1.0] * 20 + [4.0, 9.0, 5.0, 6.0, 7.0, 8.0, 4.5]
    r = _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(medians)))["pose_outliers"]
    assert r.measured == 9.0
    assert "outlying poses (0-based index" in r.message
    assert "21 (9 deg), 25 (8 deg), 24 (7 deg), 23 (6 deg), 22 (5 deg) and 2 more > 3 x" in r.message
    five = [1.0] * 10 + [4.0] * 5
    assert "and" not in _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(five)))[
        "pose_outliers"].message.split(" > ")[0]
    six = [2.0] * 20 + [7.0, 8.0, 9.0, 10.0, 11.0, 12.0]  # the stations' median 2 deg: the bound 6 deg
    r = _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(six)))["pose_outliers"]
    assert "25 (12 deg), 24 (11 deg), 23 (10 deg), 22 (9 deg), 21 (8 deg) and 1 more > 3 x the stations' median " \
           "2 deg = 6 deg: a bad measurement" in r.message
    two = [2.0] * 20 + [7.0, 8.0]
    assert _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=tuple(two)))["pose_outliers"].message\
        .startswith("outlying poses (0-based index, median residual of its pairs): 21 (8 deg), 20 (7 deg) > 3 x")
    # a zero or undefined median of the stations: nothing to compare with
    assert "pose_outliers" not in _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=(0.0, 0.0, 5.0)))
    assert "pose_outliers" not in _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=(math.nan,) * 3))


def test_outlying_poses_default_words_and_no_station_without_a_numpy_warning():
    """The default kind of a station's residual is its pairs' median; no finite station is no
    reason, without numpy's "Mean of empty slice" warning."""
    from replication.rig.quality import _outlying_poses

    r = _outlying_poses(np.array([1.0, 1.0, 1.0, 4.0]))
    assert r.message.startswith("outlying pose (0-based index, median residual of its pairs): 3 (4 deg)")
    own = _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=(1.0, 1.0, 1.0, 4.0),
                                       pose_residual_kind="its own residual"))["pose_outliers"]
    assert own.message.startswith("outlying pose (0-based index, its own residual): 3 (4 deg)")
    # a station without a measure (None) is left out of the stations' median, as a NaN one is
    r = _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=(1.0, None, 1.0, 1.0, 4.0)))["pose_outliers"]
    assert r.measured == 4.0 and r.message.startswith("outlying pose (0-based index, median residual of its pairs): "
                                                      "4 (4 deg) > 3 x the stations' median 1 deg")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _outlying_poses(np.full(3, np.nan)) is None
        assert "pose_outliers" not in _reasons(dataclasses.replace(CLEAN, pose_residual_medians_deg=(math.nan,) * 3))


def test_extra_reasons_join_and_the_worst_level_wins():
    extra = [Reason("input_mistake", "fail", 1.0, 2.0, "x")]
    v = judge(dataclasses.replace(CLEAN, n_pairs=20), extra)
    assert [r.check for r in v.reasons] == ["n_pairs", "input_mistake"] and v.level == "fail"
    assert judge(CLEAN, [None]).reasons == ()


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
    (0.01234, 0.01, False, "p = 0.012 >= the test's level 0.01"),   # two digits where they tell p from the level
    (0.01034, 0.01, False, "p = 0.0103 >= the test's level 0.01"),  # one more digit at a time, no more
    (0.01, 0.01, False, "p = 0.01 >= the test's level 0.01"),       # p at the level is not below it
    (0.01000004, 0.01, False, "p = 0.01 >= the test's level 0.01"),  # six digits at most
])
def test_a_p_value_is_printed_with_the_tests_level(p, level, significant, words):
    from replication.rig.quality import p_with_level

    assert p_with_level(p, level, significant) == words


def test_judge_levels_and_thresholds():
    good = Evidence(n_pairs=100, residual_median_deg=0.2, motion_median_deg=30.0, bootstrap_deg=0.1,
                    axis_spread_deg=10.0, offset_s=0.0, offset_correlation=0.99, max_offset_s=0.2,
                    offset_resolution_s=5e-4, blocks=100, overlap_s=100.0, interval_s=1.0)
    assert judge(good).level == "ok" and judge(good).reasons == ()
    import dataclasses

    warn = judge(dataclasses.replace(good, offset_correlation=0.8))
    assert warn.level == "warning" and warn.reasons[0].threshold == 0.9
    fail = judge(dataclasses.replace(good, bootstrap_deg=7.0, warnings=("AccuracyWarning",)))
    assert fail.level == "fail" and {r.check for r in fail.reasons} == {"bootstrap_deg", "solver_warning"}


def test_judge_tolerates_missing_residuals():
    e = dataclasses.replace(Evidence(n_pairs=12, residual_median_deg=None, motion_median_deg=None, bootstrap_deg=None),
                            radius_kind="curvature")
    # nothing to judge but the count of pairs: no error, and only that warning
    assert [(r.check, r.level) for r in judge(e).reasons] == [("n_pairs", "warning")]


class _Change:
    significant, split_time, n_before, n_after, p_value, difference_radius_deg = True, 10.0, 500, 500, 1e-6, 0.05
    level = 0.01
    R_before = R_after = np.eye(3)

    def __init__(self, angle_deg, significant=True):
        self.angle_deg, self.significant = angle_deg, significant



@pytest.mark.parametrize("ratio, flagged", [(2.99, False), (3.01, True)])
def test_outlying_station_threshold_boundary(ratio, flagged):
    medians = np.full(20, 0.4)
    medians[3] = ratio * 0.4
    e = Evidence(n_pairs=190, residual_median_deg=0.4, motion_median_deg=30.0, bootstrap_deg=0.1,
                 axis_spread_deg=10.0, pose_residual_medians_deg=tuple(medians))
    assert ("pose_outliers" in {r.check for r in judge(e).reasons}) is flagged



@pytest.mark.parametrize("motion, level", [(1.01, None), (0.99, "warning"), (0.51, "warning"), (0.49, "fail")])
def test_motion_median_threshold_boundaries(motion, level):
    e = Evidence(n_pairs=100, residual_median_deg=0.001, motion_median_deg=motion, bootstrap_deg=0.1,
                 axis_spread_deg=10.0)
    found = {r.check: r.level for r in judge(e).reasons}
    assert found.get("motion_median_deg") == level



@pytest.mark.parametrize("excitation, level", [(1.01, None), (0.99, "warning")])
def test_excitation_threshold_boundary(excitation, level):
    e = Evidence(n_pairs=100, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.1,
                 excitation_deg=excitation, radius_kind="curvature")
    found = {r.check: r.level for r in judge(e).reasons}
    assert found.get("excitation_deg") == level



@pytest.mark.parametrize("angle, significant, level", [
    (0.49, True, None), (0.51, True, "warning"), (0.74, True, "warning"), (0.76, True, "fail"), (5.0, False, None)])
def test_remount_threshold_boundaries(angle, significant, level):
    e = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.05,
                 axis_spread_deg=10.0, change=_Change(angle, significant))
    assert {r.check: r.level for r in judge(e).reasons}.get("remount_deg") == level



@pytest.mark.parametrize("fit, reported", [(0.29, True), (0.3, True), (0.31, False)])
def test_a_change_is_a_remount_only_where_each_side_fits_its_own_estimate(fit, reported):
    """An input mistake leaves both halves unfit and their estimates apart: that is not a re-mount
    (the residual reasons say what it is); the bound is residual_to_motion's fail bound, which still
    fits."""
    e = Evidence(n_pairs=1000, residual_median_deg=0.1, motion_median_deg=30.0, bootstrap_deg=0.05,
                 axis_spread_deg=10.0, change=_Change(2.0), change_sides_fit=fit)
    assert ("remount_deg" in {r.check for r in judge(e).reasons}) is reported
    assert THRESHOLDS["residual_to_motion"][1] == 0.3



def test_the_mirror_ratio_threshold_at_its_boundary():
    bound = THRESHOLDS["mirror_fit_ratio"][0]
    kw = dict(n_pairs=100, residual_median_deg=0.1, motion_median_deg=20.0, bootstrap_deg=0.05)
    below = judge(Evidence(**kw, mirror_fit_ratio=bound * (1 - 1e-9), mirror_normal=(0.0, 0.352, 0.936)))
    assert [(x.check, x.level) for x in below.reasons] == [("mirror_fit_ratio", "warning")]
    assert "little about its normal (about [0.0, 0.35, 0.94], sensor frame); rotate" in below.reasons[0].message
    assert judge(Evidence(**kw, mirror_fit_ratio=bound)).reasons == ()
