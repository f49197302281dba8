"""The clocks (replication.rig.clock): a step of the clock without a skip in the stamps and a jump
of the camera's clock are named clock_jump with their time, size and clock (not a drift); a drift
and a clean rig are not; the decision at its thresholds; the sensor re-stamped for the segment test
(a drift or a step removed). Rigs: ``replication.testing``'s noisy rig (60 s, a gyro bias) and its
clock edits."""
import warnings

import numpy as np
import pytest

from replication.rig import clock
from replication.rig.calibration import calibrate
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import RIG_R0 as R0
from replication.testing import camera_clock_jumped as camera_jump
from replication.testing import clock_drifting
from replication.testing import clock_stepped as lost
from replication.testing import noisy_rig as rig


def drifting(gyro, ppm):
    return clock_drifting(gyro, ppm, 30.0)


def _rig(seed, bias=0.0):
    return rig(seed, 60.0, 0.05, 0.005, bias_rad_s=bias)


def _cal(camera, gyro, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, gyro, n_bootstrap=0, diagnose=False, **kw)


def _profile(camera, gyro):
    return clock.offset_profile(camera, integrate_gyro(gyro), R0, 0.0)


def test_a_step_without_a_stamp_skip_is_a_clock_jump_not_a_drift():
    camera, gyro = _rig(8000, bias=0.05)
    r = _cal(camera, lost(gyro, 30.0, 6))  # 6 samples lost at 200 Hz, stamps even: the offset steps by -30 ms
    checks = {x.check: x for x in r.verdict.reasons}
    assert "clock_drift" not in checks and "segments_disagree" not in checks
    why = checks["clock_jump"]
    assert why.level == "fail" and "by -30." in why.message and "no skip in either clock's stamps" in why.message
    (j,) = r.segments["clock_jumps"]
    assert j["clock"] == "unknown" and j["found_by"] == "profile" and not j["at_gap"]
    assert abs(j["time_s"] - 30.0) <= j["time_resolution_s"] and j["size_s"] == pytest.approx(-0.030, abs=0.002)
    assert r.segments["clock_profile"]["choice"] == "step"


def test_a_jump_of_the_camera_clock_is_named_as_the_camera_s():
    camera, gyro = _rig(8001, bias=0.05)
    r = _cal(camera_jump(camera, 30.0, 0.05), gyro)
    (j,) = r.segments["clock_jumps"]
    assert j["clock"] == "camera" and abs(j["time_s"] - 30.0) < 0.1 and j["size_s"] == pytest.approx(-0.05, abs=0.002)
    (why,) = [x for x in r.verdict.reasons if x.check == "clock_jump"]
    said = why.message.split("the camera's stamps skip there: its clock jumped by +")[1]
    assert float(said.split(" ms")[0]) == pytest.approx(50.0, abs=2.0)  # as the size above
    assert "clock_drift" not in {x.check for x in r.verdict.reasons}


def test_a_jump_at_a_sensor_gap_is_named_once():
    camera, gyro = _rig(8002)
    jumped = GyroStream(np.where(gyro.t >= 30.0, gyro.t + 0.03, gyro.t), gyro.omega, "gyro")
    r = _cal(camera, jumped)
    (j,) = r.segments["clock_jumps"]
    assert j["found_by"] == "gap" and j["clock"] == "sensor" and j["size_s"] == pytest.approx(0.03, abs=0.005)


@pytest.mark.parametrize("ppm, choice", [(0.0, "one offset"), (200.0, "drift")])
def test_clean_and_drifting_clocks_are_no_step(ppm, choice):
    camera, gyro = _rig(8003)
    p = _profile(camera, drifting(gyro, ppm) if ppm else gyro)
    assert p.step is None and p.choice == choice
    if ppm:
        assert p.drift_ppm == pytest.approx(ppm, rel=0.2)


def test_the_step_threshold_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8004)
    gyro = lost(gyro, 30.0, 2)  # a 10 ms step
    ratio = min(_profile(camera, gyro).ratio_drift, _profile(camera, gyro).ratio_one)
    monkeypatch.setattr(clock, "STEP_LR", 1.01 * ratio)
    assert _profile(camera, gyro).step is None
    monkeypatch.setattr(clock, "STEP_LR", 0.99 * ratio)
    assert _profile(camera, gyro).step.size_s == pytest.approx(-0.010, abs=0.002)


def test_the_step_size_floor_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8005)
    p = _profile(camera, lost(gyro, 30.0, 2))
    size = abs(p.step.size_s)
    monkeypatch.setattr(clock, "JUMP_MIN_S", 1.01 * size)
    assert _profile(camera, lost(gyro, 30.0, 2)).step is None
    monkeypatch.setattr(clock, "JUMP_MIN_S", 0.99 * size)
    assert _profile(camera, lost(gyro, 30.0, 2)).step is not None


