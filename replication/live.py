"""The live front end of :class:`replication.online.OnlineCalibrator`: camera poses and raw gyro samples (or sensor
orientations) as they arrive, paired on the fly; and :func:`replay`, which feeds recorded streams through it in
time order, as if live (notebook 08, ``python -m replication calibrate --online``).

Data model in :mod:`replication.streams`, the clock offset from :mod:`replication.association`; conventions:
``docs/conventions.md``.
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from .checks import check_number, check_rotation_matrices
from .online import OnlineCalibrator
from .so3 import angle_between_deg, as_quaternion, exp_map, log_map

__all__ = ["LiveRig", "replay"]


class LiveRig:
    """A stream front end for :class:`OnlineCalibrator`: camera poses and raw gyro samples as they arrive.

    The gyro is integrated as it comes (:func:`replication.streams.integrate_gyro`'s trapezoidal rule) into a
    buffer that holds only the last ``interval + 2 max_offset + 1`` seconds (O(1) memory in the recording's
    length). Camera poses form pairs ``interval`` seconds long that share no pose (the radius assumes independent
    pairs; a pair ending where the next starts would share that pose's noise); each pair's sensor motion is the integrated orientation slerped to the camera times plus the clock
    offset. The offset is estimated once, on the first ``offset_window`` seconds of both streams
    (:func:`replication.association.estimate_time_offset`; those samples are held until then), unless given.
    A pair whose sensor interval contains a gap (more than ``GAP_FACTOR`` median sample intervals) is dropped.

    Parameters
    ----------
    calibrator : OnlineCalibrator
    interval : float
        Pair length (s).
    offset : float or None
        Sensor clock offset (the sensor sample stamped ``t + offset`` matches the camera's at ``t``); ``None``:
        estimate it.
    offset_window, max_offset : float
        Seconds of data for the offset estimate and the largest offset searched.
    on_pair : callable, optional
        Called with ``(t, A, B)`` for every pair formed (e.g. to feed another estimator the same pairs).
    """

    GAP_FACTOR = 5.0

    def __init__(self, calibrator: OnlineCalibrator, *, interval: float = 1.0, offset: float | None = None,
                 offset_window: float = 20.0, max_offset: float = 0.2, on_pair=None):
        for name, value in (("interval", interval), ("offset_window", offset_window), ("max_offset", max_offset)):
            check_number(name, value, minimum=0)
        self.calibrator, self.interval, self.on_pair = calibrator, float(interval), on_pair
        self.offset = None if offset is None else float(offset)
        self.offset_window, self.max_offset = float(offset_window), float(max_offset)
        self._gyro = deque()      # (t, Q) of the integrated gyro, recent only
        self._last_gyro = None    # (t, omega, Q)
        self._gyro_dt = None
        self._camera = deque()    # (t, world_from_camera) held until the offset is known
        self._start = None        # (t, world_from_camera) of the pair being formed
        self._last_camera_t = -math.inf
        self.pairs_dropped = 0
        self._now = -math.inf      # the latest time stamp seen on either stream
        self.events = []          # (time of the pair's end, time it was formed, OnlineState)

    def add_gyro(self, t: float, omega) -> None:
        """One gyro sample: time (s) and body rate (rad/s, 3)."""
        omega = np.asarray(omega, dtype=float)
        if omega.shape != (3,) or not np.all(np.isfinite(omega)) or not math.isfinite(t):
            raise ValueError(f"a gyro sample is a finite time and 3 finite rates, got t={t!r}, omega={omega!r}")
        if self._last_gyro is None:
            Q = np.eye(3)
        else:
            t0, w0, Q0 = self._last_gyro
            if not t > t0:
                raise ValueError(f"gyro time going backwards or repeated: {t!r} after {t0!r}")
            dt = t - t0
            self._gyro_dt = dt if self._gyro_dt is None else 0.99 * self._gyro_dt + 0.01 * dt  # a running typical step
            Q = Q0 @ exp_map(0.5 * (w0 + omega) * dt)  # the trapezoidal rule of integrate_gyro
        self._last_gyro = (float(t), omega, Q)
        self._push(float(t), Q)

    def add_orientation(self, t: float, world_from_sensor) -> None:
        """One sensor orientation (an orientation sensor instead of a gyro): time (s) and ``world_from_sensor``."""
        Q = check_rotation_matrices(world_from_sensor, "world_from_sensor")
        if Q.shape != (3, 3) or not math.isfinite(t):
            raise ValueError(f"a sensor pose is a finite time and one 3x3 rotation, got t={t!r}, shape {Q.shape}")
        if self._gyro and not t > self._gyro[-1][0]:
            raise ValueError(f"sensor time going backwards or repeated: {t!r} after {self._gyro[-1][0]!r}")
        if self._gyro:
            dt = t - self._gyro[-1][0]
            self._gyro_dt = dt if self._gyro_dt is None else 0.99 * self._gyro_dt + 0.01 * dt
        self._push(float(t), Q)

    def _push(self, t, Q) -> None:
        self._now = max(self._now, t)
        self._gyro.append((t, Q))
        keep = self.interval + 2 * self.max_offset + 1.0 + (self.offset_window if self.offset is None else 0.0)
        while len(self._gyro) > 2 and self._gyro[0][0] < t - keep:
            self._gyro.popleft()
        self._drain()

    def add_camera(self, t: float, world_from_camera) -> None:
        """One camera pose: time (s) and ``world_from_camera`` (3x3 rotation)."""
        C = check_rotation_matrices(world_from_camera, "world_from_camera")
        if C.shape != (3, 3) or not math.isfinite(t):
            raise ValueError(f"a camera pose is a finite time and one 3x3 rotation, got t={t!r}, shape {C.shape}")
        if not t > self._last_camera_t:
            raise ValueError(f"camera time going backwards or repeated: {t!r} after {self._last_camera_t!r}")
        self._last_camera_t = float(t)
        self._now = max(self._now, float(t))
        self._camera.append((float(t), C))
        self._drain()

    def _estimate_offset(self) -> None:
        from .association import estimate_time_offset
        from .streams import OrientationStream

        cam = OrientationStream(np.array([c[0] for c in self._camera]), np.array([c[1] for c in self._camera]))
        sen = OrientationStream(np.array([g[0] for g in self._gyro]), np.array([g[1] for g in self._gyro]))
        self.offset = estimate_time_offset(cam, sen, max_offset=self.max_offset)[0]

    def _sensor_at(self, t):
        """The integrated gyro at ``t`` (slerp between its neighbours), or None if not yet / no longer buffered or
        inside a gap."""
        times = [g[0] for g in self._gyro]
        k = np.searchsorted(times, t)
        if k == 0 or k >= len(times):
            return None
        (t0, Q0), (t1, Q1) = self._gyro[k - 1], self._gyro[k]
        if self._gyro_dt and t1 - t0 > self.GAP_FACTOR * self._gyro_dt:
            return "gap"
        s = (t - t0) / (t1 - t0)
        return Q0 @ exp_map(s * log_map(Q0.T @ Q1))

    def _drain(self) -> None:
        if self.offset is None:
            if not self._camera or not self._gyro or self._gyro[-1][0] - self._gyro[0][0] < self.offset_window \
                    or self._camera[-1][0] - self._camera[0][0] < self.offset_window:
                return
            self._estimate_offset()
        while self._camera:
            t, C = self._camera[0]
            if not self._gyro or self._gyro[-1][0] < t + self.offset:
                return  # wait for the gyro to cover this pose
            self._camera.popleft()
            if self._start is None:
                self._start = (t, C)
                continue
            t0, C0 = self._start
            if t - t0 < self.interval - 1e-9:
                continue
            Q0, Q1 = self._sensor_at(t0 + self.offset), self._sensor_at(t + self.offset)
            self._start = None  # the next pair starts at the next pose: pairs share no pose, hence no pose noise
            if Q0 is None or Q1 is None or isinstance(Q0, str) or isinstance(Q1, str) or self._gap_between(
                    t0 + self.offset, t + self.offset):
                self.pairs_dropped += 1
                continue
            A = C.T @ C0    # eq. (3) with C = Q^T: camera motion from t0 to t
            B = Q1.T @ Q0   # eq. (4)
            self.events.append((t, self._now, self.calibrator.update(A, B)))
            if self.on_pair is not None:
                self.on_pair(t, A, B)

    def _gap_between(self, t0, t1) -> bool:
        if not self._gyro_dt:
            return False
        times = np.array([g[0] for g in self._gyro])
        inside = times[(times >= t0) & (times <= t1)]
        return len(inside) > 1 and np.diff(inside).max() > self.GAP_FACTOR * self._gyro_dt




def replay(camera, sensor, calibrator: OnlineCalibrator, *, interval: float = 1.0, offset: float | None = None,
           reference=None, remount=None, on_pair=None):
    """Feed two recorded streams (camera poses; gyro samples or sensor orientations) to a :class:`LiveRig` in time
    order, as if live; one row per pair.

    ``remount = (t, R)``: from time ``t`` on, the sensor is mounted ``R`` further (its rates become
    ``R^T omega``, its orientations ``Q R``: a synthetic re-mount, for the change detector); the reference is then
    ``reference @ R``.
    Returns a :class:`pandas.DataFrame` with ``t`` (s, the pair's end), ``t_seen`` (s, when the pair was formed:
    later than ``t`` while the first ``offset_window`` seconds are held for the clock offset), ``n_pairs``, ``radius_deg``, ``ready``,
    ``alarm``, the estimate as a quaternion ``qw, qx, qy, qz`` (camera_from_sensor) and, with a reference,
    ``error_deg``.
    """
    import pandas as pd

    rig = LiveRig(calibrator, interval=interval, offset=offset, on_pair=on_pair)
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
    rows = []
    for t_end, t_seen, state in rig.events:
        q = as_quaternion(state.R)
        row = {"t": t_end, "t_seen": t_seen, "n_pairs": state.n_pairs, "radius_deg": state.radius_deg, "ready": state.ready,
               "alarm": state.alarm, "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3]}
        if reference is not None:
            ref = reference if remount is None or t_end < remount[0] else reference @ R_re
            row["error_deg"] = float(angle_between_deg(state.R, ref))
        rows.append(row)
    out = pd.DataFrame(rows)
    out.attrs.update(offset_s=rig.offset, pairs_dropped=rig.pairs_dropped, alarms=list(calibrator.alarms))
    return out
