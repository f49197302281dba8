"""A mounting that creeps, seen by the online estimator: the slope of ``R0`` over the pairs since
its last start (:class:`CreepTest`), from running sums of the pairs weighted by their index, so that
``R0`` of the early and the late pairs since a re-mount are compared at every refinement at no cost
per pair beyond one more 9x9 sum. A slope beyond its noise puts the estimate's lag behind the
mounting now into the radius, and ``ready`` is withheld, naming the creep and its rate, while that
lag and the noise together reach the target. Theory and measured numbers: ``docs/judging.md``,
section ``replication.rig.online_creep``."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..core.so3 import matrix_from_rotation_vector
from ..core.stats import chi2_quantile
from .online_drift import DRIFT_COS, DRIFT_MAX_STEP_DEG, drift_lag_deg, drift_step, follow_drift

__all__ = ["CreepTest", "follow_creep", "CREEP_LEVEL", "CREEP_MIN_PAIRS", "CREEP_BLOCK", "CREEP_MAX_BLOCKS"]

_EYE = np.eye(3)
#: Level of the test that ``R0`` has a slope over the pairs since the last start (the statistic
#: ``v^T C_v^{-1} v`` of the slope ``v`` against the ``chi^2_3`` quantile). It runs at every
#: refinement (about 10 to 25 times per stretch, strongly correlated), so stricter than one test's
#: usual 0.99; a slope it misses moves the estimate by less than about 3.7 standard errors of the
#: slope over the stretch.
CREEP_LEVEL = 0.999
#: Fewest pairs since the last start before a slope is tested (the slope needs many pairs more than
#: the rotation).
CREEP_MIN_PAIRS = 40
#: The pairs since the last start are also summed in blocks of this many (doubled whenever there
#: would be more than :data:`CREEP_MAX_BLOCKS`), so that, at a re-mount, a step of ``R0`` can be
#: told from a creep: the best single step and the best creep (a ramp from some block on, flat
#: before) are fitted to the blocks and the closer fit names the cause
#: (:meth:`CreepTest.continues`).
CREEP_BLOCK = 10
CREEP_MAX_BLOCKS = 256


def _vec(X) -> np.ndarray:
    return X.T.reshape(9)


def _rotated_bases(R) -> np.ndarray:
    """``vec(R [e_k]x)`` for ``k = 0, 1, 2`` (3, 9)."""
    out = np.empty((3, 9))
    for k in range(3):
        E = np.zeros((3, 3))
        i, j = (k + 1) % 3, (k + 2) % 3
        E[j, i], E[i, j] = 1.0, -1.0   # [e_k]x
        out[k] = _vec(R @ E)
    return out


def _gradient(M, R) -> np.ndarray:
    """``sum_j (I - B_j^T) r_j`` at ``R`` for the pairs in ``M = sum_j c_j B_j kron A_j`` (``r_j``
    the vee of the antisymmetric part of ``R^T A_j R B_j^T``, weighted by ``c_j``): the gradient of
    ``x^T M x`` along ``R exp([e_k]x)``."""
    x = _vec(R)
    return 0.5 * _rotated_bases(R) @ ((M + M.T) @ x)


def _best_fit(f, H, g):
    """The largest decrease of the Gauss-Newton cost over the models ``w_b = w0 + f[k, b] u`` (one
    per row ``k`` of ``f``; blocks' ``H_b`` (K, 3, 3) and ``g_b`` (K, 3)), ``max_k rhs^T N^{-1}
    rhs``, with its ``k`` and ``(w0, u)``; ``(nan, None, None)`` where none is finite."""
    fH = np.einsum("kb,bij->kij", f, H)
    N = np.empty((len(f), 6, 6))
    N[:, :3, :3] = H.sum(axis=0)
    N[:, :3, 3:] = N[:, 3:, :3] = fH
    N[:, 3:, 3:] = np.einsum("kb,bij->kij", f * f, H)
    rhs = np.concatenate([np.broadcast_to(g.sum(axis=0), (len(f), 3)), f @ g], axis=1)
    with np.errstate(all="ignore"):
        try:
            x = np.linalg.solve(N, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return math.nan, None, None
    red = np.einsum("ka,ka->k", rhs, x)
    if not np.isfinite(red).any():
        return math.nan, None, None
    k = int(np.nanargmax(np.where(np.isfinite(red), red, np.nan)))
    return float(red[k]), k, x[k]


class CreepTest:
    """Running sums of the pairs since the last start weighted by their index ``tau`` (counted from
    the start), and the slope of ``R0`` over them (one Gauss-Newton step of the model ``R exp([w0 +
    (tau - c) v]x)``, ``c`` the pairs' mean index). Valid with full memory only: forgetting (a drift
    followed) makes it :attr:`valid` False until the next start."""

    def __init__(self, level: float = CREEP_LEVEL):
        self.level, self.threshold = level, chi2_quantile(level, 3)
        self.reset(0)

    def reset(self, origin: int) -> None:
        """Forget every pair; the next ones are counted from pair ``origin``."""
        self.origin, self.valid = origin, True
        self._St = np.zeros((9, 9))                    # sum tau_j B_j kron A_j
        self._SBt, self._SBt2 = np.zeros((3, 3)), np.zeros((3, 3))  # sums of tau_j B_j and tau_j^2 B_j
        self._n, self._t, self._t2 = 0, 0.0, 0.0       # pairs, sums of tau_j and tau_j^2
        self.found = None   # (rate_deg_per_pair, lag_deg, statistic, pairs, axis) of the last significant slope
        self._history = []  # (latest pair, found) of every test since the start
        self._size = CREEP_BLOCK
        self._bS, self._bB = np.zeros((CREEP_MAX_BLOCKS, 9, 9)), np.zeros((CREEP_MAX_BLOCKS, 3, 3))
        self._bn, self._bt = np.zeros(CREEP_MAX_BLOCKS), np.zeros(CREEP_MAX_BLOCKS)  # pairs, sum of tau

    def add(self, T, A, B, full_memory: bool) -> None:
        """Pairs ``(A, B)`` with indices ``T`` (over the calibrator's life), just added with weight
        1 (else, with ``full_memory`` False, the test is off until the next start)."""
        if not full_memory:
            self.valid = False
        if not self.valid:
            return
        tau = np.maximum(np.asarray(T, dtype=float) - self.origin, 0.0)  # a restart's kept pairs: 0
        M = np.einsum("iab,icd->iacbd", B, A).reshape(len(tau), 81)   # each pair's B_j kron A_j
        Bf = B.reshape(len(tau), 9)
        self._St += (tau @ M).reshape(9, 9)
        self._SBt += (tau @ Bf).reshape(3, 3)
        self._SBt2 += ((tau * tau) @ Bf).reshape(3, 3)
        self._n += len(tau)
        self._t += float(tau.sum())
        self._t2 += float(tau @ tau)
        while tau.max() >= self._size * CREEP_MAX_BLOCKS:  # merge neighbouring blocks: twice as long
            for a in (self._bS, self._bB, self._bn, self._bt):
                half = a.reshape((CREEP_MAX_BLOCKS // 2, 2) + a.shape[1:]).sum(axis=1)
                a[:] = 0.0
                a[:CREEP_MAX_BLOCKS // 2] = half
            self._size *= 2
        k = (tau // self._size).astype(int)
        if k[0] == k[-1]:  # the batch in one block (mostly): plain sums
            self._bS[k[0]] += M.sum(axis=0).reshape(9, 9)
            self._bB[k[0]] += B.sum(axis=0)
            self._bn[k[0]] += len(tau)
            self._bt[k[0]] += float(tau.sum())
        else:
            np.add.at(self._bS, k, M.reshape(-1, 9, 9))
            np.add.at(self._bB, k, B)
            np.add.at(self._bn, k, 1.0)
            np.add.at(self._bt, k, tau)

    def test(self, R, S, SB, s2: float, last: int, following: bool = False):
        """The slope at the estimate ``R`` (the minimiser over the pairs; ``S``, ``SB`` the
        calibrator's sums of ``B_j kron A_j`` and ``B_j``, ``s2`` its mean square residual angle);
        ``last`` the index of the latest pair. Sets and returns :attr:`found`: None, or
        ``(rate_deg_per_pair, lag_deg, statistic, pairs, axis)``, the lag being how far the mounting
        at the latest pair is from the estimate along the slope; ``following`` a drift (its memory
        cut), the test is off until the next start."""
        self.found = None
        self.valid = self.valid and not following
        n = self._n
        if not self.valid or n < CREEP_MIN_PAIRS:
            return None
        self._history.append((last, None))
        c = self._t / n
        spread = self._t2 - n * c * c                  # sum (tau - c)^2
        Bc = self._SBt - c * SB                        # sum (tau - c) B_j
        B2 = self._SBt2 - 2.0 * c * self._SBt + c * c * SB
        G = 2.0 * n * _EYE - SB - SB.T
        G1 = -Bc - Bc.T
        G2 = 2.0 * spread * _EYE - B2 - B2.T
        N = np.block([[G, G1], [G1, G2]])
        g = np.concatenate([_gradient(S, R), _gradient(self._St - c * S, R)])
        try:
            Ni = np.linalg.inv(N)
        except np.linalg.LinAlgError:
            return None
        x = Ni @ g
        w0, v = x[:3], x[3:]
        cov_v = (s2 / 3.0) * Ni[3:, 3:]
        try:
            stat = float(v @ np.linalg.solve(cov_v, v))
        except np.linalg.LinAlgError:
            return None
        if not (math.isfinite(stat) and stat > self.threshold):
            return None
        now = w0 + (last - self.origin - c) * v
        rate = float(np.linalg.norm(v))
        self.found = (math.degrees(rate), math.degrees(float(np.linalg.norm(now))), stat, n, v / rate)
        self._history[-1] = (last, self.found)
        return self.found

    def step_or_creep(self, R):
        """The Gauss-Newton cost decrease at ``R`` of the best single step of ``R0`` at a block
        boundary and of the best creep (a ramp from a block's centre on, flat before; from the first
        block: a steady creep), over the blocks since the start: ``(step, creep, fit)``, ``fit`` the
        creep's ``(start, w0, u)``: its first pair (since the start), ``R0`` before it ``R
        exp([w0]x)`` and its slope ``u`` per pair (rad), or None."""
        used = self._bn > 0
        n, t = self._bn[used], self._bt[used] / np.maximum(self._bn[used], 1.0)
        S, SB = self._bS[used], self._bB[used]
        x = _vec(R)
        g = 0.5 * np.einsum("ka,ba->bk", _rotated_bases(R), np.einsum("bij,j->bi", S + np.swapaxes(S, 1, 2), x))
        H = 2.0 * n[:, None, None] * _EYE - SB - np.swapaxes(SB, 1, 2)
        m = len(n)
        if m < 3:
            return math.nan, math.nan, None
        idx = np.arange(m)
        steps = (idx[None, :] >= idx[1:, None]).astype(float)            # a step before block k
        creeps = np.maximum(t[None, :] - t[:-1, None], 0.0)              # a ramp from block k's centre
        creep, k, x = _best_fit(creeps, H, g)
        return _best_fit(steps, H, g)[0], creep, None if x is None else (float(t[k]), x[:3], x[3:])

    def continues(self, event):
        """Whether the re-mount ``event`` (an :class:`replication.rig.online_events.OnlineEvent`)
        continues a creep: the last test before the change's onset found a slope, the event's step
        is small (:data:`replication.rig.online_drift.DRIFT_MAX_STEP_DEG`) and in the slope's
        direction (a cosine of at least :data:`replication.rig.online_drift.DRIFT_COS`), and the
        pairs since the start fit a creep better than a step (:meth:`step_or_creep` at the estimate
        before the event: a step found late also leaves a slope, but a step fits it better). Returns
        None or ``(rate_deg_per_pair, step_deg, first, axis, R_first)``: the best creep's rate, its
        first pair and ``R0`` there (:meth:`step_or_creep`)."""
        before = [found for last, found in self._history if last < event.onset_pair]
        if not self.valid or not before or before[-1] is None:
            return None
        step = drift_step(event.R_before, event.R_after)
        size = float(np.linalg.norm(step))
        as_step, as_creep, fit = self.step_or_creep(event.R_before)
        if not size or math.degrees(size) > DRIFT_MAX_STEP_DEG or not as_creep > as_step or fit is None:
            return None
        begin, w0, u = fit   # the creep from its start on (a creep that began after the start: later, faster)
        rate = float(np.linalg.norm(u))
        if not rate or float(step @ u) / (size * rate) < DRIFT_COS:
            return None
        start = event.R_before @ matrix_from_rotation_vector(w0)
        return math.degrees(rate), math.degrees(size), self.origin + int(round(begin)), u / rate, start

    def describe(self, target_deg: float) -> str:
        """The sentence for ``not_ready`` while :attr:`found` is set."""
        rate, lag, stat, n, _ = self.found
        return (f"the mounting creeps (or a change not decided yet): R0 of the {n} pairs since pair {self.origin} "
                f"moves {rate:.3g} deg per pair "
                f"(statistic {stat:.3g} > {self.threshold:.3g}, the {100 * self.level:g} % region of its slope), "
                f"the mounting now {lag:.3g} deg from the estimate; radius and lag together not below the target "
                f"{target_deg:g} deg")


def follow_creep(cal, event, creep):
    """A re-mount that continues a creep (:meth:`CreepTest.continues`) in the calibrator ``cal``:
    one ``drift`` event from the creep's start, followed
    (:func:`replication.rig.online_drift.follow_drift`), no restart. Returns the event."""
    rate, step, origin, axis, start = creep
    began = dataclasses.replace(event, pair=origin, source="creep", R_before=start, R_after=start)  # its start
    cal._last_step = (event.pair, event.R_after, began)
    out = follow_drift(cal, event, rate, step, origin, axis)
    lag = drift_lag_deg(rate, cal.forgetting, cal.refine_every)
    return dataclasses.replace(out, message=(
        f"the frame drifts: R0 crept {rate:.3g} deg per pair over the pairs since pair {origin} (a "
        f"slope found before this change began at pair {event.onset_pair}, fitted better by a creep "
        f"than by a step), then moved {step:.3g} deg in that direction: one drift, followed, no "
        f"restart: forgetting {cal.forgetting:.4g}, lag {lag:.3g} deg added to the radius"
        + ("" if lag < cal.target_deg else f"; too fast to follow within {cal.target_deg:g} deg")))
