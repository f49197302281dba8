"""Causes named online as the batch does: a rig turning at constant speed, time stamps in different
units, a clock offset beyond the search; in the online verdict and in ``calibrate --online``'s
output; each rule at its boundary."""
import math

import numpy as np
import pytest

from replication.cli import main
from replication.core import so3
from replication.rig import online_causes
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.rig.online_causes import (
    CONSTANT_SPEED_MIN_DEG,
    CONSTANT_SPEED_SPREAD,
    PLAUSIBLE_INTERVAL_RATIO,
    WIDE_CORRELATION,
    WIDE_GAIN,
    constant_speed,
    offset_beyond_search,
    time_unit_by_rate,
)
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import RIG_R0, rig_streams


@pytest.fixture(scope="module")
def rig():
    return rig_streams(60.0, rng=np.random.default_rng(11), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)


def _summary(camera, sensor, R0, **kw):
    rows = replay(camera, sensor, OnlineCalibrator(), reference=R0, **kw)
    return rows, rows.attrs["summary"]


def _fails(summary):
    return {r["check"]: r for r in summary["verdict"]["reasons"] if r["level"] == "fail"}


def _spinning(seconds=60.0, deg_s=30.0, seed=5, noise=0.05):
    """A rig turning at a constant angular velocity about one axis (camera and gyro noise ``noise``,
    deg, deg/s)."""
    rng = np.random.default_rng(seed)
    R0 = RIG_R0
    axis = np.array([0.2, 0.5, 0.8]) / np.linalg.norm([0.2, 0.5, 0.8])
    t, ti = np.arange(0.0, seconds, 0.05), np.arange(-1.0, seconds + 1.0, 0.005)
    C = so3.matrix_from_rotation_vector(np.outer(np.radians(deg_s) * t, axis)) @ so3.matrix_from_rotation_vector(
        rng.normal(0.0, np.radians(noise) / np.sqrt(3), (len(t), 3)))
    omega = np.tile(R0.T @ axis * np.radians(deg_s), (len(ti), 1)) + rng.normal(0.0, np.radians(noise), (len(ti), 3))
    return R0, OrientationStream(t, C, "camera"), GyroStream(ti, omega, "gyro")


# ------------------------------------------------------------------------------------------------
# constant speed

def test_a_rig_turning_at_constant_speed_is_named_never_ready():
    R0, camera, gyro = _spinning()
    rows, summary = _summary(camera, gyro, R0)
    assert not rows["ready"].any() and summary["verdict"]["level"] == "fail"
    reason = _fails(summary)["constant_speed"]
    assert "turns at a constant speed" in reason["message"] and "no clock offset can be measured" in reason["message"]
    assert reason["measured"] < 0.01 and any("constant speed" in m for m in summary["not_ready"])


def test_a_noise_free_rig_at_constant_speed_is_named_from_the_camera_stream():
    """Noise-free, every pair is the same pair (refused as repeats): the camera stream's own motions
    name the cause."""
    R0, camera, gyro = _spinning(seconds=40.0, noise=0.0)
    rows, summary = _summary(camera, gyro, R0)
    assert not summary["ready"] and summary["repeated_pairs"] > 20
    assert "turns at a constant speed" in _fails(summary)["constant_speed"]["message"]
    assert sum("constant speed" in m for m in summary["not_ready"]) == 1  # named once, not by both


def test_constant_speed_on_a_stream_needs_ten_intervals_of_steady_motion(rig):
    from replication.rig.online_causes import constant_speed_stream

    R0, camera, gyro = _spinning(seconds=40.0, noise=0.0)
    assert constant_speed_stream(camera.t, camera.world_from_body, 1.0) is not None
    short = camera.t < 9.9
    assert constant_speed_stream(camera.t[short], camera.world_from_body[short], 1.0) is None
    _, moving, _, _ = rig
    assert constant_speed_stream(moving.t, moving.world_from_body, 1.0) is None  # a rig moving at varying speed


@pytest.mark.parametrize("spread, named", [(0.99 * CONSTANT_SPEED_SPREAD, True), (1.01 * CONSTANT_SPEED_SPREAD, False)])
def test_constant_speed_at_its_spread(spread, named):
    m = 30.0 * (1.0 + spread * np.array([-1.0, 1.0] * 10))  # median 30, median absolute deviation 30 x spread
    reason = constant_speed(m, 0.5, 1.0, [0.0, 0.0, 1.0])
    assert (reason is not None) is named
    if named:
        assert reason.check == "constant_speed" and reason.measured == pytest.approx(spread)


