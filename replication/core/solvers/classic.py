"""Classic closed-form solvers of the rotation part of hand-eye calibration ``A X = X B``. Theory
and measured numbers: ``docs/methods.md``, section ``replication.core.solvers.classic``."""
from __future__ import annotations

import numpy as np

from ..kernels import bottom_eigenvector4, solve3
from ..so3 import (
    matrix_from_quaternion,
    matrix_from_rotation_vector,
    nearest_rotation,
    quaternion_from_rotation_vector,
    skew,
)
from ._registry import register
from .certificate import _relaxed_from_vectors

__all__ = ["park_martin", "horaud_dornaika", "andreff", "tsai_lenz"]


@register(
    "park_martin",
    reference="F. C. Park and B. J. Martin, 'Robot sensor calibration: solving AX = XB on the "
    "Euclidean group', IEEE Trans. Robotics and Automation 10(5), 1994, eqs. (10)-(15)",
)
def park_martin(motions):
    """Park & Martin (1994): log map, then orthogonal Procrustes.

    ``A_j X = X B_j`` implies ``alpha_j = X beta_j`` for the rotation vectors
    ``alpha_j = log A_j``, ``beta_j = log B_j``. Park & Martin minimise
    ``sum_j ||X beta_j - alpha_j||^2`` with ``M = sum_j beta_j alpha_j^T`` and
    ``X = (M^T M)^{-1/2} M^T``. We use the equivalent SVD (Kabsch) form
    ``X = nearest_rotation(sum_j alpha_j beta_j^T)``, which also works for
    ``J = 2`` (``M`` of rank 2) and always returns det +1.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera and sensor relative rotations, ``J >= 2`` with non-parallel axes (or a
        :class:`~replication.core.motions.Motions` as ``A``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor``.
    """
    alpha, beta = motions.rotation_vectors  # Park & Martin eq. (10): alpha_j = log A_j, beta_j = log B_j
    # then alpha_j = X beta_j
    M = np.einsum("...ja,...jb->...ab", alpha, beta)  # sum_j alpha_j beta_j^T = M^T of eq. (13)
    return nearest_rotation(M)  # eq. (15): X = (M^T M)^{-1/2} M^T, as the SO(3) Procrustes solution


def _multiplication_matrix(q, side: str):
    """``L(q)`` with ``q * p = L(q) p`` (``side="left"``) or ``W(q)`` with ``p * q = W(q) p``
    (``"right"``).

    Scalar-first quaternions, batched: (..., 4) -> (..., 4, 4). The two differ only in the sign of
    the cross-product block (Horaud & Dornaika's ``Q`` and ``W``, their Appendix A).
    """
    w, x, y, z = np.moveaxis(q, -1, 0)
    s = 1.0 if side == "left" else -1.0
    return np.stack([
        np.stack([w, -x, -y, -z], -1),
        np.stack([x, w, -s * z, s * y], -1),
        np.stack([y, s * z, w, -s * x], -1),
        np.stack([z, -s * y, s * x, w], -1),
    ], -2)


@register(
    "horaud_dornaika",
    reference="R. Horaud and F. Dornaika, 'Hand-eye calibration', Int. J. Robotics Research 14(3), "
    "1995, Sec. 3.2 (unit-quaternion formulation, eqs. (33)-(41))",
)
def horaud_dornaika(motions):
    """Horaud & Dornaika (1995): the rotation as the eigenvector of a 4x4 matrix.

    With unit quaternions ``a_j``, ``b_j``, ``x`` of ``A_j``, ``B_j``, ``X``,
    eq. (7) reads ``a_j * x = x * b_j``, i.e. ``(L(a_j) - W(b_j)) x = 0`` with
    ``L``/``W`` the left/right multiplication matrices. The solution minimises
    ``sum_j ||(L(a_j) - W(b_j)) x||^2`` over ``||x|| = 1``: the eigenvector of
    the smallest eigenvalue of ``S = sum_j (L(a_j) - W(b_j))^T (L(a_j) - W(b_j))``.

    Quaternion signs are fixed by a non-negative scalar part; ``a_j`` and ``b_j``
    then agree in sign because ``A_j`` and ``B_j`` have the same angle. Motions
    of almost exactly 180 deg make that choice ambiguous and such pairs should
    be avoided with this solver.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera and sensor relative rotations (or a :class:`~replication.core.motions.Motions` as
        ``A``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor``.
    """
    a, b = (quaternion_from_rotation_vector(w) for w in motions.rotation_vectors)  # quaternion_from_matrix(A), (B)
    C = _multiplication_matrix(a, "left") - _multiplication_matrix(b, "right")
    # eqs. (33)-(39): a_j * x - x * b_j = C_j x
    S = np.einsum("...jki,...jkl->...il", C, C)  # eq. (40): sum_j C_j^T C_j
    x = bottom_eigenvector4(S)  # eq. (41): eigenvector of the smallest eigenvalue
    return matrix_from_quaternion(x)


