"""Warning classes of the solvers: each names a measured cause, so that no wrong answer is silent.

Filter them as usual, e.g. ``warnings.simplefilter("error", LocalMinimumWarning)``.
"""
from __future__ import annotations

__all__ = [
    "ReplicationWarning", "ObservabilityWarning", "ConvergenceWarning", "IterationCapWarning",
    "LocalMinimumWarning", "CertificateWarning",
]


class ReplicationWarning(UserWarning):
    """Base class of every warning this package issues."""


class ObservabilityWarning(ReplicationWarning):
    """The motions barely constrain ``R0`` (rotation axes nearly parallel, or tiny rotations)."""


class ConvergenceWarning(ReplicationWarning, RuntimeWarning):
    """An iterative solver stopped before converging (a fixed iteration count, or SLSQP's own stop)."""


class IterationCapWarning(ReplicationWarning):
    """The two-step iteration would need more than its cap; its limit was computed in closed form instead.

    The returned estimate is the iteration's limit (from the SVD of ``K``); the message names
    the measured cause (``sigma_2 / sigma_1`` of ``K``, or a start orthogonal to the limit).
    """


class LocalMinimumWarning(ReplicationWarning):
    """A local solver's answer costs more on eq. (8) than the certified global minimum (a wrong stationary point)."""


class CertificateWarning(ReplicationWarning):
    """Global optimality of the minimiser of eq. (8) could not be certified (the convex relaxation was not tight)."""