def test_constant_speed_needs_undetermined_motion_ten_motions_and_motion():
    m = np.full(10, 30.0)
    assert constant_speed(m, 0.999, 1.0, None) is not None
    assert constant_speed(m, 1.0, 1.0, None) is None  # the motion determines R0: not this cause
    assert constant_speed(m[:9], 0.5, 1.0, None) is None
    assert constant_speed(np.full(10, CONSTANT_SPEED_MIN_DEG), 0.5, 1.0, None) is None  # at rest: its own check
    assert constant_speed(np.full(10, 1.0001 * CONSTANT_SPEED_MIN_DEG), 0.5, 1.0, None) is not None


def test_varying_single_axis_motion_is_single_axis_not_constant_speed(rng):
    """Motions about one axis at varying speed: the motion does not determine R0 (said), but it is
    not constant."""
    from replication.study.live_study import pair_stream

    R0 = so3.random_rotations(rng, ())
    A, B = pair_stream(rng, 60, R0, axis=[0.3, 0.4, 0.5])
    oc = OnlineCalibrator()
    oc.update_many(A, B)
    checks = {r.check for r in oc.verdict().reasons}
    assert "constant_speed" not in checks and any("does not determine R0" in m for m in oc.status()["not_ready"])


# ------------------------------------------------------------------------------------------------
# units

@pytest.mark.parametrize("scale, unit", [(1e9, "ns"), (1e3, "ms")])
def test_gyro_stamps_in_another_unit_are_named_and_nothing_is_raised(rig, scale, unit):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera, GyroStream(gyro.t * scale + (1e12 if scale == 1e9 else 0.0), gyro.omega, "g"),
                             R0)
    assert not rows["ready"].any() and summary["verdict"]["level"] == "fail"
    reason = _fails(summary)["time_unit"]
    assert f"the sensor time stamps are likely in {unit} read as seconds" in reason["message"]
    if scale == 1e9:
        assert len(rows) == 0 and "no clock offset" in summary["note"] and "in ns" in summary["note"]


def test_camera_stamps_in_ms_are_named_from_the_spans(rig):
    """Camera stamps in ms beside a 200 Hz gyro: the sample intervals' ratio (1e-4) is a plausible
    keyframe rate; the streams' spans (60,000 s against 62 s) show it, as in the batch."""
    R0, camera, gyro, _ = rig
    rows, summary = _summary(OrientationStream(camera.t * 1e3, camera.world_from_body, "c"), gyro, R0)
    reason = _fails(summary)["time_unit"]
    assert "a factor of about 1e+03" in reason["message"] and "the camera file's time stamps" in reason["message"]


def test_a_keyframe_trajectory_beside_a_fast_gyro_is_not_a_unit_mistake():
    assert time_unit_by_rate(2.0, 1 / 2000) is None  # 0.5 Hz keyframes, 2000 Hz gyro


@pytest.mark.parametrize("ratio, named", [
    (PLAUSIBLE_INTERVAL_RATIO[0], None), (PLAUSIBLE_INTERVAL_RATIO[1], None), (0.1, None),
    (PLAUSIBLE_INTERVAL_RATIO[1] * 1.01, "sensor ... ms"), (PLAUSIBLE_INTERVAL_RATIO[1] * 1e3 * 1.01, "sensor ... us"),
    (0.1 * 1e9, "sensor ... ns"), (PLAUSIBLE_INTERVAL_RATIO[1] * 1e9, "sensor ... ns"),
    (PLAUSIBLE_INTERVAL_RATIO[1] * 1e9 * 1.01, None), (PLAUSIBLE_INTERVAL_RATIO[0] * 0.99, "camera ... ms"),
    (PLAUSIBLE_INTERVAL_RATIO[0] / 1e9, "camera ... ns"), (PLAUSIBLE_INTERVAL_RATIO[0] / 1e9 * 0.99, None),
    # camera stamps in us (or ns) also fit the range read as ms (us): the unit nearest a typical rig
    # is named
    (0.1 / 1e6, "camera ... us"), (0.1 / 1e9, "camera ... ns"), (0.1 * 1e3, "sensor ... ms"),
])
def test_time_units_by_the_ratio_of_sample_intervals(ratio, named):
    reason = time_unit_by_rate(0.05, 0.05 * ratio)
    if named is None:
        assert reason is None
    else:
        side, unit = named.split(" ... ")
        assert reason.check == "time_unit" and f"the {side} time stamps are likely in {unit}" in reason.message
    assert time_unit_by_rate(None, 0.01) is None and time_unit_by_rate(0.05, 0.0) is None


