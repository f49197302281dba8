"""Testing helpers shared by the test suite, the benchmarks and the online studies (and usable in a
user's own tests): the synthetic rig (:func:`rig_streams`, its mounting :data:`RIG_R0`), a rotation
comparison that names the worst index, and the writers of the file formats ``calibrate`` reads."""
from __future__ import annotations

import numpy as np

from ._jitter import jitter
from .core.checks import check_matrices
from .core.so3 import (
    angle_between_deg,
    matrix_from_rotation_vector,
    quaternion_from_matrix,
    rotation_vector_from_matrix,
)

__all__ = ["RIG_R0", "rig_motion", "rig_streams", "noisy_rig", "rig_pairs", "camera_lost", "clock_jumped",
           "samples_lost", "clock_stepped", "clock_drifting", "camera_clock_jumped", "misaligned_rig",
           "assert_rotations_close", "write_tum_trajectory", "write_euroc_imu"]

#: The synthetic rig's ``camera_from_sensor``: 40, -70, 125 deg as a rotation vector's components (a
#: generic mounting, about 150 deg).
RIG_R0 = matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))


def rig_motion(t, phase=0.0, rest_s: float = 0.0):
    """The synthetic rig's ``world_from_camera`` at times ``t`` (s): smooth turns about all three
    axes, rotation-vector components ``0.9 sin(0.7 t + p0)``, ``0.8 sin(0.45 t + 1 + p1)``, ``0.7
    cos(0.3 t + p2)`` (angles up to 0.9 rad, periods of 9-21 s); ``phase`` (a number or one per
    component) shifts the motion (another trajectory). With ``rest_s``, the rig rests until
    ``rest_s`` and starts moving over the next 2 s (a smoothstep on the rotation vector)."""
    t = np.asarray(t, dtype=float)
    p = np.broadcast_to(np.asarray(phase, dtype=float), (3,))
    w = np.stack([0.9 * np.sin(0.7 * t + p[0]), 0.8 * np.sin(0.45 * t + 1.0 + p[1]), 0.7 * np.cos(0.3 * t + p[2])],
                 axis=-1)
    if rest_s:
        s = np.clip((t - rest_s) / 2.0, 0.0, 1.0)
        w = (s * s * (3 - 2 * s))[..., None] * w
    return matrix_from_rotation_vector(w)


