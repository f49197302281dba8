"""Rotation-only hand-eye solvers for ``A X = X B`` behind one entry point.

>>> from replication.solvers import available, solve, two_step
>>> {"two_step_right", "two_step_left", "sqp"} <= set(available())
True

Add a baseline with :func:`register`::

    @register("my_method", reference="Author, Title, Year", min_motions=2)
    def my_method(A, B, **options):
        ...  # A, B: validated (..., J, 3, 3) arrays
        return R0_estimate  # (..., 3, 3)
"""
from ._registry import SolverInfo, available, register, solve, solver_info
from .sqp import SQPResult, sqp
from .two_step import ConvergenceWarning, TwoStepResult, two_step, two_step_fixed_point

__all__ = [
    "SolverInfo",
    "available",
    "register",
    "solve",
    "solver_info",
    "two_step",
    "two_step_fixed_point",
    "TwoStepResult",
    "ConvergenceWarning",
    "sqp",
    "SQPResult",
]
