"""The global minimiser of the paper's cost (8) over SO(3) and its certificate of global optimality:
the maths. Theory and measured numbers: ``docs/methods.md``, section
``replication.core.solvers.certificate``."""
from __future__ import annotations

import warnings

import numpy as np

from ..checks import check_init, det3
from ..handeye import handeye_cost, unvec, vec
from ..kernels import eigvalsh3, solve3
from ..motions import Motions
from ..so3 import matrix_from_rotation_vector, nearest_rotation_up_to_sign, skew
from ._sdp import relaxation, upper_bound
from ._warnings import CertificateWarning
from .result import Solution

__all__ = ["chordal_newton", "global_certificate", "certified_solution", "relaxed_rotation", "GAP_TOL"]

#: Duality gap, per motion pair, below which an answer is certified globally optimal: the cost (8)
#: of the answer exceeds the certified lower bound by at most ``GAP_TOL * J``.
GAP_TOL = 1e-8

_GENERATORS = skew(np.eye(3))  # [e_k]x, k = 1, 2, 3


def _vee_asym(P):
    """``vee(P - P^T)``: the vector ``w`` with ``<P, [w]x> = w . vee(P - P^T)``."""
    return np.stack([P[..., 2, 1] - P[..., 1, 2], P[..., 0, 2] - P[..., 2, 0], P[..., 1, 0] - P[..., 0, 1]], -1)


def _derivatives(M, R):
    """``g(R)``, its Riemannian gradient (..., 3) and Hessian (..., 3, 3); see the module notes."""
    x = vec(R)
    y = np.einsum("...ab,...b->...a", M, x)
    g = np.einsum("...a,...a->...", x, y)
    P = np.swapaxes(R, -1, -2) @ unvec(y)
    grad = 2.0 * _vee_asym(P)
    D = vec(R[..., None, :, :] @ _GENERATORS)  # (..., 3, 9): row k = vec(R [e_k]x)
    Ps = 0.5 * (P + np.swapaxes(P, -1, -2))
    tr = np.trace(P, axis1=-2, axis2=-1)[..., None, None]
    hess = 2.0 * ((D @ M) @ np.swapaxes(D, -1, -2)) + 2.0 * (Ps - tr * np.eye(3))  # D M D^T: two products
    return g, grad, hess


def chordal_newton(K, init, *, max_iterations: int = 30, gradient_tol: float = 1e-10):
    """Riemannian Newton for ``min_R 2J(3 - vec(R)^T sym(K) vec(R))`` on SO(3), batched.

    Parameters
    ----------
    K : ndarray, shape (..., 9, 9)
        A (possibly weighted) mean of ``B_j kron A_j``.
    init : ndarray, shape (..., 3, 3)
        Start rotations; batch dimensions broadcast against ``K``'s.
    max_iterations : int
    gradient_tol : float
        Stop when the gradient of ``g`` (the cost divided by ``-2J``) is below this.

    Returns
    -------
    (R, g, grad, hess, iterations)
        Final rotations and ``g``'s value, gradient and Hessian there.
    """
    init = np.asarray(init, dtype=float)
    batch = np.broadcast_shapes(K.shape[:-2], init.shape[:-2])
    M = np.broadcast_to(0.5 * (K + np.swapaxes(K, -1, -2)), batch + (9, 9))
    R = np.array(np.broadcast_to(init, batch + (3, 3)))
    iterations = np.zeros(batch, dtype=int)
    g, grad, hess = _derivatives(M, R)
    for _ in range(max_iterations):
        active = np.linalg.norm(grad, axis=-1) > gradient_tol
        if not active.any():
            break
        # Newton step for the minimisation of -g: (-H) w = grad, with -H made positive definite
        Hn = -hess
        lam = eigvalsh3(Hn)[..., 0]
        shift = np.where(lam < 1e-3, 1e-3 - lam, 0.0)[..., None, None] * np.eye(3)
        w = solve3(Hn + shift, grad)
        step = np.ones(w.shape[:-1])
        for _ in range(30):  # backtracking: accept a step only if g does not decrease
            R_new = R @ matrix_from_rotation_vector(w * step[..., None])
            g_new, grad_new, hess_new = _derivatives(M, R_new)
            ok = g_new >= g - 1e-15 * np.abs(g)
            if ok.all():
                break
            step = np.where(ok, step, 0.5 * step)
        take = active & ok
        R = np.where(take[..., None, None], R_new, R)
        g = np.where(take, g_new, g)
        grad = np.where(take[..., None], grad_new, grad)
        hess = np.where(take[..., None, None], hess_new, hess)
        iterations += take
        if not take.any():
            break
    return R, g, grad, hess, iterations


