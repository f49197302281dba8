"""Registry of rotation-only hand-eye solvers: adding a baseline is one decorated function."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..handeye import prepare_motions

__all__ = ["SolverInfo", "register", "available", "solver_info", "solve"]


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
    """

    name: str
    func: Callable[..., np.ndarray]
    reference: str
    min_motions: int


_REGISTRY: dict[str, SolverInfo] = {}


def register(name: str, *, reference: str, min_motions: int = 2):
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
        _REGISTRY[name] = SolverInfo(name, func, reference, int(min_motions))
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


def solve(method: str, A, B, **options) -> np.ndarray:
    """Estimate ``R0`` (camera_from_sensor) from pairs ``A_j R0 = R0 B_j`` (eq. (7)).

    Parameters
    ----------
    method : str
        A name from :func:`available`.
    A : array_like, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c``.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    **options
        Passed to the solver.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        Rotation matrices (det +1).

    Raises
    ------
    ValueError
        Unknown method (the message lists the available ones), malformed input
        (see :func:`replication.handeye.check_motion_pairs`), fewer motions than
        the solver needs, or degenerate motion (all axes parallel).
    """
    info = solver_info(method)
    A, B, _, _ = prepare_motions(A, B, min_motions=info.min_motions)
    return info.func(A, B, **options)
