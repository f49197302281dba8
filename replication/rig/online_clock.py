"""A clock step seen by the live rig (:class:`replication.rig.live.LiveRig`): after an event of its
estimator (pairs that stopped fitting: a clock step makes the sensor motions of the pairs after it
those of other instants, which the estimator sees as a change of the noise or as outliers), the
clock offset is measured again on the streams since the event's alarm (:class:`ClockWatch`); an
offset that moved by :data:`CLOCK_STEP_MIN_S` or more from the one measured the same way at the
start (on the held first window, the gyro's bias removed), with which the pairs since the alarm fit
(:data:`CLOCK_FIT_SHARE`), is a clock step: the event is renamed ``clock_jump``, a ``clock_jump``
reason names the two offsets, and the rig pairs with the new offset from then on. Theory and
measured numbers: ``docs/judging.md``, section ``replication.rig.online_clock``."""
from __future__ import annotations

import dataclasses
import math
from collections import deque

import numpy as np

from ..core.so3 import angle_between_deg

__all__ = ["ClockWatch", "CLOCK_CHECK_S", "CLOCK_STEP_MIN_S", "CLOCK_FIT_SHARE"]

#: Seconds of both streams after an event's alarm on which the offset is measured again (the first
#: offset is measured on 20 s; 15 s of a moving rig give it within a fraction of a millisecond).
CLOCK_CHECK_S = 15.0
#: A clock step is an offset that moved by this much (s). The offset of 15 s of a clean synthetic
#: rig (camera 0.05 deg, gyro 0.2 deg/s, 20 / 200 Hz) departs from the truth by up to 6.6 ms (40
#: windows of seeds 8001-8010; 5-95 %: -5.0 to +2.6 ms), so the batch's 2 ms
#: (:data:`replication.rig.clock.JUMP_MIN_S`, from the residuals with ``R0``) would name steps that
#: are not; 10 ms is above that spread.
CLOCK_STEP_MIN_S = 0.010
#: ... and the pairs since the alarm fit with it: their median residual at the estimate at most this
#: share of the one with the offset in use. A change of the gyro's bias also moves the offset the
#: speeds' correlation finds (by more than 10 ms for a step of 0.05 rad/s), but no offset makes
#: those pairs fit.
CLOCK_FIT_SHARE = 0.5


