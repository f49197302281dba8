"""The rotation-only hand-eye problem ``A X = X B`` of Section II, as linear algebra.

Notation, frames and batching (``A`` camera motions, ``B`` sensor motions, ``X = R0``, shapes
``(..., J, 3, 3)``): ``docs/conventions.md``. Eqs. (3)-(4) are :func:`relative_rotations`.

The two-step iteration of eqs. (14)-(15) is built from the linear operator
``T(X) = (1/J) sum_j A_j X B_j^T`` and its adjoint ``T*(Y) = (1/J) sum_j A_j^T Y B_j``
(see :func:`operator_T`); in column-major ``vec`` form ``T`` is the 9x9 matrix
``K = (1/J) sum_j B_j kron A_j`` (:func:`kronecker_operator`).
"""
from __future__ import annotations

import numpy as np

from .checks import check_matrices, check_rotation_matrices
from .so3 import angle_deg_from_chordal

__all__ = [
    "check_motion_pairs",
    "relative_rotations",
    "stack_H1",
    "stack_H2",
    "v2h",
    "h2v",
    "operator_T",
    "operator_T_adjoint",
    "kronecker_operator",
    "vec",
    "unvec",
    "handeye_cost",
    "handeye_cost_kron",
    "pair_residual_deg",
]


def check_motion_pairs(A, B, *, min_motions: int = 2, atol: float = 1e-6):
    """Validate camera/sensor relative-rotation pairs for ``A X = X B``.

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c``.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``, same shape as ``A``.
    min_motions : int
        Fewest motions ``J`` the caller needs.
    atol : float
        Tolerance of the rotation test (see :func:`check_rotation_matrices`): a finite
        number in ``(0, 1e-2]``.

    Returns
    -------
    (A, B) : tuple of numpy.ndarray

    Raises
    ------
    ValueError
        Wrong shapes, mismatched shapes, ``J < min_motions``, NaN/inf, a
        matrix that is not a rotation (the message names the array and index),
        or ``atol`` out of range (named).
    """
    A = check_matrices(A, "A (camera relative rotations)")
    B = check_matrices(B, "B (sensor relative rotations)")
    if A.ndim < 3 or B.ndim < 3:
        raise ValueError(
            f"A and B must have shape (..., J, 3, 3) with J motions; got A {A.shape}, B {B.shape}"
        )
    if A.shape != B.shape:
        raise ValueError(f"A and B must have the same shape; got A {A.shape}, B {B.shape}")
    J = A.shape[-3]
    if J < min_motions:
        raise ValueError(f"need at least {min_motions} motion pairs (J >= {min_motions}), got J = {J}")
    A = check_rotation_matrices(A, "A (camera relative rotations)", atol)
    B = check_rotation_matrices(B, "B (sensor relative rotations)", atol)
    return A, B


def relative_rotations(orientations, *, reference: int | None = None, pairs=None,
                       convention: str = "body_from_world", atol: float = 1e-6) -> np.ndarray:
    """Relative rotations from absolute orientations (eqs. (3)-(4)).

    The paper's ``C_t`` and ``I_t`` are body-from-world (attitude) matrices: with
    ``v_cam = R0 v_sensor`` for every vector, eq. (1) ``C_t = R0 I_t`` holds. Eq. (3),
    ``C_k = Delta R_c C_t``, gives ``Delta R_c = C_k C_t^T`` (likewise eq. (4) for the
    sensor): the motion from time ``t`` to ``k`` expressed in the body frame.

    Parameters
    ----------
    orientations : array_like, shape (..., N, 3, 3)
        Orientation at each time ``k``.
    reference : int or None
        ``None``: consecutive pairs ``(t, k) = (n, n + 1)``, ``N - 1`` motions.
        An index ``r``: every other time relative to time ``r``, ``N - 1`` motions.
    pairs : (t_index, k_index), optional
        Index arrays of equal length ``M``: the motions from time ``t_index[m]`` to ``k_index[m]``,
        ``M`` motions (instead of ``reference``).
    convention : {"body_from_world", "world_from_body"}
        What ``orientations`` hold. ``"world_from_body"`` (e.g. a SLAM or mocap
        trajectory's quaternions, ``Q_t = C_t^T``) gives ``Delta R = Q_k^T Q_t``.
    atol : float
        Tolerance of the rotation test of ``orientations`` (see
        :func:`~replication.core.checks.check_rotation_matrices`).

    Returns
    -------
    numpy.ndarray, shape (..., N - 1, 3, 3), or (..., M, 3, 3) with ``pairs``
    """
    if convention not in ("body_from_world", "world_from_body"):
        raise ValueError(
            f"convention must be 'body_from_world' or 'world_from_body', got {convention!r}"
        )
    C = check_rotation_matrices(orientations, "orientations", atol)
    if C.ndim < 3 or C.shape[-3] < 2:
        raise ValueError(f"orientations must have shape (..., N, 3, 3) with N >= 2, got {C.shape}")
    if convention == "world_from_body":
        C = np.swapaxes(C, -1, -2)
    Ct = np.swapaxes(C, -1, -2)
    if pairs is not None:
        if reference is not None:
            raise ValueError("give either reference or pairs, not both")
        t_index, k_index = (np.asarray(p) for p in pairs)
        n = C.shape[-3]
        for name, index in (("t_index", t_index), ("k_index", k_index)):
            if index.ndim != 1 or not np.issubdtype(index.dtype, np.integer) and index.size:
                raise ValueError(f"pairs: {name} must be a 1-D array of integers, got {index.dtype} "
                                 f"of shape {index.shape}")
            if index.size and (index.min() < 0 or index.max() >= n):
                raise ValueError(f"pairs: {name} out of range for N = {n} orientations "
                                 f"(min {index.min()}, max {index.max()})")
        if t_index.shape != k_index.shape:
            raise ValueError(f"pairs: t_index and k_index must have the same length, got {len(t_index)} and "
                             f"{len(k_index)}")
        return C[..., k_index, :, :] @ Ct[..., t_index, :, :]  # eq. (3): Delta R = C_k C_t^T
    if reference is None:
        return C[..., 1:, :, :] @ Ct[..., :-1, :, :]  # eq. (3): Delta R = C_k C_t^T
    n = C.shape[-3]
    if not -n <= reference < n:
        raise ValueError(f"reference index {reference} out of range for N = {n}")
    others = [k for k in range(n) if k != reference % n]
    return C[..., others, :, :] @ Ct[..., [reference], :, :]


