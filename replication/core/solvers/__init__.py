"""Rotation-only hand-eye solvers for ``A X = X B`` behind one entry point. Theory and measured
numbers: ``docs/methods.md``, section ``replication.core.solvers.__init__``."""
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
from .iteration import TwoStepHistory, two_step
from .limit import two_step_fixed_point
from .msac import robust
from .opencv import calibrate_hand_eye
from .optimal import chordal_optimal
from .result import Solution
from .slsqp import SQP_VARIANTS, SQPHistory, sqp

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
    "TwoStepHistory",
    "sqp",
    "SQPHistory",
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
