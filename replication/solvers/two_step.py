"""The paper's two-step iteration (Sec. II-B, eqs. (11)-(19)).

Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment Calibration".

With ``H1`` (eq. (11)) the camera rotations stacked vertically and ``H2``
(eq. (12)) the sensor rotations side by side, the iteration is

* eq. (14): ``R^r_n = V2H(H1 R^l_{n-1}) H2^+``
* eq. (15): ``R^l_n = H1^+ H2V(R^r_n H2)``

followed by the SVD projection of eqs. (16)-(17). Because every block is a
rotation, ``H2^+ = H2^T / J`` and ``H1^+ = H1^T / J``; eq. (14) is then the
linear map ``T(X) = (1/J) sum_j A_j X B_j^T`` and eq. (15) its adjoint ``T*``.
In ``vec`` form ``T`` is the 9x9 matrix ``K`` of
:func:`replication.handeye.kronecker_operator`, and one full iteration
``R^l_{n-1} -> R^l_n`` is one power-method step with ``K^T K``.

What that implies (demonstrated in ``notebooks/01_derivation_check.ipynb``):

* the raw iterates converge to ``c * v1`` (and ``R^r`` to ``c * sigma_1 * u1``),
  with ``v1``/``u1`` the top right/left singular vectors of ``K`` and
  ``c = <R^l_0, v1>``; noise-free ``v1 = u1 = vec(R0)/sqrt(3)``;
* if ``c < 0`` the raw iterate tends to ``-|c| R0``, whose SVD projection is
  not ``R0`` (Theorem 1 fails); ``variant="corrected"`` multiplies the raw
  iterate by ``sign(det)`` before projecting, which removes the failure;
* the error components shrink by ``(sigma_2 / sigma_1)^2`` per iteration.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..handeye import MotionObservability, handeye_cost_kron, prepare_motions, unvec, vec
from ..so3 import (
    check_rotation_matrices, chordal_to_angle_deg, frobenius_error, nearest_rotation, nearest_rotation_up_to_sign,
)
from ._registry import register

__all__ = ["TwoStepResult", "ConvergenceWarning", "two_step", "two_step_fixed_point", "two_step_iterations"]

REFERENCE = (
    "Z.-Q. Zhang, 'Cameras and Inertial/Magnetic Sensor Units Alignment Calibration', "
    "Sec. II-B, eqs. (11)-(19)"
)
VARIANTS = ("corrected", "paper")


class ConvergenceWarning(RuntimeWarning):
    """The two-step iteration stopped before reaching its fixed point."""


@dataclass(frozen=True)
class TwoStepResult:
    """Per-iteration output of :func:`two_step`; iteration ``n = 1 .. N`` is index ``n - 1``.

    Attributes
    ----------
    right, left : ndarray, shape (..., N, 3, 3)
        Projected estimates ``R^r_{0,n}`` and ``R^l_{0,n}`` (eqs. (16)-(19)).
    right_raw, left_raw : ndarray, shape (..., N, 3, 3)
        Raw iterates of eqs. (14) and (15), before projection.
    cost_right, cost_left : ndarray, shape (..., N)
        Cost of eq. (8) at the projected estimates.
    init : ndarray, shape (..., 3, 3)
        ``R^l_{0,0}``.
    fixed_point_right, fixed_point_left : ndarray, shape (..., 3, 3)
        Where the projected iterates converge (from the SVD of ``K``).
    observability : MotionObservability
    variant : str
    """

    right: np.ndarray
    left: np.ndarray
    right_raw: np.ndarray
    left_raw: np.ndarray
    cost_right: np.ndarray
    cost_left: np.ndarray
    init: np.ndarray
    fixed_point_right: np.ndarray
    fixed_point_left: np.ndarray
    observability: MotionObservability
    variant: str

    @property
    def R_right(self) -> np.ndarray:
        """Final estimate from ``R^r`` (eq. (18)), shape (..., 3, 3)."""
        return self.right[..., -1, :, :]

    @property
    def R_left(self) -> np.ndarray:
        """Final estimate from ``R^l`` (eq. (19)), shape (..., 3, 3)."""
        return self.left[..., -1, :, :]

    @property
    def distance_to_fixed_point_deg(self) -> np.ndarray:
        """Largest angle (deg) between a final estimate and its fixed point, shape (...).

        Computed as ``2 arcsin(||R - F||_F / (2 sqrt 2))``, the rotation angle of
        ``F^T R`` for rotations, and still defined for the reflections that
        ``variant="paper"`` can return.
        """
        dist = np.maximum(
            frobenius_error(self.R_right, self.fixed_point_right),
            frobenius_error(self.R_left, self.fixed_point_left),
        )
        return chordal_to_angle_deg(dist)


def _project(X: np.ndarray, variant: str) -> np.ndarray:
    # eqs. (16)-(17); the paper-literal variant keeps eq. (17) as printed (U A^T, no det handling);
    # the corrected one multiplies by sign(det) first (see module notes)
    if variant == "paper":
        return nearest_rotation(X, enforce_det=False)
    return nearest_rotation_up_to_sign(X)


def _check_init(init, batch_shape: tuple) -> np.ndarray:
    if init is None:
        return np.broadcast_to(np.eye(3), batch_shape + (3, 3))
    init = check_rotation_matrices(init, "init")
    try:
        return np.broadcast_to(init, batch_shape + (3, 3))
    except ValueError:
        raise ValueError(
            f"init must have shape (3, 3) or broadcast to the batch shape {batch_shape + (3, 3)}, "
            f"got {init.shape}"
        ) from None


def two_step_fixed_point(A, B, init=None, *, variant: str = "corrected"):
    """Limits of the projected two-step iterates, from the SVD of ``K``.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera / sensor relative rotations (see :func:`two_step`).
    init : None or array_like, shape (..., 3, 3)
        ``R^l_{0,0}``; only the sign of ``<init, v1>`` matters, and only for
        ``variant="paper"``.
    variant : {"corrected", "paper"}

    Returns
    -------
    (right, left) : tuple of ndarray, shape (..., 3, 3)
        Limits of ``R^r_{0,n}`` and ``R^l_{0,n}``: the projections of the top
        left (``u1``) and right (``v1``) singular vectors of ``K``.
    """
    _check_variant(variant)
    _, _, K, _ = prepare_motions(A, B, require_observable=False)
    init = _check_init(init, K.shape[:-2])
    return _fixed_point(K, init, variant)


def two_step_iterations(A, B, *, reduction: float = 1e-10, cap: int = 20000) -> int:
    """Iterations the two-step method needs to reach its fixed point on every problem of a batch.

    From :meth:`replication.handeye.MotionObservability.iterations_for` with
    ``inconsistent=True`` (also covers outlier pairs), at least 50 (the paper's count) and
    at most ``cap``.
    """
    obs = prepare_motions(A, B, require_observable=False)[3]
    need = obs.iterations_for(reduction, inconsistent=True)
    return int(np.clip(np.ceil(np.max(need)), 50, cap))


def _fixed_point(K: np.ndarray, init: np.ndarray, variant: str):
    U, _, Vt = np.linalg.svd(K)
    u1, v1 = U[..., :, 0], Vt[..., 0, :]
    # the iteration keeps the sign of <init, v1>; u1 is paired with v1 (K v1 = sigma1 u1)
    c = np.where(np.einsum("...i,...i->...", vec(init), v1) < 0, -1.0, 1.0)
    right = _project(unvec(c[..., None] * u1), variant)
    left = _project(unvec(c[..., None] * v1), variant)
    return right, left


def _check_variant(variant: str) -> None:
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")


def two_step(
    A,
    B,
    *,
    iterations: int,
    init=None,
    variant: str = "corrected",
    convergence_tol_deg: float = 1e-3,
) -> TwoStepResult:
    """The paper's two-step iteration, every iterate recorded (eqs. (11)-(19)).

    Solves ``A_j R0 = R0 B_j`` (eq. (7)) for ``R0`` = camera_from_sensor, with
    ``A_j = Delta R_{c,j}`` (camera) and ``B_j = Delta R_{i,j}`` (sensor).

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3)
        Camera relative rotations; ``H1`` of eq. (11) stacks them.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations; ``H2`` of eq. (12) puts them side by side.
    iterations : int
        Number ``N >= 1`` of iterations (steps 2-4 of the paper).
    init : None or array_like, shape (3, 3) or (..., 3, 3)
        ``R^l_{0,0}``, a rotation. The paper does not state it; ``None`` means the
        identity.
    variant : {"corrected", "paper"}
        ``"paper"``: exactly as printed — raw iterates projected by eq. (17)
        ``U A^T`` (may be a reflection), no check for degenerate motion.
        ``"corrected"`` (default): the raw iterate is multiplied by
        ``sign(det)`` and projected onto SO(3), and degenerate motion raises.
        The two agree whenever ``<init, R0> > 0`` and the motions are not
        degenerate; see the module notes.
    convergence_tol_deg : float
        A :class:`ConvergenceWarning` is issued when a final estimate is farther
        than this from the iteration's fixed point (too few iterations for the
        motions' ``spectral_ratio``).

    Returns
    -------
    TwoStepResult

    Raises
    ------
    ValueError
        Malformed input (shapes, NaN, non-rotations, ``J < 2``), degenerate
        motion (all rotation axes parallel; ``variant="corrected"`` only),
        ``iterations < 1``, a bad ``init`` or ``variant``.

    Examples
    --------
    >>> import numpy as np
    >>> from replication.so3 import random_rotations
    >>> rng = np.random.default_rng(0)
    >>> R0 = random_rotations(rng, ())
    >>> A = random_rotations(rng, 20)
    >>> B = R0.T @ A @ R0            # Delta R_i = R0^T Delta R_c R0
    >>> res = two_step(A, B, iterations=30)
    >>> bool(np.linalg.norm(res.R_right - R0) < 1e-9)
    True
    """
    _check_variant(variant)
    if int(iterations) != iterations or iterations < 1:
        raise ValueError(f"iterations must be a positive integer, got {iterations!r}")
    iterations = int(iterations)
    # K: vec(V2H(H1 X) H2^+) = K vec(X). The paper has no guard against degenerate motion; nor has "paper".
    A, B, K, observability = prepare_motions(A, B, require_observable=(variant == "corrected"))

    Kt = np.swapaxes(K, -1, -2)  # vec(H1^+ H2V(Y H2)) = K^T vec(Y)
    init = _check_init(init, K.shape[:-2])

    # The printed iteration never rescales: its iterates shrink like sigma_1(K)^(2n) and, with
    # inconsistent data (sigma_1 well below 1, e.g. outlier pairs), underflow to 0 after a few hundred
    # iterations. We iterate on unit vectors and carry the scale separately; the projections (16)-(19)
    # are scale-invariant, and the recorded raw iterates are the printed ones (scale * unit vector).
    x_l = vec(init)  # R^l_{0,0}: step 1, n = 1
    scale = np.ones(K.shape[:-2])
    unit_r, unit_l, scales_r, scales_l = [], [], [], []
    for _ in range(iterations):
        x_r = np.einsum("...ab,...b->...a", K, x_l)  # eq. (14): R^r_n = V2H(H1 R^l_{n-1}) H2^+
        n_r = np.linalg.norm(x_r, axis=-1)
        x_r, scale = x_r / n_r[..., None], scale * n_r
        unit_r.append(x_r)
        scales_r.append(scale)
        x_l = np.einsum("...ab,...b->...a", Kt, x_r)  # eq. (15): R^l_n = H1^+ H2V(R^r_n H2)
        n_l = np.linalg.norm(x_l, axis=-1)
        x_l, scale = x_l / n_l[..., None], scale * n_l
        unit_l.append(x_l)
        scales_l.append(scale)
    unit_r = unvec(np.stack(unit_r, axis=-2))
    unit_l = unvec(np.stack(unit_l, axis=-2))
    right_raw = unit_r * np.stack(scales_r, axis=-1)[..., None, None]
    left_raw = unit_l * np.stack(scales_l, axis=-1)[..., None, None]

    right = _project(unit_r, variant)  # eqs. (16)-(18)
    left = _project(unit_l, variant)  # eqs. (16), (17), (19)
    K_it, J = K[..., None, :, :], A.shape[-3]
    fp_right, fp_left = _fixed_point(K, init, variant)
    result = TwoStepResult(
        right=right,
        left=left,
        right_raw=right_raw,
        left_raw=left_raw,
        cost_right=handeye_cost_kron(right, K_it, J),  # eq. (8)
        cost_left=handeye_cost_kron(left, K_it, J),
        init=init,
        fixed_point_right=fp_right,
        fixed_point_left=fp_left,
        observability=observability,
        variant=variant,
    )
    gap = result.distance_to_fixed_point_deg
    if np.any(gap > convergence_tol_deg):
        need = float(np.max(observability.iterations_for(1e-8)))
        hint = (f"the motions need about {need:.0f} iterations (small or nearly single-axis motions)"
                if np.isfinite(need) else "it never converges: the motions share a rotation axis")
        warnings.warn(
            f"two_step stopped {float(np.max(gap)):.3g} deg from its fixed point after {iterations} "
            f"iterations ({int(np.sum(gap > convergence_tol_deg))} of {gap.size} problems); {hint}",
            ConvergenceWarning,
            stacklevel=2,
        )
    return result


@register("two_step_right", reference=REFERENCE + ", estimate R^r (eq. (18))")
def _solve_two_step_right(A, B, *, iterations: int = 50, **options):
    return two_step(A, B, iterations=iterations, **options).R_right


@register("two_step_left", reference=REFERENCE + ", estimate R^l (eq. (19))")
def _solve_two_step_left(A, B, *, iterations: int = 50, **options):
    return two_step(A, B, iterations=iterations, **options).R_left
