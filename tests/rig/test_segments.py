"""The segment test and the clock jumps (replication.rig.segments): segments that agree are not
named, a stretch mounted otherwise is named with its times and left out by ``use="consistent"``, the
verdict's angle bounds hold at their boundaries, calibrate gives one verdict at intervals 0.5, 1 and
2 s on a lost-tracking rig, a clock jump is found with its time and size, and no jump is not. The
rigs are :func:`replication.testing.noisy_rig` (camera 20 Hz, gyro 200 Hz, smooth three-axis
motion), as in benchmarks/bench_changepoint.py and bench_segments.py."""
import dataclasses
import warnings

import numpy as np
import pytest

from replication.core import so3
from replication.rig.calibration import calibrate
from replication.rig.changepoint import remounted
from replication.rig.clock import clock_segments, jump_candidates
from replication.rig.quality import THRESHOLDS
from replication.rig.segments import (
    MAX_LEFT_OUT_SHARE,
    Segment,
    SegmentTest,
    reasons,
    segment_test,
)
from replication.rig.streams import OrientationStream, integrate_gyro
from replication.testing import RIG_R0 as R0
from replication.testing import camera_lost, clock_jumped, noisy_rig, rig_pairs, samples_lost

WARN, FAIL = THRESHOLDS["remount_deg"]
STEP = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))


def _cal(camera, sensor, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, sensor, **{"n_bootstrap": 30, "diagnose": False, **kw})


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_segments_that_agree_are_not_named(seed):
    A, B, t, block = rig_pairs(*noisy_rig(seed, 60, 0.05, 0.005))
    r = segment_test(A, B, t, block=block)
    assert len(r.segments) == 5 and not r.disagreeing, r.summary()
    assert r.consistent == tuple(range(5)) and r.max_angle_deg == 0.0
    assert r.between_radius_deg >= r.pairs_radius_deg > 0
    for s in r.segments:
        assert so3.angle_between_deg(s.R, R0) < 3 * s.radius_deg + 0.05


def test_a_stretch_mounted_otherwise_is_named_and_left_out():
    camera, gyro = noisy_rig(21, 60, 0.05, 0.005)
    gyro = remounted(remounted(gyro, 24.0, STEP), 36.0, STEP.T)  # 2 deg off from 24 to 36 s
    A, B, t, block = rig_pairs(camera, gyro)
    r = segment_test(A, B, t, block=block)
    assert r.significant and r.p_value < 1e-6, r.summary()
    bad = [r.segments[i] for i in r.disagreeing]
    assert bad and all(s.end_s > 24.0 and s.start_s < 36.0 for s in bad), r.summary()
    assert max(s.angle_deg for s in bad) > FAIL
    assert all(r.segments[i].end_s <= 24.0 + 1.0 or r.segments[i].start_s >= 36.0 - 1.0 for i in r.consistent)
    assert r.between_radius_deg > r.pairs_radius_deg


def _fake(angle):
    seg = [Segment(10.0 * i, 10.0 * (i + 1), 180, R0, 0.1, angle if i == 1 else 0.05, 30.0 if i == 1 else 1.0,
                   1e-9 if i == 1 else 0.5, i == 1) for i in range(4)]
    return SegmentTest(tuple(seg), True, 9.0, 2.0, 1e-8, 0.01, 9, 1.0, 50.0, R0, 0.05, 0.2, (0, 2, 3),
                       angle)


@pytest.mark.parametrize("angle, level", [(0.05, "warning"), (WARN, "warning"), (FAIL - 0.01, "warning"),
                                          (FAIL + 0.01, "fail")])
def test_the_verdict_follows_the_angle_of_the_disagreeing_segment(angle, level):
    (r,) = reasons(_fake(angle), 0.0)
    assert r.check == "segments_disagree" and r.level == level and r.measured == pytest.approx(angle)
    assert "10.0-20.0 s" in r.message and "use='consistent'" in r.message and "0.0-10.0 s, 20.0-40.0 s" in r.message
    assert r.threshold == (FAIL if level == "fail" else 0.0)