# ------------------------------------------------------------------------------------------------
# offset

def test_a_clock_offset_beyond_the_search_is_named_with_its_value(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera, GyroStream(gyro.t + 3.0, gyro.omega, "gyro"), R0)
    reason = _fails(summary)["offset_beyond_search"]
    assert reason["measured"] == pytest.approx(3.0, abs=0.01) and reason["threshold"] == 0.2
    assert "raise max_offset (--max-offset) above 3 s" in reason["message"] and not rows["ready"].any()


def test_an_offset_within_the_search_names_nothing(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera, GyroStream(gyro.t + 0.1, gyro.omega, "gyro"), R0)
    assert summary["ready"] and "offset_beyond_search" not in {r["check"] for r in summary["verdict"]["reasons"]}


@pytest.mark.parametrize("offset, correlation, found, named", [
    (3.0, WIDE_CORRELATION, 0.5, True), (3.0, WIDE_CORRELATION - 1e-9, 0.5, False),
    (3.0, 0.95, 0.95 - WIDE_GAIN, True), (3.0, 0.95, 0.95 - WIDE_GAIN + 1e-9, False),
    (0.2, 0.99, 0.5, False), (-0.2001, 0.99, 0.5, True), (3.0, 0.99, None, True), (3.0, 0.99, math.nan, True),
])
def test_the_wider_search_at_its_thresholds(monkeypatch, offset, correlation, found, named):
    import replication.rig.association as association

    monkeypatch.setattr(association, "estimate_time_offset", lambda *a, **k: (offset, correlation))
    reason = offset_beyond_search(None, None, max_offset=0.2, window=20.0, found_correlation=found, resolution=5e-4)
    assert (reason is not None) is named
    if named:
        assert reason.measured == offset and ("may be larger still" in reason.message) is False


def test_the_wider_search_spans_a_quarter_of_the_window_and_says_when_at_its_bound(monkeypatch):
    import replication.rig.association as association

    seen = {}

    def fake(camera, sensor, *, max_offset, resolution):
        seen["max_offset"] = max_offset
        return max_offset, 0.99

    monkeypatch.setattr(association, "estimate_time_offset", fake)
    reason = offset_beyond_search(None, None, max_offset=0.2, window=20.0, found_correlation=0.5, resolution=5e-4)
    assert seen["max_offset"] == online_causes.WIDE_SEARCH_SHARE * 20.0 == 5.0
    assert "at the bound of a search over +-5 s: the offset may be larger still" in reason.message
    assert offset_beyond_search(None, None, max_offset=5.0, window=20.0, found_correlation=0.5,
                                resolution=5e-4) is None  # no wider search than the one made


# ------------------------------------------------------------------------------------------------
# the command line

def _write(tmp_path, camera, gyro, shift=0.0, scale=1e9):
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(camera.R)
    np.savetxt(cam_file, np.column_stack([camera.t + 1e3, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]]),
               fmt="%.9f")
    np.savetxt(imu_file, np.column_stack([np.round((gyro.t + 1e3 + shift) * scale), gyro.omega,
                                          np.zeros((len(gyro.t), 3))]), fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    return ["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro", "--online",
            "--bootstrap", "0"]


def test_cli_online_names_the_offset_beyond_the_search(tmp_path, rig, capsys):
    R0, camera, gyro, _ = rig
    assert main(_write(tmp_path, camera, gyro, shift=3.0)) == 3
    out = capsys.readouterr().out
    online = out[out.index("online:"):]
    assert "online fail: the clock offset is beyond the search (+-0.2 s): the angular speeds match best at +3.0" \
        in online


def test_cli_online_names_constant_speed(tmp_path, capsys):
    R0, camera, gyro = _spinning(seconds=30.0)
    assert main(_write(tmp_path, camera, gyro) + ["--accept"]) == 0
    out = capsys.readouterr().out
    assert "online fail: the rig turns at a constant speed" in out[out.index("online:"):]
