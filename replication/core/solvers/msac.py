"""Robust estimation of ``R0`` when some motion pairs are outliers. Theory and measured numbers:
``docs/methods.md``, section ``replication.core.solvers.msac``."""
from __future__ import annotations

from itertools import combinations

import numpy as np

from ..handeye import kronecker_operator, pair_residual_deg
from ..so3 import angle_deg_from_chordal, nearest_rotation, rotation_vector_from_matrix
from ._registry import register
from .certificate import chordal_newton

__all__ = ["robust", "MAX_ENUMERATED_PAIRS", "SCORE_BLOCK", "hypotheses", "pair_at", "scores_exact", "scores_blocked"]

REFERENCE = (
    "MSAC (P. H. S. Torr and A. Zisserman, 'MLESAC: a new robust estimator with application to "
    "estimating image geometry', CVIU 78(1), 2000) over two-pair Park & Martin (1994) samples, then "
    "IRLS with Cauchy weights on the exact minimiser of Zhang's weighted eq. (8)"
)

#: Most two-pair samples ``J (J - 1) / 2`` that :func:`robust` enumerates as an explicit list (``J
#: <= 200``). The list costs about 110 bytes and 2 us per pair (``itertools.combinations``;
#: measured: 2.3 MB and 0.04 s at J = 201, 1.9 GB at J = 6000), so the cap keeps it below ~2.5 MB
#: while covering every problem of the paper's simulation and notebook 06 (J <= 50) on the exact
#: code path of before. Above it the samples are drawn by their position in the same lexicographic
#: order (:func:`pair_at`) from the same generator call, so the hypotheses are the same ones; only
#: the scoring arithmetic differs (see :func:`scores_blocked`).
MAX_ENUMERATED_PAIRS = 20_000
#: Most residuals (hypotheses x pairs) held at once while scoring. Below
#: :data:`MAX_ENUMERATED_PAIRS` a block of ``pair_residual_deg`` costs about 220 bytes per residual
#: (three (..., 3, 3) temporaries): 2**17 of them, ~29 MB. Above it, the 81-vector form costs ~40
#: bytes per residual (2**20: ~40 MB) and larger blocks keep its matrix products efficient (measured
#: at J = 2e5, H = 200, 2 threads: 4.4 s in blocks of 2**16, 0.25 s in blocks of 2**20 for the
#: products alone).
SCORE_BLOCK = 2 ** 20
_EXACT_BLOCK = 2 ** 17


def hypotheses(J: int, max_hypotheses: int, seed) -> np.ndarray:
    """Index pairs (H, 2) in lexicographic order: all ``J (J - 1) / 2`` pairs, or a seeded subset of
    ``max_hypotheses``.

    Parameters
    ----------
    J : int
        Number of motion pairs.
    max_hypotheses : int
        Most two-pair samples.
    seed : int
        Seeds the subset (``numpy.random.default_rng(seed)``).

    Returns
    -------
    (H, 2) ndarray of int
        The samples ``(i, j)``, ``i < j``, in the order of ``itertools.combinations``.

    Notes
    -----
    Up to :data:`MAX_ENUMERATED_PAIRS` pairs the list is built and indexed (the code of before, bit
    for bit); above it the same positions are drawn from the same generator call,
    ``default_rng(seed).choice(n_pairs, max_hypotheses, replace=False)`` (which needs
    ``O(max_hypotheses)`` memory), and turned into pairs by :func:`pair_at`, so no ``O(J^2)`` list
    is built.
    """
    n_pairs = J * (J - 1) // 2
    if n_pairs <= MAX_ENUMERATED_PAIRS:
        pairs = np.array(list(combinations(range(J), 2)))
        if len(pairs) <= max_hypotheses:
            return pairs
        rng = np.random.default_rng(seed)
        return pairs[np.sort(rng.choice(len(pairs), size=max_hypotheses, replace=False))]
    if n_pairs <= max_hypotheses:
        return pair_at(np.arange(n_pairs, dtype=np.int64), J)
    rng = np.random.default_rng(seed)
    return pair_at(np.sort(rng.choice(n_pairs, size=max_hypotheses, replace=False)), J)