@pytest.mark.parametrize("p_segment, bonferroni", [(0.01 / 4 * 0.96, True), (0.01 / 4 * 1.04, False)])
@pytest.mark.parametrize("p_whole", [0.87, 1e-8])
def test_segments_disagree_says_which_test_carries_the_verdict(p_whole, p_segment, bonferroni):
    """A segment named by its own test while the test of all the segments together is not
    significant (p 0.87) says so; the Bonferroni bound is said only where every named segment's own
    p is below it (level 0.01 over 4 segments)."""
    test = _fake(1.0)
    segs = tuple(dataclasses.replace(s, p_value=p_segment) if s.disagrees else s for s in test.segments)
    test = dataclasses.replace(test, segments=segs, significant=p_whole < 0.01, p_value=p_whole)
    (r,) = reasons(test, 0.0)
    assert f"10.0-20.0 s by 1.00 deg (its radius 0.10, its own test p = {p_segment:.2g})" in r.message
    assert "each by its own test against the consistent part" in r.message
    assert ("p below 0.01 / 4 segments = 0.0025" in r.message) == bonferroni
    assert ("left out of it one by one" in r.message) == (not bonferroni)
    assert f"the test of all the segments together: p = {p_whole:.2g}" in r.message
    assert ("not significant alone (level 0.01)" in r.message) == (p_whole > 0.01)
    assert "the segments' test p" not in r.message
    summary = test.summary()
    assert ("agree within their noise as a whole" in summary) == (p_whole > 0.01)
    assert "disagreeing by their own tests: 10.0-20.0 s (1.00 deg)" in summary
    (r,) = reasons(dataclasses.replace(test, consistent=()), 0.0)  # no half agrees: no consistent part
    assert "each by its own test against the others" in r.message and "no half of the segments agrees" in r.message


def test_segments_that_agree_give_no_reason():
    test = _fake(0.3)
    test = SegmentTest(tuple(dataclasses.replace(s, disagrees=False) for s in test.segments),
                       *[getattr(test, f.name) for f in dataclasses.fields(test)][1:])
    assert reasons(test, 0.0) == []


def test_one_verdict_at_three_intervals_on_a_lost_tracking_rig_and_the_consistent_part():
    camera, gyro = noisy_rig(0, 180.0, 0.05, 0.005)  # bench_segments' lost_rig(0)
    camera = camera_lost(camera, np.random.default_rng(10 ** 6), 1.0, 46.0)
    results = [_cal(camera, gyro, interval=iv) for iv in (0.5, 1.0, 2.0)]
    assert len({r.verdict.level for r in results}) == 1 and results[0].verdict.level == "fail"
    seg = results[1].to_dict()["segments"]
    assert seg["run"] and seg["interval_s"] == 1.0 and seg["disagreeing"]
    assert all(seg["segments"][i]["end_s"] <= 46.0 + 11.0 for i in seg["disagreeing"])  # inside the lost stretch
    assert any(r.check == "segments_disagree" for r in results[1].verdict.reasons)
    c = _cal(camera, gyro, use="consistent")
    used = c.segments["use"]
    assert used["kept_s"] > 0.5 * 179 and used["dropped_s"] > 0 and used["pairs_kept"] == c.n_pairs
    assert c.n_pairs < results[1].n_pairs
    (why,) = [r for r in c.verdict.reasons if r.check == "segments_consistent_part"]
    assert why.level == "warning" and "consistent part only" in why.message
    assert c.verdict.level == "warning"  # the change test runs on the part used: the lost stretch fails it no more
    assert so3.angle_between_deg(c.R, R0) < so3.angle_between_deg(results[1].R, R0)
    assert "use='consistent': R0 from " in c.summary()


def test_use_is_checked():
    camera, gyro = noisy_rig(1, 30, 0.05, 0.005)
    with pytest.raises(ValueError, match="use must be 'all' or 'consistent'"):
        calibrate(camera, gyro, use="best")


@pytest.mark.parametrize("size, lost, found", [(0.0, 0, False), (0.001, 0, False), (0.0, 1, False), (0.0, 20, False),
                                               (0.03, 0, True), (0.1, 0, True)])
def test_a_clock_jump_is_found_with_its_time_and_size(size, lost, found):
    camera, gyro = noisy_rig(101, 60, 0.05, 0.005)
    jumped = clock_jumped(gyro, 30.0, size)
    sensor = integrate_gyro(samples_lost(jumped, 30.0, lost) if lost else jumped)
    parts, jumps = clock_segments(camera, sensor, gaps=jump_candidates(sensor.t))
    assert bool(jumps) == found, (parts, jumps)
    if found:
        (j,) = jumps
        assert abs(j.time_s - 30.0) < 0.02 and j.size_s == pytest.approx(size, abs=0.004) and j.at_gap


def test_a_clock_jump_fails_calibrate_naming_it():
    camera, gyro = noisy_rig(102, 60, 0.05, 0.005)
    r = _cal(camera, clock_jumped(gyro, 30.0, 0.03))
    (why,) = [x for x in r.verdict.reasons if x.check == "clock_jump"]
    assert why.level == "fail" and "at 30.0 s by +" in why.message and "ms" in why.message
    (j,) = r.segments["clock_jumps"]
    assert abs(j["time_s"] - 30.0) < 0.02 and j["size_s"] == pytest.approx(0.03, abs=0.005)