def rig_streams(seconds: float = 60.0, *, R0=None, rng: np.random.Generator | None = None,
                camera_noise_deg=0.0, gyro_noise_deg_s=0.0, phase=0.0, offset: float = 0.0,
                sensor_step: int = 2, remount=None, bias=None, ppm: float = 0.0, rest_s: float = 0.0):
    """A synthetic rig's streams: a camera at 20 Hz and, rigidly attached (``v_cam = R0 v_sensor``),
    a gyro at 200 Hz and an orientation sensor at ``200 / sensor_step`` Hz, moving as
    :func:`rig_motion`.

    Parameters
    ----------
    seconds : float
        Length of the camera stream (the sensor streams extend one second beyond it on both sides).
    R0 : (3, 3), optional
        ``camera_from_sensor`` (default :data:`RIG_R0`).
    rng : numpy.random.Generator, optional
        Needed for noise: isotropic Gaussian rotation-vector noise of RMS ``camera_noise_deg`` on
        each camera orientation (drawn first), and white noise of RMS ``gyro_noise_deg_s`` (deg/s,
        per axis) on each gyro sample.
    camera_noise_deg, gyro_noise_deg_s : float or callable
        A callable is a caller's own draws: called with a shape ``(n, 3)``, camera first, it returns
        the rotation vectors (rad) applied on the right of each camera orientation, or the rates
        (rad/s) added to each gyro sample.
    phase : float or (3,)
        Shifts the motion (:func:`rig_motion`).
    offset : float
        The sensor's clock reads ``offset`` s ahead of the camera's: the gyro and orientation
        samples of camera time ``t`` are stamped ``t + offset``.
    sensor_step : int
        The orientation sensor keeps every ``sensor_step``-th sample of the 200 Hz grid.
    bias : (3,), optional
        A constant gyro bias (rad/s) added to every rate (before the noise).
    ppm : float
        The gyro's clock runs fast by ``ppm`` parts per million about the middle of the recording:
        its sample of camera time ``t`` is stamped ``t + offset + ppm 1e-6 (t - seconds / 2)``.
    rest_s : float
        The rig rests until ``rest_s`` (s), then starts moving over 2 s (:func:`rig_motion`).
    remount : (float, (3, 3)), optional
        ``(time, R)``: the sensor is re-mounted ``R`` further from ``time`` (s, on the sensor's
        clock) on (:func:`replication.rig.changepoint.remounted`, applied to the gyro and the
        orientation sensor).

    Returns
    -------
    (R0, camera, gyro, sensor) : (ndarray, OrientationStream, GyroStream, OrientationStream)
        ``R0`` as mounted at the start.
    """
    from .rig.streams import GyroStream, OrientationStream

    R0 = RIG_R0 if R0 is None else np.asarray(R0, dtype=float)
    drawn = [x for x in (camera_noise_deg, gyro_noise_deg_s) if not callable(x)]
    if any(drawn) and not isinstance(rng, np.random.Generator):
        raise ValueError("noise needs rng, a numpy.random.Generator")
    t_cam = np.arange(0.0, seconds, 0.05)
    C = rig_motion(t_cam, phase, rest_s)
    if callable(camera_noise_deg):
        C = C @ matrix_from_rotation_vector(camera_noise_deg((len(t_cam), 3)))
    elif camera_noise_deg:
        C = C @ matrix_from_rotation_vector(rng.normal(0.0, np.radians(camera_noise_deg) / np.sqrt(3.0), (len(t_cam),
                                                                                                          3)))
    t_imu = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = rig_motion(t_imu, phase, rest_s) @ R0  # world_from_sensor
    # body rates over each step, at its midpoint
    omega = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    if bias is not None:
        omega = omega + np.asarray(bias, dtype=float)
    if callable(gyro_noise_deg_s):
        omega = omega + gyro_noise_deg_s(omega.shape)
    elif gyro_noise_deg_s:
        omega = omega + rng.normal(0.0, np.radians(gyro_noise_deg_s), omega.shape)
    C, omega, Q = jitter(C), jitter(omega), jitter(Q)
    t_gyro = 0.5 * (t_imu[1:] + t_imu[:-1])
    if offset or ppm:
        t_gyro, t_imu = t_gyro + offset + ppm * 1e-6 * (t_gyro - 0.5 * seconds), t_imu + offset
    gyro = GyroStream(t_gyro, omega, "gyro")
    sensor = OrientationStream(t_imu[::sensor_step], Q[::sensor_step], "sensor")
    if remount is not None:
        from .rig.changepoint import remounted

        gyro, sensor = remounted(gyro, *remount), remounted(sensor, *remount)
    return R0, OrientationStream(t_cam, C, "camera"), gyro, sensor


