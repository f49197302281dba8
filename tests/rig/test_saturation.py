"""A saturated gyro (replication.rig.saturation): samples pinned at an axis's extreme rate are found
at the run rule's boundary (MIN_RUN - 1 in a row: none; MIN_RUN: clipped), on both signs; the pairs
holding them are the ones dropped; the reason is a warning up to MAX_SPOILED_SHARE of the pairs and
a fail beyond; a camera step over clipped samples is no camera jump; ``calibrate`` on fast turns
beyond a 250 deg/s gyro names the saturation, not a map reset, and keeps R0."""
import numpy as np
import pytest

from replication.core.so3 import angle_between_deg, matrix_from_rotation_vector, rotation_vector_from_matrix
from replication.rig.calibration import calibrate
from replication.rig.camera_jumps import found_and_glued
from replication.rig.saturation import MAX_SPOILED_SHARE, MIN_RUN, Saturation, saturation_of
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import RIG_R0, noisy_rig, rig_motion

FLOOR_DEG = 0.343


def _gyro(omega, rate_hz=200.0):
    omega = np.asarray(omega, float)
    return GyroStream(np.arange(len(omega)) / rate_hz, omega, "gyro")


def _noise(n=400, seed=0):
    return np.random.default_rng(seed).normal(0.0, 0.01, (n, 3))


def _pin(w, axis, start, count, value, past=0.5):
    """A turn on ``axis`` pinned at ``value`` for ``count`` samples from ``start``: the two samples
    either side on a straight line that would reach ``past`` beyond it one sample in."""
    sign = np.sign(value)
    step, beyond = sign * (past + 0.5), value + sign * past
    w[start - 2:start, axis] = beyond - step * np.array([2.0, 1.0])
    w[start:start + count, axis] = value
    w[start + count:start + count + 2, axis] = beyond - step * np.array([1.0, 2.0])
    return w


@pytest.mark.parametrize("run, found", [(MIN_RUN - 1, False), (MIN_RUN, True)])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_run_at_the_extreme_is_clipping_at_the_rule(run, found, sign):
    sat = saturation_of(_gyro(_pin(_noise(), 1, 100, run, sign * 4.0)))
    assert bool(sat.limits) is found
    if found:
        assert sat.limits == (("y", sign * 4.0, run),)
        assert len(sat.t) == run


@pytest.mark.parametrize("past, found", [(0.0, False), (0.2, True)])
def test_only_a_run_entered_steeply_is_clipping(past, found):
    w = _pin(_noise(), 0, 100, 6, 4.0, past=past)  # past 0: the line reaches the value, no further
    assert bool(saturation_of(_gyro(w)).limits) is found


def test_a_smooth_peak_quantised_coarser_than_its_noise_is_no_clipping():
    t = np.arange(400) / 200.0
    w = np.zeros((400, 3))
    w[:, 2] = np.round(np.sin(2.0 * t) / 0.01) * 0.01  # its top level held 23 samples
    assert saturation_of(_gyro(w)).limits == ()
    w[:, 2] = np.minimum(np.round(3.0 * np.sin(20.0 * t) / 0.01) * 0.01, 2.0)  # a fast turn clipped at 2
    assert saturation_of(_gyro(w)).limits == (("z", 2.0, int(np.sum(w[:, 2] == 2.0))),)


def test_every_sample_at_the_limit_is_clipped_both_signs():
    w = _pin(_pin(_noise(), 0, 50, 5, 4.0), 2, 200, 10, -4.0)
    w[60, 0] = 4.0  # a lone sample at the limit too
    sat = saturation_of(_gyro(w))
    assert sorted((a, r, k) for a, r, k in sat.limits) == [("x", 4.0, 6), ("z", -4.0, 10)]
    assert len(sat.t) == 16


def test_equal_values_below_the_extreme_are_no_clipping():
    w = _noise()
    w[100:110, 0] = 0.5  # a run of equal values, but the axis reaches further
    w[300, 0] = 0.6
    assert saturation_of(_gyro(w)).limits == ()


def test_no_gyro_and_a_clean_gyro_have_no_saturation():
    camera, gyro = noisy_rig(3, 20.0, 0.05, 0.003)
    assert saturation_of(camera).limits == () and saturation_of(gyro).limits == ()
    assert saturation_of(gyro).reasons(np.zeros(5, bool), 5) == []
    assert saturation_of(gyro).without(gyro) is gyro