def test_too_short_a_recording_has_no_profile():
    camera, gyro = rig(8006, 29.0, 0.05, 0.005)
    assert clock.offset_profile(camera, integrate_gyro(gyro), R0, 0.0) is None
    r = _cal(camera, gyro)
    assert r.segments["clock_profile"] is None and r.segments["clock_jumps"] == []


def test_the_sensor_is_restamped_without_its_drift_and_its_step():
    t = np.arange(0.0, 40.0, 0.005)
    Q = np.broadcast_to(np.eye(3), (len(t), 3, 3))
    k, mid, d = 200e-6, 20.0, 0.01
    drifting_stream = OrientationStream(t + d + k * (t - mid), Q, "s")
    fixed = clock.corrected_sensor(drifting_stream, d, drift=(200.0, mid, d))
    assert np.allclose(fixed.t, t + d, atol=1e-12)
    step = clock.ClockJump(time_s=20.0, size_s=-0.03, offset_before_s=0.0, offset_after_s=-0.03, at_gap=False,
                           clock="unknown", time_resolution_s=1.0, found_by="profile")
    fixed = clock.corrected_sensor(OrientationStream(t, Q, "s"), 0.0, jumps=[step], interval=1.0)
    assert np.all(np.diff(fixed.t) > 0)
    gap = np.argmax(np.diff(fixed.t))
    assert fixed.t[gap] < 20.0 - 2.0 + 1e-9 and fixed.t[gap + 1] > 20.0 + 2.0  # cut over the step's time
    assert fixed.t[-1] == pytest.approx(t[-1] + 0.03) and fixed.t[0] == t[0]  # after the step: 30 ms later
    assert clock.corrected_sensor(OrientationStream(t, Q, "s"), 0.0) is None


def test_a_drift_is_removed_before_the_segment_test(monkeypatch):
    camera, gyro = _rig(8102, bias=0.05)
    gyro = drifting(gyro, 400.0)  # 24 ms over the minute: the segments' R0 follow the offset's error
    r = _cal(camera, gyro)
    checks = {x.check for x in r.verdict.reasons}
    assert "clock_drift" in checks and "segments_disagree" not in checks
    monkeypatch.setattr(clock, "corrected_sensor", lambda *a, **k: None)  # the drift left in: the segments disagree
    assert "segments_disagree" in {x.check for x in _cal(camera, gyro).verdict.reasons}


def test_a_window_without_pairs_is_left_out_not_the_profile():
    camera, gyro = _rig(8007)
    keep = (gyro.t < 27.0) | (gyro.t > 33.5)  # 6.5 s of gyro lost (a gap in its stamps, the clock unchanged)
    p = _profile(camera, GyroStream(gyro.t[keep], gyro.omega[keep], "gyro"))
    assert p is not None and p.step is None and len(p.t_s) < 12 and not np.any((p.t_s > 28.0) & (p.t_s < 32.0))
    assert p.windows_left_out >= 1 and len(p.t_s) + p.windows_left_out == 11  # 11 windows of 5.45 s


def test_a_step_beyond_the_first_search_is_found_and_one_beyond_the_reach_is_not_a_crash():
    camera, gyro = _rig(8008)
    p = _profile(camera, lost(gyro, 30.0, 30))  # 150 ms lost, stamps even
    assert p.step is not None and p.step.size_s == pytest.approx(-0.150, abs=0.003)
    far = _profile(camera, lost(gyro, 30.0, 80))  # 400 ms: beyond PROFILE_REACH_S, its windows left out
    assert far is not None and far.windows_left_out >= 4


def _two_steps(seed, bias=0.0):
    camera, gyro = _rig(seed, bias=bias)
    return camera, lost(lost(gyro, 40.0, 6), 20.0, 4)  # -20 ms at 20 s, then -30 ms more at 40 s: no stamp skip


def test_two_steps_without_a_stamp_skip_are_two_clock_jumps_not_a_drift():
    r = _cal(*_two_steps(8010, bias=0.05))
    checks = {x.check: x for x in r.verdict.reasons}
    assert "clock_drift" not in checks and checks["clock_jump"].level == "fail"
    assert checks["clock_jump"].message.count(" ms (offset ") == 2
    first, second = r.segments["clock_jumps"]
    for j, at, size in ((first, 20.0, -0.020), (second, 40.0, -0.030)):
        assert abs(j["time_s"] - at) <= j["time_resolution_s"] and j["size_s"] == pytest.approx(size, abs=0.002)
    assert r.segments["clock_profile"]["steps"] == [first, second]