def noisy_rig(seed: int, seconds: float, cam_deg: float, gyro_rad_s: float, bias_rad_s: float = 0.0, remount=None,
              drift_deg: float = 0.0):
    """``(camera, gyro)`` of :func:`rig_streams` as the change and segment tests draw it from
    ``seed``: the motion's phases uniform per component, then noise of ``cam_deg`` (deg) per axis on
    each camera orientation and ``gyro_rad_s`` (rad/s) per axis on each gyro sample, and a constant
    gyro bias of ``bias_rad_s`` (rad/s) in a random direction.

    ``drift_deg``: the camera frame also wanders (a random walk of ``drift_deg`` per 10 s per axis,
    as a SLAM trajectory's error may); ``remount = (t, R)``: the gyro is re-mounted ``R`` further at
    ``t``."""
    from .rig.streams import OrientationStream

    rng = np.random.default_rng(seed)
    phase = rng.uniform(0.0, 2.0 * np.pi, 3)
    t_cam = np.arange(0.0, seconds, 0.05)
    noise = matrix_from_rotation_vector(rng.normal(0.0, np.radians(cam_deg), (len(t_cam), 3)))
    if drift_deg:
        steps = rng.normal(0.0, np.radians(drift_deg) * np.sqrt(0.05 / 10.0), (len(t_cam), 3))
        noise = matrix_from_rotation_vector(np.cumsum(steps, axis=0)) @ noise
    camera = OrientationStream(t_cam, rig_motion(t_cam, phase) @ noise, "camera")  # a wander is no rotation vector
    _, _, gyro, _ = rig_streams(
        seconds, phase=phase, remount=remount,
        gyro_noise_deg_s=lambda n: rng.normal(0.0, gyro_rad_s, n) + bias_rad_s * rng.normal(size=3) / np.sqrt(3.0))
    return camera, gyro


def rig_pairs(camera, gyro, interval: float = 1.0):
    """``(A, B, t, block)``: pairs as ``calibrate`` forms them (the gyro integrated, the clock
    offset estimated and removed; no gaps) and the camera frames per interval."""
    from .rig.association import estimate_time_offset, motion_pairs
    from .rig.streams import integrate_gyro

    sensor = integrate_gyro(gyro)
    offset, _ = estimate_time_offset(camera, sensor, resolution=0.5e-3)
    A, B, t = motion_pairs(camera, sensor, interval, offset=offset)
    return A, B, t, max(1, round(interval / np.median(np.diff(camera.t))))


def camera_lost(camera, rng: np.random.Generator, wander_deg: float, lost_s: float):
    """``camera`` whose frame wanders during ``[0, lost_s)``: a random walk of ``wander_deg`` per 10
    s about each camera axis, bridged back to the true frame at ``lost_s`` (a SLAM frame lost and
    re-found)."""
    from .rig.streams import OrientationStream

    t = camera.t
    steps = rng.normal(0.0, np.radians(wander_deg) * np.sqrt(0.05 / 10.0), (len(t), 3)) * (t < lost_s)[:, None]
    path = np.cumsum(steps, axis=0)
    path -= np.minimum(t / lost_s, 1.0)[:, None] * path[-1]  # a bridge: the frame is found again at lost_s
    walk = matrix_from_rotation_vector(path)  # the camera frame wanders: world_from_camera' = world_from_camera W(t)
    return OrientationStream(t, camera.world_from_body @ walk, "camera (lost for a stretch)")


def clock_jumped(gyro, at: float, size: float):
    """``gyro`` whose clock jumps ahead by ``size`` s at ``at`` (its stamps from then on read
    ``size`` later)."""
    from .rig.streams import GyroStream

    t = np.where(gyro.t >= at, gyro.t + size, gyro.t)
    return GyroStream(t, gyro.omega, gyro.source)


def samples_lost(gyro, at: float, count: int):
    """``gyro`` with ``count`` samples lost from ``at`` on (a gap in the stamps, the clock
    unchanged)."""
    from .rig.streams import GyroStream

    k = np.searchsorted(gyro.t, at)
    keep = np.ones(len(gyro.t), bool)
    keep[k:k + count] = False
    return GyroStream(gyro.t[keep], gyro.omega[keep], gyro.source)


def clock_stepped(gyro, at: float, count: int):
    """``gyro`` losing ``count`` samples at ``at`` while its stamps run on evenly: its clock steps
    back by ``count`` sample intervals there, with no skip in the stamps to show it."""
    from .rig.streams import GyroStream

    i = int(np.searchsorted(gyro.t, at))
    omega = np.concatenate([gyro.omega[:i], gyro.omega[i + count:]])
    return GyroStream(gyro.t[:len(omega)], omega, gyro.source)