@register(
    "andreff",
    reference="N. Andreff, R. Horaud and B. Espiau, 'Robot hand-eye calibration using "
    "structure-from-motion', Int. J. Robotics Research 20(3), 2001, Sec. 3 (eq. (12), rotation part)",
    relaxed_start=True,
)
def andreff(motions):
    """Andreff et al. (2001): Kronecker-product linear system, solved by SVD/eigendecomposition.

    Eq. (7) is linear in ``vec(X)``: ``(I_9 - B_j kron A_j) vec(X) = 0`` (Andreff's
    eq. (12), rotation part, in column-major ``vec``). The least-squares
    solution with ``||vec(X)||^2 = 3`` minimises
    ``sum_j ||(I_9 - B_j kron A_j) x||^2 = 2 J (||x||^2 - x^T K x)`` with
    ``K = (1/J) sum_j B_j kron A_j`` — exactly the paper's cost (8) with SO(3)
    relaxed to the sphere ``||X||_F^2 = 3``. The minimiser is the eigenvector of
    the largest eigenvalue of ``(K + K^T)/2``; it is scaled, its sign chosen for
    ``det > 0`` and it is projected onto SO(3) (Andreff's orthogonalisation).

    Compare the paper's two-step iteration: it converges to the top *singular*
    vector of ``K`` (see :mod:`replication.core.solvers.iteration`); this is the top
    eigenvector of its symmetric part. Noise-free both equal ``vec(R0)/sqrt(3)``.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera and sensor relative rotations (or a :class:`~replication.core.motions.Motions` as
        ``A``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor``.
    """
    return _relaxed_from_vectors(motions.sym_eigh[1])  # eq. (12): null vector of the stacked I - B kron A


@register(
    "tsai_lenz",
    reference="R. Y. Tsai and R. K. Lenz, 'A new technique for fully autonomous and efficient 3D "
    "robotics hand/eye calibration', IEEE Trans. Robotics and Automation 5(3), 1989, eqs. (12)-(14)",
    equivariant=False,
)
def tsai_lenz(motions):
    """Tsai & Lenz (1989): modified Rodrigues parameters and linear least squares.

    With ``P = 2 sin(theta/2) n`` for a rotation by ``theta`` about ``n``
    (``P_a`` for ``A_j``, ``P_b`` for ``B_j``), eq. (7) gives Tsai's linear
    equation ``skew(P_a + P_b) p' = P_b - P_a`` for the Gibbs vector
    ``p' = tan(theta_X / 2) n_X`` of ``X``; it is solved in least squares over
    all ``J`` pairs (normal equations, one 3x3 solve per problem) and turned
    back into a rotation. Same convention as OpenCV's ``calibrateHandEyeTsai``
    with gripper motion = ``A`` and camera motion = ``B``.

    The Gibbs vector is infinite at ``theta_X = 180`` deg: accuracy degrades as
    ``R0`` approaches a half-turn, and a rotation of exactly 180 deg cannot be
    returned. For the same reason the least-squares weighting depends on the
    frames: with noise, re-expressing the camera or sensor frame changes the
    estimate by more than the frame change (not equivariant).

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera and sensor relative rotations (or a :class:`~replication.core.motions.Motions` as
        ``A``).

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``camera_from_sensor``.
    """
    # Tsai eq. (12): P = 2 sin(theta/2) n, the vector part of quaternion_from_matrix(A) (and B)
    # times 2
    Pa, Pb = (2.0 * quaternion_from_rotation_vector(w)[..., 1:] for w in motions.rotation_vectors)
    S = skew(Pa + Pb)  # eq. (12): skew(P_a + P_b) p' = P_b - P_a
    d = Pb - Pa
    StS = np.einsum("...jki,...jkl->...il", S, S)
    Std = np.einsum("...jki,...jk->...i", S, d)
    p = solve3(StS, Std)  # least squares over the J pairs
    norm = np.linalg.norm(p, axis=-1, keepdims=True)
    # eqs. (13)-(14): P_X = 2 p' / sqrt(1 + |p'|^2), i.e. theta_X = 2 atan|p'| about p'/|p'|
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(norm > 0, p / np.where(norm > 0, norm, 1.0), 0.0)
    return matrix_from_rotation_vector(axis * 2.0 * np.arctan(norm))
