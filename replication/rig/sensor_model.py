"""A raw gyro's bias and the sensor clock's drift, estimated with ``R0`` (issue 34, points 1 and 3's drift half).

A raw gyro reports ``omega + b``: integrated over a pairing interval ``T`` its bias turns every sensor motion by
about ``|b| T``, which ``A_j R0 = R0 B_j`` cannot absorb. :func:`estimate_sensor_model` refines ``(R0, b)``, the clock
offset ``d`` and its drift ``k`` (the sensor sample stamped ``t + d + k (t - t_mid)`` matches the camera sample
stamped ``t``) jointly, by Gauss-Newton on the pair residuals ``r_j = log(Delta_j R0^T A_j R0)`` (``Delta_j = B_j^T``,
the sensor's relative rotation integrated from ``omega - b``), with

* ``d r / d theta = I - Delta_j`` (``R0 <- R0 exp(theta)``),
* ``d r / d b = M_j^T J_j`` with ``M_j = R0^T A_j R0`` and the first-order bias Jacobian of the integrated
  rotation ``J_j = -Q(t_k)^T sum_s Q_{s+1} dt_s`` over the gyro steps of the pair (``Q`` the integrated
  ``world_from_body``; the steps' right Jacobians are taken as ``I``: a step turns by ``|omega| dt``, 0.005 rad at
  1 rad/s and 200 Hz),
* ``d r / d d = M_j^T (omega_k - Delta_j^T omega_i)`` and ``d r / d k`` the same with ``omega_k (t_k - t_mid)``
  and ``omega_i (t_i - t_mid)``.

The start needs no bias: the candidates are zero, the mean rate (the rates centred) and, where the gyro rests
(:func:`rest_periods`), the mean rate at rest; each is integrated, paired and solved by ``chordal_optimal``, and the
one whose pairs fit best (median residual) starts the iteration. A rest period is used where present, never
required. Pairs are weighted by Huber's rule (at 2.5 robust standard deviations) so that a few badly tracked
camera poses do not pull the bias.

Intervals: overlapping pairs share noise (a camera pose, a stretch of gyro samples), so the covariance is the
sandwich ``H^-1 S H^-1`` with ``S`` the Newey-West (Bartlett) sum of the per-pair gradients ``J_j^T w_j r_j`` over
lags up to two pairing intervals; the 95 % intervals are +-1.96 standard deviations, inflated by
:data:`INTERVAL_INFLATION` (their coverage is measured in ``benchmarks/bench_sensor_model.py``). The bias of each
half of the recording is estimated the same way (the other parameters held; one linearised step from the whole's
solution): halves that differ beyond their noise (a chi-square test at level :data:`BIAS_CHANGE_LEVEL`) mean the
bias drifts (with temperature) and one bias does not describe the recording. The bias absorbs a slow turn of the
camera trajectory's frame (a SLAM's rotation drift), which every pair sees the same way.

The verdict's reasons and what :func:`replication.rig.calibration.calibrate` does with the model:
:mod:`replication.rig.sensor_verdict`. Conventions: ``docs/conventions.md``.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..core.so3 import cumulative_product, matrix_from_rotation_vector, rotation_vector_from_matrix
from .streams import GyroStream, OrientationStream

__all__ = ["SensorModel", "estimate_sensor_model", "rest_periods", "BIAS_CHANGE_LEVEL", "MIN_CORRELATION",
           "MAX_FIT_RATIO", "INTERVAL_INFLATION"]

#: The level of the test of the two halves' biases (chi-square, 3 degrees of freedom).
BIAS_CHANGE_LEVEL = 0.01
_CHI2_3 = {0.01: 11.344866730144373}
#: A rest: at least this long (s) with the rates' spread (norm of the per-axis standard deviations) below
#: :data:`REST_SPREAD_RAD_S` and their mean below :data:`REST_MEAN_RAD_S` (a gyro's bias is well below it) in every
#: window of :data:`REST_WINDOW_S`.
REST_MIN_S, REST_SPREAD_RAD_S, REST_MEAN_RAD_S, REST_WINDOW_S = 1.0, 0.02, 0.3, 0.25
#: The sensor model is not estimated where the angular speeds correlate less (the verdict's fail bound): the streams
#: do not show one motion. Its reasons are not given where its pairs fit worse than :data:`MAX_FIT_RATIO` of the
#: median motion (the residual check's fail bound): its numbers then describe no rig.
MIN_CORRELATION, MAX_FIT_RATIO = 0.5, 0.3
_HUBER = 2.5
_Z95 = 1.959963984540054
#: The sandwich's standard deviations are multiplied by this. Without it the 95 % bias intervals held the truth on
#: 550 of 600 axes (0.917 [0.892, 0.936], seeds [3400, 0, k]) and 560 of 600 on fresh seeds (0.933 [0.910, 0.951],
#: [3401, 0, k]); a moving-block bootstrap of the linearised step did no better (0.92 on 40 runs), nor did other
#: Bartlett bandwidths: the estimate varies about 1.13 times more than the pairs' residuals say, on synthetic rigs
#: (``benchmarks/bench_sensor_model.py``; coverage with it: environment.md).
INTERVAL_INFLATION = 1.2


@dataclass(frozen=True, eq=False)
class SensorModel:
    """The gyro's bias and the sensor clock's drift, estimated with ``R0`` (:func:`estimate_sensor_model`).

    Attributes
    ----------
    bias_rad_s : ndarray (3,)
        The gyro's bias ``b`` (rad/s, sensor frame): the rates are ``omega - b``.
    bias_ci95_rad_s : ndarray (3, 2)
        Its 95 % interval per axis.
    drift_ppm, drift_ci95_ppm : float, (float, float)
        The clock drift ``k`` (1e-6 s per s) and its 95 % interval.
    offset_mid_s, t_mid_s : float
        The offset ``d`` at ``t_mid`` (camera time, s) of the model ``d + k (t - t_mid)``.
    R : ndarray (3, 3)
        ``R0`` of the joint refinement.
    start : str
        Where the iteration started (``"zero"``, ``"centred rates"``, ``"rest 12.0-14.5 s"``).
    halves_rad_s, halves_ci95_rad_s : ndarray (2, 3), (2, 3, 2)
        The bias of the first and of the second half of the pairs, each with its interval.
    change_statistic, change_threshold : float
        The chi-square statistic of the halves' difference and its bound at :data:`BIAS_CHANGE_LEVEL`.
    bias_R0_deg : float
        How far ``R0`` moves (deg) when the bias is left in the rates (first order: ``R0``'s rows of the normal
        equations re-fit with the bias at 0).
    change_R0_deg : float
        How far ``R0`` moves (deg) when the bias is off by half the halves' difference.
    fit_ratio : float
        The refined pairs' median residual over their median motion.
    n_pairs, iterations : int
    span_s : float
        The pairs' span (s, camera time).
    applied : bool
        Whether the bias was removed from the rates before the calibration (False: measured only).
    """

    bias_rad_s: np.ndarray
    bias_ci95_rad_s: np.ndarray
    drift_ppm: float
    drift_ci95_ppm: tuple
    offset_mid_s: float
    t_mid_s: float
    R: np.ndarray
    start: str
    halves_rad_s: np.ndarray
    halves_ci95_rad_s: np.ndarray
    change_statistic: float
    change_threshold: float
    n_pairs: int
    iterations: int
    span_s: float
    applied: bool = True
    covariance: np.ndarray = field(default=None, repr=False)
    bias_R0_deg: float = math.nan
    change_R0_deg: float = math.nan
    fit_ratio: float = math.nan

    @property
    def bias_changes(self) -> bool:
        """The halves' biases differ beyond their noise (the chi-square test at :data:`BIAS_CHANGE_LEVEL`)."""
        return bool(self.change_statistic > self.change_threshold)

    @property
    def drift_resolved(self) -> bool:
        """The drift's 95 % interval excludes 0."""
        lo, hi = self.drift_ci95_ppm
        return bool(lo > 0 or hi < 0)

    def corrected(self, gyro: GyroStream) -> GyroStream:
        """``gyro`` with the bias removed from its rates (times unchanged)."""
        return GyroStream(gyro.t, gyro.omega - self.bias_rad_s, gyro.source)

    def report(self) -> dict:
        """The report's fields (``gyro_bias_rad_s``, ``gyro_bias_ci95_rad_s``, ``clock_drift_ppm``,
        ``clock_drift_ci95_ppm``) and the model's details under ``sensor_model``."""
        return {
            "gyro_bias_rad_s": self.bias_rad_s.tolist(),
            "gyro_bias_ci95_rad_s": self.bias_ci95_rad_s.tolist(),
            "clock_drift_ppm": float(self.drift_ppm),
            "clock_drift_ci95_ppm": [float(v) for v in self.drift_ci95_ppm],
            "sensor_model": {
                "bias_applied": bool(self.applied), "start": self.start, "n_pairs": int(self.n_pairs),
                "iterations": int(self.iterations), "span_s": float(self.span_s),
                "offset_mid_s": float(self.offset_mid_s), "t_mid_s": float(self.t_mid_s),
                "bias_halves_rad_s": self.halves_rad_s.tolist(),
                "bias_halves_ci95_rad_s": self.halves_ci95_rad_s.tolist(),
                "bias_change_statistic": float(self.change_statistic),
                "bias_change_threshold": float(self.change_threshold), "bias_change_level": BIAS_CHANGE_LEVEL,
                "bias_changes": self.bias_changes, "drift_resolved": self.drift_resolved,
                "bias_R0_deg": float(self.bias_R0_deg), "bias_change_R0_deg": float(self.change_R0_deg),
                "fit_ratio": float(self.fit_ratio),
            },
        }


