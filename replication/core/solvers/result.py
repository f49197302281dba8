"""What :func:`replication.core.solvers.solve` returns with ``full_output=True``: the answer with its cost (8), the
observability diagnostic and the certificate of the global minimum of eq. (8)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..motions import MotionObservability

__all__ = ["Solution"]


@dataclass(frozen=True)
class Solution:
    """What :func:`solve` returns with ``full_output=True``.

    Attributes
    ----------
    R : ndarray, shape (..., 3, 3)
        Estimate of ``R0`` (camera_from_sensor); NaN where the solver declared a failure.
    method : str
    cost : ndarray, shape (...)
        Eq. (8) at ``R``: ``sum_j ||A_j R - R B_j||_F^2`` (NaN where ``R`` is NaN).
    observability : MotionObservability
        How well the motions determine ``R0`` (see
        :class:`replication.core.motions.MotionObservability`).
    lower_bound : ndarray, shape (...)
        Certified lower bound on the minimum of eq. (8) over SO(3)
        (:func:`replication.core.solvers.chordal_optimal`'s certificate).
    duality_gap : ndarray, shape (...)
        ``cost - lower_bound``: how far ``R`` can be above the global minimum of eq. (8) over SO(3);
        NaN where ``R`` is not in SO(3) (a declared failure, NaN, or a reflection).
    global_optimum : ndarray of bool, shape (...)
        ``R`` is a rotation certified to be the global minimiser of eq. (8) (``duality_gap`` at most
        ``GAP_TOL * J``); never for a NaN or a reflection. The paper's two-step method is not, once
        there is noise: its fixed point is not the minimiser of its own cost.
    """

    R: np.ndarray
    method: str
    cost: np.ndarray
    observability: MotionObservability
    lower_bound: np.ndarray
    duality_gap: np.ndarray
    global_optimum: np.ndarray
