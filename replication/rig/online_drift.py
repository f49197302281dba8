"""A frame that drifts told from a re-mount, for the online estimator: a second re-mount soon after
the first, small and in the same direction, is the same cause (:func:`recognise_drift`), one
``drift`` event followed with forgetting whose lag is a share of the target
(:func:`follow_drift`, :func:`follow_forgetting`, :func:`drift_lag_deg`), its rate measured again
on the estimate's own track (:func:`track_drift`: a new rate or the drift's end). Theory and
measured numbers: ``docs/judging.md``, section ``replication.rig.online_drift``."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["recognise_drift", "follow_drift", "follow_forgetting", "drift_lag_deg", "drift_step", "track_drift",
           "DRIFT_WITHIN_PAIRS", "DRIFT_COS", "DRIFT_MAX_STEP_DEG", "DRIFT_LAG_SHARE", "TRACK_MEMORIES",
           "TRACK_MIN_PAIRS", "TRACK_Z", "TRACK_APART"]

#: A re-mount decided within this many pairs of the last restart, in the same direction (the cosine
#: of the angle between the two steps at least :data:`DRIFT_COS`) and both steps below
#: :data:`DRIFT_MAX_STEP_DEG`, is the frame drifting, not a second re-mount: one cause, one event
#: (``drift``), no second restart.
DRIFT_WITHIN_PAIRS = 2000
DRIFT_COS = 0.7
DRIFT_MAX_STEP_DEG = 3.0
#: While following a drift, the estimate's memory (``2 / (1 - lambda)`` pairs under forgetting
#: ``lambda``) is chosen so that its lag behind the drift, ``rate x lambda / (1 - lambda)``, is this
#: share of the target; the lag is added to the radius (``ready`` then means the noise and the lag
#: together stay below the target).
DRIFT_LAG_SHARE = 0.25


def drift_step(R_before, R_after) -> np.ndarray:
    """The rotation vector ``w`` (rad, sensor frame) with ``R_after = R_before exp([w]x)``."""
    from ..core.so3 import rotation_vector_from_matrix

    return rotation_vector_from_matrix(np.swapaxes(R_before, -1, -2) @ R_after)


def recognise_drift(last, event, following: float | None):
    """Whether the re-mount ``event`` (an :class:`replication.rig.online_events.OnlineEvent`)
    continues the last change, ``last = (pair, R_latest, origin)``: the pair and estimate of the
    last re-mount or drift step, and the re-mount that began it (an event). The step from the
    estimate before the event to the event's own must be small (:data:`DRIFT_MAX_STEP_DEG`, or twice
    what the drift followed at rate ``following`` (deg per pair) moves in the pairs between), within
    :data:`DRIFT_WITHIN_PAIRS`, and in the direction of the movement so far (from the origin's
    estimate before it to the estimate before this event, ``event.R_before``: the window of the last
    step is a few pairs, its direction noisy): a cosine of at least :data:`DRIFT_COS`, or
    (``following`` a drift already, whose small steps are noisy) at least 0. Returns None or
    ``(rate_deg_per_pair, angle_deg, first_pair, axis)``: the angle between the origin's own
    estimate and the event's (where the frame was then and is now), its rate over the pairs between
    them, and the movement's direction (a unit vector, sensor frame)."""
    if last is None or not 0 < event.pair - last[0] <= DRIFT_WITHIN_PAIRS:
        return None
    origin = last[2]  # the movement so far ends at the estimate now (many pairs), not the last window's (a few)
    so_far = drift_step(origin.R_before, event.R_before)
    step = drift_step(event.R_before, event.R_after)
    a, b = float(np.linalg.norm(so_far)), float(np.linalg.norm(step))
    if a and b and float(np.linalg.norm(so_far + step)) == 0.0:
        return None
    bound = DRIFT_MAX_STEP_DEG if following is None else max(DRIFT_MAX_STEP_DEG, 2 * following * (event.pair - last[0]))
    if not (a and b) or math.degrees(max(b, 0.0 if following is not None else a)) > bound:
        return None
    if float(so_far @ step) / (a * b) < (0.0 if following is not None else DRIFT_COS):
        return None
    moved = drift_step(origin.R_after, event.R_after)  # between the windows' own estimates: where the frame was
    angle = math.degrees(float(np.linalg.norm(moved)))
    return angle / (event.pair - origin.pair), angle, origin.pair, (so_far + step) / np.linalg.norm(so_far + step)