def rest_periods(gyro: GyroStream, *, min_s: float = REST_MIN_S) -> list:
    """``(start, end)`` (s) of the stretches of at least ``min_s`` where the gyro rests: in every window of
    :data:`REST_WINDOW_S` the rates' spread is below :data:`REST_SPREAD_RAD_S` and their mean below
    :data:`REST_MEAN_RAD_S`."""
    t, w = gyro.t, gyro.omega
    n = max(2, int(round(REST_WINDOW_S / np.median(np.diff(t)))))
    k = len(t) // n
    if k < 2:
        return []
    win = w[:k * n].reshape(k, n, 3)
    quiet = (np.linalg.norm(win.std(axis=1), axis=-1) < REST_SPREAD_RAD_S) & (
        np.linalg.norm(win.mean(axis=1), axis=-1) < REST_MEAN_RAD_S)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], quiet.astype(int), [0]])))  # starts and ends of quiet runs
    spans = [(t[i * n], t[min(j * n, len(t)) - 1]) for i, j in edges.reshape(-1, 2)]
    return [(float(a), float(z)) for a, z in spans if z - a >= min_s - 1e-9]


def _integrate(t, w, b):
    """``Q`` (world_from_body, ``Q_0 = I``) of the rates ``w - b`` (trapezoidal, as
    :func:`replication.rig.streams.integrate_gyro`), ``S_n = sum_{s<n} Q_{s+1} dt_s`` (the bias Jacobian's sums) and
    the steps' rates."""
    dt = np.diff(t)
    rates = 0.5 * (w[:-1] + w[1:]) - b
    Q = np.concatenate([np.eye(3)[None], cumulative_product(matrix_from_rotation_vector(rates * dt[:, None]))])
    S = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(Q[1:] * dt[:, None, None], axis=0)])
    return Q, S, rates


