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