def clock_drifting(gyro, ppm: float, mid: float):
    """``gyro`` whose clock runs ``ppm`` parts per million fast, agreeing with the camera's at
    ``mid`` (s)."""
    from .rig.streams import GyroStream

    return GyroStream(gyro.t + ppm * 1e-6 * (gyro.t - mid), gyro.omega, gyro.source)


def camera_clock_jumped(camera, at: float, size: float):
    """``camera`` whose clock jumps ahead by ``size`` s at ``at`` (a skip in its stamps)."""
    from .rig.streams import OrientationStream

    return OrientationStream(np.where(camera.t >= at, camera.t + size, camera.t), camera.world_from_body, "camera")


def misaligned_rig(seed: int, size: float, seconds: float = 40.0, bias=(0.03, -0.02, 0.04)):
    """``(R0, camera, gyro, mu)``: :func:`rig_streams` from ``default_rng(seed)`` (its phases drawn,
    camera noise 0.05 deg, gyro noise 0.2 deg/s), the gyro reading ``T omega + bias`` with ``T = I +
    N(mu)``, ``mu`` the symmetric off-diagonal terms ``xy, xz, yz`` of ``size`` with random
    signs."""
    from .rig.gyro_model import axes_matrix
    from .rig.streams import GyroStream

    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)
    mu = size * rng.choice([-1.0, 1.0], 3)
    R0, camera, gyro, _ = rig_streams(seconds, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2, phase=phase,
                                      bias=(0.0, 0.0, 0.0))
    T = axes_matrix(np.zeros(3), mu)
    return R0, camera, GyroStream(gyro.t, gyro.omega @ T.T + np.asarray(bias, float), "gyro"), mu


def assert_rotations_close(R, R_ref, atol_deg: float, *, name: str = "R") -> None:
    """Raise ``AssertionError`` unless every rotation of ``R`` is within ``atol_deg`` of ``R_ref``.

    The message names the worst index and its angle. ``R`` and ``R_ref`` broadcast.

    >>> import numpy as np
    >>> assert_rotations_close(np.eye(3), np.eye(3), 1e-9)
    """
    R = check_matrices(R, name)
    R_ref = check_matrices(R_ref, "R_ref")
    angle = np.atleast_1d(angle_between_deg(R, R_ref))
    idx = np.unravel_index(int(np.argmax(angle)), angle.shape)
    if not angle[idx] <= atol_deg:
        raise AssertionError(
            f"{name} differs from the reference by {float(angle[idx]):.3g} deg at index "
            f"{tuple(int(i) for i in idx)} (> {atol_deg:g} deg; {int(np.sum(angle > atol_deg))} of {angle.size} off)"
        )


def write_tum_trajectory(path, stream) -> None:
    """Write an orientation stream (``t`` in s, ``R`` world_from_body) as a TUM trajectory (zero
    positions, quaternion x y z w), as ``calibrate --camera`` reads it."""
    q = quaternion_from_matrix(stream.R)
    rows = np.column_stack([stream.t, np.zeros((len(stream.t), 3)), q[:, 1:], q[:, :1]])
    np.savetxt(path, rows, fmt="%.9f")


def write_euroc_imu(path, gyro) -> None:
    """Write a gyro stream (``t`` in s, ``omega`` in rad/s) as an EuRoC ``imu0/data.csv`` (ns
    stamps, a constant accelerometer), as ``calibrate --sensor ... --sensor-kind gyro`` reads it."""
    rows = np.column_stack([np.round(gyro.t * 1e9), gyro.omega, np.tile([0.0, 0.0, 9.81], (len(gyro.t), 1))])
    np.savetxt(path, rows, fmt=["%d"] + ["%.9f"] * 6, delimiter=",", header="timestamp,w,w,w,a,a,a")
