"""Rotation-only hand-eye solvers for ``A X = X B`` behind one entry point.

>>> from replication.solvers import available, solve
>>> {"two_step_right", "two_step_left", "sqp", "chordal_optimal", "park_martin"} <= set(available())
True

Add a baseline with :func:`register`::

    @register("my_method", reference="Author, Title, Year", min_motions=2)
    def my_method(A, B, **options):
        ...  # A, B: validated (..., J, 3, 3) arrays
        return R0_estimate  # (..., 3, 3)

Modules: :mod:`.two_step` (the paper's method), :mod:`.sqp` (the paper's
comparison), :mod:`.classic` (Park & Martin, Horaud & Dornaika, Andreff,
Tsai & Lenz), :mod:`.optimal` (exact minimiser of eq. (8)), :mod:`.robust`
(outlier pairs), :mod:`.opencv` (``cv2.calibrateHandEye``).
"""
from ._registry import ObservabilityWarning, Solution, SolverInfo, available, register, solve, solver_info
from .classic import andreff, horaud_dornaika, park_martin, tsai_lenz
from .optimal import ChordalResult, chordal_optimal
from .opencv import calibrate_hand_eye
from ..handeye import pair_residual_deg
from .robust import robust
from .sqp import SQPResult, sqp
from .two_step import ConvergenceWarning, TwoStepResult, two_step, two_step_fixed_point, two_step_iterations

__all__ = [
    "SolverInfo",
    "Solution",
    "ObservabilityWarning",
    "available",
    "register",
    "solve",
    "solver_info",
    "two_step",
    "two_step_fixed_point",
    "two_step_iterations",
    "TwoStepResult",
    "ConvergenceWarning",
    "sqp",
    "SQPResult",
    "park_martin",
    "horaud_dornaika",
    "andreff",
    "tsai_lenz",
    "chordal_optimal",
    "ChordalResult",
    "robust",
    "pair_residual_deg",
    "calibrate_hand_eye",
]