def pair_at(k, J: int) -> np.ndarray:
    """The pairs ``(i, j)`` at positions ``k`` of ``itertools.combinations(range(J), 2)``, without
    building that list.

    Parameters
    ----------
    k : array_like of int
        Positions, ``0 <= k < J (J - 1) / 2``.
    J : int
        Number of motion pairs.

    Returns
    -------
    (len(k), 2) ndarray of int
        The pair at each position.

    Notes
    -----
    Row ``i`` starts at position ``i (2 J - i - 1) / 2``; ``i`` is the largest row starting at or
    before ``k`` (from the quadratic formula, then corrected in integers for rounding).
    """
    k = np.asarray(k, dtype=np.int64)

    def start(i):
        return i * (2 * J - i - 1) // 2

    b = 2.0 * J - 1.0
    i = np.clip(np.floor((b - np.sqrt(np.maximum(b * b - 8.0 * k, 0.0))) / 2.0).astype(np.int64), 0, J - 2)
    for _ in range(3):  # float rounding moves i by at most one row
        i = np.where(start(i) > k, i - 1, i)
        i = np.where((i + 1 <= J - 2) & (start(i + 1) <= k), i + 1, i)
    return np.stack([i, k - start(i) + i + 1], axis=-1)


def scores_exact(R_h, A, B, threshold_deg: float) -> np.ndarray:
    """MSAC scores (P, H) with the arithmetic of before: ``pair_residual_deg`` on blocks of problems
    x hypotheses.

    Parameters
    ----------
    R_h : (P, H, 3, 3) array
        Hypotheses per problem.
    A, B : (P, J, 3, 3) arrays
        The problems' motion pairs.
    threshold_deg : float
        Residuals are capped here (MSAC).

    Returns
    -------
    (P, H) ndarray
        ``sum_j min(r_j, threshold_deg)^2`` per hypothesis.

    Notes
    -----
    Each residual and each row sum is computed exactly as in one (P, H, J) evaluation (the block
    only selects rows), so the scores are bit-identical to it; at most :data:`_EXACT_BLOCK`
    residuals exist at once (plus one row of ``J``).
    """
    P, H, J = R_h.shape[0], R_h.shape[1], A.shape[-3]
    if H * J <= _EXACT_BLOCK:
        p, h = max(1, _EXACT_BLOCK // (H * J)), H
    else:
        p, h = 1, max(1, _EXACT_BLOCK // J)
    score = np.empty((P, H))
    for n in range(0, P, p):
        An, Bn = A[n:n + p, None], B[n:n + p, None]
        for k in range(0, H, h):
            r = pair_residual_deg(R_h[n:n + p, k:k + h], An, Bn)  # (p, h, J)
            score[n:n + p, k:k + h] = np.sum(np.minimum(r, threshold_deg) ** 2, axis=-1)  # MSAC
    return score


def scores_blocked(R_h, A, B, threshold_deg: float) -> np.ndarray:
    """MSAC scores (P, H) in ``O(SCORE_BLOCK)`` memory from one matrix product per block of pairs.

    Parameters
    ----------
    R_h, A, B, threshold_deg
        As in :func:`scores_exact`.

    Returns
    -------
    (P, H) ndarray
        The scores of :func:`scores_exact`, to rounding.

    Notes
    -----
    Term ``j`` of eq. (8) at a rotation ``R`` is ``||A_j R - R B_j||_F^2 = 6 - 2 <A_j, R B_j R^T>``
    and ``vec(R B_j R^T) = (R kron R) vec(B_j)`` (row-major ``vec``), so ``<A_j, R B_j R^T> =
    <vec(A_j) vec(B_j)^T, R kron R>``: a (pairs, 81) @ (81, hypotheses) product. The residual angle
    then follows as in :func:`~replication.core.handeye.pair_residual_deg`; it agrees with it to
    rounding (about 1e-12 deg at the residuals that count, below the threshold).
    """
    P, H, J = R_h.shape[0], R_h.shape[1], A.shape[-3]
    hs = min(H, SCORE_BLOCK)
    js = max(1, SCORE_BLOCK // hs)
    # (R kron R)[(a, b), (c, d)] = R[a, c] R[b, d]
    kron = np.einsum("phac,phbd->phabcd", R_h, R_h).reshape(P, H, 81)
    score = np.zeros((P, H))
    for n in range(P):
        for k in range(0, H, hs):
            K_t = np.ascontiguousarray(kron[n, k:k + hs].T)  # (81, hs)
            for j in range(0, J, js):
                Z = (A[n, j:j + js].reshape(-1, 9, 1) * B[n, j:j + js].reshape(-1, 1, 9)).reshape(-1, 81)
                d2 = 6.0 - 2.0 * (Z @ K_t)  # term j of eq. (8): ||A_j R - R B_j||_F^2, (js, hs)
                r = angle_deg_from_chordal(np.sqrt(np.maximum(d2, 0.0)))
                score[n, k:k + hs] += np.sum(np.minimum(r, threshold_deg) ** 2, axis=0)  # MSAC
    return score


@register("robust", reference=REFERENCE, min_motions=3)
def robust(motions, *, threshold_deg: float = 5.0, max_hypotheses: int = 200, seed: int = 0,
           irls_iterations: int = 10):
    """Outlier-robust ``R0``: MSAC consensus over two-pair samples, then Cauchy IRLS.

    1. Hypotheses: Park & Martin's rotation for every pair of motions ``(j, k)``
       (all of them if ``J (J - 1) / 2 <= max_hypotheses``, else a seeded subset).
    2. Score (MSAC): ``sum_j min(r_j, t)^2`` with ``r_j`` the residual angle
       (:func:`replication.core.handeye.pair_residual_deg`) and ``t = threshold_deg``; keep the
       best.
    3. IRLS: weights ``w_j = 1 / (1 + (r_j / c)^2)`` (Cauchy, ``c = threshold_deg / 2``)
       and the exact minimiser of ``sum_j w_j ||A_j R - R B_j||_F^2`` on SO(3),
       ``irls_iterations`` times.

    It is deterministic for a given ``seed`` (which only matters when the pairs
    are subsampled) and equivariant under changes of camera or sensor frame.

    Cost: memory ``O(J + max_hypotheses)``, time ``O(max_hypotheses J)``; J = 10^6 pairs take 5-8 s
    on 2 cores, 0.35 GB traced peak and 0.66 GB resident through
    :func:`~replication.core.solvers.solve` (``benchmarks/bench_bounded.py``). The two-pair samples
    are listed explicitly only while there are at most :data:`MAX_ENUMERATED_PAIRS` (20 000, i.e.
    ``J <= 200``): the list costs ~110 bytes per pair, 1.9 GB at J = 6000. Above the cap the seeded
    subset is drawn from the same generator call without the list (same samples as the list would
    give), and the hypotheses are scored block by block through an 81-vector form of eq. (8)
    (:data:`SCORE_BLOCK` residuals at a time) whose residuals agree with ``pair_residual_deg`` to
    rounding. Up to the cap every operation is the one of before, bit for bit.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        ``J >= 3``: with two pairs there is no redundancy to vote with (or a
        :class:`~replication.core.motions.Motions` as ``A``).
    threshold_deg : float
        Inlier threshold on the residual angle. The default, 5 deg, is above
        the residual of an inlier in the paper's simulation (camera and sensor
        noise add up to at most ``2 x 1.15`` deg) and well below a mismatched pair.
    max_hypotheses : int
        Most two-pair samples scored per problem.
    seed : int
        Seeds the subset of samples when there are more than ``max_hypotheses``
        (``numpy.random.default_rng(seed)``, one ``choice`` call shared by the problems of a batch).
    irls_iterations : int

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor``.
    """
    if not threshold_deg > 0:
        raise ValueError(f"threshold_deg must be positive, got {threshold_deg!r}")
    if int(max_hypotheses) != max_hypotheses or max_hypotheses < 1:
        raise ValueError(f"max_hypotheses must be a positive integer, got {max_hypotheses!r}")
    if int(irls_iterations) != irls_iterations or irls_iterations < 0:
        raise ValueError(f"irls_iterations must be a non-negative integer, got {irls_iterations!r}")
    A, B, J = motions.A, motions.B, motions.J
    lead = A.shape[:-3]
    idx = hypotheses(J, int(max_hypotheses), seed)  # (H, 2)
    alpha, beta = rotation_vector_from_matrix(A), rotation_vector_from_matrix(B)  # Park & Martin: alpha_j = R0 beta_j
    M = np.einsum("...hka,...hkb->...hab", alpha[..., idx, :], beta[..., idx, :])
    R_h = nearest_rotation(M)  # (..., H, 3, 3): one hypothesis per sample
    flat = (-1, J, 3, 3)
    scores = scores_exact if J * (J - 1) // 2 <= MAX_ENUMERATED_PAIRS else scores_blocked
    score = scores(R_h.reshape((-1,) + R_h.shape[-3:]), A.reshape(flat), B.reshape(flat), threshold_deg)
    best = np.argmin(score.reshape(lead + score.shape[-1:]), axis=-1)
    R = np.take_along_axis(R_h, best[..., None, None, None], axis=-3)[..., 0, :, :]
    c = 0.5 * threshold_deg
    for _ in range(int(irls_iterations)):
        w = 1.0 / (1.0 + (pair_residual_deg(R, A, B) / c) ** 2)  # Cauchy weights
        R = chordal_newton(kronecker_operator(A, B, weights=w), R)[0]  # weighted eq. (8)
    return R