@pytest.mark.parametrize("kwargs, message", [({"segment_s": -1.0}, "segment_s must be a positive"),
                                             ({"segment_s": 25.0}, "too short for a segment test")])
def test_bad_parameters_are_named(kwargs, message):
    A, B, t, block = rig_pairs(*noisy_rig(3, 60, 0.05, 0.005))
    with pytest.raises(ValueError, match=message):
        segment_test(A, B, t, block=block, **kwargs)


def test_the_command_line_takes_use_consistent():
    import argparse

    from replication.cli.calibrate import add_parser

    cal = add_parser(argparse.ArgumentParser().add_subparsers())
    base = ["--camera", "c.txt", "--sensor", "s.txt"]
    assert cal.parse_args(base).use == "all" and cal.parse_args([*base, "--use", "consistent"]).use == "consistent"
    with pytest.raises(SystemExit):
        cal.parse_args([*base, "--use", "best"])


def test_the_consistent_part_keeps_the_pairs_inside_it():
    from replication.rig.segments import consistent_mask

    test = _fake(1.0)  # segments 0-10, 10-20 (disagrees), 20-30, 30-40 s; the consistent part 0-10 and 20-40 s
    assert test.used_spans() == [[0.0, 10.0], [20.0, 40.0]]
    t = np.array([0.0, 8.9, 9.1, 10.0, 19.5, 20.0, 38.9, 39.5, 39.9])
    # a pair that ends past its span is out, but the last segment's pairs run one analysis interval
    # past its start
    assert consistent_mask(test, t, 1.0).tolist() == [True, True, False, False, False, True, True, True, True]
    assert consistent_mask(test, t, 2.0).tolist() == [True, False, False, False, False, True, True, False, False]


@pytest.mark.parametrize("share, angle, level", [
    (MAX_LEFT_OUT_SHARE - 0.01, FAIL + 0.5, "warning"),   # a short stretch left out: the majority kept
    (MAX_LEFT_OUT_SHARE + 0.01, FAIL + 0.5, "fail"),      # much left out, far off: which part is right is unknown
    (MAX_LEFT_OUT_SHARE + 0.01, FAIL - 0.01, "warning"),  # much left out, but within the fail bound
])
def test_the_consistent_part_fails_when_much_is_left_out_and_it_disagrees_beyond_the_fail_bound(share, angle, level):
    total = 100.0
    used = {"kept_s": total * (1 - share), "dropped_s": total * share, "pairs_kept": 50}
    (r,) = reasons(_fake(angle), 0.0, used)
    assert r.check == "segments_consistent_part" and r.level == level
    assert r.measured == pytest.approx(share) and r.threshold == pytest.approx(MAX_LEFT_OUT_SHARE)
    assert "majority" in r.message and f"{angle:.2f} deg" in r.message
    assert ("calibrate each on its own" in r.message) == (level == "fail")


# --------------------------------------------------------------------------------------------------
# The clocks (replication.rig.clock): a step of the clock without a skip in the stamps and a jump of
# the camera's


def test_use_consistent_keeping_a_wrong_majority_says_which_seconds_and_by_how_much_not_that_it_is_right():
    from replication.core import so3

    camera, gyro = noisy_rig(8200, 90.0, 0.05, 0.005)
    off = so3.matrix_from_rotation_vector(np.radians([1.5, 0.0, 0.0]))
    wrong = np.where((camera.t >= 25.0)[:, None, None], camera.world_from_body @ off, camera.world_from_body)
    r = _cal(OrientationStream(camera.t, wrong, "camera"), gyro, use="consistent", n_bootstrap=0)
    assert so3.angle_between_deg(r.R, R0) > 1.2  # the wrong majority (72 % of the recording) was kept
    (why,) = [x for x in r.verdict.reasons if x.check == "segments_consistent_part"]
    assert why.level == "warning" and why.measured < 1 / 3
    used = r.segments["use"]
    kept, left = used["kept_spans_s"], used["left_out_spans_s"]
    assert kept[0][0] < 30.0 and kept[-1][1] > 80.0 and left[0][0] == pytest.approx(0.0, abs=0.1)
    assert f"left out: {left[0][0]:.1f}-{left[0][1]:.1f} s" in why.message
    moves = used["R0_moves_deg_if_left_out_part_is_right"]
    assert moves == pytest.approx(1.5, abs=0.3)  # the claim: R0's error if the part left out is the right one
    assert f"R0 moves by {moves:.2f} deg" in why.message and "not known to be the right one" in why.message
    text = " ".join(x.message for x in r.verdict.reasons) + " ".join(r.summary().splitlines())
    assert "is the right one" not in text.replace("if the part left out is the well-tracked one", "")
    assert "not known to be right" in r.summary()
