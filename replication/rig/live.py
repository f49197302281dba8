"""The live front end of :class:`replication.rig.online.OnlineCalibrator`: camera poses and raw gyro
samples (or sensor orientations) as they arrive, paired on the fly; and :func:`replay`, which feeds
recorded streams through it in time order, as if live (notebook 08, ``python -m replication
calibrate --online``).

Data model in :mod:`replication.rig.streams`, the clock offset from
:mod:`replication.rig.association`, the checks from :mod:`replication.rig.quality` and
:mod:`replication.rig.diagnose`; conventions: ``docs/conventions.md``.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from .._extras import require
from ..core import so3
from ..core.checks import check_number, check_rotation_matrices
from .online import OnlineCalibrator
from .online_bias import IDENTITY3, bias_fields, exp3, hold_raw, start_rig_bias
from .online_causes import run_diagnosis
from .online_clock import ClockWatch
from .quality import Verdict
from .report import RADIUS_COVERS

__all__ = ["LiveRig", "replay", "OFFSET_RESOLUTION"]

#: Resolution of the clock-offset search (s), as :func:`replication.rig.calibration.calibrate` uses.
OFFSET_RESOLUTION = 0.5e-3


class LiveRig:
    """A stream front end for :class:`OnlineCalibrator`: camera poses and raw gyro samples as they
    arrive.

    The gyro is integrated as it comes (:func:`replication.rig.streams.integrate_gyro`'s trapezoidal
    rule) into a buffer that holds only the last ``interval + 2 max_offset + 1`` seconds (O(1)
    memory in the recording's length). Camera poses form pairs ``interval`` seconds long that share
    no pose (the radius assumes independent pairs; a pair ending where the next starts would share
    that pose's noise); each pair's sensor motion is the integrated orientation slerped to the
    camera times plus the clock offset. The offset is estimated once, on the first ``offset_window``
    seconds of both streams (:func:`replication.rig.association.estimate_time_offset`; those samples
    are held until then), unless given; :meth:`finish` (end of the streams) estimates it on whatever
    arrived if the streams were shorter. A pair whose sensor interval contains a gap (more than
    ``GAP_FACTOR`` median sample intervals) is dropped.

    The first ``offset_window`` seconds of both streams are also kept, raw, for
    :mod:`replication.rig.diagnose`: when the online verdict (:meth:`verdict`: the batch checks and
    thresholds) first fails, the usual input mistakes (quaternion order, pose direction, gyro units)
    are tried on that window and the one that fits is named.

    Parameters
    ----------
    calibrator : OnlineCalibrator
    interval : float
        Pair length (s), positive.
    offset : float or None
        Sensor clock offset (s; the sensor sample stamped ``t + offset`` matches the camera's at
        ``t``); ``None``: estimate it.
    offset_window : float or None
        Seconds of data for the offset estimate (and the diagnosis); default
        ``max(20, 2 max_offset + 10)``. It must exceed ``2 max_offset`` (the search needs an overlap
        once shifted both ways).
    max_offset : float
        Largest offset searched (s), positive.
    correct_offset : bool
        Use the estimated offset for the pairs (``False``: report it, pair the clocks as recorded).
    stride : int
        Use every ``stride``-th pair formed.
    diagnose : bool
        Run the input-mistake diagnosis when the verdict fails.
    on_pair : callable, optional
        Called with ``(t, A, B)`` for every pair used (e.g. to feed another estimator the same
        pairs).
    gyro_bias : bool
        A gyro: estimate its bias on the first ``offset_window`` seconds (pairs wait for them, also
        with a given offset) and remove it from every rate (:mod:`replication.rig.online_bias`;
        :attr:`bias` the model, or None).
    """

    GAP_FACTOR = 5.0

    def __init__(self, calibrator: OnlineCalibrator, *, interval: float = 1.0, offset: float | None = None,
                 offset_window: float | None = None, max_offset: float = 0.2, correct_offset: bool = True,
                 stride: int = 1, diagnose: bool = True, on_pair=None, gyro_bias: bool = True):
        if not isinstance(calibrator, OnlineCalibrator):
            raise ValueError(f"calibrator must be an OnlineCalibrator, got {type(calibrator).__name__}")
        check_number("interval", interval, minimum=0)
        check_number("max_offset", max_offset, minimum=0)
        if offset is not None:
            check_number("offset", offset)
        if offset_window is None:
            offset_window = max(20.0, 2.0 * max_offset + 10.0)
        check_number("offset_window", offset_window, minimum=0)
        if offset is None and not offset_window > 2.0 * max_offset + 1.0:
            raise ValueError(f"offset_window must exceed 2 max_offset + 1 s = {2.0 * max_offset + 1.0:g} s (the "
                             f"offset search shifts the window by up to max_offset both ways), got {offset_window}")
        check_number("stride", stride, minimum=1, integer=True, strict=False)
        for name, value in (("correct_offset", correct_offset), ("diagnose", diagnose), ("gyro_bias", gyro_bias)):
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {value!r}")
        if on_pair is not None and not callable(on_pair):
            raise ValueError(f"on_pair must be callable or None, got {on_pair!r}")
        self.calibrator, self.interval, self.on_pair = calibrator, float(interval), on_pair
        self.max_offset, self.offset_window = float(max_offset), float(offset_window)
        self.correct_offset, self.stride, self.diagnose = bool(correct_offset), int(stride), bool(diagnose)
        self.offset = None if offset is None else float(offset)   # the offset: given or estimated
        self.offset_given = offset is not None
        self.offset_correlation = None
        self.offset_note = None      # why no offset could be estimated, if so
        self._causes = []            # reasons named on the streams (time units, an offset beyond the search)
        self._gyro = deque()         # (t, Q) of the integrated sensor, recent only
        self._last_gyro = None       # (t, omega, Q)
        self._gyro_dt = None
        self._kind = None            # "gyro" or "orientation": the first sensor sample decides
        self._camera = deque()       # (t, world_from_camera) held until the offset is known
        self._start = None           # (t, world_from_camera) of the pair being formed
        self._last_camera_t = -math.inf
        self._early_camera, self._early_sensor = [], []  # raw samples of the first offset_window seconds
        self.pairs_formed = 0        # pairs formed (before the stride and the gap check)
        self.pairs_dropped = 0       # pairs dropped across gaps
        self._now = -math.inf        # the latest time stamp seen on either stream
        self.events = []             # (time of the pair's end, time it was formed, OnlineState)
        self.ready_at = None         # (pair end, formed) of the first pair at which the calibrator was ready
        self._times = {}             # pair index -> (pair end, formed), for the events
        self._event_times = {}       # pair index -> (pair end, formed), of every decision
        self._diagnosis = None
        self._finished = False
        self._no_offset = False      # the offset search found no overlap: no pairs
        self.bias = self.bias_effect_deg = self.scale_effect_deg = self.misalignment_effect_deg = None  # R0 radii
        self._b, self._Ti = (0.0, 0.0, 0.0), IDENTITY3  # its bias and T^-1 (rows): T^-1 (omega - b) of every rate
        self._raw = deque() if gyro_bias else None  # raw gyro samples until the bias is estimated (None: not, done)
        self._bias_next = self.offset_window   # the held camera span at which the bias is tried (next)
        self._clock = ClockWatch(self.max_offset)  # the offset measured again after an event (a clock step)

    # ---------------------------------------------------------------------------------------- input
    def _sensor_kind(self, kind: str) -> None:
        if self._kind is None:
            self._kind = kind
        elif self._kind != kind:
            raise ValueError(f"this rig's sensor gives {self._kind} samples; got a {kind} sample")

    def _keep_early(self, store, t, value) -> None:
        first = store[0][0] if store else t
        if t - first <= self.offset_window:
            store.append((t, value))

    def add_gyro(self, t: float, omega) -> None:
        """One gyro sample: time (s) and body rate (rad/s, 3)."""
        try:
            t = float(t)
            wx, wy, wz = (float(v) for v in np.asarray(omega, dtype=float).reshape(3))
        except (TypeError, ValueError):
            raise ValueError(f"a gyro sample is a finite time and 3 finite rates, "
                             f"got t={t!r}, omega={np.asarray(omega).tolist()!r}") from None
        if not math.isfinite(t + wx + wy + wz):
            raise ValueError(f"a gyro sample is a finite time and 3 finite rates, got t={t}, omega={[wx, wy, wz]}")
        if not math.isfinite(wx * wx + wy * wy + wz * wz):  # finite, but no rotation can be formed from it
            raise ValueError(f"gyro rates too large to integrate (|omega|^2 overflows): omega={[wx, wy, wz]} rad/s")
        self._sensor_kind("gyro")
        if self._raw is not None:
            hold_raw(self._raw, t, (wx, wy, wz), self.offset_window)
        (bx, by, bz), ((a, b, c), (d, e, f), (g, k, m)) = self._b, self._Ti
        wx, wy, wz = wx - bx, wy - by, wz - bz
        wx, wy, wz = a * wx + b * wy + c * wz, d * wx + e * wy + f * wz, g * wx + k * wy + m * wz
        if self._last_gyro is None:
            Q = np.eye(3)
        else:
            t0, (vx, vy, vz), Q0 = self._last_gyro
            if not t > t0:
                raise ValueError(f"gyro time going backwards or repeated: {t!r} after {t0!r}")
            dt = t - t0
            self._gyro_dt = dt if self._gyro_dt is None else 0.99 * self._gyro_dt + 0.01 * dt  # a running typical step
            h = 0.5 * dt  # the trapezoidal rule of integrate_gyro
            Q = Q0 @ exp3(h * (vx + wx), h * (vy + wy), h * (vz + wz))
        self._last_gyro = (t, (wx, wy, wz), Q)
        self._keep_early(self._early_sensor, t, np.array((wx, wy, wz)))
        self._push(t, Q)

    def add_orientation(self, t: float, world_from_sensor) -> None:
        """One sensor orientation (an orientation sensor instead of a gyro): time (s) and
        ``world_from_sensor``."""
        Q = check_rotation_matrices(world_from_sensor, "world_from_sensor")
        if Q.shape != (3, 3) or not math.isfinite(t):
            raise ValueError(f"a sensor pose is a finite time and one 3x3 rotation, got t={float(t)}, shape {Q.shape}")
        self._sensor_kind("orientation")
        if self._gyro and not t > self._gyro[-1][0]:
            raise ValueError(f"sensor time going backwards or repeated: {float(t)} after {self._gyro[-1][0]}")
        if self._gyro:
            dt = t - self._gyro[-1][0]
            self._gyro_dt = dt if self._gyro_dt is None else 0.99 * self._gyro_dt + 0.01 * dt
        self._keep_early(self._early_sensor, float(t), Q)
        self._push(float(t), Q)

    def _push(self, t, Q) -> None:
        self._now = max(self._now, t)
        self._gyro.append((t, Q))
        self._clock.add(self._clock.sensor, t, Q)
        keep = self.interval + 2 * self.max_offset + 1.0 + (self.offset_window if self.offset is None or (
            self._raw is not None and self._kind == "gyro") else 0.0)
        while len(self._gyro) > 2 and self._gyro[0][0] < t - keep:
            self._gyro.popleft()
        self._drain()

    def add_camera(self, t: float, world_from_camera) -> None:
        """One camera pose: time (s) and ``world_from_camera`` (3x3 rotation)."""
        C = check_rotation_matrices(world_from_camera, "world_from_camera")
        if C.shape != (3, 3) or not math.isfinite(t):
            raise ValueError(f"a camera pose is a finite time and one 3x3 rotation, got t={float(t)}, shape {C.shape}")
        if not t > self._last_camera_t:
            raise ValueError(f"camera time going backwards or repeated: {float(t)} after {self._last_camera_t}")
        self._last_camera_t = float(t)
        self._now = max(self._now, float(t))
        self._camera.append((float(t), C))
        self._clock.add(self._clock.camera, float(t), C)
        self._keep_early(self._early_camera, float(t), C)
        self._drain()

    def finish(self) -> None:
        """The streams ended: estimate the clock offset on whatever arrived if it is still unknown,
        form the last pairs. Idempotent."""
        if self._finished:
            return
        self._finished = True
        if self.offset is None and self._camera and self._gyro and not self._no_offset:
            self._estimate_offset()
            if self._no_offset:
                self.offset_note = (f"no clock offset: the streams ended after {self._now - self._camera[0][0]:.1f} s "
                                    f"of camera data, before the {self.offset_window:g} s offset window "
                                    f"({self.offset_note.removeprefix('no clock offset: ')})")
        self._drain()

    # -------------------------------------------------------------------------------------- pairing
    def _streams(self):
        """The first ``offset_window`` seconds as streams (camera, sensor) for the offset search and
        diagnosis."""
        from .streams import GyroStream, OrientationStream

        cam = OrientationStream(np.array([c[0] for c in self._early_camera]),
                                np.array([c[1] for c in self._early_camera]), "camera (live)")
        t = np.array([s[0] for s in self._early_sensor])
        values = np.array([s[1] for s in self._early_sensor])
        sensor = GyroStream(t, values, "gyro (live)") if self._kind == "gyro" else OrientationStream(
            t, values, "sensor (live)")
        return cam, sensor

    def _estimate_offset(self) -> None:
        """The clock offset on the held samples; where the streams' sample intervals show time
        stamps in different units, that is named
        (:func:`replication.rig.online_causes.time_unit_by_rate`); where the search finds no
        overlap, no pair is formed and the verdict fails naming why (never a raised search
        error)."""
        from .association import estimate_time_offset
        from .online_causes import constant_speed_stream, time_unit_by_rate
        from .quality import Reason
        from .streams import OrientationStream

        t_cam = np.array([c[0] for c in self._camera])
        unit = time_unit_by_rate(float(np.median(np.diff(t_cam))) if len(t_cam) > 1 else None, self._gyro_dt)
        if unit is not None:
            self._name(unit)
        steady = constant_speed_stream(t_cam, np.array([c[1] for c in self._camera]), self.interval)
        if steady is not None:  # the camera turns at constant speed: no offset can be measured, nor R0 about its axis
            self._name(steady)
        try:  # a stream too short for the search (one camera pose) is a search error too
            cam = OrientationStream(t_cam, np.array([c[1] for c in self._camera]), "camera")
            sen = OrientationStream(np.array([g[0] for g in self._gyro]), np.array([g[1] for g in self._gyro]),
                                    "sensor")
            self.offset, self.offset_correlation = estimate_time_offset(cam, sen, max_offset=self.max_offset,
                                                                        resolution=OFFSET_RESOLUTION)
        except ValueError as err:
            self._no_offset = True
            self.offset_note = f"no clock offset: {err}" + (f"; {unit.message}" if unit is not None else "")
            if unit is None:
                self._name(Reason("overlap", "fail", None, None, self.offset_note))
            return
        self.calibrator.set_context(**self.evidence())

    def _name(self, reason) -> None:
        """A cause named on the streams: judged with the estimator's evidence from now on."""
        self._causes.append(reason)
        self.calibrator.set_context(extra=tuple(self._causes) + tuple(self._diagnosis or ()))

    @property
    def used_offset(self) -> float | None:
        """The offset the pairs use (0 when an estimated one is not applied)."""
        if self.offset is None:
            return None
        return self.offset if (self.offset_given or self.correct_offset) else 0.0

    def _sensor_at(self, t):
        """The integrated gyro at ``t`` (slerp between its neighbours), or None if not yet / no
        longer buffered or inside a gap."""
        times = [g[0] for g in self._gyro]
        k = np.searchsorted(times, t)
        if k == 0 or k >= len(times):
            return None
        (t0, Q0), (t1, Q1) = self._gyro[k - 1], self._gyro[k]
        if self._gyro_dt and t1 - t0 > self.GAP_FACTOR * self._gyro_dt:
            return "gap"
        s = (t - t0) / (t1 - t0)
        return Q0 @ so3.matrix_from_rotation_vector(s * so3.rotation_vector_from_matrix(Q0.T @ Q1))

    def _drain(self) -> None:
        if self.offset is None:
            if self._no_offset or self._finished or not self._camera or not self._gyro \
                    or self._gyro[-1][0] - self._gyro[0][0] < self.offset_window \
                    or self._camera[-1][0] - self._camera[0][0] < self.offset_window:
                return
            self._estimate_offset()
            if self.offset is None:
                return
        if self._raw is not None and self._kind == "gyro" and not start_rig_bias(self):
            return
        offset = self.used_offset
        while self._camera:
            t, C = self._camera[0]
            if not self._gyro or self._gyro[-1][0] < t + offset:
                return  # wait for the gyro to cover this pose (at the end: no more pairs)
            self._camera.popleft()
            if self._start is None:
                self._start = (t, C)
                continue
            t0, C0 = self._start
            if t - t0 < self.interval - 1e-9:
                continue
            self._start = None  # the next pair starts at the next pose: pairs share no pose, hence no pose noise
            self.pairs_formed += 1
            if (self.pairs_formed - 1) % self.stride:
                continue
            Q0, Q1 = self._sensor_at(t0 + offset), self._sensor_at(t + offset)
            if Q0 is None or Q1 is None or isinstance(Q0, str) or isinstance(Q1, str) or self._gap_between(
                    t0 + offset, t + offset):
                self.pairs_dropped += 1
                continue
            A = C.T @ C0    # eq. (3) with C = Q^T: camera motion from t0 to t
            B = Q1.T @ Q0   # eq. (4)
            self._pair(t, A, B)

    def _pair(self, t, A, B) -> None:
        cal = self.calibrator
        index = cal.n_total  # the index this pair gets unless it is a repeat
        state = cal.update(A, B)
        self._times[index] = (t, self._now)
        if state.event is not None:  # decisions' times kept for good (a drift's rate spans them)
            self._event_times[index] = (t, self._now)
        if len(self._times) > 4 * cal.confirm_pairs + 256:
            for k in sorted(self._times)[:len(self._times) // 2]:
                del self._times[k]
        self.events.append((t, self._now, state))
        if state.event in ("noise_change", "outliers"):  # a clock step? its offset measured again later
            self._clock.watch(self._times.get(cal.events[-1].alarm_pair, (t,))[0], len(cal.events) - 1)
        self._clock.poll(self, OFFSET_RESOLUTION)
        if state.ready and self.ready_at is None:
            self.ready_at = (t, self._now)
        if self.on_pair is not None:
            self.on_pair(t, A, B)
        if self.diagnose and self._diagnosis is None and cal.current_verdict is not None \
                and cal.current_verdict.level == "fail":
            run_diagnosis(self, OFFSET_RESOLUTION)

    def _gap_between(self, t0, t1) -> bool:
        if not self._gyro_dt:
            return False
        times = np.array([g[0] for g in self._gyro])
        inside = times[(times >= t0) & (times <= t1)]
        return len(inside) > 1 and np.diff(inside).max() > self.GAP_FACTOR * self._gyro_dt

    # -------------------------------------------------------------------------------------- judging
    def evidence(self) -> dict:
        """The front end's part of the verdict's evidence (the batch's fields and thresholds):
        ``interval_s``, ``pairs_dropped_at_gaps``, ``pairs_before_gaps``; once an offset is
        estimated (not given) ``offset_s``, ``offset_correlation``, ``max_offset_s``,
        ``offset_resolution_s``, ``offset_applied``; with a gyro, ``gyro_rate_hz`` (1 / the running
        typical sample step). Read-only: it changes nothing (:meth:`verdict` passes it to the
        calibrator)."""
        e = {"interval_s": self.interval, "pairs_dropped_at_gaps": self.pairs_dropped,
             "pairs_before_gaps": max(1, -(-self.pairs_formed // self.stride))}  # pairs 1, 1 + stride, ... used
        if self.offset is not None and not self.offset_given:
            e.update(offset_s=self.offset, offset_correlation=self.offset_correlation, max_offset_s=self.max_offset,
                     offset_resolution_s=OFFSET_RESOLUTION, offset_applied=self.correct_offset)
        if self._kind == "gyro" and self._gyro_dt:
            e["gyro_rate_hz"] = 1.0 / self._gyro_dt
        return e

    def verdict(self):
        """The online verdict (:meth:`OnlineCalibrator.verdict` with this front end's evidence:
        clock offset, gaps, gyro rate, and a named input mistake if the diagnosis found one). Time
        stamps in different units are also looked for in the spans of the streams so far, as the
        batch does."""
        from types import SimpleNamespace

        from .calibration import _time_unit_reason

        if self._early_camera and self._early_sensor and not any(r.check == "time_unit" for r in self._causes):
            span = lambda first, last: SimpleNamespace(t=np.array([first, last]))  # noqa: E731
            unit = _time_unit_reason(span(self._early_camera[0][0], self._last_camera_t),
                                     span(self._early_sensor[0][0], self._gyro[-1][0]))
            if unit is not None:
                self._name(unit)
        self.calibrator.set_context(**self.evidence())
        return self.calibrator.verdict()

    def summary(self, t0: float = 0.0) -> dict:
        """What the online run found, for the JSON report (times in seconds since ``t0``;
        ``ready_at_s`` is when the deciding pair was formed, ``ready_pair_end_s`` when its motion
        ended)."""
        cal = self.calibrator
        verdict = self.verdict()
        undecided = cal.unresolved_end()
        if undecided is not None:  # the stream ended while the detector was undecided: not ready, said
            verdict = Verdict.of((*verdict.reasons, undecided))
        estimated = bool(self.events) and cal.n_pairs >= cal.min_pairs
        events = []
        for ev in cal.events:
            end, seen = self._event_times.get(ev.pair, (math.nan, math.nan))
            alarm = self._times.get(ev.alarm_pair, (math.nan, math.nan))[1]
            events.append({"kind": ev.kind, "t_s": seen - t0, "pair_end_s": end - t0, "alarm_t_s": alarm - t0,
                           "angle_deg": ev.angle_deg, "threshold_deg": ev.threshold_deg,
                           "pairs_dropped": ev.pairs_dropped, "message": ev.message, "rate_deg_s": None})
            if ev.kind == "drift":  # deg/s: its rate per pair (the latest measured) x pairs per second since its start
                at = end - (end - self.events[0][0]) * (ev.pair - ev.onset_pair) / max(ev.pair, 1)  # pairs even
                span = end - self._event_times.get(ev.onset_pair, (at,))[0]  # (a creep's start: no event there)
                events[-1]["rate_deg_s"] = ev.rate_deg_per_pair * (ev.pair - ev.onset_pair) / span if span > 0 else None
        status = cal.status()
        return {
            "ready": bool(cal.ready) and undecided is None,
            "ready_at_s": None if self.ready_at is None else self.ready_at[1] - t0,
            "ready_pair_end_s": None if self.ready_at is None else self.ready_at[0] - t0,
            "target_deg": cal.target_deg,
            "pairs": int(cal.n_total), "pairs_formed": int(self.pairs_formed),
            "repeated_pairs": int(cal.duplicates), "pairs_dropped_outliers": int(cal.pairs_dropped),
            "pairs_dropped_at_gaps": int(self.pairs_dropped),
            "R0_camera_from_sensor": np.round(cal.R, 12).tolist() if estimated else None,
            "quaternion_wxyz": np.round(so3.quaternion_from_matrix(cal.R), 12).tolist() if estimated else None,
            "radius_deg": cal.radius, "radius_level": cal.level, "radius_covers": RADIUS_COVERS,
            "excitation_deg": status["excitation_deg"], "effective_pairs": status["effective_pairs"],
            "clock_offset_s": self.offset, "clock_offset_given": self.offset_given,
            "clock_offset_correlation": self.offset_correlation, "clock_offset_applied": self.used_offset is not None
            and self.used_offset != 0.0 if not self.offset_given else True,
            **bias_fields(self),
            "note": self.offset_note,
            "events": events,
            "not_ready": status["not_ready"],
            "verdict": verdict.to_dict(),
        }


def replay(camera, sensor, calibrator: OnlineCalibrator, *, interval: float = 1.0, offset: float | None = None,
           max_offset: float = 0.2, correct_offset: bool = True, stride: int = 1, offset_window: float | None = None,
           reference=None, remount=None, on_pair=None, diagnose: bool = True, gyro_bias: bool = True):
    """Feed two recorded streams (camera poses; gyro samples or sensor orientations) to a
    :class:`LiveRig` in time order, as if live; one row per pair.

    ``remount = (t, R)``: from time ``t`` on, the sensor is mounted ``R`` further (its rates become
    ``R^T omega``, its orientations ``Q R``: a synthetic re-mount, for the change detector); the
    reference is then ``reference @ R``. Returns a :class:`pandas.DataFrame` with ``t`` (s, the
    pair's end), ``t_seen`` (s, when the pair was formed: later than ``t`` while the first
    ``offset_window`` seconds are held for the clock offset), ``n_pairs``, ``radius_deg``,
    ``ready``, ``alarm`` (a re-mount confirmed), ``event`` (the kind of an event decided at that
    pair, else empty), ``determined``, ``checking``, the estimate as a quaternion ``qw, qx, qy, qz``
    (camera_from_sensor) and, with a reference, ``error_deg``. Before the first estimate (fewer than
    ``min_pairs`` pairs since a start) the estimate, radius and error are NaN (empty in a CSV).
    ``attrs``: ``offset_s``, ``pairs_dropped``, ``alarms``, ``events`` and ``summary``
    (:meth:`LiveRig.summary`, times since the camera's first sample).
    """
    pd = require("pandas", "replay (its table of pairs; calibrate --online)")
    rig = LiveRig(calibrator, interval=interval, offset=offset, max_offset=max_offset, correct_offset=correct_offset,
                  stride=stride, offset_window=offset_window, on_pair=on_pair, diagnose=diagnose, gyro_bias=gyro_bias)
    events = sorted([(t, 1, k) for k, t in enumerate(camera.t)] + [(t, 0, k) for k, t in enumerate(sensor.t)])
    R_re = None if remount is None else np.asarray(remount[1], dtype=float)
    gyro_kind = hasattr(sensor, "omega")
    for t, kind, k in events:
        after = remount is not None and t >= remount[0]
        if kind == 1:
            rig.add_camera(t, camera.world_from_body[k])
        elif gyro_kind:
            rig.add_gyro(t, R_re.T @ sensor.omega[k] if after else sensor.omega[k])
        else:
            rig.add_orientation(t, sensor.world_from_body[k] @ R_re if after else sensor.world_from_body[k])
    rig.finish()
    rows = []
    for t_end, t_seen, state in rig.events:
        known = state.estimated
        q = so3.quaternion_from_matrix(state.R) if known else np.full(4, np.nan)
        row = {"t": t_end, "t_seen": t_seen, "n_pairs": state.n_pairs,
               "radius_deg": state.radius_deg if known and math.isfinite(state.radius_deg) else np.nan,
               "ready": state.ready, "alarm": state.alarm, "event": state.event or "", "determined": state.determined,
               "checking": state.checking, "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3]}
        if reference is not None:
            ref = reference if remount is None or t_end < remount[0] else reference @ R_re
            row["error_deg"] = float(so3.angle_between_deg(state.R, ref)) if known else np.nan
        rows.append(row)
    columns = ["t", "t_seen", "n_pairs", "radius_deg", "ready", "alarm", "event", "determined", "checking", "qw", "qx",
               "qy", "qz"] + (["error_deg"] if reference is not None else [])
    out = pd.DataFrame(rows, columns=columns)
    out.attrs.update(offset_s=rig.offset, pairs_dropped=rig.pairs_dropped, alarms=list(calibrator.alarms),
                     events=[e.kind for e in calibrator.events], summary=rig.summary(t0=float(camera.t[0])))
    return out