def stack_H1(A) -> np.ndarray:
    """``H1`` of eq. (11): the camera rotations stacked vertically, shape (..., 3J, 3)."""
    A = check_matrices(A, "A")
    return A.reshape(A.shape[:-3] + (-1, 3))


def stack_H2(B) -> np.ndarray:
    """``H2`` of eq. (12): the sensor rotations side by side, shape (..., 3, 3J)."""
    return v2h(stack_H1(B))


def v2h(M) -> np.ndarray:
    """``V2H``: a (..., 3J, 3) stack of 3x3 blocks to (..., 3, 3J), block by block."""
    M = np.asarray(M, dtype=float)
    if M.shape[-1] != 3 or M.shape[-2] % 3:
        raise ValueError(f"V2H needs shape (..., 3J, 3), got {M.shape}")
    J = M.shape[-2] // 3
    blocks = M.reshape(M.shape[:-2] + (J, 3, 3))
    return np.moveaxis(blocks, -3, -2).reshape(M.shape[:-2] + (3, 3 * J))


def h2v(M) -> np.ndarray:
    """``H2V``: the inverse of :func:`v2h`, (..., 3, 3J) to (..., 3J, 3)."""
    M = np.asarray(M, dtype=float)
    if M.shape[-2] != 3 or M.shape[-1] % 3:
        raise ValueError(f"H2V needs shape (..., 3, 3J), got {M.shape}")
    J = M.shape[-1] // 3
    blocks = M.reshape(M.shape[:-2] + (3, J, 3))
    return np.moveaxis(blocks, -2, -3).reshape(M.shape[:-2] + (3 * J, 3))


def operator_T(A, B, X) -> np.ndarray:
    """``T(X) = (1/J) sum_j A_j X B_j^T`` — the right-hand side of eq. (14).

    Because every block of ``H2`` is a rotation, ``H2 H2^T = J U`` and the
    pseudo-inverse is ``H2^+ = H2^T / J``; then
    ``V2H(H1 X) H2^+ = (1/J) sum_j A_j X B_j^T``.
    """
    return np.mean(A @ X[..., None, :, :] @ np.swapaxes(B, -1, -2), axis=-3)


def operator_T_adjoint(A, B, Y) -> np.ndarray:
    """``T*(Y) = (1/J) sum_j A_j^T Y B_j`` — the right-hand side of eq. (15).

    ``H1^T H1 = J U`` so ``H1^+ = H1^T / J`` and
    ``H1^+ H2V(Y H2) = (1/J) sum_j A_j^T Y B_j``. It is the adjoint of
    :func:`operator_T` in the Frobenius inner product.
    """
    return np.mean(np.swapaxes(A, -1, -2) @ Y[..., None, :, :] @ B, axis=-3)


def vec(X) -> np.ndarray:
    """Column-major vectorisation, (..., 3, 3) -> (..., 9): ``vec(A X B) = (B^T kron A) vec(X)``."""
    X = np.asarray(X, dtype=float)
    return np.swapaxes(X, -1, -2).reshape(X.shape[:-2] + (9,))


