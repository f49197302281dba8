"""Was the sensor re-mounted during the recording? A batch test of one change of ``R0`` at an
unknown time. Theory and measured numbers: ``docs/judging.md``, section
``replication.rig.changepoint``."""
from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field

import numpy as np

from ..core.checks import check_number, check_rotation_matrices
from ..core.handeye import check_motion_pairs
from ..core.so3 import angle_between_deg, rotation_vector_from_matrix
from ..core.solvers.certificate import chordal_newton, relaxed_rotation
from ..core.stats import radius_deg
from .streams import GyroStream, OrientationStream

__all__ = ["ChangeTest", "two_segment_test", "threshold", "p_value", "remounted", "MIN_EFFECTIVE_BLOCKS",
           "tail", "false_alarm"]

#: Fewest independent stretches (``(J - block) / (2 block + 1)``) the test needs: the inflation and
#: the threshold rest on them.
MIN_EFFECTIVE_BLOCKS = 10.0
#: Newton iterations per side from the relaxed start (quadratic convergence; 2-3 are used on real
#: recordings).
NEWTON_ITERATIONS = 8
#: Floor of the mean square residual angle (rad^2): a residual of 0.01 deg, below any real sensor's
#: noise, so that noise-free data is not judged by rounding (as
#: :data:`replication.rig.online.D2_FLOOR`).
S2_FLOOR = math.radians(0.01) ** 2
#: A side's ``G`` with its smallest eigenvalue below this share of its largest: motions about one
#: axis only.
DEGENERATE_TOL = 1e-10
_DOF = 3  # a rotation has three degrees of freedom
_EYE = np.eye(3)


@dataclass(frozen=True)
class ChangeTest:
    """What :func:`two_segment_test` found: the best split and whether the two sides differ beyond
    their noise.

    Attributes
    ----------
    significant : bool
        ``statistic > threshold``: the sides differ by more than their noise at false-alarm
        probability ``level``.
    statistic, threshold : float
        ``max_k W_k`` and the threshold it is compared with (see the module notes).
    p_value : float
        The false-alarm probability of a statistic this large (the approximation of the threshold,
        clipped to [0, 1]).
    level : float
        The false-alarm probability the threshold was set for.
    split_index : int
        The least-squares split (module notes; ``statistic`` is the maximum over every split, not
        necessarily this one's): index of the first pair of the ``after`` side (pairs ``split_index
        - block .. split_index - 1`` span the split and belong to neither side).
    split_time : float
        Its start time ``t[split_index]`` (s): the estimated time of the change.
    R_before, R_after : ndarray (3, 3)
        Each side's minimiser of eq. (8) (``camera_from_sensor``).
    angle_deg : float
        The angle between them.
    difference_radius_deg : float
        95 % radius of that angle's noise at this split (``phi (C_before + C_after)``; for a split
        chosen in advance, the selected one's angle is larger).
    n_before, n_after : int
        Pairs on each side.
    inflation : float
        ``phi``, the measured factor on the model covariance for overlapping pairs (>= 1).
    effective_blocks : float
        ``n_eff = (J - block) / (2 block + 1)``.
    split_times, statistics : ndarray
        Every candidate split's time and ``W_k`` (for a figure).
    """

    significant: bool
    statistic: float
    threshold: float
    p_value: float
    level: float
    split_index: int
    split_time: float
    R_before: np.ndarray = field(repr=False)
    R_after: np.ndarray = field(repr=False)
    angle_deg: float
    difference_radius_deg: float
    n_before: int
    n_after: int
    inflation: float
    effective_blocks: float
    split_times: np.ndarray = field(repr=False)
    statistics: np.ndarray = field(repr=False)

    def summary(self) -> str:
        """One line: the verdict of the test with its numbers."""
        verdict = "a change" if self.significant else "no significant change"
        return (f"{verdict}: the pairs before and after {self.split_time:.2f} s ({self.n_before} / {self.n_after} "
                f"pairs) disagree by {self.angle_deg:.3f} deg (noise 95 % radius {self.difference_radius_deg:.3f}); "
                f"statistic {self.statistic:.1f}, threshold {self.threshold:.1f} at false-alarm probability "
                f"{self.level:g} (p = {self.p_value:.2g}, inflation {self.inflation:.2f})")


