"""Lost tracking and map resets: a camera step that turns far more than the sensor can over the same
time (whatever the mounting or the clock offset: a rotation's angle is the same in both frames),
found before anything else, named with its time and size, the camera's trajectory glued across it
(the step's rotation replaced by the step before it) and the pairs that span it dropped. Theory and
measured numbers: ``docs/judging.md``, section ``replication.rig.camera_jumps``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d

from ..core.so3 import nearest_rotation, rotation_angle_deg
from .streams import OrientationStream

__all__ = ["CameraJump", "camera_jumps", "residual_jumps", "found_and_glued", "glued", "spanning", "jump_reasons",
           "JUMP_MIN_DEG", "JUMP_FACTOR", "MAX_JUMP_SHARE"]

#: A camera step is a jump where it turns more than :data:`JUMP_FACTOR` times the most the sensor
#: turns in as long a time near it (the clock-offset search on either side) plus this (deg): far
#: above any tracker's noise per pose (0.05-1 deg), far below a map re-initialisation's rotation.
JUMP_MIN_DEG = 5.0
#: The factor on the sensor's largest turn over the step's time (its fastest rate near the step) and
#: on the camera's own largest step near it (a fast turn of the camera is no jump, whatever a
#: sensor out of step with it shows: the clock 10 s off named a jump on TUM-VI without this).
JUMP_FACTOR = 2.0
#: More than this share of the camera's steps above the rule: no jumps but an input mistake
#: (unrelated streams, a time unit): named by the other tests, nothing dropped here.
MAX_JUMP_SHARE = 0.01


@dataclass(frozen=True)
class CameraJump:
    """A camera step from ``start_s`` to ``end_s`` (camera clock) turning ``angle_deg`` where the
    sensor turns at most ``sensor_deg`` in as long a time near it."""

    start_s: float
    end_s: float
    angle_deg: float
    sensor_deg: float

    def to_dict(self, t0: float) -> dict:
        return {"start_s": self.start_s - t0, "end_s": self.end_s - t0, "angle_deg": self.angle_deg,
                "sensor_max_deg": self.sensor_deg}


def camera_jumps(camera: OrientationStream, sensor: OrientationStream, max_offset: float) -> list:
    """The camera's jumps against ``sensor`` (an orientation stream, a gyro integrated): empty where
    there are none, or more than :data:`MAX_JUMP_SHARE` of the steps (no jump, an input mistake)."""
    t, Q = camera.t, camera.R
    angle = rotation_angle_deg(np.swapaxes(Q[:-1], -1, -2) @ Q[1:])
    ts = sensor.t
    speed = rotation_angle_deg(np.swapaxes(sensor.R[:-1], -1, -2) @ sensor.R[1:]) / np.diff(ts)
    width = 2.0 * max_offset + float(np.max(np.diff(t), initial=0.0))
    n = max(1, int(math.ceil(width / float(np.median(np.diff(ts))))))
    fastest = maximum_filter1d(speed, size=2 * n + 1, mode="nearest")
    mid = np.clip(np.searchsorted(ts, 0.5 * (t[1:] + t[:-1])), 0, len(speed) - 1)
    bound = fastest[mid] * np.diff(t)
    k = max(1, int(math.ceil(width / float(np.median(np.diff(t))))))
    most = np.lib.stride_tricks.sliding_window_view(np.concatenate([np.zeros(k), angle, np.zeros(k)]), k).max(axis=1)
    around = np.maximum(most[:len(angle)], most[k + 1:])  # the camera's own k steps before and k after
    inside = (t[:-1] >= ts[0]) & (t[1:] <= ts[-1])  # outside the sensor's span nothing is known
    jump = inside & (angle > JUMP_FACTOR * np.maximum(bound, around) + JUMP_MIN_DEG)
    if jump.sum() > MAX_JUMP_SHARE * inside.sum():
        return []
    return [CameraJump(float(t[i]), float(t[i + 1]), float(angle[i]), float(bound[i])) for i in np.flatnonzero(jump)]


def residual_jumps(camera: OrientationStream, sensor: OrientationStream, R, offset: float) -> list:
    """The jumps :func:`camera_jumps` cannot tell from fast motion, once ``R`` (camera_from_sensor)
    and the clock ``offset`` are known: a camera step whose rotation, in the sensor's frame, differs
    from the sensor's over the same time by more than :data:`JUMP_MIN_DEG` (the same share rule)."""
    t = camera.t[(camera.t + offset >= sensor.t[0]) & (camera.t + offset <= sensor.t[-1])]
    if len(t) < 3:
        return []
    Q, P, R = camera.at(t), sensor.at(t + offset), np.asarray(R)
    cam = R.T @ (np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) @ R
    misfit = rotation_angle_deg(np.swapaxes(np.swapaxes(P[:-1], -1, -2) @ P[1:], -1, -2) @ cam)
    jump = misfit > JUMP_MIN_DEG
    if jump.sum() > MAX_JUMP_SHARE * len(jump):
        return []
    sensor_deg = rotation_angle_deg(np.swapaxes(P[:-1], -1, -2) @ P[1:])
    angle = rotation_angle_deg(np.swapaxes(Q[:-1], -1, -2) @ Q[1:])
    return [CameraJump(float(t[i]), float(t[i + 1]), float(angle[i]), float(sensor_deg[i]))
            for i in np.flatnonzero(jump)]


