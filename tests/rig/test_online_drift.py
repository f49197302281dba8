"""One event per cause: a frame that drifts is one ``drift`` event with its rate, followed, its
lag in the radius, its rate measured again on the estimate's track and its end said; each rule of
:mod:`replication.rig.online_drift` at its boundary."""
import math
from collections import deque
from types import SimpleNamespace

import numpy as np
import pytest

from conftest import drift_pairs
from replication.core import so3
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.rig.online_drift import (
    DRIFT_COS,
    DRIFT_LAG_SHARE,
    DRIFT_MAX_STEP_DEG,
    DRIFT_WITHIN_PAIRS,
    TRACK_APART,
    TRACK_Z,
    drift_lag_deg,
    follow_forgetting,
    recognise_drift,
    track_drift,
)
from replication.rig.online_events import EVENT_KINDS, OnlineEvent
from replication.rig.streams import OrientationStream
from replication.study.live_study import pair_stream
from replication.testing import rig_streams

AXIS = np.array([0.6, 0.0, 0.8])


# --------------------------------------------------------------------------------------------------
# One event per cause: a frame that drifts is one ``drift`` event with its rate, not a storm of
# re-mounts; the estimator starts over at most once for it and then follows it (or says it cannot),
# its radius holding the lag; the rules of :func:`replication.rig.online_drift.recognise_drift` at
# their boundaries.


def _drifting(seed, n, total_deg, noise_deg=0.05):
    """``n`` pairs whose camera_from_sensor turns by ``total_deg`` about AXIS, uniformly over the
    stream."""
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    Rt = lambda j: R0 @ so3.matrix_from_rotation_vector(np.radians(total_deg * j / n) * AXIS)  # noqa: E731
    A, B = zip(*[[x[0] for x in pair_stream(rng, 1, Rt(j), noise_deg=noise_deg)] for j in range(n)])
    return Rt, np.array(A), np.array(B)


def test_the_kinds_and_constants():
    assert EVENT_KINDS == ("remount", "noise_change", "outliers", "new_information", "drift", "drift_end", "clock_jump")
    assert (DRIFT_WITHIN_PAIRS, DRIFT_COS, DRIFT_MAX_STEP_DEG, DRIFT_LAG_SHARE) == (2000, 0.7, 3.0, 0.25)


@pytest.mark.parametrize("noise_deg", [0.05, 0.2])
def test_a_frame_wandering_2_deg_is_one_drift_event_with_its_rate_and_no_restart(noise_deg):
    """2 deg over 1800 pairs: was 5 re-mounts at 0.05 deg of noise (31 in the held-out campaign's
    live case), each a restart; now one drift event, its slope found before the first re-mount
    (:mod:`replication.rig.online_creep`) so that re-mount is the drift's first step, no restart,
    never ready while wrong."""
    Rt, A, B = _drifting([41, int(noise_deg * 100)], 1800, 2.0, noise_deg)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    drifts = [e for e in oc.events if e.kind == "drift"]
    assert len(drifts) == 1 and [e.kind for e in oc.events if e.kind != "outliers"] == ["drift"]
    assert sum(s.alarm for s in states) == 0 and oc.alarms == []  # followed from its first step
    assert drifts[0].rate_deg_per_pair == pytest.approx(2.0 / 1800, rel=0.3)
    assert "the frame drifts" in drifts[0].message and "R0 crept" in drifts[0].message
    assert not any(s.ready and so3.angle_between_deg(s.R, Rt(j)) > oc.target_deg for j, s in enumerate(states))
    assert sum(s.ready for s in states) > 0.7 * len(states)
    assert oc.error_deg(Rt(1799)) < 0.3


