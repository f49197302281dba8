"""The clock offset per window of the recording and the model that fits it (one offset, a drift, a
drift that bends, one step, a step with a drift, two steps), each step named with its time, size and
clock; and ``calibrate``'s clock step, which joins them to the jumps at the sensor's gaps
(:mod:`replication.rig.clock`). Theory and measured numbers: ``docs/judging.md``, section
``replication.rig.clock_profile``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.so3 import rotation_vector_from_matrix
from .clock import JUMP_GAP_FACTOR, JUMP_MIN_S, ClockJump, clock_segments, corrected_sensor, jump_candidates

__all__ = ["OffsetProfile", "offset_profile", "merged_jumps", "clock_analysis", "PROFILE_WINDOW_S", "STEP_LR",
           "BEND_SHARE", "TWO_STEPS_VS_DRIFT", "TWO_STEPS_MIN_S", "SKIP_MATCH",
           "STEP_DRIFT_SHARE", "REFIT_SE", "skip"]

#: Length of a window of the offset profile (s): 5 s of 1 s pairs at 20 Hz are 80 pairs.
PROFILE_WINDOW_S = 5.0
#: A step is named where its scaled chi-square is below both the ramp's and the one offset's by more
#: than this. On bench_clock.py's tuning seeds 0-39 the least of the two gains reached 26.3 on clean
#: rigs (95 % quantile 16.7) and 29.6 on 50 ppm drifts (200 ppm: below 0); a 5 ms step's median was
#: 36.8, a 10 ms step's 5 % quantile 57.1. On fresh seeds 90000-90039: no false step in 120 clean
#: and drifting rigs (maximum 30.0), 5 ms found in 20 of 40, 10-50 ms in 40 of 40 each
#: (bench_clock.py's notes).
STEP_LR = 40.0
#: A stamp interval shorter than ``JUMP_GAP_FACTOR`` median intervals is a clock's skip where its
#: excess over the median is the step's size to within this share of it (a 20 ms jump of a 20 Hz
#: camera's clock: a 70 ms interval; the profile's size is within 1-2 ms of the jump's).
SKIP_MATCH = 0.25
#: A step is named where it also beats a drift that stops or changes (a ramp that bends once) by
#: this share of :data:`STEP_LR`: on seeds 96000-96039 (bench_clock.py) a share of 1 lost 12 of 24
#: 5 ms steps and 4 of 39 10 ms steps, 0.25 lost one 5 ms step; a 500 ppm drift that stops at 30 s,
#: named a step in 5 of 30 rigs (the red team's seeds) without this rival, in none with it.
BEND_SHARE = 0.25
#: Two steps are named where they beat one offset, the ramps and one step by :data:`STEP_LR`, a step
#: with a drift by this share of it where that is named itself (it beats one offset and the ramps as
#: a step is required to), and each exceeds :data:`TWO_STEPS_MIN_S` (s). On tuning seeds 7000-7019
#: (60 s, steps of 20 and 30 ms at 20 and 40 s) the gain over a step with a drift was 20.6-399; on
#: one 30 ms step it reached 39.9 (its second "step" 1.6 ms) and on a 30 ms step with a 200 ppm
#: drift 12.3 (second step 3.9 ms). Inside ``calibrate`` (seeds 0-29): two steps gained 16.4-17.0
#: over it in the 3 rigs missed (the step with a drift named in 2 of them), and a 30 ms step with a
#: +-200 ppm drift at most 17.5, its step with a drift named in 60 of 60 rigs.
TWO_STEPS_VS_DRIFT, TWO_STEPS_MIN_S = 0.5, 4e-3
#: A step with a drift is named where it beats one offset and the ramp by :data:`STEP_LR` and the
#: ramp that bends by :data:`BEND_SHARE` of it (its scale ``max(1, chi2 / (W - 5))``) and the one
#: step does not, or where it also beats the one step by this share of :data:`STEP_LR` (the step's
#: size then measured beside the drift). On seeds 0-19 (the profile on the true ``R0``) its gain
#: over the one step was below 5 for 38 of 40 pure 10 and 30 ms steps (the others 19.5 and 20.3),
#: 5.3-51 for a 10 ms step with a -100 ppm drift and 31-180 for 5 ms with -200 ppm.
STEP_DRIFT_SHARE = 0.25
#: The profile's windows whose standard error is within this many times the median refit ``R0``
#: (the windows across a step are left out: their pairs straddle it). ``calibrate``'s ``R0`` comes
#: from the sensor model, fitted with one offset and one drift: under two steps of 20 and 30 ms it
#: was 0.10-0.13 deg off on seeds 1, 4 and 14 and the windows' offsets crept by 4 ms between steps.
REFIT_SE = 3.0
#: Fewest windows the profile runs with (the step model has 4 parameters).
PROFILE_MIN_WINDOWS = 6
_H = 1e-3  # the offset's finite difference (s)
#: A window's offset is searched within this of the one offset applied (s); a window whose offset
#: leaves it (the streams show no common motion there) is left out of the profile and counted.
PROFILE_REACH_S = 0.3


@dataclass(frozen=True)
class OffsetProfile:
    """The clock offset per window and the model chosen for it (:func:`offset_profile`; times on the
    camera's clock).

    Attributes
    ----------
    t_s, offset_s, se_s : ndarray (W,)
        Each window's centre, offset (s; the sensor sample stamped ``t + offset`` matches the camera
        sample stamped ``t``) and its standard error.
    chi2 : dict
        The weighted chi-square of ``"one offset"``, ``"drift"``, ``"drift that bends"``,
        ``"step"``, ``"step and drift"`` and ``"two steps"``, unscaled.
    scale : float
        The chosen step model's excess scatter (``max(1, chi2_step / (W - 4))``, with a drift ``W -
        5``, two steps ``W - 6``) the likelihood ratios are divided by.
    ratio_drift, ratio_one : float
        The step's scaled chi-square improvement over the ramp (or over a ramp that bends once, a
        drift that stops, divided by :data:`BEND_SHARE`, where less) and over one offset: the one
        step's, or the step's with a drift where that is chosen (:data:`STEP_DRIFT_SHARE`), or the
        two steps' where chosen.
    choice : str
        ``"step"`` where both ratios exceed :data:`STEP_LR` and the step exceeds
        :data:`~replication.rig.clock.JUMP_MIN_S` (one step, or one step with a drift; two steps
        where their chi-square, scaled by ``max(1, chi2 / (W - 6))``, is below every other model's,
        the one step's too, by more than :data:`STEP_LR`, each over the floor); else ``"drift"``
        where the ramp fits better than one offset by more than :data:`STEP_LR`; else ``"one
        offset"``.
    step : ClockJump or None
        The (first) step, where chosen.
    drift_ppm : float
        The drift (1e-6 s per s): the step's with a drift where that is chosen, else the ramp's
        slope.
    windows_left_out : int
        Windows without enough pairs or motion, or whose offset left :data:`PROFILE_REACH_S`.
    steps : tuple of ClockJump
        Every step chosen (one or two), in time order.
    step_with_drift : bool
        The step chosen is a step with a drift (``drift_ppm`` its drift).
    """

    t_s: np.ndarray
    offset_s: np.ndarray
    se_s: np.ndarray
    chi2: dict
    scale: float
    ratio_drift: float
    ratio_one: float
    choice: str
    step: ClockJump | None
    drift_ppm: float
    threshold: float = STEP_LR
    windows_left_out: int = 0
    steps: tuple = ()
    step_with_drift: bool = False

    def to_dict(self, t0: float = 0.0) -> dict:
        return {"t_s": (self.t_s - t0).tolist(), "offset_s": self.offset_s.tolist(), "se_s": self.se_s.tolist(),
                "chi2": dict(self.chi2), "scale": self.scale, "ratio_drift": self.ratio_drift,
                "ratio_one": self.ratio_one, "threshold": self.threshold, "choice": self.choice,
                "drift_ppm": self.drift_ppm, "windows_left_out": self.windows_left_out,
                "step": None if self.step is None else self.step.to_dict(t0),
                "steps": [j.to_dict(t0) for j in self.steps], "step_with_drift": self.step_with_drift}


def _residuals(Ai, sensor, ti, tk, d, R):
    """``r_j = log(B_j^T R^T A_j R)`` of the pairs ``(ti, tk)`` with the sensor at ``t + d``
    (``Ai``: ``R^T A_j R``)."""
    Qi, Qk = sensor.at(ti + d), sensor.at(tk + d)
    B = np.swapaxes(Qk, -1, -2) @ Qi
    return rotation_vector_from_matrix(np.swapaxes(B, -1, -2) @ Ai)


def _window_offset(Ai, sensor, ti, tk, d, R, lags, bound):
    """One window's offset (three Gauss-Newton steps from ``d``) and its Newey-West standard error;
    NaN where a step leaves ``d +- bound`` (the streams do not show one motion there, or no
    motion)."""
    d0 = d
    for _ in range(3):
        if not abs(d - d0) <= bound:
            return math.nan, math.nan
        r = _residuals(Ai, sensor, ti, tk, d, R)
        g = (_residuals(Ai, sensor, ti, tk, d + _H, R) - r) / _H
        H = float(np.einsum("ja,ja->", g, g))
        u = np.einsum("ja,ja->j", g, r)
        step = -float(u.sum()) / H
        if _ == 2:
            break
        d += step
    if not abs(d + step - d0) <= bound:
        return math.nan, math.nan
    u = u + step * np.einsum("ja,ja->j", g, g)  # the scores at the final offset (first order)
    lrv = float(u @ u) + 2.0 * sum((1 - k / (lags + 1)) * float(u[k:] @ u[:-k])
                                   for k in range(1, min(lags, len(u) - 1) + 1))
    return d + step, math.sqrt(max(lrv, 0.0)) / H


def _fits(t, d, w):
    """The chi-squares of one offset, a ramp, a ramp that bends once (a drift that stops or
    changes), the best step and the best two steps (each at a boundary ``b`` or inside window ``b``,
    left out), a step with a drift: ``c0, c1, slope, ck, (csr, (cuts, offsets at the cut, its
    slope)), (c2, (cuts, means)), (c3, (cuts, means))``."""
    def mean_chi(k):
        if not k.any():
            return 0.0, 0.0
        m = float(np.sum(w[k] * d[k]) / np.sum(w[k]))
        return m, float(np.sum(w[k] * (d[k] - m) ** 2))

    def lsq(X, u=w):
        coef = np.linalg.lstsq(X * np.sqrt(u)[:, None], d * np.sqrt(u), rcond=None)[0]
        return coef, float(np.sum(u * (d - X @ coef) ** 2))

    n, idx = len(d), np.arange(len(d))
    _, c0 = mean_chi(np.ones(n, bool))
    coef, c1 = lsq(np.stack([np.ones_like(t), t - t.mean()], axis=1))
    knots = np.concatenate([t[1:-1], 0.5 * (t[1:] + t[:-1])])
    ck = min(lsq(np.stack([np.ones_like(t), np.minimum(t - k, 0), np.maximum(t - k, 0)], axis=1))[1] for k in knots)
    cuts = [(b, x) for b in range(1, n) for x in (None, b) if x is None or b < n - 1]

    def pieces(cs, ramp=False):  # the parts' means and chi-square between the cuts (a window cut inside: left out)
        parts, lo = [], 0
        for b, x in cs:
            parts.append((idx >= lo) & (idx < b))
            lo = b + (x is not None)
        parts.append(idx >= lo)
        fits = [mean_chi(k) for k in parts]
        if ramp:  # the parts' offsets and one drift through them (a step and a drift): the offsets at the cut
            coef, chi = lsq(np.stack(parts + [t - t.mean()], axis=1).astype(float), w * np.any(parts, axis=0))
            b, x = cs[0]
            at = (t[b] if x is not None else 0.5 * (t[b - 1] + t[b])) - t.mean()
            return chi, (cs, [float(coef[0] + coef[2] * at), float(coef[1] + coef[2] * at)], float(coef[2]))
        return sum(c for _, c in fits), (cs, [m for m, _ in fits])

    one = min((pieces([c]) for c in cuts), key=lambda f: f[0])
    two = min((pieces([c, e]) for c in cuts for e in cuts if e[0] > c[0] + (c[1] is not None)),
              key=lambda f: f[0], default=(math.inf, None))
    csr = min((pieces([c], True) for c in cuts), key=lambda f: f[0])
    return c0, c1, coef[1], ck, csr, one, two


def _split(Ai, sensor, ti, tk, m0, m1, R, m):
    """The time of a step from offset ``m0`` to ``m1`` among the pairs ``(ti, tk)``: the split of
    least cost ``sum |r_j(m0)|^2`` before, ``sum |r_j(m1)|^2`` after, the ``m`` pairs just before it
    (across it) at their smaller cost; the first pair start after it."""
    c0 = np.sum(_residuals(Ai, sensor, ti, tk, m0, R) ** 2, axis=-1)
    c1 = np.sum(_residuals(Ai, sensor, ti, tk, m1, R) ** 2, axis=-1)
    P0, P1, Pm = (np.concatenate([[0.0], np.cumsum(c)]) for c in (c0, c1, np.minimum(c0, c1)))
    q = np.arange(m, len(ti) + 1)
    cost = P0[q - m] + (P1[-1] - P1[q]) + (Pm[q] - Pm[q - m])
    best = int(q[int(np.argmin(cost))])
    return float(ti[min(best, len(ti) - 1)])


def skip(t, near, width, expect=0.0):
    """The largest stamp skip of ``t`` within ``width`` of ``near``: an interval over
    ``JUMP_GAP_FACTOR`` median intervals, or one whose excess over the median is ``expect`` (within
    :data:`SKIP_MATCH` of it, and over :data:`JUMP_MIN_S`).

    Parameters
    ----------
    t : array_like (N,)
        One stream's time stamps (s), increasing.
    near, width : float
        Where the skip is looked for (s): intervals starting within ``width`` of ``near``.
    expect : float
        The step's size with the clock's sign (s); 0 matches only the long intervals.

    Returns
    -------
    (float, float) or None
        The skip's start and its excess over one median interval (s); None where there is none.
    """
    dt = np.diff(t)
    step = float(np.median(dt))
    fits = (dt - step > JUMP_MIN_S) & (np.abs(dt - step - expect) <= SKIP_MATCH * abs(expect))
    k = np.flatnonzero(((dt > JUMP_GAP_FACTOR * step) | fits) & (np.abs(t[:-1] - near) <= width))
    if not len(k):
        return None
    k = k[int(np.argmax(dt[k]))]
    return float(t[k]), float(dt[k] - step)


def _rotation_at(A, sensor, ti, tk, where, dw, use):
    """``R0`` from the camera's pairs ``A`` and the sensor's at ``(ti, tk)`` plus the offset of the
    pair's window (``dw[where]``), the pairs of the windows in ``use`` only."""
    from .changepoint import _fit

    j = use[where]
    d = dw[where[j]]
    Qi, Qk = sensor.at(ti[j] + d), sensor.at(tk[j] + d)
    B = np.swapaxes(Qk, -1, -2) @ Qi
    kron = np.einsum("jab,jcd->acbd", B, A[j]).reshape(9, 9)
    return _fit(kron[None], B.sum(axis=0)[None], np.array([float(j.sum())]))[0][0]


def offset_profile(camera, sensor, R, offset, *, interval: float = 1.0, window_s: float = PROFILE_WINDOW_S,
                   sensor_stamps=None, refit: bool = True):
    """The clock offset per window of ``window_s`` seconds and the model that fits it (module
    notes).

    ``sensor``: an OrientationStream (a gyro integrated), ``R``: ``R0``, ``offset``: the one offset
    applied (s); ``sensor_stamps``: the sensor's own stamps where ``sensor`` was re-sampled (default
    ``sensor.t``); ``refit``: ``R`` fitted again with each pair at its window's offset (the windows
    whose standard error is within :data:`REFIT_SE` times the median) and the windows measured
    again with it. Returns an :class:`OffsetProfile`, or None where the recording makes fewer than
    :data:`PROFILE_MIN_WINDOWS` windows with at least three pairing intervals of pairs and motion
    (the others are left out).
    """
    tc = camera.t
    dt = float(np.median(np.diff(tc)))
    m = max(1, round(interval / dt))
    i = np.arange(len(tc) - m)
    k = i + m
    margin = PROFILE_REACH_S
    ok = (np.abs(tc[k] - tc[i] - interval) <= 0.5 * dt) & (tc[i] + offset - margin >= sensor.t[0]) & (
        tc[k] + offset + margin <= sensor.t[-1])
    ts = sensor.t if sensor_stamps is None else np.asarray(sensor_stamps, float)
    sdt = np.diff(ts)
    gaps = np.flatnonzero(sdt > JUMP_GAP_FACTOR * np.median(sdt))
    for g in gaps:  # pairs across a sensor gap: their integration or interpolation is wrong
        ok &= ~((tc[i] + offset - margin < ts[g + 1]) & (tc[k] + offset + margin > ts[g]))
    i, k = i[ok], k[ok]
    if not len(i):
        return None
    W = int((tc[k[-1]] - tc[i[0]]) // window_s)
    if W < PROFILE_MIN_WINDOWS:
        return None
    edges = tc[i[0]] + (tc[k[-1]] - tc[i[0]]) * np.arange(W + 1) / W
    Qc = camera.world_from_body
    A = np.swapaxes(Qc[k], -1, -2) @ Qc[i]
    where = np.clip(np.searchsorted(edges, tc[i], side="right") - 1, 0, W - 1)

    def windows(R):
        Ai = R.T @ A @ R
        tw, dw, sw = np.full(W, np.nan), np.full(W, np.nan), np.full(W, np.nan)
        for w in range(W):
            j = where == w
            if j.sum() >= 3 * m:  # a window of too few pairs (a gap) is left out
                tw[w] = 0.5 * (edges[w] + edges[w + 1])
                with np.errstate(all="ignore"):
                    dw[w], sw[w] = _window_offset(Ai[j], sensor, tc[i[j]], tc[k[j]], float(offset), R, 2 * m,
                                                  margin - 2 * _H)
        return Ai, tw, dw, sw, np.isfinite(dw) & np.isfinite(sw) & (sw > 0)  # no motion: no offset

    Ai, tw, dw, sw, good = windows(R)
    if refit and good.sum() >= PROFILE_MIN_WINDOWS:  # R0 again, each pair at its window's offset
        R = _rotation_at(A, sensor, tc[i], tc[k], where, dw, good & (sw <= REFIT_SE * np.median(sw[good])))
        Ai, tw, dw, sw, good = windows(R)
    if good.sum() < PROFILE_MIN_WINDOWS:
        return None
    left_out = int(W - good.sum())
    tw, dw, sw, edges = tw[good], dw[good], sw[good], np.append(edges[:-1][good], edges[1:][good][-1])
    W = len(tw)
    chi2, scale, r_drift, r_one, cuts, means, slope, with_drift = _choice(tw, dw, 1 / sw ** 2)
    steps = tuple(_step(camera, sensor, Ai, i, k, m, R, edges, W, interval, ts, cut, m0, m1)
                  for cut, m0, m1 in zip(cuts, means[:-1], means[1:])) if cuts else ()
    choice = "step" if steps else "drift" if (chi2["one offset"] - chi2["drift"]) / scale > STEP_LR else "one offset"
    return OffsetProfile(t_s=tw, offset_s=dw, se_s=sw, scale=float(scale), ratio_drift=float(r_drift), chi2=chi2,
                         ratio_one=float(r_one), choice=choice, step=steps[0] if steps else None, steps=steps,
                         drift_ppm=float(1e6 * slope), windows_left_out=left_out, threshold=STEP_LR,
                         step_with_drift=bool(steps) and with_drift)


def _choice(t, d, w):
    """The model of the windows' offsets ``d`` (weights ``w``) by the rules of the module notes:
    ``(chi2, scale, ratio_drift, ratio_one, cuts, means, slope, with_drift)``, ``cuts`` empty where
    no step is named (the step models' cuts and the offsets either side where one is, ``slope`` its
    drift's or the ramp's, ``with_drift`` whether it is a step with a drift)."""
    W = len(d)
    c0, c1, slope, ck, (csr, (cut_sd, at_cut, slope_sd)), (c2, (cuts, means)), (c3, two) = _fits(t, d, w)
    chi2 = {"one offset": c0, "drift": c1, "drift that bends": ck, "step": c2, "step and drift": csr,
            "two steps": c3}
    scale = max(1.0, c2 / max(W - 4, 1))
    r_drift, r_one = min(c1 - c2, (ck - c2) / BEND_SHARE) / scale, (c0 - c2) / scale
    s_sd = max(1.0, csr / max(W - 5, 1))  # a step with a drift: where it alone passes, or its drift is kept
    sd_drift, sd_one = min(c1 - csr, (ck - csr) / BEND_SHARE) / s_sd, (c0 - csr) / s_sd
    keep = min(r_drift, r_one) <= STEP_LR or (c2 - csr) / s_sd > STEP_DRIFT_SHARE * STEP_LR
    step_slope, with_drift = slope, False
    if min(sd_drift, sd_one) > STEP_LR and keep:
        cuts, means, scale, r_drift, r_one, step_slope = cut_sd, at_cut, s_sd, sd_drift, sd_one, slope_sd
        with_drift = True
    if two is not None:  # two steps: beyond one offset, either ramp and one step, and a step and a drift if named
        s2 = max(1.0, c3 / max(W - 6, 1))
        rival = min(sd_drift, sd_one) > STEP_LR and (csr - c3) / s2 <= TWO_STEPS_VS_DRIFT * STEP_LR
        big = np.all(np.abs(np.diff(two[1])) > TWO_STEPS_MIN_S)
        if (min(c0, c1, ck, c2) - c3) / s2 > STEP_LR and not rival and big:
            (cuts, means), scale, step_slope, with_drift = two, s2, slope, False
            r_drift, r_one = (min(c1, ck) - c3) / scale, (c0 - c3) / scale
    if min(r_drift, r_one) > STEP_LR and np.all(np.abs(np.diff(means)) > JUMP_MIN_S):
        return chi2, scale, r_drift, r_one, cuts, means, step_slope, with_drift
    return chi2, scale, r_drift, r_one, [], [], slope, False


def _step(camera, sensor, Ai, i, k, m, R, edges, W, interval, ts, cut, m0, m1):
    """The :class:`ClockJump` of a step from ``m0`` to ``m1`` at ``cut`` (its time from its pairs,
    its clock from the stamps that skip there)."""
    tc, b = camera.t, cut[0]
    j = (tc[i] >= edges[max(b - 1, 0)]) & (tc[i] < edges[min(b + 2, W)])  # the step's time from its pairs
    at = _split(Ai[j], sensor, tc[i[j]], tc[k[j]], m0, m1, R, m)
    res = 2.0 * interval  # the split's error reached 1.4 s for 5 ms steps (bench_clock.py, seeds 0-39)
    width = res + interval
    cam, sen = skip(tc, at, width, m0 - m1), skip(ts, at + m0, width, m1 - m0)
    clock = "camera" if cam is not None else "sensor" if sen is not None else "unknown"
    if cam is not None:
        at, res = cam[0], float(np.median(np.diff(tc)))
    elif sen is not None:
        at, res = sen[0] - m0, float(np.median(np.diff(ts)))
    return ClockJump(time_s=float(at), size_s=float(m1 - m0), offset_before_s=float(m0), offset_after_s=float(m1),
                     at_gap=sen is not None, clock=clock, time_resolution_s=float(res), found_by="profile")


def merged_jumps(jumps, profile, window_s: float = PROFILE_WINDOW_S) -> list:
    """The jumps found at the sensor's gaps and the profile's step, once each (the gap's where both
    found one)."""
    out = list(jumps)
    for s in () if profile is None else profile.steps:
        if not any(abs(j.time_s - s.time_s) <= window_s for j in out):
            out.append(s)
    return sorted(out, key=lambda j: j.time_s)


def clock_analysis(camera, oriented, A, B, offset, model=None, *, max_offset: float = 0.2, seed: int = 0,
                   sensor_stamps=None):
    """``calibrate``'s clock step: the jumps at the sensor's gaps (:func:`clock_segments`), the
    offset profile (:func:`offset_profile`, ``R0`` from the sensor ``model`` or from the pairs
    ``A``, ``B``) and the sensor re-stamped for the change and segment tests
    (:func:`corrected_sensor`: the jumps, with the profile's drift where its step has one, or the
    model's drift where resolved). Returns ``(parts,
    jumps, profile, corrected or None)``."""
    from .changepoint import _fit

    parts, jumps = clock_segments(camera, oriented, max_offset=max_offset, seed=seed, offset_s=offset,
                                  gaps=jump_candidates(oriented.t, max_offset))
    if model is not None:
        R = model.R
    else:
        kron = np.einsum("jab,jcd->acbd", B, A).reshape(9, 9)
        R = _fit(kron[None], B.sum(axis=0)[None], np.array([float(len(A))]))[0][0]
    profile = offset_profile(camera, oriented, R, offset, sensor_stamps=sensor_stamps)
    jumps = merged_jumps(jumps, profile)
    drift = (model.drift_ppm, model.t_mid_s, model.offset_mid_s) if model is not None and model.drift_resolved else None
    if jumps:  # the model's drift was fitted without the steps: the profile's, where its step has one
        s = profile.step if profile is not None and profile.step_with_drift and profile.step in jumps else None
        drift = None if s is None else (profile.drift_ppm, s.time_s, s.offset_before_s)
    return parts, jumps, profile, corrected_sensor(oriented, offset, jumps=jumps, drift=drift)