def test_the_two_steps_threshold_at_its_boundary(monkeypatch):
    camera, gyro = _two_steps(8011)
    p = _profile(camera, gyro)
    c, n = p.chi2, len(p.t_s)
    rivals = min(c["one offset"], c["drift"], c["drift that bends"], c["step"])
    s2 = max(1.0, c["two steps"] / (n - 6))
    gain = min(rivals - c["two steps"], (c["step and drift"] - c["two steps"]) / clock.TWO_STEPS_VS_DRIFT) / s2
    monkeypatch.setattr(clock, "STEP_LR", 1.01 * gain)
    assert len(_profile(camera, gyro).steps) <= 1
    monkeypatch.setattr(clock, "STEP_LR", 0.99 * gain)
    assert [round(s.size_s, 2) for s in _profile(camera, gyro).steps] == [-0.02, -0.03]


def test_the_two_steps_size_floor_at_its_boundary(monkeypatch):
    camera, gyro = _two_steps(8011)
    least = min(abs(s.size_s) for s in _profile(camera, gyro).steps)
    monkeypatch.setattr(clock, "TWO_STEPS_MIN_S", 1.01 * least)
    assert len(_profile(camera, gyro).steps) <= 1
    monkeypatch.setattr(clock, "TWO_STEPS_MIN_S", 0.99 * least)
    assert len(_profile(camera, gyro).steps) == 2


def test_one_step_and_a_slow_drift_are_not_two_steps():
    camera, gyro = _rig(8000, bias=0.05)  # a 30 ms step; the offsets after it creep by 3 ms (one step and a drift)
    p = _cal(camera, lost(gyro, 30.0, 6)).segments["clock_profile"]
    (step,) = p["steps"]
    assert step["size_s"] == pytest.approx(-0.030, abs=0.002) and p["chi2"]["two steps"] < p["chi2"]["step"]


def test_a_20_ms_jump_of_the_camera_clock_is_named_the_camera_s_though_its_skip_is_short():
    camera, gyro = _rig(8012, bias=0.05)
    r = _cal(camera_jump(camera, 30.0, 0.02), gyro)  # a 70 ms frame interval among 50 ms ones (under 1.5 intervals)
    (j,) = r.segments["clock_jumps"]
    assert j["clock"] == "camera" and abs(j["time_s"] - 30.0) < 0.1 and j["size_s"] == pytest.approx(-0.02, abs=0.002)
    (why,) = [x for x in r.verdict.reasons if x.check == "clock_jump"]
    assert "the camera's stamps skip there" in why.message and "no skip" not in why.message


def test_a_short_skip_is_the_clock_s_at_the_match_boundary(monkeypatch):
    t = np.concatenate([np.arange(0.0, 30.0, 0.05), np.arange(30.02, 60.0, 0.05)])  # one 70 ms interval
    share = abs(0.020 - 0.025) / 0.025  # a 20 ms skip read against a 25 ms step
    monkeypatch.setattr(clock, "SKIP_MATCH", 1.01 * share)
    assert clock._skip(t, 30.0, 3.0, 0.025)[1] == pytest.approx(0.02)
    monkeypatch.setattr(clock, "SKIP_MATCH", 0.99 * share)
    assert clock._skip(t, 30.0, 3.0, 0.025) is None
    assert clock._skip(t, 30.0, 3.0, -0.02) is None  # the skip says the other clock's sign
    assert clock._skip(t, 40.0, 3.0, 0.02) is None  # not near the step


def test_the_no_skip_words_say_how_far_the_stamps_were_searched():
    camera, gyro = _rig(8000, bias=0.05)
    (why,) = [x for x in _cal(camera, lost(gyro, 30.0, 6)).verdict.reasons if x.check == "clock_jump"]
    assert "no skip in either clock's stamps near it (no interval over 1.5 median intervals" in why.message


def _drift_stops(gyro, ppm, stop):
    return GyroStream(gyro.t + ppm * 1e-6 * (np.minimum(gyro.t, stop) - stop), gyro.omega, gyro.source)


def test_a_drift_that_stops_is_no_step():
    camera, gyro = _rig(8039, bias=0.05)  # before the drift that bends was a rival: a false 11 ms step at 17.6 s
    r = _cal(camera, _drift_stops(gyro, 500.0, 30.0))
    p = r.segments["clock_profile"]
    assert r.segments["clock_jumps"] == [] and p["choice"] == "drift" and p["steps"] == []
    assert p["chi2"]["drift that bends"] < p["chi2"]["step"] < p["chi2"]["drift"]  # the step only beat the one ramp


def test_the_bend_share_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8004)
    gyro = lost(gyro, 30.0, 2)  # a 10 ms step: it beats the drift that bends by far less than the one ramp
    p = _profile(camera, gyro)
    share = (p.chi2["drift that bends"] - p.chi2["step"]) / (p.scale * clock.STEP_LR)
    assert p.step is not None and share < 1.0
    monkeypatch.setattr(clock, "BEND_SHARE", 1.01 * share)
    assert _profile(camera, gyro).step is None
    monkeypatch.setattr(clock, "BEND_SHARE", 0.99 * share)
    assert _profile(camera, gyro).step.size_s == pytest.approx(-0.010, abs=0.002)