def test_while_following_the_radius_holds_the_lag():
    Rt, A, B = _drifting([42, 0], 900, 2.0)
    oc = OnlineCalibrator()
    oc.update_many(A, B)
    drift = next(e for e in oc.events if e.kind == "drift")
    lag = drift_lag_deg(drift.rate_deg_per_pair, oc.forgetting, oc.refine_every)  # the event's rate: the one followed
    assert oc.forgetting < 1.0 and lag > 0 and oc.radius > lag
    assert lag == pytest.approx(DRIFT_LAG_SHARE * oc.target_deg, rel=1e-6)  # the memory chosen for a quarter


def test_an_outlier_burst_while_a_drift_is_followed_is_its_own_event_and_the_drift_event_stays():
    """Eight random camera motions at pairs 800-807 of a drift followed since pair 117, decided at
    pair 813: not a re-mount (today ``new_information``: the window's pairs that fit, fit the frame
    now better than the lagging estimate; see the strict xfail below), so not the drift's next step
    (the drift checks read re-mounts only); another onset, so the drift event stays; and after it
    the detector's reference restarts at the refined estimate, so the pairs after it raise no more
    alarms. The radius covers the error the burst leaves and nothing is ready while wrong."""
    Rt, A, B = _drifting([42, 0], 900, 2.0)
    A[800:808] = so3.random_rotations(np.random.default_rng(3), 8)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    (drift, burst) = oc.events
    assert (drift.kind, drift.pair, drift.onset_pair) == ("drift", 117, 4)
    assert (burst.pair, burst.onset_pair) == (813, 800) and burst.kind in ("new_information", "outliers")
    assert [s.event for s in states if s.event] == ["drift", burst.kind] and oc.alarms == []
    assert oc.forgetting < 1.0 and oc.events[0].rate_deg_per_pair > 0  # the drift still followed
    assert states[-1].radius_deg >= oc.error_deg(Rt(899))
    assert not any(s.ready and so3.angle_between_deg(s.R, Rt(j)) > oc.target_deg for j, s in enumerate(states))


def test_an_outlier_burst_while_a_drift_is_followed_is_kept_out():
    """The burst above: its eight random camera motions fit neither the estimate nor the window's
    own rotation (``d^2`` far above cap times the level at both). When the lagging estimate makes
    the window new information, only the pairs that fit the window's own rotation are added: adding
    every pair knocked the estimate 8.3 deg off (1.2 deg at the end). Bursts of 8 random camera
    motions at pairs 500-799 of this drift (``_drifting([90, s], 900, 2.0)``): new_information in 1
    of 30 (s = 0-29), confirmed on fresh seeds s = 30-89: 1 of 60 (Wilson 95 % 0.3-8.9 %)."""
    Rt, A, B = _drifting([42, 0], 900, 2.0)
    A[800:808] = so3.random_rotations(np.random.default_rng(3), 8)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    burst = oc.events[-1]
    assert burst.pairs_dropped >= 8 and oc.pairs_dropped >= 8
    if burst.kind == "new_information":
        assert f"added; {burst.pairs_dropped} pairs that do not fit it kept out" in burst.message
    assert max(so3.angle_between_deg(s.R, Rt(j)) for j, s in enumerate(states) if j >= 800) < oc.target_deg


def test_a_drift_too_fast_to_follow_is_said_and_not_ready():
    """60 deg over 600 pairs (0.1 deg per pair): the shortest memory lags more than the target."""
    Rt, A, B = _drifting([43, 0], 600, 60.0, noise_deg=0.2)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    drifts = [e for e in oc.events if e.kind == "drift"]
    assert len(drifts) == 1 and sum(s.alarm for s in states) == 1
    assert "too fast to follow within 0.5 deg" in drifts[0].message
    assert not any(s.ready for s in states[drifts[0].pair:])


