"""Registry of rotation-only hand-eye solvers: adding a baseline is one decorated function."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import warnings

import numpy as np

from ..handeye import MotionObservability, handeye_cost, prepare_motions

__all__ = ["SolverInfo", "Solution", "ObservabilityWarning", "register", "available", "solver_info", "solve"]


class ObservabilityWarning(UserWarning):
    """The motions barely constrain ``R0`` (rotation axes nearly parallel, or tiny rotations)."""


@dataclass(frozen=True)
class SolverInfo:
    """A registered solver.

    Attributes
    ----------
    name : str
        The ``method`` name given to :func:`solve`.
    func : callable
        ``func(A, B, **options) -> (..., 3, 3)``; receives validated float arrays.
    reference : str
        The paper the solver implements.
    min_motions : int
        Fewest motion pairs ``J`` it accepts.
    local : bool
        ``True`` for a local method whose answer depends on a start ``init``
        (an option it accepts); it may converge to a wrong stationary point
        from a start far from ``R0``.
    equivariant : bool
        ``True`` if re-expressing the camera frame by ``G`` (``A -> G A G^T``)
        maps the estimate to ``G R``, and likewise for the sensor frame
        (``B -> G B G^T``, ``R -> R G^T``), also with noisy data. Tsai & Lenz's
        Gibbs-vector parametrisation is not.
    """

    name: str
    func: Callable[..., np.ndarray]
    reference: str
    min_motions: int
    local: bool = False
    equivariant: bool = True


@dataclass(frozen=True)
class Solution:
    """What :func:`solve` returns with ``full_output=True``.

    Attributes
    ----------
    R : ndarray, shape (..., 3, 3)
        Estimate of ``R0`` (camera_from_sensor).
    method : str
    cost : ndarray, shape (...)
        Eq. (8) at ``R``: ``sum_j ||A_j R - R B_j||_F^2``.
    observability : MotionObservability
        How well the motions determine ``R0`` (see
        :class:`replication.handeye.MotionObservability`).
    """

    R: np.ndarray
    method: str
    cost: np.ndarray
    observability: MotionObservability


_REGISTRY: dict[str, SolverInfo] = {}


def register(name: str, *, reference: str, min_motions: int = 2, local: bool = False,
             equivariant: bool = True):
    """Decorator adding ``func(A, B, **options) -> R0 estimate`` to the registry.

    The function receives ``A`` (camera relative rotations) and ``B`` (sensor
    relative rotations), both float arrays of shape ``(..., J, 3, 3)`` already
    validated by :func:`solve` (rotations, same shape, ``J >= min_motions``,
    not degenerate), and returns ``camera_from_sensor`` of shape ``(..., 3, 3)``.

    Raises
    ------
    ValueError
        If ``name`` is already registered or ``min_motions < 1``.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"solver name must be a non-empty string, got {name!r}")
    if min_motions < 1:
        raise ValueError(f"min_motions must be >= 1, got {min_motions}")

    def decorate(func):
        if name in _REGISTRY:
            raise ValueError(f"a solver named {name!r} is already registered")
        _REGISTRY[name] = SolverInfo(name, func, reference, int(min_motions), bool(local),
                                     bool(equivariant))
        return func

    return decorate


def available() -> list[str]:
    """Names of all registered solvers, sorted."""
    return sorted(_REGISTRY)


def solver_info(method: str) -> SolverInfo:
    """The :class:`SolverInfo` of ``method``; unknown names raise ``ValueError`` listing all."""
    try:
        return _REGISTRY[method]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown solver {method!r}; available: {', '.join(available())}"
        ) from None


def solve(method: str, A, B, *, full_output: bool = False, warn_axis_spread_deg: float = 1.0,
          **options):
    """Estimate ``R0`` (camera_from_sensor) from pairs ``A_j R0 = R0 B_j`` (eq. (7)).

    Parameters
    ----------
    method : str
        A name from :func:`available`.
    A : array_like, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c``.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    full_output : bool
        ``False``: return the rotations. ``True``: return a :class:`Solution`
        with the cost (8) and the observability diagnostic.
    warn_axis_spread_deg : float
        Issue an :class:`ObservabilityWarning` when the camera or sensor axis
        spread (:class:`replication.handeye.MotionObservability`) of a problem is
        below this: nearly single-axis motion leaves the rotation about that
        axis poorly determined. Exactly single-axis motion raises instead.
    **options
        Passed to the solver.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3), or Solution
        Rotation matrices (det +1).

    Raises
    ------
    ValueError
        Unknown method (the message lists the available ones), malformed input
        (see :func:`replication.handeye.check_motion_pairs`), fewer motions than
        the solver needs, or degenerate motion (all axes parallel).
    """
    info = solver_info(method)
    A, B, _, obs = prepare_motions(A, B, min_motions=info.min_motions)
    spread = np.minimum(obs.camera_axis_spread_deg, obs.sensor_axis_spread_deg)
    weak = spread < warn_axis_spread_deg
    if np.any(weak):
        warnings.warn(
            f"{int(np.sum(weak))} of {weak.size} problems have nearly single-axis motion (axis spread "
            f"down to {float(np.min(spread)):.3g} deg < {warn_axis_spread_deg:g} deg): the rotation about "
            f"that axis is poorly determined; add motions about other axes",
            ObservabilityWarning,
            stacklevel=2,
        )
    R = info.func(A, B, **options)
    if not full_output:
        return R
    return Solution(R=R, method=method, cost=handeye_cost(R, A, B), observability=obs)