def _lagrangian_upper_bound(M, R):
    """Upper bound on ``max g`` over O(3) from the multiplier ``Lambda = sym(R^T unvec(M vec
    R))``."""
    P = np.swapaxes(R, -1, -2) @ unvec(np.einsum("...ab,...b->...a", M, vec(R)))
    Lam = 0.5 * (P + np.swapaxes(P, -1, -2))
    # vec(R Lambda) = (Lambda kron I) vec(R) for symmetric Lambda (column-major vec)
    S = np.einsum("...ab,ij->...aibj", Lam, np.eye(3)).reshape(Lam.shape[:-2] + (9, 9)) - M
    # every rotation: g = x^T (Lambda kron I) x - x^T S x <= tr(Lambda) - 3 lambda_min(S)
    return np.trace(Lam, axis1=-2, axis2=-1) - 3.0 * np.linalg.eigvalsh(S)[..., 0]


def _chordal_core(m: Motions, *, init=None, max_iterations: int = 30, gradient_tol: float = 1e-10,
                  hessian_tol: float = 0.0, certify: bool = True) -> Solution:
    """:func:`chordal_optimal` on validated motions."""
    K, J, M = m.K, m.J, m.sym
    start = _relaxed_from_vectors(m.sym_eigh[1]) if init is None else check_init(init, m.batch_shape)
    R, g, grad, hess, its = chordal_newton(K, start, max_iterations=max_iterations, gradient_tol=gradient_tol)
    grad_norm = np.linalg.norm(grad, axis=-1)
    hmin = eigvalsh3(-hess)[..., 0]
    local = (grad_norm <= gradient_tol) & (hmin > hessian_tol)
    upper = np.full(R.shape[:-2], np.nan)
    how = np.full(R.shape[:-2], "none", dtype=object)
    if certify:
        upper = np.asarray(_lagrangian_upper_bound(M, R), dtype=float)  # step 1 (fast path)
        ok = 2.0 * J * (upper - g) <= GAP_TOL * J
        how[ok] = "lagrangian"
        if not ok.all():
            R, g, upper, how = _sdp_fallback(K, M, J, R, g, upper, how, ~ok)  # step 2
            # the fallback may have replaced R: judge stationarity at the final answer (else
            # Newton's stands)
            _, grad, hess = _derivatives(np.broadcast_to(M, R.shape[:-2] + (9, 9)), R)
            grad_norm = np.linalg.norm(grad, axis=-1)
            hmin = eigvalsh3(-hess)[..., 0]
            local = (grad_norm <= gradient_tol) & (hmin > hessian_tol)
    gap = np.clip(2.0 * J * (upper - g), 0.0, None)
    cost = np.clip(2.0 * J * (3.0 - g), 0.0, None)  # eq. (8) on SO(3)
    res = Solution(
        R=R, method="chordal_optimal", cost=cost, lower_bound=cost - gap if certify else upper,
        duality_gap=gap if certify else upper, global_optimum=(gap <= GAP_TOL * J) & local & certify,
        certificate=how.astype(str), iterations=its, gradient_norm=2.0 * grad_norm,
        hessian_min_eigenvalue=2.0 * hmin, local_minimum=local, _motions=m,
    )
    if certify and not res.global_optimum.all():
        bad = ~res.global_optimum
        loose = bad & ~local
        causes = []
        if np.any(loose):
            causes.append(f"{int(loose.sum())} are not at a stationary point (Newton stopped after "
                          f"{max_iterations} iterations; gradient up to {float(np.max(2.0 * grad_norm[loose])):.3g} J)")
        if np.any(bad & local):
            causes.append(f"for {int((bad & local).sum())} the semidefinite relaxation was not tight (duality gap up "
                          f"to {float(np.max(gap[bad & local])):.3g} > {GAP_TOL:g} J): a local minimum that may not "
                          f"be global")
        warnings.warn(
            f"chordal_optimal could not certify the global minimum of eq. (8) for {int(bad.sum())} of "
            f"{bad.size} problems: " + "; ".join(causes),
            CertificateWarning, stacklevel=3,
        )
    return res


