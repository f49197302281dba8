"""The testing helpers (:mod:`replication.testing`): the one synthetic rig, its options and its
draws."""
import numpy as np
import pytest

from replication.core import so3
from replication.rig.changepoint import remounted
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import (
    RIG_R0,
    camera_lost,
    clock_jumped,
    noisy_rig,
    rig_motion,
    rig_pairs,
    rig_streams,
    samples_lost,
)


def test_the_rig_is_rigid_with_r0_and_its_rates_at_the_step_midpoints():
    R0, camera, gyro, sensor = rig_streams(5.0)
    assert np.array_equal(R0, RIG_R0)
    assert isinstance(camera, OrientationStream) and isinstance(gyro, GyroStream)
    assert len(camera.t) == 100 and camera.t[1] - camera.t[0] == pytest.approx(0.05)
    assert gyro.t[0] == pytest.approx(-0.9975) and sensor.t[1] - sensor.t[0] == pytest.approx(0.01)  # 100 Hz
    np.testing.assert_allclose(sensor.R, rig_motion(sensor.t) @ RIG_R0, atol=1e-12)  # v_cam = R0 v_sensor
    # a rate integrated over one step turns the sensor from one sample to the next
    Q = rig_motion(np.arange(-1.0, 6.0, 0.005)) @ RIG_R0
    np.testing.assert_allclose(Q[:-1] @ so3.matrix_from_rotation_vector(gyro.omega * 0.005), Q[1:], atol=1e-12)


def test_the_options_shift_the_clock_turn_the_mount_and_keep_every_sample():
    _, camera0, gyro0, sensor0 = rig_streams(10.0)
    _, camera, gyro, sensor = rig_streams(10.0, offset=0.0123)
    assert np.array_equal(camera.t, camera0.t) and np.array_equal(camera.R, camera0.R)
    np.testing.assert_allclose(gyro.t - gyro0.t, 0.0123, atol=1e-12)
    np.testing.assert_allclose(sensor.t - sensor0.t, 0.0123, atol=1e-12)
    assert len(rig_streams(10.0, sensor_step=1)[3].t) == 2 * len(sensor0.t) == len(gyro0.t) + 1
    R = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))
    _, _, gyro_r, sensor_r = rig_streams(10.0, remount=(4.0, R))
    assert np.array_equal(gyro_r.omega, remounted(gyro0, 4.0, R).omega)
    assert np.array_equal(sensor_r.R, remounted(sensor0, 4.0, R).R)
    before, after = gyro0.t < 4.0, gyro0.t >= 4.0
    assert np.array_equal(gyro_r.omega[before], gyro0.omega[before]) and not np.allclose(gyro_r.omega[after],
                                                                                         gyro0.omega[after])


def test_phase_shifts_each_component_and_a_number_shifts_all():
    t = np.linspace(0.0, 20.0, 7)
    assert np.array_equal(rig_motion(t, 0.4), rig_motion(t, (0.4, 0.4, 0.4)))
    assert not np.allclose(rig_motion(t, (0.4, 0.0, 0.0)), rig_motion(t, 0.4))
    np.testing.assert_allclose(so3.rotation_vector_from_matrix(rig_motion(t, (0.0, 0.0, 0.3)))[:, 2],
                               0.7 * np.cos(0.3 * t + 0.3),
                               atol=1e-12)


def test_noise_is_drawn_camera_first_and_a_callable_is_the_callers_own_draws():
    a = rig_streams(10.0, rng=np.random.default_rng(4), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)
    rng = np.random.default_rng(4)
    shapes = []

    def camera_noise(shape):
        shapes.append(("camera", shape))
        return rng.normal(0.0, np.radians(0.05) / np.sqrt(3.0), shape)

    def gyro_noise(shape):
        shapes.append(("gyro", shape))
        return rng.normal(0.0, np.radians(0.05), shape)

    b = rig_streams(10.0, camera_noise_deg=camera_noise, gyro_noise_deg_s=gyro_noise)
    assert shapes == [("camera", (200, 3)), ("gyro", (2399, 3))]
    assert np.array_equal(a[1].R, b[1].R) and np.array_equal(a[2].omega, b[2].omega)
    # the RMS camera angle is the one asked for (isotropic noise of RMS 0.05 deg), within 10 %
    clean = rig_streams(10.0)[1].R
    rms = np.sqrt(np.mean(so3.angle_between_deg(a[1].R, clean) ** 2))
    assert 0.045 < rms < 0.055


