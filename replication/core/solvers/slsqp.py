"""SQP baseline: problem (8)-(10) solved by SciPy's SLSQP, with per-iteration history. Theory and
measured numbers: ``docs/methods.md``, section ``replication.core.solvers.slsqp``."""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from ..checks import check_init
from ..handeye import handeye_cost_kron, unvec, vec
from ..motions import Motions, prepare_motions
from ..so3 import nearest_rotation
from ._registry import check_local_answer, register, warn_if_weak
from ._warnings import ConvergenceWarning
from .certificate import certified_solution
from .result import Solution

__all__ = ["SQPHistory", "sqp", "SQP_VARIANTS"]

#: Named SQP settings (options of :func:`sqp`); see the module notes.
SQP_VARIANTS = {
    "analytic": {"gradient": "analytic"},
    "finite-difference": {"gradient": "finite-difference"},
    "capped": {"gradient": "finite-difference", "ftol": 1e-6, "max_iterations": 30},
    "per-pair cost": {"gradient": "analytic", "cost": "per-pair"},
}

REFERENCE = (
    "Problem (8)-(10) of Z.-Q. Zhang's paper, solved by sequential quadratic programming "
    "(D. Kraft, 'A software package for sequential quadratic programming', DFVLR-FB 88-28, 1988; "
    "scipy.optimize.minimize(method='SLSQP'))"
)
_UPPER = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


@dataclass(frozen=True)
class SQPHistory:
    """The per-iteration history of :func:`sqp` (its :class:`Solution`'s ``history``); iteration
    ``n = 1 .. N`` is index ``n - 1``.

    Attributes
    ----------
    iterates : ndarray, shape (..., N, 3, 3)
        SLSQP's iterate after each major iteration (raw, possibly infeasible).
        A run that stopped after ``n < N`` iterations repeats its last iterate.
    projected : ndarray, shape (..., N, 3, 3)
        ``nearest_rotation(iterates)``.
    cost : ndarray, shape (..., N)
        Eq. (8) at the raw iterates.
    n_evaluations : ndarray of int, shape (...)
        Objective evaluations SLSQP used (its major iterations: the solution's ``iterations``).
    success : ndarray of bool, shape (...)
        SLSQP's own convergence flag.
    message : ndarray of str, shape (...)
        SLSQP's exit message.
    """

    iterates: np.ndarray
    projected: np.ndarray
    cost: np.ndarray
    n_evaluations: np.ndarray
    success: np.ndarray
    message: np.ndarray


def _constraints(kind: str, analytic: bool = True):
    def orth(x):
        R = unvec(x)
        M = R @ R.T - np.eye(3)
        return np.array([M[a, b] for a, b in _UPPER])  # eq. (9)

    def orth_jac(x):
        R = unvec(x)
        jac = np.zeros((6, 9))
        for row, (a, b) in enumerate(_UPPER):
            G = np.zeros((3, 3))  # d (R R^T)_ab / dR = e_a R_b + e_b R_a (rows)
            G[a] += R[b]
            G[b] += R[a]
            jac[row] = vec(G)
        return jac

    def det(x):
        return np.array([np.linalg.det(unvec(x)) - 1.0])  # eq. (10)

    def det_jac(x):
        R = unvec(x)
        cof = np.stack([np.cross(R[1], R[2]), np.cross(R[2], R[0]), np.cross(R[0], R[1])])
        return vec(cof)[None, :]

    cons = [{"type": "eq", "fun": orth, "jac": orth_jac}]
    if kind == "paper":
        cons.append({"type": "eq", "fun": det, "jac": det_jac})
    if not analytic:  # SciPy approximates the constraint Jacobians by finite differences as well
        cons = [{"type": c["type"], "fun": c["fun"]} for c in cons]
    return cons


def _sqp_one(K, J, init, max_iterations, ftol, cons, analytic, scale):
    sym = K + K.T
    c = 2.0 * J * scale

    def f(x):
        # eq. (8) as in handeye_cost_kron (times ``scale``), written out on the flat vector: it runs
        # in SLSQP's inner loop, and the recorded histories (chaotic when SQP diverges) depend on
        # its rounding
        return c * (x @ x - x @ K @ x)

    def grad(x):
        return c * (2.0 * x - sym @ x)

    history = []
    out = minimize(
        f, vec(init), jac=grad if analytic else None, method="SLSQP", constraints=cons,
        callback=lambda xk: history.append(np.array(xk, dtype=float)),
        options={"maxiter": max_iterations, "ftol": ftol},
    )
    if not history:
        history = [np.asarray(out.x, dtype=float)]
    n_it = len(history)
    history += [history[-1]] * (max_iterations - n_it)
    return np.stack(history[:max_iterations]), n_it, int(out.nfev), bool(out.success), str(out.message)