def _sdp_fallback(K, M, J, R, g, upper, how, todo):
    """Step 2 of the certificate for the problems in ``todo``: relaxation, polish, keep the better
    minimum."""
    if not todo.any():
        return R, g, upper, how
    R, g, upper, how = (np.array(a) for a in (np.broadcast_to(R, todo.shape + (3, 3)), g, upper, how))
    idx = [tuple(i) for i in np.argwhere(todo)]
    solved = [relaxation(M[i]) for i in idx]
    K_todo = np.stack([K[i] for i in idx])
    R_sdp, g_sdp = chordal_newton(K_todo, np.stack([r[1] for r in solved]))[:2]  # polish the relaxed answer
    for n, i in enumerate(idx):
        if g_sdp[n] > g[i]:
            R[i], g[i] = R_sdp[n], g_sdp[n]
        bound = upper_bound(M[i], R[i], solved[n][0])
        if np.isfinite(bound) and bound < upper[i]:
            upper[i] = bound
        if 2.0 * J * (upper[i] - g[i]) <= GAP_TOL * J:
            how[i] = "sdp"
    return R, g, upper, how


def global_certificate(motions: Motions) -> Solution:
    """:func:`chordal_optimal` with default options on prepared motions, computed once per
    :class:`Motions`.

    Raises ``ValueError`` for degenerate motion (see
    :meth:`replication.core.motions.Motions.require`).
    """
    motions.require()
    return motions._cached("chordal_optimal", lambda: _chordal_core(motions))


def _gap_to_global(motions: Motions, R: np.ndarray, cert=None):
    """``(cost, lower_bound, gap)`` of estimates ``R`` against the certified minimum of eq. (8)."""
    cert = global_certificate(motions) if cert is None else cert
    J = motions.J
    x = vec(R)
    g = np.einsum("...a,...ab,...b->...", x, motions.sym, x)
    # gap = f(R) - lower bound, computed as 2J (g_upper - g) to avoid cancelling two costs near 2J *
    # 3
    gap = np.clip(2.0 * J * (3.0 - g) - cert.lower_bound, 0.0, None)
    return handeye_cost(R, motions.A, motions.B), cert.lower_bound, gap


def certified_solution(method: str, motions: Motions, R: np.ndarray, *, certify: bool = True,
                       **fields) -> Solution:
    """``method``'s answer ``R`` on ``motions`` as a :class:`Solution`: its cost (8) and its gap to
    the certified global minimum (what :func:`replication.core.solvers.solve` returns with
    ``full_output=True``); ``fields`` fills the rest (``iterations``, ``history``).

    No gap where ``R`` is not in SO(3) (a NaN block, a declared failure, or a reflection): the
    minimum is over SO(3). ``certify=False``: no certificate (``lower_bound`` and ``duality_gap``
    NaN, ``certificate`` ``"none"``, ``global_optimum`` False), as ``chordal_optimal(...,
    certify=False)``.
    """
    finite = np.isfinite(R).all(axis=(-2, -1))
    outside = ~finite | (det3(np.where(finite[..., None, None], R, np.eye(3))) < 0)
    if certify:
        cost, lower, gap = _gap_to_global(motions, R)
        how = global_certificate(motions).certificate
    else:
        cost, lower, gap = handeye_cost(R, motions.A, motions.B), np.full(finite.shape, np.nan), np.nan
        how = np.full(finite.shape, "none")
    gap = np.where(outside, np.nan, gap)  # no gap to the minimum over SO(3) from outside it: not certified
    return Solution(R=R, method=method, cost=cost, lower_bound=lower, duality_gap=gap,
                    global_optimum=gap <= GAP_TOL * motions.J, certificate=how, _motions=motions, **fields)


def relaxed_rotation(K) -> np.ndarray:
    """The relaxed minimiser of eq. (8), projected onto SO(3), from ``K`` (see :func:`andreff`).

    Parameters
    ----------
    K : ndarray, shape (..., 9, 9)
        A (possibly weighted) mean of ``B_j kron A_j``
        (:func:`replication.core.handeye.kronecker_operator`).

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    M = 0.5 * (K + np.swapaxes(K, -1, -2))
    return _relaxed_from_vectors(np.linalg.eigh(M)[1][..., :, ::-1])


def _relaxed_from_vectors(vecs) -> np.ndarray:
    """:func:`relaxed_rotation` from the eigenvectors of ``sym(K)``, columns by descending
    eigenvalue (as :attr:`replication.core.motions.Motions.sym_eigh` holds them: one decomposition
    serves the start and the eigenvalues every solver's checks need)."""
    # eigenvector of the largest eigenvalue of sym(K); it has no sign, so take the one with det > 0
    return nearest_rotation_up_to_sign(unvec(vecs[..., :, 0]))
