"""Name the usual input mistakes of a calibration where the data show them.

When a calibration's verdict is not ``ok``, :func:`input_mistakes` re-reads the inputs under each usual mistake
undone and calibrates again (quickly: the certified minimiser, no bootstrap):

* quaternion component order: a file's ``(w, x, y, z)`` read as ``(x, y, z, w)``, or the reverse, for the camera
  stream and for an orientation sensor stream;
* pose direction: ``camera_from_world`` (or ``sensor_from_world``) written where ``world_from_body`` belongs;
* gyro units: rates in deg/s read as rad/s.

A hypothesis is named when, with it undone, the median pair residual falls below :data:`FIT_SHARE` of the
calibration's and below :data:`FIT_TO_MOTION` of the median motion (what a correct ``R0`` leaves, see
:mod:`replication.quality`); the reason then carries both residuals. Time-unit mistakes show before any
calibration, in the streams' spans (:func:`replication.calibration.calibrate` names them when refusing streams
that do not overlap).
"""
from __future__ import annotations

import warnings

import numpy as np

from .quality import Reason
from .so3 import as_quaternion, quaternion_to_matrix
from .streams import GyroStream, OrientationStream

__all__ = ["input_mistakes", "pose_direction", "FIT_SHARE", "FIT_TO_MOTION", "POSE_FIT_SHARE"]

#: Static pose sets: an inverted hypothesis is named when its median residual is below this share of the input's.
POSE_FIT_SHARE = 0.6

#: A hypothesis fits when its median residual is below this share of the calibration's ...
FIT_SHARE = 0.2
#: ... and below this share of the median motion angle.
FIT_TO_MOTION = 0.1

#: Reorderings of a stored ``(w, x, y, z)`` quaternion that undo a component-order mistake.
_ORDERS = {
    "quaternions in (w, x, y, z) order read as (x, y, z, w)": [1, 2, 3, 0],
    "quaternions in (x, y, z, w) order read as (w, x, y, z)": [3, 0, 1, 2],
}


def _reordered(stream: OrientationStream, order) -> OrientationStream:
    q = as_quaternion(stream.world_from_body)[:, order]
    return OrientationStream(stream.t, quaternion_to_matrix(q), stream.source)


def _inverted(stream: OrientationStream) -> OrientationStream:
    return OrientationStream(stream.t, np.swapaxes(stream.world_from_body, -1, -2), stream.source)


def _hypotheses(camera, sensor):
    """``(side, mistake, camera, sensor)`` with the mistake undone."""
    for name, order in _ORDERS.items():
        yield "camera", name, _reordered(camera, order), sensor
    yield "camera", "camera_from_world poses where world_from_camera belongs", _inverted(camera), sensor
    if isinstance(sensor, OrientationStream):
        for name, order in _ORDERS.items():
            yield "sensor", name, camera, _reordered(sensor, order)
        yield "sensor", "sensor_from_world poses where world_from_sensor belongs", camera, _inverted(sensor)
        yield "camera and sensor", "inverted poses (body_from_world) in both", _inverted(camera), _inverted(sensor)
    if isinstance(sensor, GyroStream):
        yield "sensor", "gyro rates in deg/s read as rad/s", camera, GyroStream(sensor.t, np.radians(sensor.omega),
                                                                               sensor.source)


def input_mistakes(camera, sensor, result, *, interval: float, max_offset: float) -> list[Reason]:
    """Reasons naming each input mistake whose undoing makes the calibration fit (see the module notes)."""
    from .calibration import calibrate

    base = result.residual_deg["median"]
    motion = result.diagnostics.get("motion_median_deg", np.nan)
    fits = []
    for side, mistake, cam, sen in _hypotheses(camera, sensor):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trial = calibrate(cam, sen, interval=interval, max_offset=max_offset, n_bootstrap=0, diagnose=False)
        except ValueError:
            continue
        fit = trial.residual_deg["median"]
        if fit < FIT_SHARE * base and fit < FIT_TO_MOTION * trial.diagnostics["motion_median_deg"]:
            fits.append((fit, f"the {side} file holds {mistake}", trial.time_offset_correlation))
    if not fits:
        return []
    fits.sort(key=lambda f: f[0])
    best = fits[0][0]
    # some mistakes change every motion the same way up to one fixed rotation (absorbed by R0): the residuals
    # cannot tell them apart, so all that fit as well are named
    names = [f[1] for f in fits if f[0] <= 1.1 * best]
    which = names[0] if len(names) == 1 else " or ".join(names) + " (the motions alone cannot tell which)"
    return [Reason("input_mistake", "fail", float(best), float(base),
                   f"likely input mistake: {which}; with that undone the median pair residual falls from {base:.3g} "
                   f"deg to {best:.3g} deg (median motion {motion:.3g} deg) and the time-offset correlation is "
                   f"{fits[0][2]:.3f}")]


def pose_direction(C, S, result, *, pairs: str, min_motion_deg: float) -> list[Reason]:
    """Static pose sets: calibrate with the camera poses or the robot poses inverted; a ``fail`` reason
    naming the pose direction when one fits clearly better (median residual below :data:`POSE_FIT_SHARE` of the
    input's). Static poses carry no clock or speed to check, so this runs on every pose calibration."""
    from .calibration import calibrate_poses

    base = result.residual_deg["median"]
    inv = lambda M: np.swapaxes(M, -1, -2)  # noqa: E731
    fits = []
    # (both sets inverted is a consistent problem for another unknown, the world-to-world rotation: the rotations
    # alone cannot show it, only a reference can; see replication.quality)
    for mistake, c, s in (("camera poses inverted (target_from_camera where camera_from_target belongs)", inv(C), S),
                          ("robot poses inverted (base_from_hand where hand_from_base belongs)", C, inv(S))):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trial = calibrate_poses(c, s, pairs=pairs, min_motion_deg=min_motion_deg, n_bootstrap=0,
                                        diagnose=False)
        except ValueError:
            continue
        fits.append((trial.residual_deg["median"], mistake))
    best = min(fits, default=None)
    if best is None or not best[0] < POSE_FIT_SHARE * base:
        return []
    return [Reason("input_mistake", "fail", float(best[0]), float(base),
                   f"likely input mistake: {best[1]}; with that undone the median pair residual falls from "
                   f"{base:.3g} deg to {best[0]:.3g} deg")]