def test_the_pairs_holding_a_clipped_sample_within_a_sample_period():
    sat = Saturation(np.array([10.0]), (("x", 4.0, 3),), 0.005)
    starts = np.array([8.99, 8.996, 9.0, 9.5, 10.004, 10.01])  # interval 1 s, offset 0
    assert sat.pairs(starts, 1.0, 0.0).tolist() == [False, True, True, True, True, False]
    assert sat.pairs(starts - 0.5, 1.0, 0.5).tolist() == [False, True, True, True, True, False]


@pytest.mark.parametrize("dropped, level", [(50, "warning"), (51, "fail")])
def test_the_reason_warns_then_fails_past_the_share(dropped, level):
    assert MAX_SPOILED_SHARE == 0.5
    sat = Saturation(np.array([1.0, 1.005, 1.01]), (("z", -np.radians(250.0), 3),), 0.005)
    (r,) = sat.reasons(dropped, 100)
    assert (r.check, r.level) == ("gyro_saturation", level)
    assert r.measured == pytest.approx(dropped / 100)
    assert "z at -250.0 deg/s (3 samples)" in r.message and f"the {dropped} of 100 pairs" in r.message
    assert "np." not in r.message


def test_without_drops_the_clipped_samples_only():
    gyro = _gyro(_pin(_noise(), 1, 100, 10, 4.0))
    rest = saturation_of(gyro).without(gyro)
    assert len(rest.t) == len(gyro.t) - 10 and not np.isin(gyro.t[100:110], rest.t).any()


def _whipped(seed, clip_dps, seconds=30.0, whips=(10.0, 20.0)):
    """The rig's motion with fast turns (90 deg in 0.2 s, about 500 deg/s at the peak) at ``whips``,
    a 20 Hz camera (0.05 deg) and a 200 Hz gyro (0.2 deg/s, a bias) clipped at ``clip_dps``."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)
    axis = np.array([0.2, 1.0, 0.1]) / np.linalg.norm([0.2, 1.0, 0.1])

    def motion(t):
        u = sum(np.clip((t - at) / 0.2, 0, 1) for at in whips)
        turn = np.radians(90.0) * sum(np.clip((t - at) / 0.2, 0, 1) ** 2 * (3 - 2 * np.clip((t - at) / 0.2, 0, 1))
                                      for at in whips) * np.ones_like(u)
        return rig_motion(t, phase) @ matrix_from_rotation_vector(turn[:, None] * axis)

    t_cam = np.arange(0.0, seconds, 0.05)
    C = motion(t_cam) @ matrix_from_rotation_vector(rng.normal(0.0, np.radians(0.05) / np.sqrt(3), (len(t_cam), 3)))
    t_imu = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = motion(t_imu) @ RIG_R0
    omega = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    omega = omega + np.array([0.03, -0.02, 0.04]) + rng.normal(0.0, np.radians(0.2), omega.shape)
    omega = np.clip(omega, -np.radians(clip_dps), np.radians(clip_dps))
    return OrientationStream(t_cam, C, "camera"), GyroStream(0.5 * (t_imu[1:] + t_imu[:-1]), omega, "gyro")


def test_a_camera_step_over_clipped_samples_is_no_jump_a_reset_elsewhere_is():
    camera, gyro = _whipped(1, 250.0)
    oriented, sat = integrate_gyro(gyro), saturation_of(gyro)
    assert sat.limits
    given = dict(R=RIG_R0, offset=0.0)  # the pass against R0, where the clipped turns were named
    named = found_and_glued(camera, oriented, 0.2, **given)[1]
    assert named and all(min(abs(j.start_s - 10.0), abs(j.start_s - 20.0)) < 0.2 for j in named)
    assert found_and_glued(camera, oriented, 0.2, excused=sat, **given)[1] == []
    R = np.array(camera.R)
    R[camera.t > 15.02] = matrix_from_rotation_vector(np.radians([0.0, 60.0, 0.0])) @ R[camera.t > 15.02]
    reset = OrientationStream(camera.t, R, "camera")
    for kw in ({}, given):
        assert [round(j.start_s, 2) for j in found_and_glued(reset, oriented, 0.2, excused=sat, **kw)[1]] == [15.0]


def test_calibrate_names_the_saturation_not_a_map_reset():
    camera, gyro = _whipped(2, 250.0)
    r = calibrate(camera, gyro, n_bootstrap=20, diagnose=False)
    checks = {x.check: x for x in r.verdict.reasons}
    assert "camera_jump" not in checks and checks["gyro_saturation"].level == "warning"
    assert r.segments["camera_jumps"] == []
    assert angle_between_deg(r.R, RIG_R0) < FLOOR_DEG
