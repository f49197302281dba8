"""Name the usual input mistakes of a calibration where the data show them. Theory and measured
numbers: ``docs/judging.md``, section ``replication.rig.diagnose``."""
from __future__ import annotations

import warnings

import numpy as np

from ..core.so3 import angle_between_deg, matrix_from_quaternion, quaternion_from_matrix
from .quality import THRESHOLDS, Reason
from .streams import GyroStream, OrientationStream

__all__ = ["input_mistakes", "pose_direction", "reference_mistakes", "HYPOTHESES", "POSE_HYPOTHESES", "FIT_SHARE",
           "FIT_TO_MOTION", "POSE_FIT_SHARE", "TIE_SHARE", "TIE_ATOL", "IMU_AS_CAMERA_DEG"]

#: The camera file looks like the IMU's own trajectory when ``R0`` is within this angle (deg) of the
#: identity while the reference is more than twice as far from it. Measured with the IMU body's pose
#: as the camera (TUM-VI mocap0 against its raw gyro, intervals 0.5 / 1 / 2 s): 0.04-0.07 deg; with
#: a gyro bias added, EuRoC's (about 0.08 rad/s) 0.42-0.98 deg, 0.1 rad/s on one axis and 0.05 on
#: two 1.07-3.65 deg. The rigs' references are 89 deg (EuRoC cam0) and 179 deg (TUM-VI cam0) from
#: the identity. The same bound (the reference check's fail bound) tells the files swapped: ``R0``
#: within it of the reference's inverse (EuRoC, ground truth as camera and the camera's SLAM
#: trajectory as sensor: 0.14-0.18 deg; TUM-VI: 0.09-0.11 deg).
IMU_AS_CAMERA_DEG = 5.0

#: Static pose sets: an inverted hypothesis is named when its median residual is below this share of
#: the input's.
POSE_FIT_SHARE = 0.6

#: A hypothesis fits when its median residual is below this share of the calibration's ...
FIT_SHARE = 0.2
#: ... and below this share of the median motion angle.
FIT_TO_MOTION = 0.1
#: Fitting hypotheses whose median residual is within this factor of the best one (plus
#: :data:`TIE_ATOL`) are one finding: the data cannot tell them apart (measured: tied hypotheses
#: differ in the 14th digit on real recordings; distinct ones by factors of 2 and more).
TIE_SHARE = 1.1
#: ... and within this (deg) in absolute terms: residual angles of data that fit exactly
#: (noise-free) are rounding,
#: 1e-14 to 1e-12 deg, whose order means nothing.
TIE_ATOL = 1e-6

#: Reorderings of a stored ``(w, x, y, z)`` quaternion that undo a component-order mistake.
_ORDERS = {
    "quaternions in (w, x, y, z) order read as (x, y, z, w)": [1, 2, 3, 0],
    "quaternions in (x, y, z, w) order read as (w, x, y, z)": [3, 0, 1, 2],
}

#: Every stream hypothesis, in the order findings name them: ``(side, mistake)``.
HYPOTHESES = (
    *(("camera", name) for name in _ORDERS),
    ("camera", "camera_from_world poses where world_from_camera belongs"),
    *(("sensor", name) for name in _ORDERS),
    ("sensor", "sensor_from_world poses where world_from_sensor belongs"),
    ("camera and sensor", "inverted poses (body_from_world) in both"),
    ("sensor", "gyro rates in deg/s read as rad/s"),
)

#: Static pose-set hypotheses, in the order findings name them.
POSE_HYPOTHESES = (
    "camera poses inverted (target_from_camera where camera_from_target belongs)",
    "robot poses inverted (base_from_hand where hand_from_base belongs)",
)


def _reordered(stream: OrientationStream, order) -> OrientationStream:
    q = quaternion_from_matrix(stream.world_from_body)[:, order]
    return OrientationStream(stream.t, matrix_from_quaternion(q), stream.source)


def _inverted(stream: OrientationStream) -> OrientationStream:
    return OrientationStream(stream.t, np.swapaxes(stream.world_from_body, -1, -2), stream.source)


def _undone(side: str, mistake: str, camera, sensor):
    """``(camera, sensor)`` with the mistake undone, or None where it does not apply to these
    streams."""
    orientation = isinstance(sensor, OrientationStream)
    if mistake in _ORDERS:
        if side == "camera":
            return _reordered(camera, _ORDERS[mistake]), sensor
        return (camera, _reordered(sensor, _ORDERS[mistake])) if orientation else None
    if mistake.startswith("camera_from_world"):
        return _inverted(camera), sensor
    if mistake.startswith("sensor_from_world"):
        return (camera, _inverted(sensor)) if orientation else None
    if mistake.startswith("inverted poses"):
        return (_inverted(camera), _inverted(sensor)) if orientation else None
    if isinstance(sensor, GyroStream):
        return camera, GyroStream(sensor.t, np.radians(sensor.omega), sensor.source)
    return None


def _one_finding(fits, base, names, reference, what_else=""):
    """The tied group of ``fits`` (``(order, residual, name, R, extra)``) as one sentence, in the
    fixed order."""
    best = min(f[1] for f in fits)
    tied = sorted((f for f in fits if f[1] <= TIE_SHARE * best + TIE_ATOL), key=lambda f: f[0])
    note = ""
    if len(tied) > 1 and reference is not None:
        bound = THRESHOLDS["reference_error_deg"][1]
        angles = [float(angle_between_deg(f[3], reference)) for f in tied]
        agree = [f for f, a in zip(tied, angles) if a <= bound]
        if agree and len(agree) < len(tied):
            note = ("; the reference tells them apart: " + ", ".join(
                f"{names(f)} {a:.3g} deg from it" for f, a in zip(tied, angles)))
            tied = agree
    if len(tied) == 1:
        which = names(tied[0])
    else:
        which = ", or ".join(names(f) for f in tied) + ": the data cannot tell which; a reference can"
    return tied, (f"likely input mistake: {which}{note}; with that undone the median pair residual falls from "
                  f"{base:.3g} deg to {best:.3g} deg{what_else}")