def _check(A, B, t, block, min_share, level):
    check_number("block", block, minimum=1, integer=True, strict=False)
    check_number("min_share", min_share, minimum=0)
    if not min_share < 0.5:
        raise ValueError(f"min_share must be < 0.5 (a share of the pairs on each side), got {min_share!r}")
    check_number("level", level, minimum=0)
    if not level < 0.5:
        raise ValueError(f"level must be < 0.5 (the false-alarm probability), got {level!r}")
    A, B = check_motion_pairs(A, B)
    if A.ndim != 3:
        raise ValueError(f"A and B must have shape (J, 3, 3), got {A.shape}")
    try:
        t = np.asarray(t, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"t must be a 1-D array of pair start times: {err}") from None
    if t.ndim != 1 or len(t) != len(A):
        raise ValueError(f"t must hold one start time per pair: got shape {t.shape} for {len(A)} pairs")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise ValueError("t must be finite and non-decreasing (pairs in time order)")
    return A, B, t


def _sides(J: int, block: int, min_share: float) -> np.ndarray:
    """Candidate splits ``k`` (first pair after): every quarter ``block``, at least ``min_share`` of
    the pairs, 5 blocks and 10 pairs on each side. ``ValueError`` when there are too few pairs."""
    n_eff = (J - block) / (2 * block + 1)
    n_min = max(math.ceil(min_share * J), 5 * block, 10)
    if n_eff < MIN_EFFECTIVE_BLOCKS:
        raise ValueError(f"too few pairs for a change test: {J} pairs at {block} per block are {n_eff:.1f} independent "
                         f"stretches, fewer than {MIN_EFFECTIVE_BLOCKS:g} (need "
                         f"{math.ceil(MIN_EFFECTIVE_BLOCKS * (2 * block + 1) + block)} pairs)")
    if J - block - 2 * n_min < 0:
        raise ValueError(f"too few pairs for a change test: {J} pairs cannot leave {n_min} (min_share {min_share:g}, "
                         f"and 5 blocks of {block}) on each side of a split")
    return np.arange(n_min + block, J - n_min + 1, max(1, block // 4))


def _fit(S, SB, n):
    """Each side's minimiser of eq. (8), its cost, mean square residual angle and ``G``, from sums
    over its pairs.

    ``S``: (m, 9, 9) sums of ``B_j kron A_j``; ``SB``: (m, 3, 3) sums of ``B_j``; ``n``: (m,) pair
    counts.
    """
    K = S / n[:, None, None]
    R, g = chordal_newton(K, relaxed_rotation(K), max_iterations=NEWTON_ITERATIONS)[:2]
    cost = np.clip(2.0 * n * (3.0 - g), 0.0, None)          # eq. (8) at R, from K
    s2 = np.maximum(cost / (2.0 * (n - 3.0)), S2_FLOOR)      # mean square residual angle (rad^2)
    G = 2.0 * n[:, None, None] * _EYE - SB - np.swapaxes(SB, -1, -2)
    lam = np.linalg.eigvalsh(G)
    if np.any(lam[:, 0] <= DEGENERATE_TOL * lam[:, -1]):
        raise ValueError("degenerate motion on one side of a split: the sensor turns about one axis only there, so R0 "
                         "is not determined on that side (G = sum_j (2I - B_j - B_j^T) is singular); a change test "
                         "needs motions about other axes on both sides")
    return R, cost, s2, G


def _long_run(A, B, R, m: int):
    """``sum_j sum_{|l| <= m} u_j u_{j+l}^T`` over one side, ``u_j = (I - B_j)^T r_j`` at ``R``
    (3x3)."""
    # residual rotation vectors: R^T A_j R B_j^T = exp([r_j]x)
    r = rotation_vector_from_matrix(R.T @ A @ R @ np.swapaxes(B, -1, -2))
    u = np.einsum("jba,jb->ja", _EYE - B, r)
    c = np.concatenate([np.zeros((1, 3)), np.cumsum(u, axis=0)])
    j = np.arange(len(u))
    window = c[np.minimum(j + m + 1, len(u))] - c[np.maximum(j - m, 0)]  # sum of u over lags -m..m inside the side
    return u.T @ window


def tail(c, lam1: float, lam2: float):
    """P(sup over [lam1, lam2] of |B(lam)|^2 / (lam (1 - lam)) > c), B a 3-dim Brownian bridge, for
    large c (1 at or below 3, the degrees of freedom).

    Parameters
    ----------
    c : array_like
        Statistics, any shape.
    lam1, lam2 : float
        The range of split fractions searched, ``0 < lam1 < lam2 < 1``.

    Returns
    -------
    ndarray
        The tail probability of each statistic, in ``[0, 1]``.
    """
    c = np.asarray(c, dtype=float)
    span = math.log(lam2 * (1.0 - lam1) / (lam1 * (1.0 - lam2)))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lead = np.exp(0.5 * _DOF * np.log(c) - 0.5 * c - 0.5 * _DOF * math.log(2.0) - math.lgamma(0.5 * _DOF))
        value = lead * ((1.0 - _DOF / c) * span + 4.0 / c)
    return np.where(c > _DOF, np.clip(value, 0.0, 1.0), 1.0)


#: Nodes of the average over phi's sampling error: standard normal quantiles at the midpoints of 200
#: equal bins.
_Z = np.array([statistics.NormalDist().inv_cdf((i + 0.5) / 200) for i in range(200)])


def false_alarm(c, n_eff: float, lam1: float, lam2: float):
    """False-alarm probability of ``max_k W_k > c`` (module notes): the tail (:func:`tail`) at the
    threshold the test puts on the statistic against the true inflation, averaged over the sampling
    error of the measured one.

    Parameters
    ----------
    c : array_like
        Statistics, any shape.
    n_eff : float
        Effective number of independent stretches behind the measured inflation.
    lam1, lam2 : float
        The range of split fractions searched.

    Returns
    -------
    ndarray
        The false-alarm probability of each statistic (the shape of ``c``).
    """
    nu = n_eff
    # chi2_nu / nu (Wilson-Hilferty)
    x = np.clip(1.0 - 2.0 / (9.0 * nu) + _Z * math.sqrt(2.0 / (9.0 * nu)), 0.0, None) ** 3
    cx = np.asarray(c, dtype=float)[..., None] * x
    # V where W / phi_hat = c x: phi_hat = phi (1 - (1 + V/3)/n_eff) x
    v = cx * (1.0 - 1.0 / n_eff) / (1.0 + cx / (_DOF * n_eff))
    return tail(v, lam1, lam2).mean(axis=-1)


def threshold(level: float, n_eff: float, lam1: float, lam2: float) -> float:
    """The threshold on ``max_k W_k`` for false-alarm probability ``level`` (module notes), by
    bisection."""
    lo, hi = float(_DOF), 1e3
    if false_alarm(hi, n_eff, lam1, lam2) > level:
        return math.inf
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if false_alarm(mid, n_eff, lam1, lam2) > level else (lo, mid)
        if hi - lo < 1e-6:
            break
    return hi


def p_value(statistic: float, n_eff: float, lam1: float, lam2: float) -> float:
    """The false-alarm probability of a statistic at least ``statistic`` (the approximation of
    :func:`threshold`)."""
    return float(false_alarm(statistic, n_eff, lam1, lam2))


def two_segment_test(A, B, t, *, block: int = 1, min_share: float = 0.15, level: float = 0.01) -> ChangeTest:
    """Test whether the pairs before and after some split time agree on ``R0`` (one re-mount at an
    unknown time).

    For every candidate split ``k`` (every ``max(1, block // 4)`` pairs, at least ``min_share`` of
    the pairs and 5 blocks on each side), each side's minimiser of the paper's eq. (8) and the
    statistic ``W_k = d_k^T (C_before + C_after)^{-1} d_k / phi`` with ``d_k = log(R_before^T
    R_after)``; the test compares ``max_k W_k`` with a threshold for false-alarm probability
    ``level`` (module notes). O(J) time and memory.

    Parameters
    ----------
    A, B : array_like, shape (J, 3, 3)
        Camera and sensor relative rotations of the pairs, in time order (eqs. (3)-(4)).
    t : array_like, shape (J,)
        The pairs' start times (s), non-decreasing (``result.diagnostics['pair_times']`` of
        :func:`~replication.rig.calibration.calibrate`).
    block : int
        Pairs per interval: a pair overlaps the ``block - 1`` pairs after it and shares a pose with
        the one ``block`` after (``interval`` times the camera rate over the stride, as
        ``calibrate`` computes it; 1 for pairs that share nothing).
    min_share : float
        Fewest pairs on each side as a share of ``J``, in (0, 0.5).
    level : float
        False-alarm probability of the test (the chance of ``significant`` without a change), in (0,
        0.5).

    Returns
    -------
    ChangeTest

    Raises
    ------
    ValueError
        A parameter out of range (named), ``A``, ``B`` not rotations of the same shape, ``t`` not
        one time per pair in order, or too few pairs (fewer than :data:`MIN_EFFECTIVE_BLOCKS`
        independent stretches, or no split leaving ``min_share`` and 5 blocks on each side).
    """
    A, B, t = _check(A, B, t, block, min_share, level)
    J, m = len(A), int(block)
    ks = _sides(J, m, min_share)
    # prefix sums over the pairs; layout of replication.core.handeye.kronecker_operator:
    # [(a, c), (b, d)] = B[a, b] A[c, d]
    kron = np.einsum("jab,jcd->jacbd", B, A).reshape(J, 9, 9)
    PK = np.concatenate([np.zeros((1, 9, 9)), np.cumsum(kron, axis=0)])
    PB = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(B, axis=0)])
    end = ks - m                                   # the before side: pairs 0 .. k - block - 1 (they end by t_k)
    nb, na = end.astype(float), (J - ks).astype(float)
    Rb, cb, s2b, Gb = _fit(PK[end], PB[end], nb)
    Ra, ca, s2a, Ga = _fit(PK[J] - PK[ks], PB[J] - PB[ks], na)
    Cb = (s2b / 3.0)[:, None, None] * np.linalg.inv(Gb)
    Ca = (s2a / 3.0)[:, None, None] * np.linalg.inv(Ga)
    d = rotation_vector_from_matrix(np.swapaxes(Rb, -1, -2) @ Ra)
    W = np.einsum("ka,ka->k", d, np.linalg.solve(Cb + Ca, d[..., None])[..., 0])
    # the split: least squares (Bai 1994) over the pairs on either side; the block spanning the
    # split is left out at every split alike (it straddles the change), so the sums compare the same
    # number of pairs
    i = int(np.argmin(cb + ca))
    k = int(ks[i])
    # the inflation for overlapping pairs, on the two-segment fit at that split
    omega = _long_run(A[:k - m], B[:k - m], Rb[i], m) + _long_run(A[k:], B[k:], Ra[i], m)
    Gi = np.linalg.inv(Gb[i] + Ga[i])
    model = (s2b[i] / 3.0) * Gb[i] + (s2a[i] / 3.0) * Ga[i]
    phi = max(1.0, float(np.trace(Gi @ omega @ Gi) / np.trace(Gi @ model @ Gi)))
    n_eff = (J - m) / (2 * m + 1)
    lam1, lam2 = float(ks[0] - m / 2) / J, float(ks[-1] - m / 2) / J
    stats = W / phi
    top = float(stats.max())
    c = threshold(level, n_eff, lam1, lam2)
    return ChangeTest(
        significant=bool(top > c), statistic=top, threshold=float(c),
        p_value=p_value(top, n_eff, lam1, lam2), level=float(level), split_index=k,
        split_time=float(t[k]), R_before=Rb[i], R_after=Ra[i], angle_deg=float(angle_between_deg(Ra[i], Rb[i])),
        difference_radius_deg=radius_deg(phi * (Cb[i] + Ca[i]), 0.95), n_before=int(nb[i]), n_after=int(na[i]),
        inflation=phi, effective_blocks=float(n_eff), split_times=t[ks], statistics=stats,
    )


