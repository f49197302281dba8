"""The clocks: the offset on either side of the sensor's gaps and the jumps there, the sensor
re-stamped for a jump or a drift, and the jumps in the report and the verdict (the offset per window
and its model: :mod:`replication.rig.clock_profile`). Theory and measured numbers:
``docs/judging.md``, section ``replication.rig.clock``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .segments import SEGMENT_S
from .streams import OrientationStream

__all__ = ["ClockJump", "clock_segments", "jump_candidates", "clock_report", "clock_reasons", "JUMP_MIN_S", "JUMP_Z",
           "corrected_sensor"]

#: A clock jump is at least this large (s; four times the offset search's resolution) and beyond the
#: two parts' offset intervals.
JUMP_MIN_S = 2e-3
#: The two sides' offsets must differ by this many standard errors (from their 95 % bootstrap
#: intervals): 1.96 named one sample lost (5 ms of stamps skipped, no jump) a jump in 1 of 40
#: synthetic rigs, the bootstrap interval of a 20 s side of smooth motion missing its offset by 7 ms
#: (benchmarks/bench_segments.py, seeds 0-39).
JUMP_Z = 3.0
#: A sensor interval longer than this many median intervals is a candidate clock jump (a jump of 2.5
#: ms at 200 Hz); the :data:`JUMP_CANDIDATES` longest are tested.
JUMP_GAP_FACTOR, JUMP_CANDIDATES = 1.5, 5


@dataclass(frozen=True)
class ClockJump:
    """A jump of a clock: at ``time_s`` (s, on the camera's clock, to within ``time_resolution_s``)
    the offset of the sensor's clock to the camera's changes by ``size_s``. ``clock``: ``"sensor"``,
    ``"camera"`` (the clock whose stamps skip there) or ``"unknown"`` (no skip in either's stamps);
    ``found_by``: ``"gap"`` (:func:`clock_segments`) or ``"profile"``
    (:func:`~replication.rig.clock_profile.offset_profile`)."""

    time_s: float
    size_s: float
    offset_before_s: float
    offset_after_s: float
    at_gap: bool
    clock: str = "sensor"
    time_resolution_s: float = 0.0
    found_by: str = "gap"

    def to_dict(self, t0: float = 0.0) -> dict:
        return {"time_s": self.time_s - t0, "size_s": self.size_s, "offset_before_s": self.offset_before_s,
                "offset_after_s": self.offset_after_s, "at_gap": self.at_gap, "clock": self.clock,
                "time_resolution_s": self.time_resolution_s, "found_by": self.found_by}


def jump_candidates(t, max_offset: float = math.inf) -> np.ndarray:
    """``(start, end)`` of the sensor intervals that may hide a clock jump (:data:`JUMP_GAP_FACTOR`;
    a skip beyond ``max_offset``, the offset search's bound, is no jump it could measure: samples
    lost), the :data:`JUMP_CANDIDATES` longest, in time order."""
    dt = np.diff(t)
    step = np.median(dt)
    k = np.flatnonzero((dt > JUMP_GAP_FACTOR * step) & (dt - step <= max_offset))
    k = np.sort(k[np.argsort(-dt[k])[:JUMP_CANDIDATES]])
    return np.stack([t[k], t[k + 1]], axis=-1)


def clock_segments(camera, sensor, *, max_offset: float = 0.2, gaps=None, n_bootstrap: int = 50, seed: int = 0,
                   offset_s: float | None = None, window_s: float = 2 * SEGMENT_S):
    """The clock offset on each side of the sensor stream's gaps, and the jumps among them.

    A sensor clock that jumps ahead by ``size`` leaves a gap of ``size`` (plus a sample interval) in
    its stamps; a gap where samples were lost leaves the offset as it was. On each side of a gap,
    the camera's samples within ``window_s`` of it (up to the neighbouring gaps; at least
    :data:`SEGMENT_S`) get their own offset
    (:func:`replication.rig.association.estimate_time_offset`; given the whole recording's
    ``offset_s`` the search spans ``|offset_s|`` plus the largest skip plus 20 ms only, within
    ``max_offset``). Where the two differ by more than :data:`JUMP_MIN_S` and by about what the
    stamps skipped (the gap less one median interval; within half of it, or the bound plus
    :data:`JUMP_MIN_S`), their 95 % intervals (:func:`~replication.rig.association.
    offset_analysis`, ``n_bootstrap`` replicates) decide: beyond ``JUMP_Z sqrt(se_1^2 + se_2^2)``
    (``se`` = interval width / 3.92) it is a jump at that gap, its size what the stamps skipped (the
    offsets of parts of smooth motion may be off by several ms; the stamps are exact). A gap where
    samples were lost leaves the offset as it was: no jump, however long.

    Returns ``(parts, jumps)``: one dict per gap side tested (``start_s``, ``end_s``, ``offset_s``,
    ``ci95_s``: NaN where no jump was in question, the bootstrap being run only there), a list of
    :class:`ClockJump`.
    """
    from .association import estimate_time_offset, offset_analysis

    gaps = np.empty((0, 2)) if gaps is None else np.asarray(gaps, dtype=float).reshape(-1, 2)
    if not len(gaps):
        return [], []
    step = float(np.median(np.diff(sensor.t)))
    if offset_s is not None and math.isfinite(offset_s):
        max_offset = min(max_offset, abs(offset_s) + float(np.max(gaps[:, 1] - gaps[:, 0])) + 0.02)
    edges = np.concatenate([[sensor.t[0]], gaps.ravel(), [sensor.t[-1]]])

    def side(lo, hi):
        if hi - lo < SEGMENT_S or np.sum((camera.t >= lo + max_offset) & (camera.t <= hi - max_offset)) < 10:
            return None
        view = camera.between(lo + max_offset, hi - max_offset)
        with np.errstate(all="ignore"):
            d = estimate_time_offset(view, sensor, max_offset=max_offset)[0]
        return {"start_s": float(lo), "end_s": float(hi), "offset_s": float(d), "ci95_s": [math.nan, math.nan],
                "view": view}

    def se(part):  # the side's 95 % interval, computed where a jump is in question only (the bootstrap's cost)
        v = part["view"]
        with np.errstate(all="ignore"):
            est = offset_analysis(v, sensor, max_offset=max_offset, n_bootstrap=n_bootstrap, seed=seed,
                                  block_s=min(1.0, 0.25 * (v.t[-1] - v.t[0])))
        part["ci95_s"] = [float(x) for x in est.ci95_s]
        lo, hi = part["ci95_s"]
        return max((hi - lo) / 3.92, 0.0) if math.isfinite(hi - lo) else math.inf

    def agrees(size, stamps, bound):
        return abs(size) > max(JUMP_MIN_S, bound) and abs(stamps - size) <= max(0.5 * abs(stamps), bound + JUMP_MIN_S)
    parts, jumps = [], []
    for i, gap in enumerate(gaps):
        p = side(max(edges[2 * i], gap[0] - window_s), gap[0])
        q = side(gap[1], min(edges[2 * i + 3], gap[1] + window_s))
        parts += [x for x in (p, q) if x is not None]
        if p is None or q is None:
            continue
        size = q["offset_s"] - p["offset_s"]
        stamps = float(gap[1] - gap[0] - step)  # what the stamps skipped beyond one sample interval
        if agrees(size, stamps, 0.0) and agrees(size, stamps, JUMP_Z * math.hypot(se(p), se(q))):
            jumps.append(ClockJump(time_s=float(gap[0] - p["offset_s"]), size_s=stamps,
                                   offset_before_s=p["offset_s"], offset_after_s=q["offset_s"], at_gap=True))
    return [{k: v for k, v in x.items() if k != "view"} for x in parts], jumps


def corrected_sensor(sensor: OrientationStream, offset: float, *, jumps=(), drift=None, interval: float = 1.0):
    """``sensor`` re-stamped so that the one ``offset`` holds throughout: with jumps, its stamps
    before the first shifted by ``offset`` less the offset there and after each further by the
    jump's size, the stamps within the jump's time resolution plus ``interval`` of it cut (a gap, so
    that pairs across it are dropped), and a ``drift = (ppm, t_mid, offset_mid)`` given with them
    removed to first order (``k (s - t_mid - offset_mid)`` off the stamp ``s``; ``offset_mid`` the
    offset before the first jump at ``t_mid``); or, without jumps, the drift removed (the sample
    stamped ``s`` restamped ``t + offset``, ``t = (s - offset_mid + k t_mid) / (1 + k)``). None
    where there is nothing to correct."""
    t = sensor.t.astype(float).copy()
    keep = np.ones(len(t), bool)
    if jumps:
        jumps = sorted(jumps, key=lambda j: j.time_s)
        new = t + (offset - jumps[0].offset_before_s)
        if drift is not None:  # the drift through offset_mid at t_mid (the sensor's stamp t_mid + offset_mid)
            new = new - drift[0] * 1e-6 * (t - drift[1] - drift[2])
        for j in jumps:
            at = j.time_s + j.offset_before_s
            keep &= np.abs(t - at) > j.time_resolution_s + interval + abs(j.size_s)
            new = np.where(t > at, new - j.size_s, new)
        t = new
    elif drift is not None:
        k = drift[0] * 1e-6
        t = (t - drift[2] + k * drift[1]) / (1.0 + k) + offset
    else:
        return None
    t, Q = t[keep], sensor.world_from_body[keep]
    order = np.argsort(t, kind="stable")
    return OrientationStream(t[order], Q[order], sensor.source)


def clock_report(parts, jumps, t0: float, profile=None) -> dict:
    """The clock offset of each part between the sensor's gaps, the offset profile and the jumps,
    for the report (times since ``t0``, on the sensor's clock for the parts)."""
    return {"clock_offsets": [{**o, "start_s": o["start_s"] - t0, "end_s": o["end_s"] - t0} for o in parts],
            "clock_profile": None if profile is None else profile.to_dict(t0),
            "clock_jumps": [j.to_dict(t0) for j in jumps]}


def _where(j, t0):
    at = f"at {j.time_s - t0:.1f} s" + (f" (+-{j.time_resolution_s:.1f} s)" if j.time_resolution_s >= 0.05 else "")
    who = {"sensor": "the sensor's clock jumped",
           "camera": f"the camera's stamps skip there: its clock jumped by {-1e3 * j.size_s:+.1f} ms",
           "unknown": f"no skip in either clock's stamps near it (no interval over {JUMP_GAP_FACTOR:g} median "
                      f"intervals or over the median by about the step): one of them lost samples and stamped on "
                      "evenly (which one cannot be told from the data)"}[j.clock]
    how = ("where the sensor stream has a gap" if j.at_gap and j.found_by == "gap" else
           "found in the offset per window: a step fits it better than one offset and than a steady drift or one "
           "that stops"
           if j.found_by == "profile" else "")
    return (f"{at} by {1e3 * j.size_s:+.1f} ms (offset {1e3 * j.offset_before_s:+.1f} ms before, "
            f"{1e3 * j.offset_after_s:+.1f} ms after; {who}" + (f"; {how})" if how else ")"))


def clock_reasons(jumps, t0: float, offset_s: float) -> list:
    """A ``fail`` reason per recording with clock jumps: the one offset removed is wrong for part of
    it."""
    from .quality import Reason

    if not jumps:
        return []
    named = "; ".join(_where(j, t0) for j in jumps)
    worst = max(abs(j.size_s) for j in jumps)
    return [Reason("clock_jump", "fail", worst, JUMP_MIN_S,
                   f"the clock offset jumps: {named}; the one offset removed ({1e3 * offset_s:+.2f} ms) is wrong for "
                   f"part of the recording, and its interval does not say so; R0 is not corrected for it; calibrate "
                   f"each part on its own, or correct the time stamps at the jump")]