def _at(times, t, Q, S, rates):
    """``Q``, ``S`` and the rate at ``times`` inside ``t``: ``Q_n exp(rate_n (tau - t_n))`` (the geodesic between the
    samples, i.e. their slerp), ``S`` linearly, the step's rate."""
    n = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = times - t[n]
    return (Q[n] @ matrix_from_rotation_vector(rates[n] * h[:, None]),
            S[n] + (S[n + 1] - S[n]) * (h / (t[n + 1] - t[n]))[:, None, None],
            rates[n])


def _pairs(camera, t_gyro, interval, offset, max_offset):
    """Camera index pairs ``(i, k)`` about ``interval`` apart whose sensor times (shifted by up to ``max_offset``
    besides ``offset``) stay inside the gyro stream and cross none of its gaps (5 median steps without a sample)."""
    t = camera.t
    margin = abs(offset) + max_offset
    inside = np.flatnonzero((t - margin >= t_gyro[0]) & (t + margin <= t_gyro[-1]))
    if len(inside) < 2:
        return np.empty(0, int), np.empty(0, int)
    tt = t[inside]
    j = np.clip(np.searchsorted(tt, tt + interval), 1, len(tt) - 1)
    j = np.where(np.abs(tt[j - 1] - tt - interval) < np.abs(tt[j] - tt - interval), j - 1, j)
    tol = 0.5 * np.median(np.diff(tt)) if len(tt) > 1 else 0.0
    ok = (np.abs(tt[j] - tt - interval) <= tol) & (j > np.arange(len(tt)))
    i, k = inside[ok], inside[j[ok]]
    dt = np.diff(t_gyro)
    gaps = np.flatnonzero(dt > 5.0 * np.median(dt))
    if len(gaps):
        g0, g1 = t_gyro[gaps], t_gyro[gaps + 1]
        cross = ((t[i, None] + offset - max_offset < g1) & (t[k, None] + offset + max_offset > g0)).any(axis=1)
        i, k = i[~cross], k[~cross]
    return i, k


