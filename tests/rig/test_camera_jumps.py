"""Lost tracking and map resets (replication.rig.camera_jumps): a clean recording has none, a world
frame that turns in one camera step is found at its time with its size, the rule holds at its
boundaries (the angle, the share of steps), the glued trajectory keeps every relative rotation that
does not span a jump, and the pairs that span one are the ones dropped."""
import numpy as np
import pytest

from replication.core.so3 import angle_between_deg, matrix_from_rotation_vector
from replication.rig.camera_jumps import (
    JUMP_FACTOR,
    JUMP_MIN_DEG,
    MAX_JUMP_SHARE,
    CameraJump,
    camera_jumps,
    glued,
    jump_reasons,
    residual_jumps,
    spanning,
)
from replication.rig.streams import OrientationStream, integrate_gyro
from replication.testing import RIG_R0, noisy_rig, rig_streams

AXIS = np.array([0.6, 0.0, 0.8])


def _reset(camera, times, deg):
    """The camera's world frame turned by ``deg`` about AXIS after each of ``times``."""
    R = np.array(camera.R)
    for at in times:
        R[camera.t > at] = matrix_from_rotation_vector(np.radians(deg) * AXIS) @ R[camera.t > at]
    return OrientationStream(camera.t, R, camera.source)


@pytest.fixture(scope="module")
def resting():
    """A rig at rest for 30 s (the sensor turns by nothing: the rule's bound is JUMP_MIN_DEG)."""
    _, camera, gyro, _ = rig_streams(40.0, rest_s=30.0)
    return camera, integrate_gyro(gyro)


@pytest.mark.parametrize("seed", [3, 4])
def test_a_clean_recording_has_no_jumps(seed):
    camera, gyro = noisy_rig(seed, 60.0, 0.05, 0.003, bias_rad_s=0.05)
    assert camera_jumps(camera, integrate_gyro(gyro), 0.2) == []


def test_map_resets_are_found_at_their_times_with_their_sizes():
    camera, gyro = noisy_rig(7, 60.0, 0.05, 0.003, bias_rad_s=0.05)
    jumps = camera_jumps(_reset(camera, [20.02, 40.02], 90.0), integrate_gyro(gyro), 0.2)
    assert [round(j.start_s, 2) for j in jumps] == [20.0, 40.0]
    assert [j.angle_deg for j in jumps] == pytest.approx([90.0, 90.0], abs=10.0)


@pytest.mark.parametrize("deg, found", [(0.95 * JUMP_MIN_DEG, False), (1.05 * JUMP_MIN_DEG, True)])
def test_the_angle_bound_at_rest(resting, deg, found):
    camera, oriented = resting
    assert bool(camera_jumps(_reset(camera, [10.02], deg), oriented, 0.2)) is found


def test_the_bound_grows_with_the_sensors_turn():
    """A jump found at rest (just above JUMP_MIN_DEG) is not where the sensor turns fast enough."""
    camera, gyro = noisy_rig(8, 30.0, 0.0, 0.0)
    oriented = integrate_gyro(gyro)
    t = camera.t
    steps = angle_between_deg(camera.R[:-1], camera.R[1:])
    i = int(np.argmax(steps[20:-20])) + 20
    near = (gyro.t > t[i] - 0.2) & (gyro.t < t[i + 1] + 0.2)  # inside the module's window
    bound = JUMP_FACTOR * np.degrees(np.linalg.norm(gyro.omega[near], axis=-1)).max() * (t[i + 1] - t[i])
    assert bound > steps[i] + 0.05 * JUMP_MIN_DEG  # the motion is fast enough to hide it
    assert not camera_jumps(_reset(camera, [t[i] + 0.01], 1.05 * JUMP_MIN_DEG), oriented, 0.2)
    assert camera_jumps(_reset(camera, [t[i] + 0.01], 90.0), oriented, 0.2)


def test_more_than_max_jump_share_of_the_steps_is_no_jump_but_a_mistake(resting):
    camera, oriented = resting
    steps = int(np.sum((camera.t[:-1] >= oriented.t[0]) & (camera.t[1:] <= oriented.t[-1])))
    allowed = int(MAX_JUMP_SHARE * steps)
    times = 1.0 + 1.0 * np.arange(allowed + 1) + 0.02  # further apart than the camera's own window
    assert len(camera_jumps(_reset(camera, times[:allowed], 20.0), oriented, 0.2)) == allowed
    assert camera_jumps(_reset(camera, times, 20.0), oriented, 0.2) == []


