"""Online alignment: the paper's two-step iteration as a live estimator, with a calibrated "ready" signal and
re-mount detection.

The paper's operator is a running mean, ``K = (1/J) sum_j B_j kron A_j`` (eqs. (14)-(15) in ``vec`` form,
:func:`replication.handeye.kronecker_operator`), so each new pair costs O(1): :class:`OnlineCalibrator` keeps

* the running sums of ``B_j kron A_j`` (9x9) and of ``G_j = 2I - B_j - B_j^T`` (3x3), with optional exponential
  forgetting (weights ``lambda^age``);
* a warm-started two-step step (eqs. (14)-(17): ``R^r = proj(K vec R^l)``, ``R^l = proj(K^T vec R^r)``) every
  ``step_every`` pairs, which starts the next refinement, and a warm-started Newton refinement to the minimiser of
  eq. (8), which is the published estimate
  (:func:`replication.solvers.optimal.chordal_newton`) at ``min_pairs`` and then every ``refine_every`` pairs or
  every tenth of the pairs so far, whichever is more (so its cost per pair falls as ``1 / J``), and on demand
  (:meth:`OnlineCalibrator.estimate`): fed the same pairs, it equals the batch ``chordal_optimal``. Pairs are
  buffered between steps and added to the sums in one batched product, so a pair costs a validation, the
  change detector's residual and an append;
* a 95 % error radius from the local curvature of eq. (8) and a running noise estimate (below), computed at
  each refinement (about the minimiser), and ``ready`` once the radius is below a target;
* a CUSUM on the pair residuals that raises an alarm when ``R0`` changes (the sensor was re-mounted), then
  starts over.

**The radius.** Near the minimiser, perturbing ``R`` to ``R exp([w]x)`` changes the residual rotation vector of
pair ``j`` by about ``(I - B_j^T) w``, so the least-squares estimate's error is ``w = G^{-1} sum_j (I - B_j) r_j``
with ``G = sum_j (I - B_j)(I - B_j^T) = sum_j (2I - B_j - B_j^T)``. With independent, isotropic pair residuals
of mean square ``s^2`` (``s^2 / 3`` per axis), ``cov(w) = (s^2 / 3) G^{-1}``. ``s^2`` comes from the cost (8)
itself: ``||A_j R - R B_j||_F^2 = 8 sin^2(theta_j / 2) ~ 2 theta_j^2``, so ``s^2 = cost / (2 (J - 3))``, again
O(1) from the running ``K``. The radius at level ``p`` is the ``p`` quantile of ``|w|`` for that covariance
(Welch-Satterthwaite: ``|w|^2 ~ a chi^2_nu`` with ``a = sum l^2 / sum l``, ``nu = (sum l)^2 / sum l^2`` over the
eigenvalues ``l``). Pairs must not overlap in time (overlapping pairs share their noise; the stream front end,
:class:`replication.live.LiveRig`, forms pairs that share no pose).

**What the radius cannot see.** It measures the estimator's own noise. An error that every pair shares (a SLAM
trajectory that disagrees with the sensor in a consistent way, a clock offset left in, a gyro scale error) leaves
small residuals and a small radius: ``ready`` is then declared while the estimate is farther off than the target.
Notebook 08 shows this on EuRoC MH01 (its SLAM run against the ground truth); check such a rig against a reference
or with :func:`replication.calibration.calibrate`'s verdict before trusting ``ready``. Its coverage is measured in ``tests/test_online.py`` and notebook 08.

**Re-mount detection.** After ``min_pairs`` pairs, each new pair's ``d_j^2 = ||A_j R - R B_j||_F^2`` is compared
with a reference level ``m``: the mean of the pairs so far at the estimate of that moment (the cost (8) over ``J``),
then an exponential average of the pairs' ``d_j^2`` (rate ``reference_rate``, each capped at ``cap m``) taken
while the detector's sum is below ``h / 3``, so that the reference follows a residual level that drifts (faster
motion, a worse SLAM segment) but not the pairs after a change; it never goes below :data:`D2_FLOOR`: ``S = max(0, S + min(d_j^2 / m, cap) - k)``; an alarm when
``S > h``. Without a change ``d^2 / m`` is about ``chi^2_3 / 3`` (mean 1); after a re-mount by ``delta`` it jumps to
about ``(delta / s)^2`` times the motion, for every pair, so the alarm comes within a few pairs; the ``cap``
keeps a single outlier pair from raising it alone.

Notation and frames: ``docs/conventions.md`` (``A`` camera motions, ``B`` sensor motions, ``R0 =
camera_from_sensor``).
"""
from __future__ import annotations

