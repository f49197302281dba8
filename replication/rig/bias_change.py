"""When and how the gyro's bias changes: the residual rate ``omega_sensor - R0^T omega_camera`` per
camera step, once the sensor model's one bias is removed, fitted by a step at the least-squares time
and by a steady ramp; the better of the two is removed from the rates so that the change and segment
tests do not read a bias change as a re-mount. Theory and measured numbers: ``docs/judging.md``,
section ``replication.rig.bias_change``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.so3 import rotation_vector_from_matrix
from .streams import GyroStream, OrientationStream

__all__ = ["BiasChange", "rate_residuals", "fit_bias_change", "bias_change_of", "named_in", "MIN_SIDE_S", "CLIP_MAD"]

#: A step leaves at least this much of the recording (s) on each side: a shorter side's mean is the
#: camera's noise.
MIN_SIDE_S = 2.0
#: Residual rates further than this many robust standard deviations (1.4826 MAD) from the median,
#: per axis, are clipped there: a camera pose tracked badly must not move a side's mean.
CLIP_MAD = 5.0


@dataclass(frozen=True)
class BiasChange:
    """The bias change removed: ``kind`` ``"step"`` (``time_s``, ``before`` and ``after`` the bias
    left by the one-bias model on either side, rad/s) or ``"ramp"`` (``before`` and ``after`` the
    bias at the recording's first and last step); ``size_rad_s`` ``|after - before|``; ``t0``,
    ``t1`` the span fitted (s, camera clock); ``offset_s`` the sensor's clock offset used."""

    kind: str
    time_s: float
    before: np.ndarray
    after: np.ndarray
    t0: float
    t1: float
    offset_s: float

    @property
    def size_rad_s(self) -> float:
        return float(np.linalg.norm(self.after - self.before))

    def bias_at(self, t) -> np.ndarray:
        """The fitted change at camera times ``t`` (n, 3): what is left of the bias there."""
        t = np.asarray(t, dtype=float)
        if self.kind == "step":
            return np.where((t < self.time_s)[:, None], self.before, self.after)
        f = np.clip((t - self.t0) / (self.t1 - self.t0), 0.0, 1.0)[:, None]
        return self.before + f * (self.after - self.before)

    def corrected(self, gyro: GyroStream) -> GyroStream:
        """``gyro`` with the change removed (its sample times shifted to the camera's clock by
        ``offset_s``)."""
        return GyroStream(gyro.t, gyro.omega - self.bias_at(gyro.t - self.offset_s), gyro.source)

    def to_dict(self, t0: float) -> dict:
        return {"kind": self.kind, "time_s": self.time_s - t0 if self.kind == "step" else None,
                "size_rad_s": self.size_rad_s, "before_rad_s": self.before.tolist(),
                "after_rad_s": self.after.tolist()}

    def words(self, t0: float) -> str:
        size = f"{math.degrees(self.size_rad_s):.3g} deg/s"
        if self.kind == "step":
            return f"a step of {size} at {self.time_s - t0:.1f} s"
        return f"a steady drift of {size} from {self.t0 - t0:.1f} s to {self.t1 - t0:.1f} s"


def rate_residuals(camera: OrientationStream, oriented: OrientationStream, R, offset: float):
    """Per camera step inside the sensor's span: its mid time, its length and ``omega_sensor - R^T
    omega_camera`` (rad/s, the sensor's frame; ``R = camera_from_sensor``), each body rate the
    step's relative rotation over its length."""
    t = camera.t[(camera.t + offset >= oriented.t[0]) & (camera.t + offset <= oriented.t[-1])]
    if len(t) < 3:
        raise ValueError("fewer than 3 camera samples inside the sensor's span")
    Q, P = camera.at(t), oriented.at(t + offset)
    dt = np.diff(t)
    wc = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / dt[:, None]
    ws = rotation_vector_from_matrix(np.swapaxes(P[:-1], -1, -2) @ P[1:]) / dt[:, None]
    return 0.5 * (t[1:] + t[:-1]), dt, ws - wc @ np.asarray(R)


def _clipped(e):
    med = np.median(e, axis=0)
    s = 1.4826 * np.median(np.abs(e - med), axis=0) + 1e-12
    return np.clip(e, med - CLIP_MAD * s, med + CLIP_MAD * s)


def fit_bias_change(camera: OrientationStream, oriented: OrientationStream, R, offset: float) -> BiasChange | None:
    """The step (at the least-squares time, :data:`MIN_SIDE_S` on each side) or the ramp that fits
    the residual rates better (least squares weighted by the steps' lengths); None where the
    recording is too short for a step."""
    tm, dt, e = rate_residuals(camera, oriented, R, offset)
    e = _clipped(e)
    T = np.concatenate([[0.0], np.cumsum(dt)])
    S = np.concatenate([np.zeros((1, 3)), np.cumsum(e * dt[:, None], axis=0)])
    k = np.flatnonzero((T >= MIN_SIDE_S) & (T <= T[-1] - MIN_SIDE_S))
    k = k[(k > 0) & (k < len(dt))]
    if not len(k):
        return None
    mb, ma = S[k] / T[k, None], (S[-1] - S[k]) / (T[-1] - T[k])[:, None]
    gain_step = T[k] * (T[-1] - T[k]) / T[-1] * np.sum((mb - ma) ** 2, axis=-1)  # the sum of squares explained
    i = int(np.argmax(gain_step))
    x = tm - np.average(tm, weights=dt)
    slope = (x * dt) @ e / float((x * dt) @ x)
    gain_ramp = float((x * dt) @ x) * float(slope @ slope)
    t0, t1 = float(tm[0]), float(tm[-1])
    if gain_step[i] >= gain_ramp:
        return BiasChange("step", float(tm[k[i]] - 0.5 * dt[k[i]]), mb[i], ma[i], t0, t1, float(offset))
    mean = np.average(e, axis=0, weights=dt)
    return BiasChange("ramp", math.nan, mean + slope * (t0 - np.average(tm, weights=dt)),
                      mean + slope * (t1 - np.average(tm, weights=dt)), t0, t1, float(offset))


def named_in(reasons, change: BiasChange | None, t0: float) -> tuple:
    """``reasons`` with the ``gyro_bias_change`` reason naming ``change`` (times since ``t0``) and
    what was done with it."""
    if change is None:
        return tuple(reasons)
    import dataclasses

    return tuple(dataclasses.replace(x, message=x.message + f"; the change fits best as {change.words(t0)}, removed "
                                     "from the rates before the change and segment tests and the fit (not a re-mount)")
                 if x.check == "gyro_bias_change" else x for x in reasons)


def bias_change_of(model, camera: OrientationStream, oriented: OrientationStream) -> BiasChange | None:
    """:func:`fit_bias_change` about the sensor ``model``'s ``R0`` and offset (``oriented``: its
    rates integrated) where its halves' biases differ beyond their noise (``model.bias_changes``);
    else None. Not only where that moves the whole's ``R0`` (``gyro_bias_change``'s floor): a
    split's short side takes up the bias left in its pairs (0.025 deg for the whole, 3.6 deg
    between the sides of a split at 52.8 s of 60 s)."""
    if not model.bias_changes:
        return None
    return fit_bias_change(camera, oriented, model.R, model.offset_mid_s)