def sqp(A, B=None, *, init=None, max_iterations: int = 100, ftol: float = 1e-12,
        constraints: str = "orthonormal", gradient: str = "analytic", cost="sum") -> Solution:
    """Solve problem (8)-(10) by SLSQP from ``init``, recording every iteration.

    SQP is a local method: from a start far from ``R0`` it can reach its iteration
    limit far from the minimum (notebooks 03, 05 and 07; how often depends on the scale of
    the objective, ``cost``), or converge to one of the other strict local minima of eq. (8)
    over SO(3) (notebooks 03 and 06). Its answer is therefore checked against the certified global
    minimum of eq. (8) (:func:`replication.core.solvers.chordal_optimal`), and a
    :class:`~replication.core.solvers.LocalMinimumWarning` names the problems where it is
    not that minimum; a :class:`~replication.core.solvers.ConvergenceWarning` names those
    where SLSQP itself reports no convergence (e.g. its iteration limit).

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3), or Motions
        Camera relative rotations ``Delta R_c`` (or prepared motions, ``B=None``).
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    init : None or array_like, shape (3, 3) or (..., 3, 3)
        Start, a rotation; ``None`` = identity (as for the two-step method).
    max_iterations : int
        SLSQP ``maxiter``; the history has this length.
    ftol : float
        SLSQP ``ftol`` (precision goal on the objective).
    constraints : {"orthonormal", "paper"}
        ``"orthonormal"`` (default): eq. (9) only; ``"paper"``: eqs. (9) and (10)
        literally (linearly dependent at rotations; see the module notes).
    gradient : {"analytic", "finite-difference"}
        Analytic gradients (default) or SciPy's finite differences (see the module notes).
    cost : {"sum", "per-pair"} or float
        The objective SLSQP sees: eq. (8) as printed, a sum over the ``J`` pairs (default), divided
        by ``2J`` (``"per-pair"``), or multiplied by a positive number; the minimiser is the same.
        SLSQP is not invariant to the objective's scale (its first Hessian estimate is the identity,
        ``ftol`` is absolute), so its path, speed and failures change with it (notebook 03); the
        paper does not say which scale its SQP saw. The solution's ``cost`` and its history's are
        eq. (8) as printed either way.

    Returns
    -------
    Solution
        ``R`` is the last iterate projected onto SO(3), what ``solve("sqp", ...)`` returns; its cost
        (8) and gap to the certified global minimum, the observability diagnostic,
        ``iterations`` (SLSQP's major iterations) and ``history``, an :class:`SQPHistory` (every
        iterate, raw and projected, SLSQP's evaluations, flag and message).

    Raises
    ------
    ValueError
        Malformed or degenerate input, bad ``init``, ``max_iterations < 1``,
        unknown ``constraints`` or ``gradient``.
    """
    m = prepare_motions(A, B)
    warn_if_weak(m)
    steps, its = _sqp_core(m, init=init, max_iterations=max_iterations, ftol=ftol, constraints=constraints,
                           gradient=gradient, cost=cost)
    R = steps.projected[..., -1, :, :]
    check_local_answer(m, R, "sqp", stacklevel=3)
    return certified_solution("sqp", m, R, iterations=its, history=steps)


def _sqp_core(m: Motions, *, init=None, max_iterations: int = 100, ftol: float = 1e-12,
              constraints: str = "orthonormal", gradient: str = "analytic", cost="sum",
              stacklevel: int = 3) -> tuple[SQPHistory, np.ndarray]:
    """:func:`sqp` on validated motions (without the global-minimum check, which the door does): its
    history and SLSQP's major iterations per problem."""
    if isinstance(cost, str):
        if cost not in ("sum", "per-pair"):
            raise ValueError(f"cost must be 'sum', 'per-pair' or a positive number, got {cost!r}")
        scale = 1.0 if cost == "sum" else 1.0 / (2.0 * m.J)
    else:
        scale = float(cost)
        if not (np.isfinite(scale) and scale > 0):
            raise ValueError(f"cost must be 'sum', 'per-pair' or a positive number, got {cost!r}")
    if constraints not in ("paper", "orthonormal"):
        raise ValueError(f"constraints must be 'paper' or 'orthonormal', got {constraints!r}")
    if gradient not in ("analytic", "finite-difference"):
        raise ValueError(f"gradient must be 'analytic' or 'finite-difference', got {gradient!r}")
    analytic = gradient == "analytic"
    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise ValueError(f"max_iterations must be a positive integer, got {max_iterations!r}")
    if not ftol > 0:
        raise ValueError(f"ftol must be positive, got {ftol!r}")
    max_iterations = int(max_iterations)
    K, batch, J = m.K, m.batch_shape, m.J
    init = check_init(init, batch)
    cons = _constraints(constraints, analytic)
    flat_K, flat_init = K.reshape(-1, 9, 9), init.reshape(-1, 3, 3)
    runs = [_sqp_one(flat_K[n], J, flat_init[n], max_iterations, ftol, cons, analytic, scale)
            for n in range(len(flat_K))]
    iterates = unvec(np.stack([r[0] for r in runs])).reshape(batch + (max_iterations, 3, 3))
    res = SQPHistory(
        iterates=iterates,
        projected=nearest_rotation(iterates),
        cost=handeye_cost_kron(iterates, K[..., None, :, :], J),
        n_evaluations=np.array([r[2] for r in runs]).reshape(batch),
        success=np.array([r[3] for r in runs]).reshape(batch),
        message=np.array([r[4] for r in runs]).reshape(batch),
    )
    if not res.success.all():
        failed = ~res.success
        reasons = sorted(set(res.message[failed].ravel().tolist()))
        warnings.warn(
            f"SLSQP stopped without converging in {int(failed.sum())} of {failed.size} problems "
            f"({'; '.join(reasons)}; max_iterations = {max_iterations})",
            ConvergenceWarning, stacklevel=stacklevel,
        )
    return res, np.array([r[1] for r in runs]).reshape(batch)


@register("sqp", reference=REFERENCE, local=True)
def _solve_sqp(motions, **options):
    return _sqp_core(motions, stacklevel=4, **options)[0].projected[..., -1, :, :]