class ClockWatch:
    """The last :data:`CLOCK_CHECK_S` seconds (and the offset search's margin) of the integrated
    sensor and of the camera, and the events waiting for their offset check."""

    def __init__(self, max_offset: float):
        self.max_offset = max_offset
        self.keep = CLOCK_CHECK_S + 2.0 * max_offset + 2.0
        self.sensor, self.camera = deque(), deque()
        self.pending = []     # (time of the alarm pair's end, event index in the calibrator's events)
        self.found = []       # the clock steps found: Reason
        self.baseline = None  # the offset measured as the checks measure it, at the start (then each step's)

    def add(self, store, t: float, R) -> None:
        store.append((t, R))
        while store and store[0][0] < t - self.keep:
            store.popleft()

    def watch(self, t_alarm: float, k: int) -> None:
        """Check event ``k`` of the calibrator once :data:`CLOCK_CHECK_S` seconds after its alarm
        (``t_alarm``) have arrived."""
        self.pending.append((t_alarm, k))

    def poll(self, rig, resolution: float) -> None:
        """Run the checks that are due on the live rig ``rig``; a step found is acted on
        (:meth:`act`)."""
        if not self.camera or not self.sensor or rig.offset is None or rig._raw is not None:
            return  # nothing held, or the first window's offset and bias not known yet
        if self.baseline is None:  # on the held first window, the bias removed as every later check
            self.baseline = self.measure(self.camera[0][0], resolution)
            self.baseline = rig.offset if self.baseline is None else self.baseline
        if not self.pending:
            return
        now = min(self.camera[-1][0], self.sensor[-1][0] - self.max_offset)
        due = [p for p in self.pending if now - p[0] >= CLOCK_CHECK_S]
        self.pending = [p for p in self.pending if now - p[0] < CLOCK_CHECK_S]
        for t_alarm, k in due:
            offset = self.measure(t_alarm, resolution)
            if offset is None or abs(offset - self.baseline) < CLOCK_STEP_MIN_S:
                continue
            used, new = (self.residual_deg(rig, t_alarm, d) for d in (rig.used_offset, offset))
            if math.isfinite(new) and new <= CLOCK_FIT_SHARE * used:  # what the pairs lacked (not a bias change)
                self.act(rig, k, t_alarm, self.baseline, offset, used, new)

    def measure(self, t_from: float, resolution: float):
        """The offset on the streams from ``t_from`` on, or None where they do not give one."""
        from .association import estimate_time_offset
        from .streams import OrientationStream

        cam = [(t, C) for t, C in self.camera if t >= t_from]
        sen = [(t, Q) for t, Q in self.sensor if t >= t_from - self.max_offset - 1.0]
        if len(cam) < 10 or len(sen) < 10:
            return None
        try:
            offset, _ = estimate_time_offset(
                OrientationStream(np.array([c[0] for c in cam]), np.array([c[1] for c in cam])),
                OrientationStream(np.array([s[0] for s in sen]), np.array([s[1] for s in sen])),
                max_offset=self.max_offset, resolution=resolution)
        except ValueError:
            return None
        return float(offset) if math.isfinite(offset) else None

    def residual_deg(self, rig, t_from: float, offset: float) -> float:
        """The median residual (deg) at the estimate of the pairs formed from ``t_from`` on with
        ``offset`` (the sensor at its sample nearest each camera time plus the offset); inf if
        none."""
        cam = [(t, C) for t, C in self.camera if t >= t_from]
        ts = np.array([s[0] for s in self.sensor])
        R, out, start = rig.calibrator.R, [], None
        for t, C in cam:
            if start is None:
                start = (t, C)
                continue
            if t - start[0] < rig.interval - 1e-9:
                continue
            i = np.clip(np.searchsorted(ts, [start[0] + offset, t + offset]), 0, len(ts) - 1)
            if abs(ts[i[0]] - start[0] - offset) < 0.05 and abs(ts[i[1]] - t - offset) < 0.05:
                A, B = C.T @ start[1], self.sensor[i[1]][1].T @ self.sensor[i[0]][1]
                out.append(float(angle_between_deg(A @ R, R @ B)))
            start = None
        return float(np.median(out)) if out else math.inf

    def act(self, rig, k: int, t_alarm: float, before: float, after: float, used: float, new: float) -> None:
        """A clock step: event ``k`` renamed, a ``clock_jump`` reason, the new offset used."""
        from .quality import Reason

        cal, t0 = rig.calibrator, rig._early_camera[0][0] if rig._early_camera else 0.0
        size = after - before
        words = (f"the clock offset moved from {1e3 * before:+.1f} ms to {1e3 * after:+.1f} ms ({1e3 * size:+.1f} "
                 f"ms, measured on the {CLOCK_CHECK_S:g} s after the alarm at {t_alarm - t0:.1f} s): a clock "
                 f"step (the sensor's or the camera's), not a change of the noise: the pairs since then fit with "
                 f"it (median residual {new:.3g} deg, {used:.3g} with the old); the pairs use the new offset "
                 f"from now on, those between the step and now are in the estimate")
        if 0 <= k < len(cal.events):
            ev = cal.events[k]
            cal.events[k] = dataclasses.replace(ev, kind="clock_jump", message=f"{words} (decided as "
                                                f"{ev.kind}: {ev.message})")
        self.found.append(Reason("clock_jump", "warning", abs(size), CLOCK_STEP_MIN_S, words))
        rig.offset = self.baseline = after   # paired with from now on (where the offset is applied)
        rig._name(self.found[-1])