def _linearise(X, b, d, kappa, A, ti, tk, t_mid, t_g, w_g):
    """Residuals ``(J, 3)`` and Jacobians ``(J, 3, 8)`` (theta, b, d, k) of the pairs at the parameters."""
    Q, S, rates = _integrate(t_g, w_g, b)
    si, sk = ti + d + kappa * (ti - t_mid), tk + d + kappa * (tk - t_mid)
    (Qi, Si, wi), (Qk, Sk, wk) = _at(si, t_g, Q, S, rates), _at(sk, t_g, Q, S, rates)
    Delta = np.swapaxes(Qi, -1, -2) @ Qk
    Jb = -np.swapaxes(Qk, -1, -2) @ (Sk - Si)
    M = X.T @ A @ X
    r = rotation_vector_from_matrix(Delta @ M)
    Mt = np.swapaxes(M, -1, -2)
    wi_in_k = np.einsum("jba,jb->ja", Delta, wi)  # Delta^T omega_i
    jac = np.empty((len(A), 3, 8))
    jac[:, :, :3] = np.eye(3) - Delta
    jac[:, :, 3:6] = Mt @ Jb
    jac[:, :, 6] = np.einsum("jab,jb->ja", Mt, wk - wi_in_k)
    jac[:, :, 7] = np.einsum("jab,jb->ja", Mt, wk * (tk - t_mid)[:, None] - wi_in_k * (ti - t_mid)[:, None])
    return r, jac


def _weights(r):
    """Huber weights of the pairs' residual norms: 1 up to :data:`_HUBER` times their median (3.8 standard
    deviations of a component for Gaussian residuals), then falling as 1 / norm."""
    n = np.linalg.norm(r, axis=-1)
    c = _HUBER * np.median(n) + 1e-15  # the norm's median is 1.54 standard deviations of a component
    return np.where(n <= c, 1.0, c / np.maximum(n, 1e-300))


def _sandwich(r, jac, wts, lags, cols):
    """The Newey-West sandwich covariance of the parameters ``cols`` (Bartlett weights, ``lags`` pairs)."""
    Jc = jac[:, :, cols]
    H = np.einsum("j,jai,jak->ik", wts, Jc, Jc)
    g = np.einsum("j,jai,ja->ji", wts, Jc, r)
    S = g.T @ g
    for lag in range(1, min(lags, len(g) - 1) + 1):
        G = g[lag:].T @ g[:-lag]
        S += (1.0 - lag / (lags + 1.0)) * (G + G.T)
    Hi = np.linalg.pinv(H)
    return Hi @ S @ Hi