@pytest.mark.parametrize("kw", [{"camera_noise_deg": 0.05}, {"gyro_noise_deg_s": 0.05}])
def test_noise_without_a_generator_is_refused(kw):
    with pytest.raises(ValueError, match="noise needs rng, a numpy.random.Generator"):
        rig_streams(5.0, **kw)
    rig_streams(5.0, camera_noise_deg=lambda shape: np.zeros(shape))  # a caller's own draws need none


def test_a_bias_a_fast_clock_and_a_rest_are_what_they_say():
    _, camera0, gyro0, _ = rig_streams(20.0)
    _, camera, gyro, _ = rig_streams(20.0, bias=(0.1, -0.1, 0.07), ppm=100.0, offset=0.01, rest_s=3.0)
    # the clock: offset plus 100 ppm about the middle (10 s): 1 ms late at the end, 1 ms early at
    # the start
    np.testing.assert_allclose(gyro.t - gyro0.t, 0.01 + 1e-4 * (gyro0.t - 10.0), atol=1e-12)
    # the rest: no motion before 3 s, full motion from 5 s on; the bias: every rate moved by it
    still = gyro0.t < 3.0
    np.testing.assert_allclose(gyro.omega[still], np.tile([0.1, -0.1, 0.07], (still.sum(), 1)), atol=1e-9)
    moving = gyro0.t > 5.0
    np.testing.assert_allclose(gyro.omega[moving] - gyro0.omega[moving], np.tile([0.1, -0.1, 0.07], (moving.sum(), 1)),
                               atol=1e-9)
    assert np.array_equal(camera.R[camera.t > 5.0], camera0.R[camera0.t > 5.0])
    assert so3.angle_between_deg(camera.R[0], camera.R[camera.t < 3.0][-1]) < 1e-9


def test_the_stream_edits_jump_the_clock_lose_samples_and_lose_the_camera_for_a_stretch():
    camera, gyro = noisy_rig(1, 20.0, 0.05, 0.005)
    jumped = clock_jumped(gyro, 10.0, 0.03)
    assert np.array_equal(jumped.t[gyro.t < 10.0], gyro.t[gyro.t < 10.0])
    np.testing.assert_allclose(jumped.t[gyro.t >= 10.0] - gyro.t[gyro.t >= 10.0], 0.03, atol=1e-12)
    lost = samples_lost(gyro, 10.0, 7)
    assert len(lost.t) == len(gyro.t) - 7 and np.diff(lost.t).max() == pytest.approx(0.04, abs=1e-9)
    wandered = camera_lost(camera, np.random.default_rng(0), 5.0, 12.0)
    off = so3.angle_between_deg(wandered.R, camera.R)
    assert off[(camera.t > 2.0) & (camera.t < 10.0)].max() > 0.1  # lost
    assert off[camera.t >= 12.0].max() < 1e-9  # found again, exactly the true frame


def test_the_noisy_rig_is_seeded_and_its_pairs_recover_r0():
    a, b = noisy_rig(3, 15.0, 0.05, 0.005), noisy_rig(3, 15.0, 0.05, 0.005)
    assert np.array_equal(a[0].R, b[0].R) and np.array_equal(a[1].omega, b[1].omega)
    assert not np.array_equal(noisy_rig(4, 15.0, 0.05, 0.005)[0].R, a[0].R)
    A, B, t, block = rig_pairs(*a)
    assert block == 20 and len(A) == len(B) == len(t) > 10
    # A = R0 B R0^T (camera motions from the sensor's): within the noise for every pair
    assert np.max(so3.angle_between_deg(A, RIG_R0 @ B @ RIG_R0.T)) < 0.5