import functools
import math
import statistics
from dataclasses import dataclass

import numpy as np

from .checks import check_number, check_rotation_matrices
from .handeye import unvec, vec
from .so3 import angle_between_deg, nearest_rotation_up_to_sign

__all__ = ["OnlineCalibrator", "OnlineState", "radius_deg", "MIN_PAIRS"]

_EYE = np.eye(3)
#: Floor of the change detector's reference level ``d^2``: a residual of 0.01 deg (``d^2 ~ 2 theta^2``), below any
#: real sensor's noise; noise-free data would otherwise make rounding look like a change.
D2_FLOOR = 2.0 * math.radians(0.01) ** 2

#: Pairs before the radius, ``ready`` and the change detector mean anything (3 unknowns, noise from J - 3).
MIN_PAIRS = 10


def radius_deg(cov, level: float = 0.95) -> float:
    """The ``level`` quantile of ``|w|`` (degrees) for ``w ~ N(0, cov)`` (radians).

    ``|w|^2`` is a weighted sum of chi-square variables; Welch-Satterthwaite matches it with ``a chi^2_nu``
    (``a = sum l^2 / sum l``, ``nu = (sum l)^2 / sum l^2`` over the eigenvalues ``l`` of ``cov``), whose quantile
    comes from the Wilson-Hilferty cube-root normal approximation (within 1 % for ``nu >= 1``).
    """
    lam = np.clip(np.linalg.eigvalsh(cov), 0.0, None)
    total, squares = float(lam.sum()), float((lam ** 2).sum())
    if not total > 0:
        return 0.0
    a, nu = squares / total, total ** 2 / squares
    z = _normal_quantile(level)
    q = nu * (1.0 - 2.0 / (9.0 * nu) + z * math.sqrt(2.0 / (9.0 * nu))) ** 3  # chi^2_nu quantile
    return math.degrees(math.sqrt(a * q))


@functools.lru_cache(maxsize=8)
def _normal_quantile(level: float) -> float:
    return statistics.NormalDist().inv_cdf(level)


@dataclass(frozen=True)
class OnlineState:
    """What :meth:`OnlineCalibrator.update` returns after each pair."""

    n_pairs: int          # pairs since the last (re)start
    R: np.ndarray         # current camera_from_sensor estimate
    radius_deg: float     # error radius at the calibrator's level (inf before MIN_PAIRS)
    ready: bool           # radius below the target
    alarm: bool           # a re-mount was detected at this pair (the calibrator then started over)


