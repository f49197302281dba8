"""The cost (8) as a quadratic in ``vec(R)``, computed here independently of the solvers' own code:
its constant Hessian, that Hessian's spectrum over problems (is the cost convex?), and the cost's
gradient and Hessian on SO(3) at given rotations (is an end point a strict local minimum?)."""
from __future__ import annotations

import numpy as np

from ...core.checks import check_rotation_matrices
from ...core.handeye import vec
from ...core.so3 import skew

__all__ = ["cost_hessian_vec", "cost_convexity", "cost_derivatives_on_so3"]

_GENERATORS = skew(np.eye(3))  # [e_k]x, k = 1, 2, 3


def _kron(P, Q):
    """``P kron Q`` of 3x3 matrices, batched: (..., 9, 9)."""
    return np.einsum("...ab,...cd->...acbd", P, Q).reshape(np.broadcast_shapes(P.shape[:-2], Q.shape[:-2]) + (9, 9))


def cost_hessian_vec(A, B) -> np.ndarray:
    """The Hessian of eq. (8), ``f(X) = sum_j ||A_j X - X B_j||_F^2``, in ``vec(X)`` for any 3x3
    ``X``.

    ``f(X) = vec(X)^T H vec(X) / 2`` with ``H = 2 sum_j L_j^T L_j``, ``L_j = I kron A_j - B_j^T kron
    I`` (column-major ``vec``, :func:`replication.core.handeye.vec`): a constant, positive
    semi-definite matrix, so ``f`` is a convex quadratic on the 9-dimensional space of 3x3 matrices.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)

    Returns
    -------
    ndarray, shape (..., 9, 9)
    """
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    if A.shape != B.shape or A.shape[-2:] != (3, 3) or A.ndim < 3:
        raise ValueError(f"A and B must have the same shape (..., J, 3, 3), got {A.shape} and {B.shape}")
    L = _kron(np.eye(3), A) - _kron(np.swapaxes(B, -1, -2), np.eye(3))
    return 2.0 * np.einsum("...jka,...jkb->...ab", L, L)


def cost_convexity(A, B, tol: float = 1e-12) -> dict:
    """The spectrum of :func:`cost_hessian_vec` over problems: is eq. (8) convex in ``vec(R)``?

    Returns ``problems``, ``PSD`` (problems whose smallest eigenvalue is at least ``-tol * J``:
    positive semi-definite to rounding), ``smallest / J (min)``, ``smallest / J (max)`` and
    ``largest / J (max)``.
    """
    A = np.asarray(A, dtype=float)
    J = A.shape[-3]
    eig = np.linalg.eigvalsh(cost_hessian_vec(A, B)).reshape(-1, 9) / J
    return {"problems": len(eig), "PSD": int(np.sum(eig[:, 0] >= -tol)), "smallest / J (min)": float(eig[:, 0].min()),
            "smallest / J (max)": float(eig[:, 0].max()), "largest / J (max)": float(eig[:, -1].max())}


def cost_derivatives_on_so3(A, B, R):
    """Eq. (8) at rotations ``R`` and the gradient and Hessian of ``w -> f(R exp([w]x))`` at ``w =
    0``.

    Computed from :func:`cost_hessian_vec` alone (not from the solvers' code): with ``f(X) = x^T H x
    / 2``, ``x = vec(X)``, ``g = H vec(R)`` and ``D_k = vec(R [e_k]x)``, the gradient is ``D_k^T g``
    and the Hessian ``D_k^T H D_l + g^T vec(R ([e_k]x [e_l]x + [e_l]x [e_k]x) / 2)``. The first term
    is positive semi-definite (the convex cost); the second is the constraint's curvature. At a
    stationary point this is the Riemannian Hessian of (8) on SO(3): positive definite there means a
    strict local minimum.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
    R : array_like, shape (..., 3, 3)
        Rotations; leading dimensions broadcast against ``A``'s batch dimensions (e.g. a starts axis
        in front).

    Returns
    -------
    (cost, gradient, hessian) : ndarrays (...), (..., 3), (..., 3, 3)
    """
    H = cost_hessian_vec(A, B)
    R = check_rotation_matrices(R, "R")
    x = vec(R)
    g = np.einsum("...ab,...b->...a", H, x)
    cost = 0.5 * np.einsum("...a,...a->...", x, g)
    D = vec(R[..., None, :, :] @ _GENERATORS)  # (..., 3, 9)
    pairs = _GENERATORS[:, None] @ _GENERATORS[None]  # [e_k]x [e_l]x, (3, 3, 3, 3)
    curvature = vec(R[..., None, None, :, :] @ (0.5 * (pairs + np.swapaxes(pairs, 0, 1))))  # (..., 3, 3, 9)
    gradient = np.einsum("...ka,...a->...k", D, g)
    hessian = np.einsum("...ka,...ab,...lb->...kl", D, H, D) + np.einsum("...kla,...a->...kl", curvature, g)
    return cost, gradient, hessian
