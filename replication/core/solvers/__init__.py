"""Rotation-only hand-eye solvers for ``A X = X B`` behind one entry point.

>>> from replication.core.solvers import available, solve
>>> {"two_step_right", "two_step_left", "sqp", "chordal_optimal", "park_martin"} <= set(available())
True

Every solver has one public door that validates once (:func:`solve`, or the exported
function of the same name) and a private core that receives a validated
:class:`replication.core.motions.Motions`. Add a baseline with :func:`register`::

    @register("my_method", reference="Author, Title, Year", min_motions=2)
    def my_method(motions, **options):
        A, B = motions.A, motions.B  # validated (..., J, 3, 3) arrays; motions.K is cached
        return R0_estimate  # (..., 3, 3)

``my_method(A, B)`` then validates like ``solve("my_method", A, B)``.

Modules (no function shares a module's name): :mod:`.iteration` (the paper's two-step
iteration, :func:`two_step`), :mod:`.slsqp` (the paper's SQP comparison, :func:`sqp`),
:mod:`.classic` (Park & Martin, Horaud & Dornaika, Andreff, Tsai & Lenz), :mod:`.optimal`
(the certified global minimiser of eq. (8)), :mod:`.msac` (outlier pairs, :func:`robust`),
:mod:`.opencv` (``cv2.calibrateHandEye``).
Warnings (:mod:`._warnings`) name the measured cause whenever an answer may be wrong.
"""
from ..handeye import pair_residual_deg
from ..motions import Motions, prepare_motions
from ._registry import (
    LOCAL_ANGLE_TOL_DEG,
    LOCAL_ATOL,
    LOCAL_RTOL,
    WEAK_GAP_FACTOR,
    SolverAnswerError,
    SolverInfo,
    available,
    check_answer,
    checked_core,
    register,
    solve,
    solver_info,
)
from ._warnings import (
    AccuracyWarning,
    CertificateWarning,
    ConvergenceWarning,
    IterationCapWarning,
    LocalMinimumWarning,
    ObservabilityWarning,
    ReplicationWarning,
)
from .certificate import GAP_TOL, global_certificate
from .classic import andreff, horaud_dornaika, park_martin, tsai_lenz
from .iteration import TwoStepResult, two_step
from .limit import two_step_fixed_point
from .msac import robust
from .opencv import calibrate_hand_eye
from .optimal import chordal_optimal
from .result import Solution
from .slsqp import SQP_VARIANTS, SQPResult, sqp

__all__ = [
    "Motions",
    "prepare_motions",
    "SolverInfo",
    "Solution",
    "available",
    "register",
    "solve",
    "solver_info",
    "ReplicationWarning",
    "ObservabilityWarning",
    "ConvergenceWarning",
    "IterationCapWarning",
    "LocalMinimumWarning",
    "AccuracyWarning",
    "CertificateWarning",
    "GAP_TOL",
    "LOCAL_RTOL",
    "LOCAL_ATOL",
    "LOCAL_ANGLE_TOL_DEG",
    "WEAK_GAP_FACTOR",
    "check_answer",
    "checked_core",
    "SolverAnswerError",
    "two_step",
    "two_step_fixed_point",
    "TwoStepResult",
    "sqp",
    "SQPResult",
    "SQP_VARIANTS",
    "park_martin",
    "horaud_dornaika",
    "andreff",
    "tsai_lenz",
    "chordal_optimal",
    "global_certificate",
    "robust",
    "pair_residual_deg",
    "calibrate_hand_eye",
]