def reference_mistakes(R, reference) -> list[Reason]:
    """Reasons naming the likely cause where the estimate ``R`` disagrees with the ``reference``
    beyond the reference check's ``fail`` bound: the camera file holding the IMU's own trajectory
    (``R`` within :data:`IMU_AS_CAMERA_DEG` of the identity, the reference more than twice that from
    it), or the camera and sensor files swapped (``R`` within the fail bound of the reference's
    inverse). ``[]`` otherwise, or without a reference."""
    if reference is None or R is None:
        return []
    bound = THRESHOLDS["reference_error_deg"][1]
    error = float(angle_between_deg(R, reference))
    if not error > bound:
        return []
    to_identity, reference_to_identity = (float(angle_between_deg(M, np.eye(3))) for M in (R, reference))
    if to_identity <= IMU_AS_CAMERA_DEG and reference_to_identity > 2 * IMU_AS_CAMERA_DEG:
        return [Reason("imu_as_camera", "fail", to_identity, IMU_AS_CAMERA_DEG,
                       f"the camera file looks like the IMU's own trajectory (a VIO output, or the IMU body's ground "
                       f"truth or mocap): R0 within {to_identity:.3g} deg of the identity (<= {IMU_AS_CAMERA_DEG:g} "
                       f"deg), while the reference is {reference_to_identity:.3g} deg from it; give the camera's own "
                       f"trajectory (vision only), or the camera is mounted with the IMU's axes and the reference "
                       f"is for another rig")]
    swapped = float(angle_between_deg(R, np.swapaxes(reference, -1, -2)))
    if swapped <= bound:
        return [Reason("files_swapped", "fail", swapped, bound,
                       f"the camera and sensor files look swapped: R0 is {swapped:.3g} deg from the reference's "
                       f"inverse (<= {bound:g} deg) and {error:.3g} deg from the reference; give the camera's "
                       f"trajectory as --camera and the sensor's as --sensor")]
    return []


def input_mistakes(camera, sensor, *, base_residual_deg: float, motion_deg: float, interval: float,
                   max_offset: float, calibrate, reference=None, R=None) -> list[Reason]:
    """Reasons naming each input mistake whose undoing makes the calibration fit (see the module
    notes).

    Parameters
    ----------
    camera, sensor : streams
        As given to the calibration.
    base_residual_deg, motion_deg : float
        The calibration's median pair residual and median motion angle.
    interval, max_offset : float
        As given to the calibration.
    calibrate : callable
        :func:`replication.rig.calibration.calibrate` (re-run on each hypothesis, no bootstrap, no
        diagnosis).
    reference : (3, 3) array, optional
        A reference ``R0``: tells tied hypotheses apart where it agrees with some of them only.
    R : (3, 3) array, optional
        The calibration's estimate: with ``reference``, :func:`reference_mistakes` is checked too.
    """
    named = reference_mistakes(R, reference)
    fits = []
    for order, (side, mistake) in enumerate(HYPOTHESES):
        streams = _undone(side, mistake, camera, sensor)
        if streams is None:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trial = calibrate(*streams, interval=interval, max_offset=max_offset, n_bootstrap=0, diagnose=False)
        except ValueError:
            continue
        fit = trial.residual_deg["median"]
        if fit < FIT_SHARE * base_residual_deg and fit < FIT_TO_MOTION * trial.diagnostics["motion_median_deg"]:
            fits.append((order, fit, f"the {side} file holds {mistake}", trial.R, trial.time_offset_correlation))
    if not fits:
        return named
    tied, message = _one_finding(fits, base_residual_deg, lambda f: f[2], reference)
    message += f" (median motion {motion_deg:.3g} deg) and the time-offset correlation is {tied[0][4]:.3f}"
    return [Reason("input_mistake", "fail", float(min(f[1] for f in fits)), float(base_residual_deg), message),
            *named]


def pose_direction(C, S, *, base_residual_deg: float, pairs: str, min_motion_deg: float, calibrate_poses,
                   reference=None) -> list[Reason]:
    """Static pose sets: calibrate with the camera poses or the robot poses inverted; a ``fail``
    reason naming the pose direction when one fits clearly better (median residual below
    :data:`POSE_FIT_SHARE` of the input's). Static poses carry no clock or speed to check, so this
    runs on every pose calibration. Both sets inverted is a consistent problem for another unknown
    (the world-to-world rotation): the rotations alone cannot show it, only a reference can (see
    :mod:`replication.rig.quality`)."""
    inv = lambda M: np.swapaxes(M, -1, -2)  # noqa: E731
    fits = []
    for order, (mistake, c, s) in enumerate(zip(POSE_HYPOTHESES, (inv(C), C), (S, inv(S)))):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trial = calibrate_poses(c, s, pairs=pairs, min_motion_deg=min_motion_deg, n_bootstrap=0,
                                        diagnose=False)
        except ValueError:
            continue
        if trial.residual_deg["median"] < POSE_FIT_SHARE * base_residual_deg:
            fits.append((order, trial.residual_deg["median"], mistake, trial.R, None))
    if not fits:
        return []
    _, message = _one_finding(fits, base_residual_deg, lambda f: f[2], reference)
    return [Reason("input_mistake", "fail", float(min(f[1] for f in fits)), float(base_residual_deg), message)]