def follow_drift(cal, event, rate: float, angle: float, first: int, axis):
    """Act on a drift recognised by :func:`recognise_drift` in the calibrator ``cal``
    (:class:`replication.rig.online.OnlineCalibrator`): the drift event (the first re-mount's
    restart folded into it, one event per cause), forgetting that follows it
    (:func:`follow_forgetting`), the older pairs' weight cut to the new memory; no restart. Returns
    the event."""
    import dataclasses

    if cal._drift_rate is None:  # the first re-mount of this cause becomes the drift's start; its track begins
        cal._track.clear()
        cal.events = [e for e in cal.events if not (e.kind == "remount" and e.pair == first)]
        cal.alarms = [a for a in cal.alarms if a != first]
    cal._flush()
    lam = follow_forgetting(rate, cal.target_deg, (cal.min_pairs - 1) / (cal.min_pairs + 1), cal.refine_every)
    c = min(1.0, 1.0 / ((1.0 - lam) * cal._w)) if cal._w else 1.0
    cal._S, cal._SB, cal._w, cal._SB2, cal._w2 = c * cal._S, c * cal._SB, c * cal._w, c * c * cal._SB2, c * c * cal._w2
    cal._wt *= c  # the pairs' centroid unchanged
    cal._last_step, cal._drift_rate, cal.forgetting = (event.pair, event.R_after, cal._last_step[2]), rate, lam
    cal._drift_axis = axis
    lag = drift_lag_deg(rate, lam, cal.refine_every)
    return dataclasses.replace(
        event, kind="drift", onset_pair=first, angle_deg=angle, rate_deg_per_pair=rate,
        message=f"the frame drifts: {angle:.3g} deg in {event.pair - first} pairs ({rate:.3g} deg per pair) since "
                + (f"pair {first}, where a creep began (found as a slope; followed, no restart)" if
                   cal._last_step[2].source == "creep" else f"the re-mount decided at pair {first} (started over "
                   "once, then followed)") + f": forgetting {lam:.4g}, lag "
                f"{lag:.3g} deg added to the radius" + (
                    "" if lag < cal.target_deg else f"; too fast to follow within {cal.target_deg:g} deg"))


def follow_forgetting(rate_deg_per_pair: float, target_deg: float, lowest: float, every: int) -> float:
    """The forgetting factor that keeps the lag behind a drift (:func:`drift_lag_deg`, refined every
    ``every`` pairs) at :data:`DRIFT_LAG_SHARE` of the target (at least ``lowest``, the factor that
    still gives the estimator its distinct pairs; below 1)."""
    memory = DRIFT_LAG_SHARE * target_deg / max(rate_deg_per_pair, 1e-12) - every   # lambda / (1 - lambda)
    return min(max(memory / (1.0 + memory), lowest), 1.0 - 1e-9) if memory > 0 else lowest


def drift_lag_deg(rate_deg_per_pair: float, forgetting: float, every: int) -> float:
    """The lag (deg) behind a drift of an estimate with forgetting ``lambda`` refined every
    ``every`` pairs: ``rate x (lambda / (1 - lambda) + every)`` (the weighted mean age of its pairs,
    and the pairs since its last refinement)."""
    return rate_deg_per_pair * (forgetting / (1.0 - forgetting) + every)


#: While following a drift, its rate is measured again on the estimate's own track: the movement
#: along the drift's axis between the estimate now and the one at least :data:`TRACK_MEMORIES`
#: memories (``(1 + lambda) / (1 - lambda)`` pairs) and :data:`TRACK_MIN_PAIRS` pairs ago (two
#: nearly independent estimates), pairs counted between the estimates' centroids (the weighted mean
#: index of their pairs, ``OnlineCalibrator.centroid``): a steady drift moves an estimate as far as
#: its centroid moves, whereas an estimate soon after a restart or a cut of the memory lags less
#: than a steady one (counted between the pairs received, it moved about half what the rate
#: predicts). The span is also long enough for none and the rate followed to be :data:`TRACK_APART`
#: ``TRACK_Z`` standard errors apart, and a drift's end is said only once they are (else the track
#: waits): a drift that goes on, its rate over-estimated by a quarter and tested every refinement on
#: a short span, was said to stop in 15 of 30 runs (0.002 deg per pair at 0.3 deg of pair noise). A
#: movement that differs from the one the rate followed predicts by more than :data:`TRACK_Z`
#: standard errors is a new rate (a drift that speeds up or slows down), or, nearer none than that
#: prediction (below half of it), a drift that stopped: said (``drift_end``), and the estimator
#: returns to its own memory. Over a memory the rate followed moves the estimate about twice its lag
#: (half the target).
TRACK_MEMORIES = 1.5
TRACK_MIN_PAIRS = 100
TRACK_Z = 3.0
#: None and the rate followed are this many ``TRACK_Z`` standard errors apart before a drift's end
#: is said. Measured on 30 runs (0.002 deg per pair for 1500 pairs, then still for 1500, 0.3 deg of
#: pair noise, seeds [41000-41029, 7] of ``drift_stream``): at 2, an end said during the drift in 9
#: runs, the stop told within 600 pairs in 29; at 2.5, 2 and 27; at 3, 0 and 22 (every stop told
#: within 1500 pairs, median 544); at 4, 0 and 15.
TRACK_APART = 3.0