def test_two_remounts_in_different_directions_are_two_remounts(rng):
    R0 = so3.random_rotations(rng, ())
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(2.0) * AXIS)
    # perpendicular to the first step
    R2 = R1 @ so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.0, 1.0, 0.0]))
    parts = [pair_stream(rng, 250, R, noise_deg=0.2) for R in (R0, R1, R2)]
    oc = OnlineCalibrator()
    oc.update_many(np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
    assert [e.kind for e in oc.events] == ["remount", "remount"] and len(oc.alarms) == 2
    assert oc.error_deg(R2) < 0.2


def test_a_wandering_camera_frame_live_is_one_drift_with_its_rate_in_deg_per_s():
    seconds, total = 600.0, 2.0
    R0, camera, gyro, _ = rig_streams(seconds, rng=np.random.default_rng(44), camera_noise_deg=0.05,
                                      gyro_noise_deg_s=0.05)
    phi = np.radians(total) * camera.t / seconds
    # camera_from_sensor R0 exp(phi AXIS)
    C = camera.world_from_body @ R0 @ so3.matrix_from_rotation_vector(-np.outer(phi, AXIS)) @ R0.T
    rows = replay(OrientationStream(camera.t, C, "camera"), gyro, OnlineCalibrator(), diagnose=False)
    events = rows.attrs["summary"]["events"]
    assert [e["kind"] for e in events] == ["drift"] and int(rows["alarm"].sum()) == 0  # its slope found first
    assert events[0]["rate_deg_s"] == pytest.approx(total / seconds, rel=0.3)
    assert rows["ready"].iloc[-1] and rows["ready"].mean() > 0.6


# ------------------------------------------------------------------------------------------------
# the rules

def _event(pair, R_before, R_after):
    return OnlineEvent("remount", pair, pair - 10, "drift", pair - 20, 25, 0.0, 0.1, 3.0, 1.0, 0, R_before, R_after,
                       "m")


def _steps(first_deg, second_deg, cos, gap=100):
    """A re-mount by ``first_deg`` about x at pair 100, then one by ``second_deg`` whose axis makes
    ``cos`` with x."""
    R = np.eye(3)
    R1 = so3.matrix_from_rotation_vector(np.radians(first_deg) * np.array([1.0, 0.0, 0.0]))
    axis = np.array([cos, math.sqrt(max(0.0, 1.0 - cos * cos)), 0.0])
    R2 = R1 @ so3.matrix_from_rotation_vector(np.radians(second_deg) * axis)
    first = _event(100, R, R1)
    return (100, R1, first), _event(100 + gap, R1, R2)


@pytest.mark.parametrize("cos, following, drift", [
    (DRIFT_COS + 1e-6, None, True), (DRIFT_COS - 1e-6, None, False),
    (1e-6, 1e-3, True), (-1e-6, 1e-3, False),
])
def test_a_drift_continues_in_the_direction_so_far(cos, following, drift):
    last, event = _steps(0.3, 0.3, cos)
    assert (recognise_drift(last, event, following) is not None) is drift


@pytest.mark.parametrize("gap, drift", [(DRIFT_WITHIN_PAIRS, True), (DRIFT_WITHIN_PAIRS + 1, False), (0, False)])
def test_a_drift_continues_within_its_pairs(gap, drift):
    last, event = _steps(0.3, 0.3, 1.0, gap=gap)
    assert (recognise_drift(last, event, None) is not None) is drift


@pytest.mark.parametrize("first, second, following, drift", [
    (0.3, 0.999 * DRIFT_MAX_STEP_DEG, None, True), (0.3, 1.001 * DRIFT_MAX_STEP_DEG, None, False),
    (1.001 * DRIFT_MAX_STEP_DEG, 0.3, None, False), (1.001 * DRIFT_MAX_STEP_DEG, 0.3, 1e-3, True),
    (0.3, 1.001 * DRIFT_MAX_STEP_DEG, 1e-3, False),  # following at 1e-3 deg per pair: 100 pairs move 0.1 deg
    (0.3, 4.0, 0.02 * 1.001, True), (0.3, 4.0, 0.02 * 0.999, False),  # 100 pairs at 0.02: 2 deg, twice that 4 deg
])
def test_a_drift_moves_in_small_steps(first, second, following, drift):
    last, event = _steps(first, second, 1.0)
    assert (recognise_drift(last, event, following) is not None) is drift


def test_the_drift_rate_is_between_the_windows_own_estimates():
    last, event = _steps(0.3, 0.4, 1.0, gap=200)
    rate, angle, first, axis = recognise_drift(last, event, None)
    assert angle == pytest.approx(0.4) and rate == pytest.approx(0.4 / 200) and first == 100
    assert np.allclose(axis, [1.0, 0.0, 0.0])
    assert recognise_drift(None, event, None) is None


@pytest.mark.parametrize("rate", [1e-4, 1e-3, 5e-3])
def test_the_memory_keeps_the_lag_at_a_quarter_of_the_target(rate):
    lam = follow_forgetting(rate, 0.5, 0.8, 10)
    assert drift_lag_deg(rate, lam, 10) == pytest.approx(DRIFT_LAG_SHARE * 0.5, rel=1e-9)


def test_the_memory_is_never_shorter_than_the_distinct_pairs_allow():
    assert follow_forgetting(0.1, 0.5, 0.8, 10) == 0.8  # the quarter would need a negative memory
    assert follow_forgetting(0.1 / 9.0, 0.5, 0.8, 10) == 0.8  # memory 1.25 pairs < 4 (lowest 0.8): clamped
    assert follow_forgetting(1e-15, 0.5, 0.8, 10) == 1.0 - 1e-9


# --------------------------------------------------------------------------------- a drift followed
def _cubic(seed, n=1800, total_deg=6.0, noise_deg=0.1):
    """A drift that speeds up: ``total_deg (j / n)^3`` about AXIS (rate at the end ``3 total_deg /
    n``)."""
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    Rt = lambda j: R0 @ so3.matrix_from_rotation_vector(np.radians(total_deg * (j / n) ** 3) * AXIS)  # noqa: E731
    A, B = zip(*[[x[0] for x in pair_stream(rng, 1, Rt(j), noise_deg=noise_deg)] for j in range(n)])
    return Rt, np.array(A), np.array(B)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_drift_that_speeds_up_is_followed_at_its_current_rate(seed):
    """6 deg * (j / 1800)^3 at 0.1 deg of noise (a case once found: ready while wrong on 92, 101 and
    63 pairs of seeds [71, 0/1/2], the rate reported stale: a third of the final one): the rate is
    measured again on the estimate's track, the forgetting and the lag follow it; never ready while
    wrong, the rate within 25 % of the final one."""
    Rt, A, B = _cubic([71, seed])
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    drifts = [e for e in oc.events if e.kind == "drift"]
    assert len(drifts) == 1 and sum(s.alarm for s in states) <= 1
    assert not any(s.ready and so3.angle_between_deg(s.R, Rt(j)) > oc.target_deg for j, s in enumerate(states))
    assert drifts[0].rate_deg_per_pair == pytest.approx(3 * 6.0 / 1800, rel=0.25)
    assert "rate now" in drifts[0].message


def test_a_drift_that_stops_is_said_and_full_memory_returns():
    """2 deg over 1200 pairs, then still for 1800 (a case once found: it kept forgetting, about 28
    effective pairs, and advised a longer recording): one ``drift`` and one ``drift_end`` within 500
    pairs of the stop, forgetting back to 1, the effective pairs growing again."""
    rng = np.random.default_rng([72, 0])
    R0 = so3.random_rotations(rng, ())
    Rt = lambda j: R0 @ so3.matrix_from_rotation_vector(np.radians(2.0 * min(j, 1200) / 1200) * AXIS)  # noqa: E731
    A, B = zip(*[[x[0] for x in pair_stream(rng, 1, Rt(j), noise_deg=0.05)] for j in range(3000)])
    oc = OnlineCalibrator()
    states = oc.update_many(np.array(A), np.array(B))
    kinds = [e.kind for e in oc.events if e.kind != "outliers"]
    assert kinds == ["drift", "drift_end"] and sum(s.alarm for s in states) == 0  # its slope found first
    end = oc.events[-1]
    assert 1200 < end.pair < 1700 and end.rate_deg_per_pair == 0.0 and states[end.pair].event == "drift_end"
    assert "stopped" in end.message and "full memory" in end.message
    assert oc.forgetting == 1.0 and oc.effective_pairs > 1000 and oc.error_deg(Rt(2999)) < 0.05
    assert not any(s.ready and so3.angle_between_deg(s.R, Rt(j)) > oc.target_deg for j, s in enumerate(states))


def _tracked(moved_deg, span=400, rate=0.001, sd_deg=0.02):
    """A calibrator-like record following a drift at ``rate`` whose estimate moved ``moved_deg``
    along its axis in ``span`` pairs, the estimate's noise ``sd_deg`` along the axis (lag
    excluded)."""
    from types import SimpleNamespace

    from replication.rig.online_drift import track_drift

    axis = AXIS / np.linalg.norm(AXIS)
    lam = 0.99
    lag = math.radians(drift_lag_deg(rate, lam, 10))
    R = so3.matrix_from_rotation_vector(np.radians(moved_deg) * axis)
    cal = SimpleNamespace(n_total=1000 + span, _R=R, forgetting=lam, _drift_rate=rate, _drift_axis=axis,
                          _cov=np.eye(3) * math.radians(sd_deg) ** 2 + lag ** 2 * np.outer(axis, axis),
                          refine_every=10, target_deg=0.5, min_pairs=10, _fgt=1.0, centroid=1000.0 + span,
                          _last_step=None)
    cal.events = [OnlineEvent("drift", 900, 900, "cusum", 500, 25, 0.4, 0.3, 1.0, 1.0, 0, np.eye(3), np.eye(3),
                              "the frame drifts", rate)]
    from collections import deque
    cal._track = deque([(1000, np.eye(3), cal._cov)])  # (pair, estimate, its covariance)
    return cal, track_drift(cal)


def test_the_track_needs_a_memory_and_a_half_of_pairs():
    from replication.rig.online_drift import TRACK_MEMORIES, TRACK_MIN_PAIRS, TRACK_Z

    assert (TRACK_MEMORIES, TRACK_MIN_PAIRS, TRACK_Z) == (1.5, 100, 3.0)
    span = math.ceil(1.5 * 1.99 / 0.01)  # (1 + lambda) / (1 - lambda) at lambda 0.99: 199 pairs
    cal, _ = _tracked(0.0, span=span - 1, sd_deg=0.01)
    assert cal._drift_rate == 0.001  # not measured yet
    cal, kind = _tracked(0.0, span=span, sd_deg=0.01)
    assert kind == "drift_end"


@pytest.mark.parametrize("z, changed", [(2.99, False), (3.01, True)])
def test_a_new_rate_beyond_three_standard_errors(z, changed):
    se = math.sqrt(2) * 0.02
    cal, kind = _tracked(0.001 * 400 + z * se)
    assert kind is None and (cal._drift_rate != 0.001) is changed and cal.forgetting != 1.0
    if changed:
        assert cal._drift_rate == pytest.approx((0.4 + z * se) / 400, rel=1e-6)


@pytest.mark.parametrize("share, ended", [(0.49, True), (0.51, False)])
def test_a_drift_ends_nearer_none_than_its_rate(share, ended):
    cal, kind = _tracked(share * 0.001 * 400, sd_deg=0.01)
    assert (kind == "drift_end") is ended and (cal._drift_rate is None) is ended
    assert (cal.forgetting == 1.0) is ended


def test_the_direction_so_far_ends_at_the_estimate_not_at_the_last_window():
    """The last step's window estimate is a few pairs (seed [36, 4] of a slow drift: 0.28 deg off,
    its direction at a cosine of 0.57 with the next step's: two re-mounts, two restarts); the
    estimate before the new event holds many: the movement so far ends there. Here the window was 60
    deg off the drift's axis, the estimate on it."""
    x = np.array([1.0, 0.0, 0.0])
    # the window: cosine 0.5 with x
    noisy = so3.matrix_from_rotation_vector(np.radians(0.3) * np.array([0.5, math.sqrt(0.75), 0.0]))
    first = _event(100, np.eye(3), noisy)
    now = so3.matrix_from_rotation_vector(np.radians(0.6) * x)      # the estimate before the next event: along x
    event = _event(700, now, now @ so3.matrix_from_rotation_vector(np.radians(0.3) * x))
    assert recognise_drift((100, noisy, first), event, None) is not None
    # the estimate itself off the step
    off = so3.matrix_from_rotation_vector(np.radians(0.6) * np.array([0.5, math.sqrt(0.75), 0.0]))
    assert recognise_drift((100, noisy, first), _event(700, off,
                                                       off @ so3.matrix_from_rotation_vector(np.radians(0.3) * x)),
                           None) is None


def test_the_report_schema_names_every_kind():
    import json
    from pathlib import Path

    schema = json.loads((Path(__file__).parents[2] / "docs" / "calibration_report.schema.json").read_text())
    found = []

    def walk(node):
        if isinstance(node, dict):
            if "enum" in node and "remount" in node["enum"]:
                found.append(tuple(node["enum"]))
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)

    walk(schema)
    assert found == [EVENT_KINDS]


