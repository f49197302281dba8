"""Robust estimation of ``R0`` when some motion pairs are outliers.

An outlier pair is one whose camera and sensor rotations do not describe the
same motion (a mismatched time stamp, a PnP flip, a magnetic disturbance). The
least-squares solvers spread its error over the estimate; :func:`robust`
finds a consensus first and then down-weights what disagrees with it.

Method: MSAC hypothesise-and-verify (Torr & Zisserman 2000) over minimal
samples of two pairs (Park & Martin's solution of two pairs is exact for
noise-free, non-parallel motions), then iteratively re-weighted least squares
with the Cauchy weight on the exact minimiser of the weighted eq. (8)
(:func:`replication.solvers.optimal.chordal_newton`).
"""
from __future__ import annotations

from itertools import combinations

import numpy as np

from ..handeye import kronecker_operator, pair_residual_deg
from ..so3 import log_map, nearest_rotation
from ._registry import register
from .optimal import chordal_newton

__all__ = ["robust"]

REFERENCE = (
    "MSAC (P. H. S. Torr and A. Zisserman, 'MLESAC: a new robust estimator with application to "
    "estimating image geometry', CVIU 78(1), 2000) over two-pair Park & Martin (1994) samples, then "
    "IRLS with Cauchy weights on the exact minimiser of Zhang's weighted eq. (8)"
)


def _hypotheses(J: int, max_hypotheses: int, seed) -> np.ndarray:
    """Index pairs (H, 2): all ``J (J - 1) / 2`` pairs, or a seeded subset of ``max_hypotheses``."""
    pairs = np.array(list(combinations(range(J), 2)))
    if len(pairs) <= max_hypotheses:
        return pairs
    rng = np.random.default_rng(seed)
    return pairs[np.sort(rng.choice(len(pairs), size=max_hypotheses, replace=False))]


@register("robust", reference=REFERENCE, min_motions=3)
def robust(motions, *, threshold_deg: float = 5.0, max_hypotheses: int = 200, seed: int = 0,
           irls_iterations: int = 10):
    """Outlier-robust ``R0``: MSAC consensus over two-pair samples, then Cauchy IRLS.

    1. Hypotheses: Park & Martin's rotation for every pair of motions ``(j, k)``
       (all of them if ``J (J - 1) / 2 <= max_hypotheses``, else a seeded subset).
    2. Score (MSAC): ``sum_j min(r_j, t)^2`` with ``r_j`` the residual angle
       (:func:`replication.handeye.pair_residual_deg`) and ``t = threshold_deg``; keep the best.
    3. IRLS: weights ``w_j = 1 / (1 + (r_j / c)^2)`` (Cauchy, ``c = threshold_deg / 2``)
       and the exact minimiser of ``sum_j w_j ||A_j R - R B_j||_F^2`` on SO(3),
       ``irls_iterations`` times.

    It is deterministic for a given ``seed`` (which only matters when the pairs
    are subsampled) and equivariant under changes of camera or sensor frame.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        ``J >= 3``: with two pairs there is no redundancy to vote with (or a
        :class:`~replication.motions.Motions` as ``A``).
    threshold_deg : float
        Inlier threshold on the residual angle. The default, 5 deg, is above
        the residual of an inlier in the paper's simulation (camera and sensor
        noise add up to at most ``2 x 1.15`` deg) and well below a mismatched pair.
    max_hypotheses : int
        Most two-pair samples scored per problem.
    seed : int
        Seeds the subset of samples when there are more than ``max_hypotheses``.
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
    idx = _hypotheses(J, int(max_hypotheses), seed)  # (H, 2)
    alpha, beta = log_map(A), log_map(B)  # Park & Martin: alpha_j = R0 beta_j
    M = np.einsum("...hka,...hkb->...hab", alpha[..., idx, :], beta[..., idx, :])
    R_h = nearest_rotation(M)  # (..., H, 3, 3): one hypothesis per sample
    r = pair_residual_deg(R_h, A[..., None, :, :, :], B[..., None, :, :, :])  # (..., H, J)
    score = np.sum(np.minimum(r, threshold_deg) ** 2, axis=-1)  # MSAC
    best = np.argmin(score, axis=-1)
    R = np.take_along_axis(R_h, best[..., None, None, None], axis=-3)[..., 0, :, :]
    c = 0.5 * threshold_deg
    for _ in range(int(irls_iterations)):
        w = 1.0 / (1.0 + (pair_residual_deg(R, A, B) / c) ** 2)  # Cauchy weights
        R = chordal_newton(kronecker_operator(A, B, weights=w), R)[0]  # weighted eq. (8)
    return R
