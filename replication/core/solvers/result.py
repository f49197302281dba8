"""The one answer type of the solvers: what :func:`replication.core.solvers.solve` returns with
``full_output=True`` and what :func:`replication.core.solvers.chordal_optimal`,
:func:`replication.core.solvers.two_step` and :func:`replication.core.solvers.sqp` return: the
answer with its cost (8), the certificate of the global minimum of eq. (8), the observability
diagnostic and, from the paper's protocol functions, their per-iteration history."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..motions import MotionObservability, Motions

__all__ = ["Solution"]


@dataclass(frozen=True)
class Solution:
    """A solver's answer with its cost (8), its certificate and the observability diagnostic.

    Attributes
    ----------
    R : ndarray, shape (..., 3, 3)
        Estimate of ``R0`` (camera_from_sensor); NaN where the solver declared a failure.
    method : str
        The registered solver's name (:func:`replication.core.solvers.available`).
    cost : ndarray, shape (...)
        Eq. (8) at ``R``: ``sum_j ||A_j R - R B_j||_F^2`` (NaN where ``R`` is NaN).
    lower_bound : ndarray, shape (...)
        Certified lower bound on the minimum of eq. (8) over SO(3) (the certificate of
        :func:`replication.core.solvers.chordal_optimal`; NaN where none was computed,
        ``certify=False``).
    duality_gap : ndarray, shape (...)
        ``cost - lower_bound``: how far ``R`` can be above the global minimum of eq. (8) over SO(3);
        NaN where ``R`` is not in SO(3) (a declared failure, NaN, or a reflection) or no certificate
        was computed.
    global_optimum : ndarray of bool, shape (...)
        ``R`` is a rotation certified to be the global minimiser of eq. (8) (``duality_gap`` at most
        ``GAP_TOL * J``; for ``chordal_optimal`` also a strict local minimum, ``local_minimum``);
        never for a NaN or a reflection. The paper's two-step method is not, once there is noise:
        its fixed point is not the minimiser of its own cost. Where another minimum has a cost
        within that tolerance (motions that nearly admit a second solution; an
        :class:`~replication.core.solvers.ObservabilityWarning` says so), eq. (8) cannot tell the
        two apart.
    certificate : ndarray of str, shape (...), or None
        How ``lower_bound`` was certified: ``"lagrangian"`` (the fast O(3) dual at the Newton
        solution), ``"sdp"`` (the semidefinite relaxation), ``"none"`` (not certified; see
        ``duality_gap``).
    iterations : ndarray of int, shape (...), or None
        Iterations the solver ran (``None`` from :func:`solve`): ``chordal_optimal``'s Newton
        iterations from the relaxed start (the fallback's polish not counted); ``two_step``'s
        iterations (the fixed ``N``, or those run to the limit with ``iterations="auto"``);
        ``sqp``'s SLSQP major iterations.
    gradient_norm, hessian_min_eigenvalue, local_minimum : ndarray, shape (...), or None
        How ``chordal_optimal``'s Riemannian Newton ended (``None`` otherwise): the norm of the
        Riemannian gradient of eq. (8) at ``R`` and the smallest eigenvalue of its Riemannian
        Hessian, both divided by ``J``; ``gradient_norm <= 2 gradient_tol`` and
        ``hessian_min_eigenvalue > hessian_tol`` (a strict local minimum).
    history : TwoStepHistory, SQPHistory or None
        The per-iteration history of the paper's protocol functions:
        :class:`~replication.core.solvers.TwoStepHistory` from ``two_step`` (both estimates
        ``R^r`` and ``R^l`` of every iteration, their costs, the fixed points),
        :class:`~replication.core.solvers.SQPHistory` from ``sqp`` (every SLSQP iterate, raw and
        projected, and SLSQP's own counts and flag); ``None`` from the other solvers.
    observability : MotionObservability
        How well the motions determine ``R0``
        (:class:`replication.core.motions.MotionObservability`), computed on first access (the
        certificate does not need the singular values of ``K``; a call that never reads them does
        not pay for their decomposition); ``None`` for a solution built without its motions.
    """

    R: np.ndarray
    method: str
    cost: np.ndarray
    lower_bound: np.ndarray
    duality_gap: np.ndarray
    global_optimum: np.ndarray
    certificate: np.ndarray | None = None
    iterations: np.ndarray | None = None
    gradient_norm: np.ndarray | None = None
    hessian_min_eigenvalue: np.ndarray | None = None
    local_minimum: np.ndarray | None = None
    history: object | None = None
    _motions: Motions | None = field(default=None, repr=False, compare=False)

    @property
    def observability(self) -> MotionObservability | None:
        """See the class notes."""
        return None if self._motions is None else self._motions.observability

    @property
    def sdp_used(self) -> np.ndarray | None:
        """Problems the fast certificate could not settle (``certificate != "lagrangian"``: the
        relaxation was solved), ``None`` without a certificate field."""
        return None if self.certificate is None else self.certificate != "lagrangian"
