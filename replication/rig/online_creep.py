"""A mounting that creeps, seen by the online estimator: the slope of ``R0`` over the pairs since
its last start (:class:`CreepTest`), from running sums of the pairs weighted by their index, so that
``R0`` of the early and the late pairs since a re-mount are compared at every refinement at no cost
per pair beyond one more 9x9 sum. A slope beyond its noise puts the estimate's lag behind the
mounting now into the radius, and ``ready`` is withheld, naming the creep and its rate, while that
lag and the noise together reach the target. Theory and measured numbers: ``docs/judging.md``,
section ``replication.rig.online_creep``."""
from __future__ import annotations

import math

import numpy as np

from ..core.stats import _normal_quantile

__all__ = ["CreepTest", "CREEP_LEVEL", "CREEP_MIN_PAIRS"]

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


def _chi2_3(level: float) -> float:
    """The ``level`` quantile of ``chi^2_3`` (Wilson-Hilferty)."""
    return 3.0 * (1.0 - 2.0 / 27.0 + _normal_quantile(level) * math.sqrt(2.0 / 27.0)) ** 3


def _vec(X) -> np.ndarray:
    return X.T.reshape(9)


def _gradient(M, R) -> np.ndarray:
    """``sum_j (I - B_j^T) r_j`` at ``R`` for the pairs in ``M = sum_j c_j B_j kron A_j`` (``r_j``
    the vee of the antisymmetric part of ``R^T A_j R B_j^T``, weighted by ``c_j``): the gradient of
    ``x^T M x`` along ``R exp([e_k]x)``."""
    x = _vec(R)
    Ms = (M + M.T) @ x
    out = np.empty(3)
    for k in range(3):
        E = np.zeros((3, 3))
        i, j = (k + 1) % 3, (k + 2) % 3
        E[j, i], E[i, j] = 1.0, -1.0   # [e_k]x
        out[k] = 0.5 * float(_vec(R @ E) @ Ms)
    return out


class CreepTest:
    """Running sums of the pairs since the last start weighted by their index ``tau`` (counted from
    the start), and the slope of ``R0`` over them (one Gauss-Newton step of the model ``R exp([w0 +
    (tau - c) v]x)``, ``c`` the pairs' mean index). Valid with full memory only: forgetting (a drift
    followed) makes it :attr:`valid` False until the next start."""

    def __init__(self, level: float = CREEP_LEVEL):
        self.level, self.threshold = level, _chi2_3(level)
        self.reset(0)

    def reset(self, origin: int) -> None:
        """Forget every pair; the next ones are counted from pair ``origin``."""
        self.origin, self.valid = origin, True
        self._St = np.zeros((9, 9))                    # sum tau_j B_j kron A_j
        self._SBt, self._SBt2 = np.zeros((3, 3)), np.zeros((3, 3))  # sums of tau_j B_j and tau_j^2 B_j
        self._n, self._t, self._t2 = 0, 0.0, 0.0       # pairs, sums of tau_j and tau_j^2
        self.found = None   # (rate_deg_per_pair, lag_deg, statistic, pairs, axis) of the last significant slope

    def add(self, T, A, B, full_memory: bool) -> None:
        """Pairs ``(A, B)`` with indices ``T`` (over the calibrator's life), just added with weight
        1 (else, with ``full_memory`` False, the test is off until the next start)."""
        if not full_memory:
            self.valid = False
        if not self.valid:
            return
        tau = np.asarray(T, dtype=float) - self.origin
        self._St += np.einsum("i,iab,icd->acbd", tau, B, A).reshape(9, 9)
        self._SBt += np.einsum("i,iab->ab", tau, B)
        self._SBt2 += np.einsum("i,iab->ab", tau * tau, B)
        self._n += len(tau)
        self._t += float(tau.sum())
        self._t2 += float(tau @ tau)

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
        return self.found

    def describe(self, target_deg: float) -> str:
        """The sentence for ``not_ready`` while :attr:`found` is set."""
        rate, lag, stat, n, _ = self.found
        return (f"the mounting creeps (or a change not decided yet): R0 of the {n} pairs since pair {self.origin} "
                f"moves {rate:.3g} deg per pair "
                f"(statistic {stat:.3g} > {self.threshold:.3g}, the {100 * self.level:g} % region of its slope), "
                f"the mounting now {lag:.3g} deg from the estimate; radius and lag together not below the target "
                f"{target_deg:g} deg")