def remounted(sensor, time: float, R):
    """``sensor`` as if it had been mounted ``R`` further from ``time`` (s) on: a synthetic
    re-mount.

    The sensor frame turns by ``R`` (sensor-frame vectors ``v`` become ``R^T v``): ``R0 =
    camera_from_sensor`` becomes ``R0 R``, a gyro's rates ``R^T omega`` and an orientation stream's
    ``world_from_sensor`` ``Q R`` (as :func:`replication.rig.live.replay`'s ``remount``).

    Parameters
    ----------
    sensor : GyroStream or OrientationStream
    time : float
        When the re-mount happens (s, on the sensor's clock); samples at or after it are changed.
    R : array_like (3, 3)
        The extra rotation.
    """
    if not isinstance(sensor, (GyroStream, OrientationStream)):
        raise ValueError(f"sensor must be a GyroStream or OrientationStream, got {type(sensor).__name__}")
    R = check_rotation_matrices(R, "R")
    check_number("time", time)
    after = sensor.t >= time
    if isinstance(sensor, GyroStream):
        omega = np.array(sensor.omega)
        omega[after] = omega[after] @ R  # rows: (R^T omega)^T = omega^T R
        return GyroStream(sensor.t, omega, sensor.source)
    Q = np.array(sensor.world_from_body)
    Q[after] = Q[after] @ R
    return OrientationStream(sensor.t, Q, sensor.source)