def _gauss_newton(X, b, d, kappa, A, ti, tk, t_mid, t_g, w_g, cols, iterations=8):
    """Weighted Gauss-Newton on the parameters ``cols`` (indices into theta, b, d, k), step halving on the cost
    (at most 3 halvings); stops when a step lowers the cost by less than 1e-8 of it."""
    params = [X, np.array(b, float), float(d), float(kappa)]

    def unpack(p, step):
        X, b, d, k = p
        full = np.zeros(8)
        full[cols] = step
        return [X @ matrix_from_rotation_vector(full[:3]), b + full[3:6], d + full[6], k + full[7]]

    r, jac = _linearise(*params, A, ti, tk, t_mid, t_g, w_g)
    done = 0
    for _ in range(iterations):
        done += 1
        wts = _weights(r)
        cost = float(np.sum(wts * np.sum(r * r, axis=-1)))
        Jc = jac[:, :, cols]
        H = np.einsum("j,jai,jak->ik", wts, Jc, Jc)
        g = np.einsum("j,jai,ja->i", wts, Jc, r)
        scale = np.sqrt(np.maximum(np.diag(H), 1e-300))
        step = -np.linalg.lstsq(H / np.outer(scale, scale), g / scale, rcond=None)[0] / scale
        for _ in range(4):
            trial = unpack(params, step)
            r2, jac2 = _linearise(*trial, A, ti, tk, t_mid, t_g, w_g)
            new = float(np.sum(wts * np.sum(r2 * r2, axis=-1)))
            if new <= cost:
                break
            step = 0.5 * step
        else:
            break
        params, r, jac = trial, r2, jac2
        if cost - new <= 1e-8 * cost:
            break
    return params, r, jac, _weights(r), done


def _start(camera, gyro, interval, max_offset):
    """The candidate starts and the one whose solved pairs fit best: ``(label, b0, offset, R0)``."""
    from ..core.handeye import pair_residual_deg
    from ..core.solvers import solve
    from .association import estimate_time_offset, motion_pairs
    from .streams import integrate_gyro

    w = gyro.omega
    candidates = [("zero", np.zeros(3)), ("centred rates", w.mean(axis=0))]
    rests = rest_periods(gyro)
    if rests:
        keep = np.zeros(len(gyro.t), bool)
        for a, z in rests:
            keep |= (gyro.t >= a) & (gyro.t <= z)
        label = "rest " + ", ".join(f"{a - camera.t[0]:.1f}-{z - camera.t[0]:.1f} s" for a, z in rests[:3])
        candidates.append((label, w[keep].mean(axis=0)))
    best = None
    try:  # the offset of the rates as recorded: a bias barely moves the angular speeds' correlation peak
        offset, corr = estimate_time_offset(camera, integrate_gyro(gyro), max_offset=max_offset)
    except ValueError as err:
        raise ValueError(f"no start for the gyro bias: {err}") from None
    if not corr >= MIN_CORRELATION:
        raise ValueError(f"the camera's and the gyro's angular speeds do not match (correlation {corr:.3g} < "
                         f"{MIN_CORRELATION:g}): no bias to estimate")
    for label, b0 in candidates:
        oriented = integrate_gyro(GyroStream(gyro.t, w - b0, gyro.source))
        try:
            A, B, _ = motion_pairs(camera, oriented, interval, offset=offset)
            with warnings.catch_warnings():  # a start: the refinement and the calibration judge the fit
                warnings.simplefilter("ignore")
                R = solve("chordal_optimal", A, B)
        except (ValueError, np.linalg.LinAlgError):
            continue
        cost = float(np.median(pair_residual_deg(R, A, B)))
        if best is None or cost < best[0]:
            best = (cost, label, b0, offset, R)
    if best is None:
        raise ValueError("no start for the gyro bias: no candidate bias gives pairs to solve")
    return best[1:]