def unvec(x) -> np.ndarray:
    """Inverse of :func:`vec`, (..., 9) -> (..., 3, 3)."""
    x = np.asarray(x, dtype=float)
    return np.swapaxes(x.reshape(x.shape[:-1] + (3, 3)), -1, -2)


def kronecker_operator(A, B, weights=None) -> np.ndarray:
    """The 9x9 matrix ``K = (1/J) sum_j B_j kron A_j`` with ``vec(T(X)) = K vec(X)``.

    Each ``B_j kron A_j`` is orthogonal, so ``||K||_2 <= 1``; noise-free,
    ``K vec(R0) = vec(R0)`` (eq. (7)) and ``sigma_1(K) = 1``.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
    weights : None or array_like, shape (..., J)
        Non-negative pair weights: ``K_w = sum_j w_j B_j kron A_j / sum_j w_j``
        (used by robust re-weighting). ``None``: equal weights.

    Returns
    -------
    numpy.ndarray, shape (..., 9, 9)
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    lead, J = A.shape[:-3], A.shape[-3]
    if weights is None:
        w = np.full(lead + (J,), 1.0 / J)
    else:
        w = np.asarray(weights, dtype=float)
        w = w / w.sum(axis=-1, keepdims=True)
    # sum_j w_j B_j[a, b] A_j[c, d] as one (9 x J) @ (J x 9) product per problem, no (J, 9, 9)
    # intermediate
    S = np.swapaxes((B * w[..., None, None]).reshape(lead + (J, 9)), -1, -2) @ A.reshape(lead + (J, 9))
    # (B kron A)[(a, c), (b, d)] = B[a, b] A[c, d]
    return np.swapaxes(S.reshape(lead + (3, 3, 3, 3)), -3, -2).reshape(lead + (9, 9))


def handeye_cost(R, A, B) -> np.ndarray:
    """The cost of eq. (8): ``sum_j ||A_j R - R B_j||_F^2``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Estimate(s) of ``R0``; may carry extra leading dimensions beyond those of
        ``A`` (e.g. an iteration axis), which are broadcast against ``A``/``B``'s
        batch dimensions placed on the left.
    A, B : array_like, shape (..., J, 3, 3)

    Returns
    -------
    numpy.ndarray, shape (...)

    Notes
    -----
    Fig. 4's caption and text print the cost without the square; eq. (8) squares
    it. This function implements eq. (8).
    """
    diff = _pair_differences(R, A, B)
    return np.einsum("...jab,...jab->...", diff, diff)


def _pair_differences(R, A, B) -> np.ndarray:
    """``A_j R - R B_j`` for every pair, shape (..., J, 3, 3); ``R`` broadcast as in
    :func:`handeye_cost`."""
    Rj = np.asarray(R, dtype=float)[..., None, :, :]
    return np.asarray(A, dtype=float) @ Rj - Rj @ np.asarray(B, dtype=float)


def pair_residual_deg(R, A, B) -> np.ndarray:
    """Per-pair residual angle in degrees: the angle of ``R^T A_j R B_j^T``.

    It is 0 when pair ``j`` satisfies eq. (7) exactly, and relates to the pair's
    term of eq. (8) by ``||A_j R - R B_j||_F = 2 sqrt(2) sin(angle / 2)``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    A, B : array_like, shape (..., J, 3, 3)

    Returns
    -------
    numpy.ndarray, shape (..., J)
    """
    diff = _pair_differences(R, A, B)
    return angle_deg_from_chordal(np.sqrt(np.einsum("...ab,...ab->...", diff, diff)))


def handeye_cost_kron(R, K, n_motions: int) -> np.ndarray:
    """Eq. (8) through the operator ``K``: ``2 J (||R||_F^2 - vec(R)^T K vec(R))``.

    Exact for any 3x3 ``R`` (not only rotations) when every ``A_j``, ``B_j`` is a
    rotation, because then ``||A_j R||_F = ||R B_j||_F = ||R||_F`` and
    ``sum_j <A_j R, R B_j> = J vec(R)^T K vec(R)``. Costs one 9x9 quadratic form
    per estimate instead of ``J`` matrix products; absolute rounding error about
    ``1e-14 J`` (cancellation), so use :func:`handeye_cost` for tiny costs.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Estimates; leading dimensions broadcast against ``K``'s.
    K : array_like, shape (..., 9, 9)
        :func:`kronecker_operator` of the motions.
    n_motions : int
        ``J``.
    """
    x = vec(R)
    quad = np.einsum("...a,...ab,...b->...", x, K, x)
    return 2.0 * n_motions * (np.einsum("...a,...a->...", x, x) - quad)
