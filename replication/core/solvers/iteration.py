"""The paper's two-step iteration (Sec. II-B, eqs. (11)-(19)). Theory and measured numbers:
``docs/methods.md``, section ``replication.core.solvers.iteration``."""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..checks import check_init, det3
from ..handeye import handeye_cost_kron, unvec, vec
from ..kernels import eigvalsh3
from ..motions import Motions, prepare_motions
from ..so3 import angle_deg_from_chordal, frobenius_error
from ._registry import register, warn_if_weak
from ._warnings import AccuracyWarning, ConvergenceWarning, IterationCapWarning
from .certificate import certified_solution
from .limit import REPEATED_TOL, _check_unique_limit, _check_variant, _fixed_point, _project
from .result import Solution

__all__ = ["TwoStepHistory", "two_step"]

REFERENCE = (
    "Z.-Q. Zhang, 'Cameras and Inertial/Magnetic Sensor Units Alignment Calibration', "
    "Sec. II-B, eqs. (11)-(19)"
)
#: ``|<init, v1>| / ||init||`` below which a start counts as orthogonal to the limit.
ORTHOGONAL_TOL = 1e-8


@dataclass(frozen=True)
class TwoStepHistory:
    """The per-iteration history of :func:`two_step` (its :class:`Solution`'s ``history``);
    iteration ``n = 1 .. N`` is index ``n - 1``.

    With ``iterations="auto"`` only the final estimate is kept (``N`` axis of length 1)
    and the solution's ``iterations`` says how many iterations each problem took.

    Attributes
    ----------
    right, left : ndarray, shape (..., N, 3, 3)
        Projected estimates ``R^r_{0,n}`` and ``R^l_{0,n}`` (eqs. (16)-(19)).
    right_raw, left_raw : ndarray, shape (..., N, 3, 3)
        Raw iterates of eqs. (14) and (15), before projection (``"auto"``: unit-norm
        iterates, or the singular vectors where the limit came from the closed form).
    cost_right, cost_left : ndarray, shape (..., N)
        Cost of eq. (8) at the projected estimates.
    init : ndarray, shape (..., 3, 3)
        ``R^l_{0,0}``.
    fixed_point_right, fixed_point_left : ndarray, shape (..., 3, 3)
        Where the projected iterates converge (from the top singular vectors of ``K``).
    variant : str
    closed_form : ndarray of bool, shape (...)
        ``"auto"`` only: the estimate is the closed-form limit (the iteration would have
        needed more than its cap); always False for a fixed ``N``.
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
    variant: str
    closed_form: np.ndarray

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
        return angle_deg_from_chordal(dist)


def _history(m: Motions, init: np.ndarray, iterations: int, variant: str, keep: bool = True):
    """The paper's protocol: exactly ``iterations`` steps, every raw iterate recorded (``keep``) or
    the last only."""
    K = m.K
    Kt = np.swapaxes(K, -1, -2)  # vec(H1^+ H2V(Y H2)) = K^T vec(Y)
    # The printed iteration never rescales: its iterates shrink like sigma_1(K)^(2n) and, with
    # inconsistent data (sigma_1 well below 1, e.g. outlier pairs), underflow to 0 after a few
    # hundred iterations. We iterate on unit vectors and carry the scale separately; the projections
    # (16)-(19) are scale-invariant, and the recorded raw iterates are the printed ones (scale *
    # unit vector).
    x_l = vec(init)  # R^l_{0,0}: step 1, n = 1
    scale = np.ones(K.shape[:-2])
    unit_r, unit_l, scales_r, scales_l = [], [], [], []
    for n in range(iterations):
        x_r = np.einsum("...ab,...b->...a", K, x_l)  # eq. (14): R^r_n = V2H(H1 R^l_{n-1}) H2^+
        n_r = np.linalg.norm(x_r, axis=-1)
        x_r, scale = x_r / n_r[..., None], scale * n_r
        x_l = np.einsum("...ab,...b->...a", Kt, x_r)  # eq. (15): R^l_n = H1^+ H2V(R^r_n H2)
        if keep or n == iterations - 1:
            unit_r.append(x_r)
            scales_r.append(scale)
        n_l = np.linalg.norm(x_l, axis=-1)
        x_l, scale = x_l / n_l[..., None], scale * n_l
        if keep or n == iterations - 1:
            unit_l.append(x_l)
            scales_l.append(scale)
    unit = unvec(np.stack(unit_r + unit_l, axis=-2))  # (..., 2N, 3, 3): one SVD call for both sides
    scales = np.stack(scales_r + scales_l, axis=-1)[..., None, None]
    projected = _project(unit, variant)  # eqs. (16)-(19)
    N = len(unit_r)
    return projected[..., :N, :, :], projected[..., N:, :, :], (unit * scales)[..., :N, :, :], \
        (unit * scales)[..., N:, :, :]


def _auto(m: Motions, init: np.ndarray, variant: str, fp_r, fp_l, u, v, tol: float, cap: int):
    """Iterate until the projected estimates are within ``tol`` of their limits, at most ``cap``
    iterations.

    Returns ``(right, left, raw_right, raw_left, n_iterations, closed_form, orthogonal)`` over the
    flattened batch. Problems that do not converge within ``cap`` get the closed-form limits.
    """
    batch = m.batch_shape
    n = int(np.prod(batch, dtype=int))
    K = m.K.reshape(n, 9, 9)
    Kt = np.swapaxes(K, -1, -2)
    fr, fl = fp_r.reshape(n, 3, 3), fp_l.reshape(n, 3, 3)
    uf, vf = u.reshape(n, 9), v.reshape(n, 9)
    x = vec(init).reshape(n, 9)
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    orthogonal = np.abs(np.einsum("ni,ni->n", x, vf)) < ORTHOGONAL_TOL
    # a unit iterate within d of the unit limit is projected within about lip * d of the projected
    # limit; sigma_2 + sigma_3 of unvec(v) from the closed-form eigenvalues of its Gram matrix (no
    # 3x3 SVD per problem)
    V = unvec(vf)
    ev = np.sqrt(np.clip(eigvalsh3(np.swapaxes(V, -1, -2) @ V), 0.0, None))
    lip = 2.0 / (ev[:, 1] + ev[:, 0])
    R_r, R_l = fr.copy(), fl.copy()
    raw_r, raw_l = unvec(uf).copy(), unvec(vf).copy()
    its = np.zeros(n, dtype=int)
    done = orthogonal.copy()
    active = np.flatnonzero(~done)
    xa = x[active]
    # the active problems' operators and limits, gathered again only when problems leave (not every
    # iteration)
    Ka, Kta, lip_a, ua, va, fra, fla = (a[active] for a in (K, Kt, lip, uf, vf, fr, fl))
    k, next_check = 0, 1
    while active.size and k < cap:
        xr = np.einsum("nab,nb->na", Ka, xa)  # eq. (14)
        xr /= np.linalg.norm(xr, axis=-1, keepdims=True)
        xa = np.einsum("nab,nb->na", Kta, xr)  # eq. (15)
        xa /= np.linalg.norm(xa, axis=-1, keepdims=True)
        k += 1
        # cheap test every iteration (distance of the unit vectors), projected test on a geometric
        # schedule
        vec_close = lip_a * np.maximum(np.linalg.norm(xr - ua, axis=-1), np.linalg.norm(xa - va, axis=-1)) <= tol
        if vec_close.all() or k >= next_check or k == cap:
            next_check = k + max(1, k // 4)
            Pr, Pl = _project(unvec(xr), variant), _project(unvec(xa), variant)  # eqs. (16)-(19)
            dist = np.maximum(np.linalg.norm(Pr - fra, axis=(-2, -1)), np.linalg.norm(Pl - fla, axis=(-2, -1)))
            conv = vec_close | (dist <= tol)
            if conv.any():
                idx = active[conv]
                R_r[idx], R_l[idx] = Pr[conv], Pl[conv]
                raw_r[idx], raw_l[idx] = unvec(xr[conv]), unvec(xa[conv])
                its[idx] = k
                done[idx] = True
                keep = ~conv
                active, xa = active[keep], xa[keep]
                Ka, Kta, lip_a, ua, va, fra, fla = (a[keep] for a in (Ka, Kta, lip_a, ua, va, fra, fla))
    its[active] = k
    closed = ~done | orthogonal
    shape = lambda a, tail: a.reshape(batch + tail)
    return (shape(R_r, (3, 3)), shape(R_l, (3, 3)), shape(raw_r, (3, 3)), shape(raw_l, (3, 3)),
            shape(its, ()), shape(closed, ()), shape(orthogonal, ()))


def _warn_closed_form(m: Motions, closed, orthogonal, cap: int, tol: float, stacklevel: int) -> None:
    if not np.any(closed):
        return
    ratio = m.observability.spectral_ratio
    slow = closed & ~orthogonal
    causes = []
    if np.any(slow):
        worst = float(np.max(ratio[slow]))
        rate = float(np.max(m.observability.two_step_rate[slow]))
        causes.append(
            f"{int(np.sum(slow))} would need more than {cap} iterations (measured: sigma_2 / sigma_1 of K up to "
            f"{worst:.6g}, so the raw iterate's error shrinks by its square per iteration; projected-error rate "
            f"sigma_max(mean_j B_j)^2 up to {rate:.6g})"
        )
    if np.any(orthogonal):
        causes.append(
            f"{int(np.sum(orthogonal))} started orthogonal to the limit (|<init, v1>| / ||init|| < "
            f"{ORTHOGONAL_TOL:g}), from which the iteration cannot reach it"
        )
    s = m.singular_values
    gap = np.where(closed, 1.0 - s[..., 1] / s[..., 0], np.inf)
    precision = np.finfo(float).eps / float(np.min(gap))
    warnings.warn(
        f"two_step: of {np.size(closed)} problems, {' and '.join(causes)}; their estimate is the iteration's "
        f"limit computed in closed form from the top singular vectors of K, determined by rounding to about "
        f"eps / (1 - sigma_2 / sigma_1) = {precision:.1g} (relative)",
        IterationCapWarning, stacklevel=stacklevel,
    )


def _two_step_core(m: Motions, *, iterations="auto", init=None, variant: str = "corrected",
                   convergence_tol_deg: float = 1e-3, tol: float = 1e-12, cap: int = 1000, history: bool = True,
                   stacklevel: int = 3) -> tuple[TwoStepHistory, np.ndarray]:
    """:func:`two_step` on validated motions: its history and the iterations run per problem."""
    _check_variant(variant)
    auto = isinstance(iterations, str)
    if auto and iterations != "auto":
        raise ValueError(f"iterations must be a positive integer or 'auto', got {iterations!r}")
    if not auto and (int(iterations) != iterations or iterations < 1):
        raise ValueError(f"iterations must be a positive integer or 'auto', got {iterations!r}")
    if int(cap) != cap or cap < 1:
        raise ValueError(f"cap must be a positive integer, got {cap!r}")
    if not tol > 0:
        raise ValueError(f"tol must be positive, got {tol!r}")
    if variant == "corrected":  # the paper has no guard against degenerate motion; nor has "paper"
        m.require(observable=True)
    if auto:
        _check_unique_limit(m)
    init = check_init(init, m.batch_shape)
    fp_r, fp_l, u, v = _fixed_point(m, init, variant)
    observability = m.observability
    if auto:
        right, left, raw_r, raw_l, its, closed, orthogonal = _auto(m, init, variant, fp_r, fp_l, u, v, tol, int(cap))
        _warn_closed_form(m, closed, orthogonal, int(cap), tol, stacklevel + 1)
        right, left, raw_r, raw_l = (a[..., None, :, :] for a in (right, left, raw_r, raw_l))
    else:
        iterations = int(iterations)
        right, left, raw_r, raw_l = _history(m, init, iterations, variant, keep=bool(history))
        its = np.full(m.batch_shape, iterations)
        closed = np.zeros(m.batch_shape, dtype=bool)
    K_it, J = m.K[..., None, :, :], m.J
    result = TwoStepHistory(
        right=right,
        left=left,
        right_raw=raw_r,
        left_raw=raw_l,
        cost_right=handeye_cost_kron(right, K_it, J),  # eq. (8)
        cost_left=handeye_cost_kron(left, K_it, J),
        init=init,
        fixed_point_right=fp_r,
        fixed_point_left=fp_l,
        variant=variant,
        closed_form=closed,
    )
    if not auto:
        gap = result.distance_to_fixed_point_deg
        late = gap > convergence_tol_deg
        if np.any(late):
            ratio = float(np.max(observability.spectral_ratio[late]))
            rate = float(np.max(observability.two_step_rate[late]))
            need = float(np.max(observability.iterations_for(1e-8)[late]))
            if m.J == 2 or 1.0 - ratio <= REPEATED_TOL:
                warnings.warn(
                    f"two_step stopped {float(np.max(gap)):.3g} deg from the projected top singular vector of K after "
                    f"{iterations} iterations ({int(np.sum(late))} of {gap.size} problems), but that limit is not "
                    f"unique: the top singular value of K is repeated (J = {m.J}; sigma_2 / sigma_1 = {ratio:.6g}), "
                    f"so the iteration settles on a start-dependent point",
                    ConvergenceWarning, stacklevel=stacklevel)
                return result, its
            warnings.warn(
                f"two_step stopped {float(np.max(gap)):.3g} deg from its fixed point after {iterations} "
                f"iterations ({int(np.sum(late))} of {gap.size} problems); the motions need about {need:.3g} "
                f"iterations (measured: projected-error rate sigma_max(mean_j B_j)^2 up to {rate:.6g}, "
                f"sigma_2 / sigma_1 of K up to {ratio:.6g}); use iterations='auto' for the limit",
                ConvergenceWarning,
                stacklevel=stacklevel,
            )
    return result, its


def two_step(
    A,
    B=None,
    *,
    iterations="auto",
    init=None,
    variant: str = "corrected",
    convergence_tol_deg: float = 1e-3,
    tol: float = 1e-12,
    cap: int = 1000,
    history: bool = True,
    certify: bool = True,
) -> Solution:
    """The paper's two-step iteration (eqs. (11)-(19)), run to its limit or for a fixed count.

    Solves ``A_j R0 = R0 B_j`` (eq. (7)) for ``R0`` = camera_from_sensor, with
    ``A_j = Delta R_{c,j}`` (camera) and ``B_j = Delta R_{i,j}`` (sensor).

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3), or Motions
        Camera relative rotations; ``H1`` of eq. (11) stacks them (or prepared motions, ``B=None``).
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations; ``H2`` of eq. (12) puts them side by side.
    iterations : "auto" or int
        ``"auto"`` (default): iterate until the projected estimates are within ``tol``
        (Frobenius) of the iteration's limit; problems that would need more than ``cap``
        iterations (or start orthogonal to the limit) get the closed-form limit, with an
        :class:`IterationCapWarning` naming the measured cause; only the final estimate
        is recorded. An integer ``N >= 1``: the paper's protocol, exactly ``N`` iterations
        (steps 2-4), every iterate recorded.
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
        Fixed ``N`` only: a :class:`ConvergenceWarning` is issued when a final estimate
        is farther than this from the iteration's fixed point.
    tol : float
        ``"auto"`` only: convergence threshold on ``||R_n - R_limit||_F``.
    cap : int
        ``"auto"`` only: most iterations before finishing from the closed form.
    history : bool
        Fixed ``N`` only: record (and project) every iterate (default), or only the last one
        (the lean run the paper's timing claim is about; the ``N`` axis then has length 1).
    certify : bool
        Compare the estimate with the certified global minimum of eq. (8) (default; as
        :func:`replication.core.solvers.solve` does with ``full_output=True``). ``False``: no
        certificate (``lower_bound`` and ``duality_gap`` NaN, ``global_optimum`` False), the lean
        run timed against SQP. With ``variant="paper"`` a batch holding degenerate motion is not
        certified (its minimum is not unique): ``certificate`` is ``"none"``.

    Returns
    -------
    Solution
        ``R`` is the final ``R^r`` (eq. (18)), what ``two_step_right`` returns (``method``
        ``"two_step_right"``); its cost (8), its gap to the certified global minimum (the
        two-step fixed point is not that minimum once there is noise), the observability
        diagnostic, ``iterations`` (run per problem) and ``history``, a :class:`TwoStepHistory`
        (both estimates of every recorded iteration; the final ``R^l`` of eq. (19), what
        ``two_step_left`` returns, is ``history.R_left``).

    Raises
    ------
    ValueError
        Malformed input (shapes, NaN, non-rotations, ``J < 2``), degenerate
        motion (all rotation axes parallel; ``variant="corrected"`` only), a bad
        ``iterations``, ``init``, ``variant``, ``tol`` or ``cap``; with ``"auto"``
        also ``J = 2`` or a repeated top singular value of ``K`` (no unique limit).

    Examples
    --------
    >>> import numpy as np
    >>> from replication.core.so3 import random_rotations
    >>> rng = np.random.default_rng(0)
    >>> R0 = random_rotations(rng, ())
    >>> A = random_rotations(rng, 20)
    >>> B = R0.T @ A @ R0            # Delta R_i = R0^T Delta R_c R0
    >>> res = two_step(A, B)         # iterations="auto": run to the limit
    >>> bool(np.linalg.norm(res.R - R0) < 1e-9), int(res.iterations) < 50
    (True, True)
    >>> len(two_step(A, B, iterations=30).history.right)   # the paper's protocol: every iterate
    30
    """
    m = prepare_motions(A, B, require_observable=False)
    if variant == "corrected":
        m.require()
        warn_if_weak(m)
    steps, its = _two_step_core(m, iterations=iterations, init=init, variant=variant,
                                convergence_tol_deg=convergence_tol_deg, tol=tol, cap=cap, history=history)
    if variant == "paper":
        for R in (steps.R_right, steps.R_left):
            if np.any(det3(R) < 0):
                warnings.warn(
                    f"two_step (variant='paper') returned a reflection (det -1), not a rotation, in "
                    f"{int(np.sum(det3(R) < 0))} of {np.size(det3(R))} problems: the printed algorithm fails so from a "
                    f"start more than 120 deg from R0; variant='corrected' (the default) does not",
                    AccuracyWarning, stacklevel=2)
                break
        if certify:
            try:
                m.require()
            except ValueError:  # degenerate motion: no unique minimum to certify
                certify = False
    return certified_solution("two_step_right", m, steps.R_right, certify=certify, iterations=its, history=steps)


@register("two_step_right", reference=REFERENCE + ", estimate R^r (eq. (18))", min_motions=3)
def _solve_two_step_right(motions, **options):
    return _two_step_core(motions, stacklevel=4, **options)[0].R_right


@register("two_step_left", reference=REFERENCE + ", estimate R^l (eq. (19))", min_motions=3)
def _solve_two_step_left(motions, **options):
    return _two_step_core(motions, stacklevel=4, **options)[0].R_left