def test_the_glued_trajectory_keeps_every_step_but_the_jumps():
    camera, gyro = noisy_rig(9, 30.0, 0.05, 0.003)
    reset = _reset(camera, [10.02], 90.0)
    (jump,) = camera_jumps(reset, integrate_gyro(gyro), 0.2)
    fixed = glued(reset, [jump])
    rel = [np.swapaxes(s.R[:-1], -1, -2) @ s.R[1:] for s in (camera, fixed)]
    i = int(np.searchsorted(camera.t, jump.start_s))
    others = np.arange(len(rel[0])) != i
    assert angle_between_deg(rel[0][others], rel[1][others]).max() < 1e-6
    assert angle_between_deg(rel[1][i], rel[1][i - 1]) < 1e-9  # the jump's step: the one before it
    assert angle_between_deg(rel[0][i], rel[1][i]) < 1.0  # within a step's change of the true one


def test_the_pairs_spanning_a_jump_are_dropped_and_said():
    jump = CameraJump(10.0, 10.05, 90.0, 1.0)
    t = np.array([8.99, 9.0, 9.01, 10.05, 10.06])
    assert spanning([jump], t, 1.0).tolist() == [False, False, True, False, False]
    (reason,) = jump_reasons([jump], 2.0, 20)
    assert reason.check == "camera_jump" and reason.level == "warning"
    assert "8.00 s (90.0 deg)" in reason.message and "the 20 pairs" in reason.message
    assert jump_reasons([], 0.0, 0) == []


@pytest.mark.parametrize("deg, found", [(0.95 * JUMP_MIN_DEG, False), (1.05 * JUMP_MIN_DEG, True)])
def test_against_r0_a_jump_hidden_by_fast_motion_is_found_above_jump_min_deg(deg, found):
    """Where the sensor turns fast, camera_jumps cannot see a 20 deg reset; against R0 and the
    offset the camera step's misfit is the reset's own angle, whatever the motion."""
    camera, gyro = noisy_rig(8, 30.0, 0.0, 0.0)
    oriented = integrate_gyro(gyro)
    i = int(np.argmax(angle_between_deg(camera.R[:-1], camera.R[1:])[20:-20])) + 20
    at = camera.t[i] + 0.01
    assert not camera_jumps(_reset(camera, [at], 1.05 * JUMP_MIN_DEG), oriented, 0.2)
    jumps = residual_jumps(_reset(camera, [at], deg), oriented, RIG_R0, 0.0)
    assert bool(jumps) is found
    if found:
        assert jumps[0].start_s == camera.t[i]
    assert residual_jumps(camera, oriented, RIG_R0, 0.0) == []


def test_a_fast_camera_turn_is_no_jump_against_a_sensor_out_of_step():
    """The sensor's clock 10 s off: a fast camera step where the sensor rests is not a jump (the
    camera's own neighbouring steps are as large); a reset there is."""
    _, camera, gyro, _ = rig_streams(40.0, rest_s=30.0)
    R = camera.R.copy()
    fast = matrix_from_rotation_vector(np.radians(8.0) * AXIS)
    i = int(np.searchsorted(camera.t, 10.0))
    for j in range(i - 5, i + 6):  # a fast turn, 8 deg per step, in the rest
        R[j + 1:] = R[j + 1:] @ fast
    moving = OrientationStream(camera.t, R, "camera")
    assert camera_jumps(moving, integrate_gyro(gyro), 0.2) == []
    assert len(camera_jumps(_reset(moving, [20.02], 30.0), integrate_gyro(gyro), 0.2)) == 1


def test_glued_poses_stay_rotations_however_many_jumps():
    """Each glue turns the rest of the trajectory by an exact rotation: after 30 jumps every pose
    passes the streams' rotation check (an unprojected turn multiplied the rounding by about 5 a
    jump: 1e-6 after 15, beyond the check's 1e-5 after 20)."""
    rng = np.random.default_rng(0)
    t = np.arange(2700) * 0.05
    R = matrix_from_rotation_vector(np.cumsum(rng.normal(0, 0.05, (len(t), 3)), axis=0))
    camera = OrientationStream(t, R, "camera")
    k = np.searchsorted(t, np.linspace(5.0, 130.0, 30))
    fixed = glued(camera, [CameraJump(float(t[i]), float(t[i + 1]), 30.0, 1.0) for i in k])
    assert np.linalg.norm(np.swapaxes(fixed.R, -1, -2) @ fixed.R - np.eye(3), axis=(1, 2)).max() < 1e-12
    steps = np.swapaxes(fixed.R[:-1], -1, -2) @ fixed.R[1:]
    kept = np.ones(len(t) - 1, bool)
    kept[k] = False
    np.testing.assert_allclose(steps[kept], (np.swapaxes(R[:-1], -1, -2) @ R[1:])[kept], atol=1e-12)
