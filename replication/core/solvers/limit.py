"""The limit of the paper's two-step iteration in closed form: the top singular vectors of ``K``.

One full iteration (eqs. (14)-(15)) is a power-method step with ``K^T K`` (see
:mod:`replication.core.solvers.iteration`), so the raw iterates tend to ``c v1`` (``R^l``) and
``c sigma_1 u1`` (``R^r``), ``c = sign <R^l_0, v1>``; the estimates are their SVD projections
(eqs. (16)-(17)). The limit is unique only if ``sigma_1 > sigma_2``: never with ``J = 2``.
"""
from __future__ import annotations

import numpy as np

from ..checks import _first_index, check_init
from ..handeye import unvec, vec
from ..motions import Motions, prepare_motions
from ..so3 import nearest_rotation, nearest_rotation_up_to_sign

__all__ = ["two_step_fixed_point", "REPEATED_TOL", "VARIANTS"]

VARIANTS = ("corrected", "paper")
#: ``1 - sigma_2 / sigma_1`` of ``K`` at or below which the top singular value counts as repeated
#: (no unique limit). The limit's rounding error is about ``eps / (sigma_1 - sigma_2)``.
REPEATED_TOL = 1e-8


def _project(X: np.ndarray, variant: str) -> np.ndarray:
    # eqs. (16)-(17); the paper-literal variant keeps eq. (17) as printed (U A^T, no det handling);
    # the corrected one multiplies by sign(det) first (see module notes)
    if variant == "paper":
        return nearest_rotation(X, enforce_det=False)
    return nearest_rotation_up_to_sign(X)


def _check_variant(variant: str) -> None:
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")


def _fixed_point(m: Motions, init: np.ndarray, variant: str):
    """Projected limits ``(right, left)`` and the signed unit limits ``(u, v)`` from the top
    singular vectors of ``K`` (:attr:`~replication.core.motions.Motions.top_singular_vectors`, one
    ``eigh`` of ``K^T K``)."""
    u1, _, v1 = m.top_singular_vectors
    # the iteration keeps the sign of <init, v1>; u1 is paired with v1 (K v1 = sigma1 u1)
    c = np.where(np.einsum("...i,...i->...", vec(init), v1) < 0, -1.0, 1.0)[..., None]
    u, v = c * u1, c * v1
    return _project(unvec(u), variant), _project(unvec(v), variant), u, v


def _first(mask) -> str:
    idx = _first_index(mask)
    return f" (first at batch index {idx})" if idx else ""


def _check_unique_limit(m: Motions) -> None:
    """Raise ``ValueError`` where the top singular value of ``K`` is repeated (the limit depends on
    the start)."""
    if m.J == 2:
        raise ValueError(
            "the two-step iteration cannot determine R0 from J = 2 motion pairs: the top singular value of K "
            "is then triple whatever the motions (K^T K has the eigenvalue 1 on R0 span{I, c c^T, [c]x}, c the "
            "axis of B_1^T B_2), so the limit is R0 Rot(c, phi) with phi set by the start. Add motion pairs, or "
            "use a solver that needs only two non-parallel motions (chordal_optimal, park_martin, andreff)"
        )
    s = m.singular_values
    gap = 1.0 - s[..., 1] / s[..., 0]
    repeated = gap <= REPEATED_TOL
    if np.any(repeated):
        raise ValueError(
            f"the two-step iteration has no unique limit for {int(np.sum(repeated))} of {repeated.size} "
            f"problems{_first(repeated)}: the top singular value of K is repeated (sigma_2 / sigma_1 = 1 - "
            f"{float(np.min(gap)):.2g}, at most 1 - {REPEATED_TOL:g}), so the limit depends on the start. The "
            f"relative motions B_1^T B_j are tiny or nearly share one axis (RMS motion "
            f"{float(np.min(m.rms_motion_deg[repeated] if repeated.ndim else m.rms_motion_deg)):.3g} deg); add larger "
            f"motions about other axes, or use chordal_optimal"
        )


def two_step_fixed_point(A, B=None, init=None, *, variant: str = "corrected"):
    """Limits of the projected two-step iterates, from the top singular vectors of ``K``.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
        Camera / sensor relative rotations (see :func:`two_step`), or a
        :class:`~replication.core.motions.Motions` as ``A`` (``B=None``).
    init : None or array_like, shape (..., 3, 3)
        ``R^l_{0,0}``; only the sign of ``<init, v1>`` matters, and only for
        ``variant="paper"``.
    variant : {"corrected", "paper"}

    Returns
    -------
    (right, left) : tuple of ndarray, shape (..., 3, 3)
        Limits of ``R^r_{0,n}`` and ``R^l_{0,n}``: the projections of the top
        left (``u1``) and right (``v1``) singular vectors of ``K``. Where the top
        singular value is repeated (e.g. motions about one axis) the limit depends on
        the start and this is one of them (see the module notes).
    """
    _check_variant(variant)
    m = prepare_motions(A, B, require_observable=False)
    return _fixed_point(m, check_init(init, m.batch_shape), variant)[:2]
