"""The numerical core of the gyro's sensor model (:mod:`replication.rig.sensor_model`): the rates
integrated with their Jacobians' sums, the pairs inside the gyro stream, the pair residuals and
their Jacobian in the eleven parameters ``(theta, b, d, k, sigma, mu)``, Huber's weights, the
Newey-West sandwich, the block jackknife, the weighted Gauss-Newton, and the critical value of its
intervals (:func:`critical_value`).

The rates used are ``T^-1 (omega - b)``, ``T = diag(exp(sigma)) + N(mu)`` the gyro's axes (it reads
``T omega + b``: Kalibr's and OpenVINS's ``T_g``), ``s = exp(sigma)`` the scale per axis and
``N(mu)`` the symmetric off-diagonal part, ``mu = (xy, xz, yz)`` (the misalignment: the
antisymmetric part of ``T_g`` is a rotation of the sensor's frame, which ``R0`` absorbs, so only the
symmetric part is identifiable), so that with ``R0 <- R0 exp(theta)``:

* ``d r / d b = M_j^T J_j T^-1`` with ``J_j = -Q(t_k)^T sum_s Q_{s+1} dt_s`` (the first-order bias
  Jacobian),
* ``d r / d (sigma, mu) = -M_j^T Q(t_k)^T sum_s Q_{s+1} T^-1 D(w_s) dt_s`` (``w_s`` the step's rate
  as used: a change ``dT`` of the axes changes each step's rate by ``-T^-1 dT w_s``; ``D(w) =
  [diag(s w), (w_y, w_x, 0), (w_z, 0, w_x), (0, w_z, w_y)]``, the columns of ``dT w`` per
  parameter).
"""
from __future__ import annotations

import numpy as np

from ..core.so3 import cumulative_product, matrix_from_rotation_vector, rotation_vector_from_matrix

__all__ = ["critical_value", "N_PARAMETERS", "MISALIGNMENT_AXES", "axes_matrix"]

#: theta (3), b (3), d, k, sigma (3), mu (3: xy, xz, yz).
N_PARAMETERS = 14
#: The pairs of axes of ``mu``.
MISALIGNMENT_AXES = ((0, 1), (0, 2), (1, 2))
_HUBER = 2.5
_Z95 = 1.959963984540054


def critical_value(n_blocks: int) -> float:
    """The two-sided 95 % critical value of a parameter over its jackknife standard deviation from
    ``n_blocks`` blocks: Student's t with ``n_blocks - 1`` degrees of freedom (2.45 at 7 blocks, a
    15 s recording; 2.10 at 19, 40 s; 2.05 at 29, 60 s): the variance is itself estimated from that
    many blocks."""
    from scipy.stats import t

    return float(t.ppf(0.975, max(1, int(n_blocks) - 1)))


def axes_matrix(sigma, mu) -> np.ndarray:
    """``T = diag(exp(sigma)) + N(mu)``: the gyro reads ``T omega + b`` (``mu`` the symmetric
    off-diagonal terms ``xy, xz, yz``)."""
    T = np.diag(np.exp(np.asarray(sigma, float)))
    for m, (a, c) in zip(np.asarray(mu, float), MISALIGNMENT_AXES):
        T[a, c] = T[c, a] = m
    return T


def _integrate(t, w, b, sigma, mu=None):
    """``Q`` (world_from_body, ``Q_0 = I``) of the rates ``T^-1 (w - b)`` (trapezoidal, as
    :func:`replication.rig.streams.integrate_gyro`), ``S_n = sum_{s<n} Q_{s+1} dt_s`` (the bias
    Jacobian's sums), ``U_n = sum_{s<n} Q_{s+1} T^-1 D(w_s) dt_s`` (the axes' six: scale and
    misalignment), the steps' rates ``w_s`` and ``T^-1``."""
    dt = np.diff(t)
    if np.max(np.abs(sigma)) > 30.0:  # a scale of 1e13: no gyro (and exp overflows further on)
        raise np.linalg.LinAlgError("the gyro's axes' matrix is out of range")
    T = axes_matrix(sigma, np.zeros(3) if mu is None else mu)
    if not np.linalg.cond(T) < 1e12:
        raise np.linalg.LinAlgError("the gyro's axes' matrix is singular")
    Ti = np.linalg.inv(T)
    rates = (0.5 * (w[:-1] + w[1:]) - b) @ Ti.T
    Q = np.concatenate([np.eye(3)[None], cumulative_product(matrix_from_rotation_vector(rates * dt[:, None]))])
    Qdt = Q[1:] * dt[:, None, None]
    zero = np.zeros((1, 3, 6))
    S = np.concatenate([zero[:, :, :3], np.cumsum(Qdt, axis=0)])
    D = np.zeros((len(rates), 3, 6))
    D[:, [0, 1, 2], [0, 1, 2]] = rates * np.diag(T)
    for j, (a, c) in enumerate(MISALIGNMENT_AXES):
        D[:, a, 3 + j], D[:, c, 3 + j] = rates[:, c], rates[:, a]
    U = np.concatenate([zero, np.cumsum((Qdt @ Ti) @ D, axis=0)])
    return Q, S, U, rates, Ti


