"""The clocks (replication.rig.clock): a step of the clock without a skip in the stamps and a jump
of the camera's clock are named clock_jump with their time, size and clock (not a drift); a drift
and a clean rig are not; the verdict's words; the sensor re-stamped for the segment test
(a drift or a step removed). Rigs: ``replication.testing``'s noisy rig (60 s, a gyro bias) and its
clock edits."""

import json
import pathlib

import jsonschema
import numpy as np
import pytest

from conftest import clock_rig as _rig
from conftest import drifting
from conftest import quiet_calibrate as _cal
from replication.rig import clock, clock_profile
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import camera_clock_jumped as camera_jump
from replication.testing import clock_stepped as lost


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
    # the sensor model's line through the step is no drift: null, and the summary says why
    note = r.sensor_model["sensor_model"]["drift_note"]
    assert r.sensor_model["clock_drift_ppm"] is None and r.sensor_model["clock_drift_ci95_ppm"] is None
    assert "not measured beside the clock step at" in note and "finds no drift beside it" in note
    assert f"clock drift: {note}" in r.summary().splitlines()


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


def test_the_sensor_is_restamped_without_a_step_and_its_drift():
    t = np.arange(0.0, 40.0, 0.005)
    Q = np.broadcast_to(np.eye(3), (len(t), 3, 3))
    k, at, d = -200e-6, 20.0, 0.004  # the offset 4 ms at the step, drifting, 30 ms more after it
    stamps = t + d + k * (t - at) + 0.03 * (t > at)
    step = clock.ClockJump(time_s=at, size_s=0.03, offset_before_s=d, offset_after_s=d + 0.03, at_gap=False,
                           clock="unknown", time_resolution_s=1.0, found_by="profile")
    fixed = clock.corrected_sensor(OrientationStream(stamps, Q, "s"), 0.0, jumps=[step], drift=(-200.0, at, d))
    kept = np.abs(stamps - (at + d)) > 1.0 + 1.0 + 0.03  # the cut about the step (its resolution, interval, size)
    assert np.allclose(fixed.t, t[kept], atol=1e-5)  # first order: k times the offset and step, 6 us here
    alone = clock.corrected_sensor(OrientationStream(stamps, Q, "s"), 0.0, jumps=[step])
    assert np.max(np.abs(alone.t - t[kept])) == pytest.approx(200e-6 * 20.0, rel=0.01)  # the drift left in: 4 ms


def test_a_drift_is_removed_before_the_segment_test(monkeypatch):
    camera, gyro = _rig(8102, bias=0.05)
    gyro = drifting(gyro, 400.0)  # 24 ms over the minute: the segments' R0 follow the offset's error
    r = _cal(camera, gyro)
    checks = {x.check for x in r.verdict.reasons}
    assert "clock_drift" in checks and "segments_disagree" not in checks
    # no step found: the sensor model's drift and its interval are printed
    assert not r.segments["clock_jumps"] and "drift_note" not in r.sensor_model["sensor_model"]
    lo, hi = r.sensor_model["clock_drift_ci95_ppm"]
    assert lo < 400.0 < hi and lo < r.sensor_model["clock_drift_ppm"] < hi
    assert f"clock drift: {r.sensor_model['clock_drift_ppm']:+.1f} ppm, 95 % interval [{lo:+.1f}" in r.summary()
    # the drift left in: the segments disagree
    monkeypatch.setattr(clock_profile, "corrected_sensor", lambda *a, **k: None)
    assert "segments_disagree" in {x.check for x in _cal(camera, gyro).verdict.reasons}


def test_a_step_with_a_drift_is_a_clock_jump_and_both_are_removed_for_the_segment_test(monkeypatch):
    camera, gyro = _rig(8000, bias=0.05)
    gyro = drifting(lost(gyro, 30.0, 2), -200.0)  # 10 ms lost, and a drift of 6 ms the same way over the minute
    r = _cal(camera, gyro)
    checks = {x.check for x in r.verdict.reasons}
    assert "clock_jump" in checks and "segments_disagree" not in checks and "clock_drift" not in checks
    p = r.segments["clock_profile"]
    assert p["step_with_drift"] and p["drift_ppm"] == pytest.approx(-200.0, abs=80.0)
    (j,) = r.segments["clock_jumps"]
    assert j["size_s"] == pytest.approx(-0.010, abs=0.002) and abs(j["time_s"] - 30.0) <= j["time_resolution_s"]
    # a step found: no drift printed from the line through the step; the profile's drift in words
    model = r.sensor_model
    assert model["clock_drift_ppm"] is None and model["clock_drift_ci95_ppm"] is None
    assert not model["sensor_model"]["drift_resolved"]
    said = model["sensor_model"]["drift_note"].split("the offset profile's step with a drift gives ")[1]
    assert float(said.split(" ppm")[0]) == pytest.approx(p["drift_ppm"], abs=0.05)
    assert "clock drift: not measured beside the clock step at" in r.summary()
    assert "95 % interval" not in next(ln for ln in r.summary().splitlines() if ln.startswith("clock drift"))
    schema = json.loads((pathlib.Path(__file__).resolve().parents[2] / "docs" / "calibration_report.schema.json")
                        .read_text())
    jsonschema.validate(r.to_dict(), schema)

    def without_the_drift(sensor, offset, *, jumps=(), drift=None, interval=1.0):
        return clock.corrected_sensor(sensor, offset, jumps=jumps, interval=interval)
    monkeypatch.setattr(clock_profile, "corrected_sensor", without_the_drift)  # the step removed, the drift left in
    assert "segments_disagree" in {x.check for x in _cal(camera, gyro).verdict.reasons}


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


def test_a_20_ms_jump_of_the_camera_clock_is_named_the_camera_s_though_its_skip_is_short():
    camera, gyro = _rig(8012, bias=0.05)
    r = _cal(camera_jump(camera, 30.0, 0.02), gyro)  # a 70 ms frame interval among 50 ms ones (under 1.5 intervals)
    (j,) = r.segments["clock_jumps"]
    assert j["clock"] == "camera" and abs(j["time_s"] - 30.0) < 0.1 and j["size_s"] == pytest.approx(-0.02, abs=0.002)
    (why,) = [x for x in r.verdict.reasons if x.check == "clock_jump"]
    assert "the camera's stamps skip there" in why.message and "no skip" not in why.message


def test_the_no_skip_words_say_how_far_the_stamps_were_searched():
    camera, gyro = _rig(8000, bias=0.05)
    (why,) = [x for x in _cal(camera, lost(gyro, 30.0, 6)).verdict.reasons if x.check == "clock_jump"]
    assert "no skip in either clock's stamps near it (no interval over 1.5 median intervals" in why.message