# --------------------------------------------------------------------------------------------------
# the drift's end on the estimates' centroids (point 2) and the live gyro bias


TRACK_AXIS = np.array([0.6, -0.48, 0.64])


def test_a_steady_drift_is_not_said_to_end():
    """0.002 deg per pair for 1500 pairs at 0.3 deg of pair noise (seed 20000 of a reproducer said
    ``drift_end`` 220 pairs after the drift was recognised): followed, never ended."""
    A, B = drift_pairs(20000)
    cal = OnlineCalibrator()
    cal.update_many(A, B)
    kinds = [e.kind for e in cal.events]
    assert "drift" in kinds and "drift_end" not in kinds


def _tracked_centroid(moved_deg, sd_deg, span=400, rate=0.001):
    """A calibrator-like record following a drift at ``rate``; its estimate moved ``moved_deg``
    along the drift's axis over ``span`` pairs of centroid, its noise ``sd_deg`` along the axis."""
    axis = TRACK_AXIS / np.linalg.norm(TRACK_AXIS)
    lam = 0.99
    lag = math.radians(drift_lag_deg(rate, lam, 10))
    cov = np.eye(3) * math.radians(sd_deg) ** 2 + lag ** 2 * np.outer(axis, axis)
    cal = SimpleNamespace(n_total=1000 + span, centroid=1000.0 + span,
                          _R=so3.matrix_from_rotation_vector(np.radians(moved_deg) * axis),
                          forgetting=lam, _drift_rate=rate, _drift_axis=axis, _cov=cov, refine_every=10,
                          target_deg=0.5, min_pairs=10, _fgt=1.0, _last_step=None)
    cal.events = [OnlineEvent("drift", 900, 900, "cusum", 500, 25, 0.4, 0.3, 1.0, 1.0, 0, np.eye(3), np.eye(3),
                              "the frame drifts", rate)]
    cal._track = deque([(1000.0, np.eye(3), cal._cov)])
    return cal, track_drift(cal)


@pytest.mark.parametrize("factor, ended", [(1.01, False), (0.99, True)])
def test_an_end_waits_until_none_and_the_rate_are_far_enough_apart(factor, ended):
    """Nothing moved in 400 pairs at 0.001 deg per pair (0.4 deg): said to end only if 0.4 deg is at
    least TRACK_APART x Z standard errors of the two estimates' difference; below that the track
    waits (no new rate)."""
    assert TRACK_APART == 3.0
    se = 0.4 / (TRACK_APART * TRACK_Z) * factor
    cal, kind = _tracked_centroid(0.0, sd_deg=se / math.sqrt(2))
    assert (kind == "drift_end") is ended and (cal._drift_rate is None) is ended
    assert len(cal._track) == (1 if ended else 2)