def found_and_glued(camera: OrientationStream, sensor: OrientationStream, max_offset: float, jumps=(), R=None,
                    offset: float = 0.0, excused=None):
    """``(camera glued, every jump so far)``: :func:`camera_jumps` (``R`` None), or
    :func:`residual_jumps` with ``R`` and ``offset``, added to ``jumps``; ``excused`` (a
    :class:`~replication.rig.saturation.Saturation`): no jump where the sensor's side of the step
    (within ``max_offset``, or at ``offset`` given ``R``) holds a clipped sample (reading short)."""
    more = camera_jumps(camera, sensor, max_offset) if R is None else residual_jumps(camera, sensor, R, offset)
    if excused is not None and more:
        lo, hi = (-max_offset, max_offset) if R is None else (offset, offset)
        held = excused.holds([j.start_s + lo for j in more], [j.end_s + hi for j in more])
        more = [j for j, h in zip(more, held) if not h]
    return (glued(camera, more) if more else camera), sorted([*jumps, *more], key=lambda j: j.start_s)


def glued(camera: OrientationStream, jumps) -> OrientationStream:
    """``camera`` with each jump's step replaced by the step before it (the world frame after it
    turned back): the relative rotations that do not span a jump are unchanged, and each pose stays
    a rotation to rounding however many jumps are glued."""
    Q = np.array(camera.R)
    for j in jumps:
        i = int(np.searchsorted(camera.t, j.start_s))
        before = Q[i - 1].T @ Q[i] if i > 0 else np.eye(3)
        W = nearest_rotation(Q[i] @ before @ Q[i + 1].T)  # an exact rotation: errors add, not multiply
        Q[i + 1:] = W @ Q[i + 1:]
    return OrientationStream(camera.t, Q, camera.source)


def spanning(jumps, t_start, interval: float) -> np.ndarray:
    """Mask of the pairs (start times ``t_start`` on the camera's clock, ``interval`` long) that
    span a jump."""
    t_start = np.asarray(t_start, dtype=float)
    drop = np.zeros(len(t_start), bool)
    for j in jumps:
        drop |= (t_start < j.end_s) & (t_start + interval > j.start_s)
    return drop


def jump_reasons(jumps, t0: float, dropped: int) -> list:
    """A ``warning`` naming the jumps (times since ``t0``, sizes) and the pairs dropped for them."""
    from .quality import Reason

    if not jumps:
        return []
    named = ", ".join(f"{j.start_s - t0:.2f} s ({j.angle_deg:.1f} deg)" for j in jumps)
    worst = max(j.angle_deg for j in jumps)
    return [Reason("camera_jump", "warning", worst, JUMP_MIN_DEG,
                   f"the camera's tracking was lost or its map re-initialised {len(jumps)} time(s), at {named}: "
                   f"in one camera step the camera turns far from what the sensor turns over the same time (the "
                   f"sensor at most {max(j.sensor_deg for j in jumps):.1f} deg there; more than {JUMP_FACTOR:g} "
                   f"times its fastest turn nearby plus {JUMP_MIN_DEG:g} deg, or {JUMP_MIN_DEG:g} deg from its "
                   f"turn given R0); the {dropped} pairs that span them were dropped and R0 is from the rest (the "
                   f"trajectory glued across each jump)")]