def _at(times, t, Q, S, U, rates):
    """``Q``, ``S``, ``U`` and the rate at ``times`` inside ``t``: ``Q_n exp(rate_n (tau - t_n))``
    (the geodesic between the samples, i.e. their slerp), ``S`` and ``U`` linearly, the step's
    rate."""
    n = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = times - t[n]
    f = (h / (t[n + 1] - t[n]))[:, None, None]
    Qh = Q[n] @ matrix_from_rotation_vector(rates[n] * h[:, None])
    return Qh, S[n] + (S[n + 1] - S[n]) * f, U[n] + (U[n + 1] - U[n]) * f, rates[n]


def _pairs(camera, t_gyro, interval, offset, max_offset):
    """Camera index pairs ``(i, k)`` about ``interval`` apart whose sensor times (shifted by up to
    ``max_offset`` besides ``offset``) stay inside the gyro stream and cross none of its gaps (5
    median steps without a sample)."""
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


def _linearise(X, b, d, kappa, A, ti, tk, t_mid, t_g, w_g, sigma=None, mu=None):
    """Residuals ``(J, 3)`` and Jacobians ``(J, 3, 14)`` (theta, b, d, k, sigma, mu) of the pairs at
    the parameters (``sigma`` the log-scales and ``mu`` the misalignment, 0 by default)."""
    sigma = np.zeros(3) if sigma is None else np.asarray(sigma, float)
    Q, S, U, rates, Ti = _integrate(t_g, w_g, b, sigma, mu)
    si, sk = ti + d + kappa * (ti - t_mid), tk + d + kappa * (tk - t_mid)
    (Qi, Si, Ui, wi), (Qk, Sk, Uk, wk) = _at(si, t_g, Q, S, U, rates), _at(sk, t_g, Q, S, U, rates)
    Delta = np.swapaxes(Qi, -1, -2) @ Qk
    QkT = np.swapaxes(Qk, -1, -2)
    M = X.T @ A @ X
    r = rotation_vector_from_matrix(Delta @ M)
    Mt = np.swapaxes(M, -1, -2)
    wi_in_k = np.einsum("jba,jb->ja", Delta, wi)  # Delta^T omega_i
    jac = np.empty((len(A), 3, N_PARAMETERS))
    jac[:, :, :3] = np.eye(3) - Delta
    jac[:, :, 3:6] = -(Mt @ QkT @ (Sk - Si)) @ Ti
    jac[:, :, 6] = np.einsum("jab,jb->ja", Mt, wk - wi_in_k)
    jac[:, :, 7] = np.einsum("jab,jb->ja", Mt, wk * (tk - t_mid)[:, None] - wi_in_k * (ti - t_mid)[:, None])
    jac[:, :, 8:] = -(Mt @ QkT @ (Uk - Ui))
    return r, jac


def _weights(r):
    """Huber weights of the pairs' residual norms: 1 up to :data:`_HUBER` times their median (3.8
    standard deviations of a component for Gaussian residuals), then falling as 1 / norm."""
    n = np.linalg.norm(r, axis=-1)
    c = _HUBER * np.median(n) + 1e-15  # the norm's median is 1.54 standard deviations of a component
    return np.where(n <= c, 1.0, c / np.maximum(n, 1e-300))


def _sandwich(r, jac, wts, lags, cols):
    """The Newey-West sandwich covariance of the parameters ``cols`` (Bartlett weights, ``lags``
    pairs)."""
    Jc = jac[:, :, cols]
    H = np.einsum("j,jai,jak->ik", wts, Jc, Jc)
    g = np.einsum("j,jai,ja->ji", wts, Jc, r)
    S = g.T @ g
    for lag in range(1, min(lags, len(g) - 1) + 1):
        G = g[lag:].T @ g[:-lag]
        S += (1.0 - lag / (lags + 1.0)) * (G + G.T)
    Hi = np.linalg.pinv(H)
    return Hi @ S @ Hi


