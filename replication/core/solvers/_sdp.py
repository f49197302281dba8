"""Convex (semidefinite) relaxation of eq. (8) over SO(3), solved by Clarabel: a global lower bound.
Theory and measured numbers: ``docs/methods.md``, section ``replication.core.solvers._sdp``."""
from __future__ import annotations

import numpy as np

from ..handeye import unvec, vec
from ..so3 import nearest_rotation_up_to_sign

__all__ = ["relaxation", "upper_bound"]

_N = 10
#: Clarabel's ``PSDTriangleConeT`` order: the upper triangle, column by column.
_TRIU = [(i, j) for j in range(_N) for i in range(j + 1)]
_OFF = np.array([i != j for i, j in _TRIU])


def _quadratic(terms) -> np.ndarray:
    """The symmetric 10x10 ``A`` with ``y^T A y = sum c y_a y_b`` over ``terms = [(a, b, c),
    ...]``."""
    A = np.zeros((_N, _N))
    for a, b, c in terms:
        A[a, b] += 0.5 * c
        A[b, a] += 0.5 * c
    return A


def _constraints():
    col = lambda i, m: 3 * i + m  # entry m of column i in vec(R) (column-major)
    row = lambda a, m: a + 3 * m  # entry m of row a
    A, b = [_quadratic([(9, 9, 1.0)])], [1.0]  # h^2 = 1
    for i in range(3):
        for j in range(i, 3):
            A.append(_quadratic([(col(i, m), col(j, m), 1.0) for m in range(3)]))  # R^T R = I
            b.append(float(i == j))
            A.append(_quadratic([(row(i, m), row(j, m), 1.0) for m in range(3)]))  # R R^T = I
            b.append(float(i == j))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):  # c_i x c_j = h c_k
        for m in range(3):
            m1, m2 = (m + 1) % 3, (m + 2) % 3
            A.append(_quadratic([(col(i, m1), col(j, m2), 1.0), (col(i, m2), col(j, m1), -1.0),
                                 (9, col(k, m), -1.0)]))
            b.append(0.0)
    return np.stack(A), np.array(b)


_A, _B = _constraints()


def _triu_coefficients(S: np.ndarray) -> np.ndarray:
    """Coefficients of ``tr(S Z)`` in the upper-triangle entries of a symmetric ``Z``."""
    idx = tuple(np.array(_TRIU).T)
    return S[(...,) + idx] * np.where(_OFF, 2.0, 1.0)


def relaxation(M: np.ndarray, *, tol: float = 1e-10):
    """Solve the relaxation for one problem.

    Parameters
    ----------
    M : ndarray, shape (9, 9)
        ``sym(K)`` of the problem.
    tol : float
        Clarabel's gap and feasibility tolerances.

    Returns
    -------
    (lam, R, rank_ratio, status)
        ``lam``: the 22 multipliers (NaN if the solver failed), to be turned into a rigorous
        bound by :func:`upper_bound`; ``R``: the rotation read off the top eigenvector of
        ``Z`` (the global minimiser when the relaxation is tight; a start for a local
        polish); ``rank_ratio``: second over first eigenvalue of ``Z`` (0 when tight);
        ``status``: Clarabel's status.
    """
    import clarabel  # imported here: only problems the fast certificate cannot settle need it
    from scipy import sparse

    Q = _objective(M)
    n_var = len(_TRIU)
    scale = np.where(_OFF, np.sqrt(2.0), 1.0)
    A_eq = _triu_coefficients(_A)
    Acl = sparse.csc_matrix(np.vstack([A_eq, -np.diag(scale)]))  # s = svec(Z) in the PSD cone
    bcl = np.concatenate([_B, np.zeros(n_var)])
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    for name in ("tol_gap_abs", "tol_gap_rel", "tol_feas"):
        setattr(settings, name, tol)
    solver = clarabel.DefaultSolver(sparse.csc_matrix((n_var, n_var)), _triu_coefficients(Q), Acl, bcl,
                                    [clarabel.ZeroConeT(len(_B)), clarabel.PSDTriangleConeT(_N)], settings)
    sol = solver.solve()
    status = str(sol.status)
    z = np.asarray(sol.x, dtype=float)
    lam = -np.asarray(sol.z, dtype=float)[: len(_B)]  # multipliers of tr(A_k Z) = b_k
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(lam))):
        return np.full(len(_B), np.nan), np.eye(3), np.nan, status
    Z = np.zeros((_N, _N))
    for k, (i, j) in enumerate(_TRIU):
        Z[i, j] = Z[j, i] = z[k]
    ev, V = np.linalg.eigh(Z)
    y = V[:, -1] * (1.0 if V[9, -1] >= 0 else -1.0)
    rank_ratio = float(ev[-2] / ev[-1]) if ev[-1] > 0 else np.nan
    x = y[:9] / y[9] if abs(y[9]) > 1e-12 else y[:9]
    return lam, nearest_rotation_up_to_sign(unvec(x)), rank_ratio, status


def _objective(M):
    Q = np.zeros((_N, _N))
    Q[:9, :9] = -M
    return Q


def upper_bound(M: np.ndarray, R: np.ndarray, lam: np.ndarray) -> float:
    """A rigorous upper bound on ``max_{R in SO(3)} g`` from multipliers ``lam``, refined at a
    candidate ``R``.

    The multipliers of a tight relaxation satisfy ``S(lam) y* = 0`` at the global minimiser
    ``y* = [vec(R*); 1]``. The solver's ``lam`` meets this only to its tolerance, which would
    loosen the bound by about that much; we first correct ``lam`` by the least-norm change
    that makes ``S(lam) y = 0`` at the candidate ``R`` (exactly, up to rounding), then apply
    weak duality: ``g(R') <= -lam . b - 4 min(0, lambda_min(S))`` for every rotation ``R'``.
    Any ``lam`` gives a valid bound; the correction only makes it tight when ``R`` is the
    global minimiser.
    """
    if not np.all(np.isfinite(lam)):
        return np.nan
    Q = _objective(M)
    y = np.append(vec(R), 1.0)
    G = np.einsum("kab,b->ak", _A, y)  # column k: A_k y
    lam = lam + np.linalg.lstsq(G, Q @ y - G @ lam, rcond=None)[0]  # S(lam) y = Q y - G lam = 0
    S = Q - np.einsum("k,kab->ab", lam, _A)
    return float(-(lam @ _B + 4.0 * min(0.0, np.linalg.eigvalsh(S)[0])))