def estimate_sensor_model(camera: OrientationStream, gyro: GyroStream, *, interval: float = 1.0,
                          max_offset: float = 0.2, lags: int | None = None, applied: bool = True) -> SensorModel:
    """The gyro's bias and the clock's drift with ``R0`` (see the module notes).

    Parameters
    ----------
    camera : OrientationStream
    gyro : GyroStream
        The raw rates (bias included).
    interval : float
        The pairing interval (s).
    max_offset : float
        The clock-offset search of the start (s).
    lags : int, optional
        Newey-West lags in pairs (default: two pairing intervals of camera samples).
    applied : bool
        Recorded in the result: whether the caller removes the bias.

    Raises
    ------
    ValueError
        Too few pairs (fewer than 20) to estimate eight parameters with an interval.
    """
    if not isinstance(camera, OrientationStream) or not isinstance(gyro, GyroStream):
        raise ValueError("the sensor model needs a camera OrientationStream and a GyroStream")
    label, b0, d0, R_start = _start(camera, gyro, interval, max_offset)
    ti_idx, tk_idx = _pairs(camera, gyro.t, interval, d0, max_offset)
    if len(ti_idx) < 20:
        raise ValueError(f"only {len(ti_idx)} pairs inside the gyro stream: too few to estimate the gyro bias")
    ti, tk = camera.t[ti_idx], camera.t[tk_idx]
    A = np.swapaxes(camera.R[tk_idx], -1, -2) @ camera.R[ti_idx]  # eq. (3): C_k C_t^T with C = Q^T
    t_mid = 0.5 * (ti[0] + tk[-1])
    lags = int(lags) if lags is not None else max(1, int(round(2 * interval / np.median(np.diff(camera.t)))))
    everything = np.arange(8)
    (X, b, d, kappa), r, jac, wts, its = _gauss_newton(R_start, b0, d0, 0.0, A, ti, tk, t_mid, gyro.t, gyro.omega,
                                                       everything)
    cov = INTERVAL_INFLATION ** 2 * _sandwich(r, jac, wts, lags, everything)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    halves, halves_cov = [], []
    mid = np.median(ti)
    for part in (ti <= mid, ti > mid):  # one Gauss-Newton step on the half's bias from the whole's solution
        jh, wh = jac[part][:, :, 3:6], wts[part]
        step = -np.linalg.solve(np.einsum("j,jai,jak->ik", wh, jh, jh), np.einsum("j,jai,ja->i", wh, jh, r[part]))
        halves.append(b + step)
        halves_cov.append(INTERVAL_INFLATION ** 2 * _sandwich(r[part] + jh @ step, jac[part], wh, lags,
                                                              np.arange(3, 6)))
    diff = halves[0] - halves[1]
    stat = float(diff @ np.linalg.pinv(halves_cov[0] + halves_cov[1]) @ diff)
    H = np.einsum("j,jai,jak->ik", wts, jac, jac)
    sensitivity = -np.linalg.solve(H[:3, :3], H[:3, 3:6])  # R0's rotation (rad) per bias change (rad/s), re-fit
    halves = np.array(halves)
    hsd = np.sqrt(np.maximum(np.array([np.diag(c) for c in halves_cov]), 0.0))
    return SensorModel(
        bias_rad_s=b, bias_ci95_rad_s=np.stack([b - _Z95 * sd[3:6], b + _Z95 * sd[3:6]], axis=-1),
        drift_ppm=1e6 * kappa, drift_ci95_ppm=(1e6 * (kappa - _Z95 * sd[7]), 1e6 * (kappa + _Z95 * sd[7])),
        offset_mid_s=float(d), t_mid_s=float(t_mid), R=X, start=label, halves_rad_s=halves,
        halves_ci95_rad_s=np.stack([halves - _Z95 * hsd, halves + _Z95 * hsd], axis=-1),
        change_statistic=stat, change_threshold=_CHI2_3[BIAS_CHANGE_LEVEL], n_pairs=len(A), iterations=its,
        span_s=float(tk[-1] - ti[0]), applied=applied, covariance=cov,
        bias_R0_deg=float(np.degrees(np.linalg.norm(sensitivity @ b))),
        change_R0_deg=float(np.degrees(np.linalg.norm(sensitivity @ (0.5 * diff)))),
        fit_ratio=float(np.median(np.linalg.norm(r, axis=-1))
                        / max(np.median(np.linalg.norm(rotation_vector_from_matrix(A), axis=-1)), 1e-12)))
