"""Warning classes of the solvers: each names a measured cause, so that no wrong answer is silent.

Filter them as usual, e.g. ``warnings.simplefilter("error", LocalMinimumWarning)``.
"""
from __future__ import annotations

__all__ = [
    "ReplicationWarning", "ObservabilityWarning", "ConvergenceWarning", "IterationCapWarning",
    "LocalMinimumWarning", "AccuracyWarning", "CertificateWarning",
]


class ReplicationWarning(UserWarning):
    """Base class of every warning this package issues."""


class ObservabilityWarning(ReplicationWarning):
    """The motions barely constrain ``R0``: axes nearly parallel, motions small for the data's
    noise, or a second rotation fitting eq. (8) almost as well."""


class ConvergenceWarning(ReplicationWarning, RuntimeWarning):
    """An iterative solver stopped before converging (a fixed iteration count, or SLSQP's own
    stop)."""


class IterationCapWarning(ReplicationWarning):
    """The two-step iteration would need more than its cap; its limit was computed in closed form
    instead.

    The returned estimate is the iteration's limit (from the SVD of ``K``); the message names
    the measured cause (``sigma_2 / sigma_1`` of ``K``, or a start orthogonal to the limit).
    """


class LocalMinimumWarning(ReplicationWarning):
    """A local solver's answer is far from, and costs more on eq. (8) than, the certified global
    minimum.

    Either it stopped before converging (e.g. SLSQP's iteration limit from a start far from ``R0``)
    or on another stationary point; the message says which, from the gradient of (8) at the answer.
    """


class AccuracyWarning(ReplicationWarning):
    """A (non-local) solver's answer is far from the certified minimiser of eq. (8); or any solver's
    answer is not a rotation (a reflection, or NaN: a failure the solver declares).

    Raised where the answer's cost (8) is more than ``GROSS_FACTOR`` (10) times the certified
    minimum (plus a small absolute tolerance): e.g. Park & Martin, Horaud & Dornaika or Tsai & Lenz
    when a motion of (nearly) 180 deg has its axis or quaternion sign flipped between the two sides.
    """


class CertificateWarning(ReplicationWarning):
    """Global optimality of the minimiser of eq. (8) could not be certified (the convex relaxation
    was not tight)."""
