"""A saturated gyro: on an axis, a run of at least :data:`MIN_RUN` consecutive samples pinned at the
same largest rate (the axis's largest value, or its smallest, exactly), entered or left steeply
(the rate heading past it), the gyro clipping at its full scale; every sample at that value is
clipped. The pairs whose sensor-side interval holds a clipped sample are dropped (the integrated
turn is short by what the gyro did not read) and named as a ``gyro_saturation`` reason; a camera
step over clipped samples is no camera jump (the sensor's turn is short there, not the camera's).
Theory and measured numbers: ``docs/judging.md``, section ``replication.rig.saturation``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Saturation", "saturation_of", "MIN_RUN", "MAX_SPOILED_SHARE"]

#: Consecutive samples at an axis's extreme value that make it a clipping limit (entered or left
#: steeply): a noisy gyro does not hold its largest value this many samples in a row; a clipped
#: fast turn of a few tens of ms at 100-1000 Hz holds it for more. A gyro quantised coarser than
#: its noise holds a smooth peak this long: the steep entry tells the two apart.
MIN_RUN = 3
#: More than this share of the pairs holding clipped samples: the rest is too little of the motion
#: to decide R0 (a fail); at or below it, a warning and the rest decide.
MAX_SPOILED_SHARE = 0.5
_AXES = "xyz"


@dataclass(frozen=True)
class Saturation:
    """The clipped samples' times ``t`` (sensor clock), the limits found, ``limits``: tuples
    ``(axis, rate rad/s, samples)``, and the gyro's sample period ``dt_s`` (a sample's rate turns
    the orientation up to one period either side of its time); empty where the gyro never clips."""

    t: np.ndarray
    limits: tuple = ()
    dt_s: float = 0.0

    def holds(self, start, end) -> np.ndarray:
        """Mask: the spans ``[start, end]`` (sensor clock) that hold a clipped sample, or end
        within a sample period of one."""
        start, end = np.asarray(start, float) - self.dt_s, np.asarray(end, float) + self.dt_s
        if not len(self.t):
            return np.zeros(start.shape, bool)
        return np.searchsorted(self.t, end, side="right") > np.searchsorted(self.t, start, side="left")

    def pairs(self, t_start, interval: float, offset: float) -> np.ndarray:
        """Mask of the pairs (start times on the camera's clock; the sensor's: plus ``offset``)
        whose interval holds a clipped sample."""
        s = np.asarray(t_start, float) + offset
        return self.holds(s, s + interval)

    def without(self, gyro):
        """``gyro`` (a :class:`~replication.rig.streams.GyroStream`, or None) without its clipped
        samples: a fit on it crosses or skips the stretch instead of reading the clipped rates."""
        if gyro is None or not len(self.t):
            return gyro
        keep = ~np.isin(gyro.t, self.t)
        return type(gyro)(gyro.t[keep], gyro.omega[keep], gyro.source)

    def reasons(self, dropped, total: int) -> list:
        """A ``gyro_saturation`` reason naming the limits and the ``dropped`` pairs (a mask or a
        count) of ``total``: a fail past :data:`MAX_SPOILED_SHARE`, else a warning."""
        from .quality import Reason

        if not self.limits:
            return []
        n = int(np.sum(dropped))
        share = n / max(1, int(total))
        named = ", ".join(f"{a} at {'+' if r > 0 else '-'}{math.degrees(abs(r)):.1f} deg/s ({k} samples)"
                          for a, r, k in self.limits)
        tail = (f"more than {MAX_SPOILED_SHARE:.0%} of the pairs: the rest is too little to decide R0"
                if share > MAX_SPOILED_SHARE else "R0 is from the rest")
        return [Reason("gyro_saturation", "fail" if share > MAX_SPOILED_SHARE else "warning", share,
                       MAX_SPOILED_SHARE,
                       f"the gyro saturated (clipped at its full scale): {named}, {len(self.t)} samples pinned at "
                       f"an axis's largest rate ({MIN_RUN} or more in a row, the rate heading past it); the {n} of "
                       f"{int(total)} pairs ({share:.1%}) whose interval holds one were dropped, {tail}; a fast "
                       f"turn beyond the gyro's range reads short (set a larger full-scale range)")]


NONE = Saturation(np.zeros(0))


def _runs(mask: np.ndarray) -> list:
    """The runs of True in ``mask``: ``(start, end)`` index pairs, ``end`` exclusive."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def _pinned(w: np.ndarray, at: np.ndarray, value: float) -> bool:
    """Whether a run of :data:`MIN_RUN` or more samples at ``value`` is entered or left steeply: the
    rate's straight line through the two samples outside the run reaches past ``value`` one sample
    into it by more than the axis's quantum plus three times its noise there (a smooth peak held
    within one quantum never does)."""
    levels = np.unique(w)
    quantum = float(np.min(np.diff(levels))) if len(levels) > 1 else 0.0
    sigma = 1.4826 * float(np.median(np.abs(np.diff(w, 2)))) / math.sqrt(6.0) if len(w) > 2 else 0.0
    margin, sign, n = quantum + 3.0 * math.sqrt(5.0) * sigma, math.copysign(1.0, value), len(w)
    for i, j in _runs(at):
        if j - i < MIN_RUN:
            continue
        ahead = [2 * w[i - 1] - w[i - 2]] if i >= 2 else []
        ahead += [2 * w[j] - w[j + 1]] if j + 1 < n else []
        if any(sign * (x - value) > margin for x in ahead):
            return True
    return False


def saturation_of(sensor) -> Saturation:
    """The clipped samples of ``sensor`` (a :class:`~replication.rig.streams.GyroStream`; anything
    else: none)."""
    omega = getattr(sensor, "omega", None)
    if omega is None or len(omega) < MIN_RUN:
        return NONE
    clipped = np.zeros(len(omega), bool)
    limits = []
    for k in range(3):
        w = omega[:, k]
        for value in dict.fromkeys((float(w.max()), float(w.min()))):
            at = w == value
            if value != 0.0 and _pinned(w, at, value):
                clipped |= at
                limits.append((_AXES[k], value, int(at.sum())))
    if not limits:
        return NONE
    t = np.asarray(sensor.t)
    return Saturation(t[clipped], tuple(limits), float(np.median(np.diff(t))))