def _block_jackknife(r, jac, wts, block, cols):
    """The delete-a-block jackknife covariance of the parameters ``cols`` and its number of blocks:
    the pairs cut into consecutive blocks of ``block`` pairs, each block's removal re-fitted by one
    Gauss-Newton step from the solution (``(H - H_B)^-1 g_B``), the spread of the re-fits times ``(m
    - 1) / m``. Unlike the sandwich, whose residuals are those of the fit, it sees how much each
    block pulls the fit (its leverage): the drift is a slope carried by the blocks at the
    recording's ends, which the fit follows, so the sandwich's residuals there are too small; with
    few blocks the sandwich's drift deviation was 1.7 times too small (15 s: 7 blocks), 1.3 times at
    40 s (19 blocks)."""
    Jc = jac[:, :, cols]
    Hj = np.einsum("j,jai,jak->jik", wts, Jc, Jc)
    g = np.einsum("j,jai,ja->ji", wts, Jc, r)
    H, total = Hj.sum(axis=0), g.sum(axis=0)
    m = max(2, len(r) // max(1, block))
    edges = np.linspace(0, len(r), m + 1).astype(int)
    deltas = []
    for a, z in zip(edges[:-1], edges[1:]):
        gB = g[a:z].sum(axis=0) - total * (z - a) / len(r)  # the solution's gradient is 0 up to its tolerance
        deltas.append(np.linalg.lstsq(H - Hj[a:z].sum(axis=0), gB, rcond=None)[0])
    d = np.array(deltas)
    d -= d.mean(axis=0)
    return (m - 1.0) / m * (d.T @ d), m


def _gauss_newton(X, b, d, kappa, A, ti, tk, t_mid, t_g, w_g, cols, iterations=8, sigma=None, mu=None):
    """Weighted Gauss-Newton on the parameters ``cols`` (indices into theta, b, d, k, sigma, mu),
    step halving on the cost (at most 3 halvings); stops when a step lowers the cost by less than
    1e-8 of it. Returns the parameters ``[X, b, d, k, sigma, mu]``, the residuals, the Jacobians,
    the weights and the iterations done."""
    params = [X, np.array(b, float), float(d), float(kappa), np.zeros(3) if sigma is None else np.array(sigma, float),
              np.zeros(3) if mu is None else np.array(mu, float)]

    def unpack(p, step):
        X, b, d, k, s, m = p
        full = np.zeros(N_PARAMETERS)
        full[cols] = step
        return [X @ matrix_from_rotation_vector(full[:3]), b + full[3:6], d + full[6], k + full[7], s + full[8:11],
                m + full[11:]]

    def linearise(p):
        return _linearise(*p[:4], A, ti, tk, t_mid, t_g, w_g, p[4], p[5])

    r, jac = linearise(params)
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
            try:
                r2, jac2 = linearise(trial)
                new = float(np.sum(wts * np.sum(r2 * r2, axis=-1)))
            except np.linalg.LinAlgError:  # the step made the axes' matrix singular: halved as a costlier one
                new = np.inf
            if new <= cost:
                break
            step = 0.5 * step
        else:
            break
        params, r, jac = trial, r2, jac2
        if cost - new <= 1e-8 * cost:
            break
    return params, r, jac, _weights(r), done



def _held_account(r, jac, wts, block, cols, held):
    """What the parameters ``held`` (indices, held at their nominal value) leave unknown, from the
    joint fit of ``cols`` and ``held``: one Gauss-Newton step from the solution (``step``, the
    parameters of ``cols`` then of ``held``: the estimates had all been fitted), their joint
    block-jackknife covariance (same order) and how each held one moves the free ones with them
    re-fitted (``moves``, ``(len(cols), len(held))``: ``-H_FF^-1 H_FH``)."""
    both = np.concatenate([cols, held])
    Jc = jac[:, :, both]
    H = np.einsum("j,jai,jak->ik", wts, Jc, Jc)
    g = np.einsum("j,jai,ja->i", wts, Jc, r)
    step = -np.linalg.lstsq(H, g, rcond=None)[0]
    n = len(cols)
    moves = -np.linalg.lstsq(H[:n, :n], H[:n, n:], rcond=None)[0]
    return step, _block_jackknife(r, jac, wts, block, both)[0], moves
