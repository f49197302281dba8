"""The registered solver ``chordal_optimal``: the global minimiser of the paper's cost (8) over
SO(3), with a certificate of global optimality.

Neither the two-step iteration nor the relaxed solution of
:func:`replication.core.solvers.classic.andreff` minimises eq. (8) on SO(3) once there is noise;
this solver does: Riemannian Newton on SO(3) from the relaxed solution, with a first- and
second-order optimality certificate (the derivation is in :mod:`.certificate`'s notes).

The Newton steps, the certificate and the relaxed start are in :mod:`.certificate`; this module is
the public door.
"""
from __future__ import annotations

from ..motions import prepare_motions
from ._registry import register, warn_if_weak
from .certificate import _chordal_core, global_certificate
from .result import Solution

__all__ = ["chordal_optimal"]

REFERENCE = (
    "Exact minimiser of Zhang's eq. (8) on SO(3) by Riemannian Newton (P.-A. Absil, R. Mahony and "
    "R. Sepulchre, 'Optimization Algorithms on Matrix Manifolds', Princeton 2008, Sec. 6.2) started "
    "from the relaxed solution of Andreff et al. (2001)"
)

def chordal_optimal(A, B, *, init=None, max_iterations: int = 30, gradient_tol: float = 1e-10,
                    hessian_tol: float = 0.0, certify: bool = True) -> Solution:
    """The global minimiser of the paper's eq. (8) over SO(3), with a certificate of global
    optimality.

    Solves ``min_{R in SO(3)} sum_j ||A_j R - R B_j||_F^2`` (eq. (8) subject to
    eqs. (9)-(10)) by Riemannian Newton with backtracking, started from the
    relaxed (Andreff) solution, and certifies the result globally (see the module
    notes): ``global_optimum`` and ``duality_gap`` say whether and how tightly.
    Problems the fast Lagrangian certificate cannot settle go through a semidefinite
    relaxation (Clarabel), whose solution replaces a non-global Newton minimum.
    A :class:`~replication.core.solvers.CertificateWarning` is issued for any problem left
    uncertified.

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3), or Motions
        Camera relative rotations ``Delta R_c`` (or prepared motions, ``B=None``).
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    init : None or array_like, shape (3, 3) or (..., 3, 3)
        Newton start; ``None``: the relaxed solution
        (:func:`replication.core.solvers.classic.andreff`).
    max_iterations : int
        Newton iterations at most.
    gradient_tol : float
        Convergence threshold on the gradient of ``vec(R)^T sym(K) vec(R)``.
    hessian_tol : float
        ``local_minimum`` requires ``hessian_min_eigenvalue > hessian_tol``.
    certify : bool
        Compute the global certificate (default). ``False`` gives the Newton result alone
        (``global_optimum`` False, ``lower_bound`` NaN).

    Returns
    -------
    Solution
        The answer, its cost (8) and certificate (as :func:`replication.core.solvers.solve` returns
        with ``full_output=True``), and how the Newton iteration ended (``iterations``,
        ``gradient_norm``, ``hessian_min_eigenvalue``, ``local_minimum``).

    Raises
    ------
    ValueError
        Malformed or degenerate input (see :func:`replication.core.motions.prepare_motions`).
    """
    m = prepare_motions(A, B, _sym_vectors=True)  # one decomposition of sym(K): the relaxed start and the checks
    warn_if_weak(m)
    return _chordal_core(m, init=init, max_iterations=max_iterations, gradient_tol=gradient_tol,
                         hessian_tol=hessian_tol, certify=certify)


@register("chordal_optimal", reference=REFERENCE, relaxed_start=True)
def _solve_chordal(motions, **options):
    if "certify" in options:
        raise ValueError("solve('chordal_optimal') always certifies its answer; call "
                         "replication.core.solvers.chordal_optimal(A, B, certify=False) for the bare Newton result")
    if not options:
        return global_certificate(motions).R
    return _chordal_core(motions, **options).R