def track_drift(cal):
    """Measure the drift followed by ``cal`` (:class:`replication.rig.online.OnlineCalibrator`) on
    its track of estimates (see :data:`TRACK_MEMORIES`) and act: a new rate (forgetting and the
    drift event updated), or the drift's end (event ``drift_end``, forgetting back to the
    calibrator's own). Returns the kind of event added, or None."""
    import dataclasses

    now, at, R_now = cal.n_total, cal.centroid, cal._R
    track = cal._track
    track.append((at, R_now, cal._cov))
    lam, rate, axis = cal.forgetting, cal._drift_rate, cal._drift_axis
    lag = math.radians(drift_lag_deg(rate, lam, cal.refine_every))
    if cal._cov is None:
        return None
    se_now = math.degrees(math.sqrt(2.0 * max(float(axis @ cal._cov @ axis) - lag ** 2, 0.0)))  # two such estimates
    span_least = max(TRACK_MEMORIES * (1.0 + lam) / (1.0 - lam), TRACK_MIN_PAIRS, TRACK_APART * TRACK_Z * se_now / rate)
    then = next((t for t in reversed(track) if at - t[0] >= span_least), None)
    if then is None or then[2] is None:
        return None
    span = at - then[0]  # between the centroids: an estimate after a restart lags less than a steady one
    var = [max(float(axis @ c @ axis) - lag ** 2, 0.0) for c in (then[2], cal._cov)]  # noise along the axis, no lag
    se = math.degrees(math.sqrt(sum(var)))                         # of the difference of the two estimates
    whole = drift_step(cal._last_step[2].R_before, R_now) if cal._last_step is not None else np.zeros(3)
    if math.degrees(float(np.linalg.norm(whole))) > 2 * TRACK_Z * se:  # the whole drift so far: its axis, better
        cal._drift_axis = axis = whole / np.linalg.norm(whole)        # than the first steps' (55 deg off seen)
    moved = math.degrees(float(drift_step(then[1], R_now) @ axis))
    if abs(moved - rate * span) <= TRACK_Z * se:
        return None
    if moved < 0.5 * rate * span < 0.5 * TRACK_APART * TRACK_Z * se:  # nearer none, but not far enough apart: wait
        return None
    drift = next((e for e in reversed(cal.events) if e.kind == "drift"), None)
    track.clear()
    track.append((at, R_now, cal._cov))
    if moved < 0.5 * rate * span:  # nearer none than the rate followed, and beyond its standard errors: stopped
        cal._drift_rate, cal._drift_axis, cal.forgetting = None, None, cal._fgt
        onset = drift.onset_pair if drift is not None else round(then[0])
        cal.events.append(dataclasses.replace(
            drift, kind="drift_end", pair=now - 1, alarm_pair=now - 1, source="track", onset_pair=onset,
            window_pairs=round(span), angle_deg=moved, threshold_deg=TRACK_Z * se, median_z_before=math.nan,
            median_z_after=math.nan, pairs_dropped=0, R_before=np.array(then[1]), R_after=np.array(R_now),
            rate_deg_per_pair=0.0,
            message=f"the drift that began at pair {onset} stopped: the estimate moved {moved:.3g} deg along it in "
                    f"the last {span:.0f} pairs, where its rate ({rate:.3g} deg per pair) says {rate * span:.3g} deg "
                    f"(more than {TRACK_Z:g} standard errors, {TRACK_Z * se:.3g} deg, apart); no more forgetting: "
                    f"full memory"))
        return "drift_end"
    new_rate = max(moved / span, 0.0)
    cal._drift_rate = new_rate
    cal.forgetting = lam = follow_forgetting(new_rate, cal.target_deg, (cal.min_pairs - 1) / (cal.min_pairs + 1),
                                             cal.refine_every)
    if drift is not None:
        lag = drift_lag_deg(new_rate, lam, cal.refine_every)
        k = cal.events.index(drift)
        cal.events[k] = dataclasses.replace(drift, rate_deg_per_pair=new_rate, message=(
            f"{drift.message.split('; rate now')[0]}; rate now {new_rate:.3g} deg per pair (measured over the last "
            f"{span:.0f} pairs at pair {now}): forgetting {lam:.4g}, lag {lag:.3g} deg"
            + ("" if lag < cal.target_deg else f"; too fast to follow within {cal.target_deg:g} deg")))
    return None