class OnlineCalibrator:
    """The two-step iteration as a live estimator (see the module notes).

    Parameters
    ----------
    target_deg : float
        ``ready`` once the error radius is below this (degrees).
    level : float
        Confidence of the radius (default 0.95).
    forgetting : float
        Exponential forgetting factor in (0, 1]; 1 keeps every pair with weight 1 (then the state equals the
        batch problem of all pairs since the last start).
    step_every, refine_every : int
        A two-step step every ``step_every`` pairs; a Newton refinement (and the radius) every ``refine_every``
        pairs or every tenth of the pairs so far, whichever is more.
    min_pairs : int
        Pairs before ``ready`` and the change detector.
    cusum_k, cusum_h, cusum_cap : float
        The change detector's allowance, threshold and per-pair cap (see the module notes).
    reference_rate : float
        How fast the detector's reference level follows the in-control residuals (an exponential average).
    init : array_like (3, 3), optional
        Start of the iteration (default identity).
    """

    def __init__(self, *, target_deg: float = 0.5, level: float = 0.95, forgetting: float = 1.0,
                 step_every: int = 5, refine_every: int = 10, min_pairs: int = MIN_PAIRS,
                 cusum_k: float = 2.0, cusum_h: float = 30.0, cusum_cap: float = 10.0, reference_rate: float = 1 / 30,
                 init=None):
        for name, value in (("target_deg", target_deg), ("cusum_h", cusum_h), ("cusum_k", cusum_k),
                            ("cusum_cap", cusum_cap)):
            check_number(name, value, minimum=0)
        if not 0.0 < level < 1.0:
            raise ValueError(f"level must be in (0, 1), got {level!r}")
        if not 0.0 < forgetting <= 1.0:
            raise ValueError(f"forgetting must be in (0, 1], got {forgetting!r}")
        for name, value in (("step_every", step_every), ("refine_every", refine_every), ("min_pairs", min_pairs)):
            check_number(name, value, minimum=1, integer=True, strict=False)
        if min_pairs < 4:
            raise ValueError(f"min_pairs must be at least 4 (3 unknowns and a noise estimate), got {min_pairs}")
        self.target_deg, self.level, self.forgetting = float(target_deg), float(level), float(forgetting)
        self.step_every, self.refine_every, self.min_pairs = int(step_every), int(refine_every), int(min_pairs)
        self.cusum_k, self.cusum_h, self.cusum_cap = float(cusum_k), float(cusum_h), float(cusum_cap)
        if not 0.0 < reference_rate <= 1.0:
            raise ValueError(f"reference_rate must be in (0, 1], got {reference_rate!r}")
        self.reference_rate = float(reference_rate)
        self._init = np.eye(3) if init is None else check_rotation_matrices(init, "init")
        self.alarms: list[int] = []  # pair indices (over the calibrator's life) where a re-mount was detected
        self.n_total = 0
        self.restart()

    # ------------------------------------------------------------------------------------------------ state
    def restart(self, init=None) -> None:
        """Forget every pair (after a re-mount): the estimate starts again from ``init`` (default: the last one)."""
        self._S = np.zeros((9, 9))     # sum of weights x (B kron A)
        self._SB = np.zeros((3, 3))    # sum of weights x B  (G = 2 w I - SB - SB^T)
        self._SB2 = np.zeros((3, 3))   # sum of squared weights x B (forgetting: the covariance's middle factor)
        self._w = 0.0                  # sum of weights (J without forgetting)
        self._w2 = 0.0                 # sum of squared weights
        self._n = 0                    # pairs since the start
        self._bufA, self._bufB = [], []  # pairs not yet in the sums (at most step_every of them)
        self._mean_d2 = math.nan       # mean d_j^2 = cost (8) / J at the current estimate (the detector's reference)
        self._cusum = 0.0
        start = self._init if init is None and not hasattr(self, "_R") else (self._R if init is None else init)
        self._R = np.array(start, dtype=float)      # the published estimate: the last refinement's minimiser
        self._warm = self._R                          # the two-step iterate: the next refinement's start
        self._radius = math.inf
        self._next_refine = self.min_pairs

    def _flush(self) -> None:
        """Add the buffered pairs to the running sums (one batched product; weights lambda^age)."""
        if not self._bufA:
            return
        A, B = np.array(self._bufA), np.array(self._bufB)
        m = len(A)
        w = self.forgetting ** np.arange(m - 1, -1, -1.0)
        decay = self.forgetting ** m
        # sum_i w_i B_i kron A_i, laid out as replication.handeye.kronecker_operator: [(a, c), (b, d)] = B[a, b] A[c, d]
        S = np.einsum("i,iab,icd->acbd", w, B, A).reshape(9, 9)
        self._S = decay * self._S + S
        self._SB = decay * self._SB + np.einsum("i,iab->ab", w, B)
        self._SB2 = decay ** 2 * self._SB2 + np.einsum("i,iab->ab", w ** 2, B)
        self._w = decay * self._w + w.sum()
        self._w2 = decay ** 2 * self._w2 + (w ** 2).sum()
        self._bufA.clear()
        self._bufB.clear()

    @property
    def K(self) -> np.ndarray:
        """The running ``K`` (9x9): the weighted mean of ``B_j kron A_j``."""
        self._flush()
        return self._S / self._w if self._w else np.zeros((9, 9))

    @property
    def R(self) -> np.ndarray:
        return self._R

    @property
    def n_pairs(self) -> int:
        return self._n

    @property
    def radius(self) -> float:
        """The current error radius (degrees) at :attr:`level`."""
        return self._radius

    @property
    def ready(self) -> bool:
        return self._n >= self.min_pairs and self._radius < self.target_deg

    # ------------------------------------------------------------------------------------------------ update
    def update(self, A, B) -> OnlineState:
        """Add one pair ``(A_j, B_j)`` (camera and sensor motion over the same interval). O(1) work and memory."""
        try:
            M = np.array((A, B), dtype=float)
        except (TypeError, ValueError) as err:
            raise ValueError(f"a pair is two 3x3 rotations: {err}") from None
        if M.shape != (2, 3, 3):
            raise ValueError(f"a pair is two 3x3 rotations, got shapes {np.shape(A)} and {np.shape(B)}")
        # the checks of replication.checks.check_rotation_matrices, inline: this is the per-pair hot path
        err = np.abs(np.swapaxes(M, -1, -2) @ M - _EYE).max(axis=(1, 2)).tolist()
        for name, e_k, (a, b, c, d, e, f, g, h, i) in zip(("A (camera motion)", "B (sensor motion)"), err,
                                                          M.reshape(2, 9).tolist()):
            if not e_k <= 1e-6:  # also catches NaN / inf
                raise ValueError(f"{name} is not a rotation matrix: max |R^T R - I| = {e_k:.3g}")
            if a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) < 0:
                raise ValueError(f"{name} is a reflection (det -1), not a rotation")
        return self._update(M[0], M[1])

    def _update(self, A, B) -> OnlineState:
        alarm = False
        if self._n >= self.min_pairs:  # the change detector, on the pair before it is added
            R = self._R
            d2 = 6.0 - 2.0 * float(np.vdot(A @ R, R @ B))  # ||A R - R B||_F^2
            mean = max(self._mean_d2, D2_FLOOR)
            z = min(d2 / mean, self.cusum_cap)
            self._cusum = max(0.0, self._cusum + z - self.cusum_k)
            if self._cusum <= self.cusum_h / 3:  # no change building up: the reference follows the residual level
                self._mean_d2 += self.reference_rate * (min(d2, self.cusum_cap * mean) - self._mean_d2)
            if self._cusum > self.cusum_h:
                alarm = True
                self.alarms.append(self.n_total)
                self.restart(init=R)
        self._bufA.append(A)
        self._bufB.append(B)
        self._n += 1
        self.n_total += 1
        if self._n >= self._next_refine:
            self._refine()
            self._next_refine = self._n + max(self.refine_every, self._n // 10)
        elif self._n % self.step_every == 0:
            self._step()
        return OnlineState(self._n, self._R, self._radius, self.ready, alarm)

    def update_many(self, A, B) -> list[OnlineState]:
        """:meth:`update` for each pair of ``(J, 3, 3)`` arrays in order (a replay); validated once, up front."""
        A = check_rotation_matrices(A, "A (camera motions)")
        B = check_rotation_matrices(B, "B (sensor motions)")
        if A.shape != B.shape or A.ndim != 3:
            raise ValueError(f"need two (J, 3, 3) arrays of the same J, got {A.shape} and {B.shape}")
        return [self._update(a, b) for a, b in zip(A, B)]

    # ------------------------------------------------------------------------------------------------ estimates
    def _step(self) -> None:
        """One warm-started two-step iteration (eqs. (14)-(17)) on the next refinement's start. The published
        estimate stays the last minimiser of eq. (8), the one the radius describes: the two-step fixed point is
        not that minimiser and is farther from ``R0`` (notebook 01), so publishing it would leave the radius
        describing another estimate."""
        K = self.K
        right = nearest_rotation_up_to_sign(unvec(K @ vec(self._warm)))   # eq. (14), projected (16)
        self._warm = nearest_rotation_up_to_sign(unvec(K.T @ vec(right)))  # eq. (15), projected (17)

    def _refine(self, max_iterations: int = 30) -> None:
        """Newton on SO(3) to the minimiser of eq. (8) from the two-step iterate (warm start), then the radius."""
        from .solvers.optimal import chordal_newton

        self._R = self._warm = chordal_newton(self.K, self._warm, max_iterations=max_iterations)[0]
        self._update_radius()

    def _update_radius(self) -> None:
        if self._n < self.min_pairs:
            self._radius = math.inf
            return
        x = vec(self._R)
        cost = max(2.0 * (3.0 * self._w - x @ (0.5 * (self._S + self._S.T)) @ x), 0.0)  # eq. (8) from the running K
        if not self._mean_d2 > 0:  # the detector's reference starts from the cost; then it follows in-control pairs
            self._mean_d2 = cost / self._w
        s2 = cost / (2.0 * max(self._w - 3.0, 1.0))                          # mean square residual angle
        G = 2.0 * self._w * _EYE - self._SB - self._SB.T                    # sum_j w_j (2I - B_j - B_j^T)
        try:
            Gi = np.linalg.inv(G)
        except np.linalg.LinAlgError:
            self._radius = math.inf
            return
        if self.forgetting == 1.0:
            cov = (s2 / 3.0) * Gi
        else:  # weighted least squares: G^-1 (sum_j w_j^2 (2I - B_j - B_j^T)) G^-1
            G2 = 2.0 * self._w2 * _EYE - self._SB2 - self._SB2.T
            cov = (s2 / 3.0) * Gi @ G2 @ Gi
        self._radius = radius_deg(cov, self.level) if np.all(np.isfinite(cov)) else math.inf

    def estimate(self) -> np.ndarray:
        """The minimiser of eq. (8) over the pairs so far (Newton to convergence from the current iterate)."""
        self._flush()
        if self._w:
            self._refine(max_iterations=100)
        return self._R

    def error_deg(self, R0) -> float:
        """Angle (degrees) between the current estimate and ``R0``."""
        return float(angle_between_deg(self._R, np.asarray(R0, dtype=float)))
