"""Uncertainty of the verdicts: standard errors, paired bootstrap intervals, comparisons in standard
errors.

Every interval takes an explicit :class:`numpy.random.Generator`, so a notebook's numbers are
seeded.
"""
from __future__ import annotations

import functools
import math
import statistics

import numpy as np

from .._jitter import guard_failed, margin_scale

__all__ = ["mean_se", "paired_ratio_ci", "z_score", "format_ci", "share_range", "bracket", "declared_bound",
           "ROUNDING_RUNS", "wilson_interval", "poisson_upper", "radius_deg", "chi2_quantile"]


def mean_se(x, axis=0):
    """Mean and its standard error ``std / sqrt(n)`` (``ddof=1``) along ``axis``."""
    x = np.asarray(x, dtype=float)
    n = x.shape[axis]
    if n < 2:
        raise ValueError(f"need at least 2 values for a standard error, got {n}")
    return x.mean(axis=axis), x.std(axis=axis, ddof=1) / np.sqrt(n)


def paired_ratio_ci(a, b, rng: np.random.Generator, *, n_boot: int = 2000, level: float = 0.95):
    """``mean(a) / mean(b)`` and its percentile bootstrap interval, resampling the pairs ``(a_i,
    b_i)`` together.

    Parameters
    ----------
    a, b : array_like, shape (n,) or (..., n)
        Paired values (e.g. two methods' errors on the same problems), the pairs on the last axis.
    rng : numpy.random.Generator
    n_boot : int
        Bootstrap replicates.
    level : float
        Coverage of the interval.

    Returns
    -------
    (ratio, low, high) : ndarrays of shape (...)
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or a.shape[-1] < 2:
        raise ValueError(f"a and b must be paired samples of the same shape (..., n >= 2), got {a.shape}, {b.shape}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    n = a.shape[-1]
    idx = rng.integers(0, n, size=(int(n_boot), n))
    boot = a[..., idx].mean(axis=-1) / b[..., idx].mean(axis=-1)  # (..., n_boot)
    tail = 100 * (1 - level) / 2
    low, high = np.percentile(boot, [tail, 100 - tail], axis=-1)
    return a.mean(axis=-1) / b.mean(axis=-1), low, high


def z_score(ours_mean, ours_se, paper_mean, paper_se):
    """``(ours - paper) / sqrt(se_ours^2 + se_paper^2)``: a difference in standard errors."""
    return (np.asarray(ours_mean) - np.asarray(paper_mean)) / np.hypot(ours_se, paper_se)


def format_ci(low, high, digits: int = 2) -> str:
    """``"[low, high]"`` rounded to ``digits`` decimals."""
    return f"[{low:.{digits}f}, {high:.{digits}f}]"


def _guard(value, low, high, margin, what, text, problem, *, at_zero=False):
    """Raise ``ValueError("<what> <value> <problem>")`` unless ``value`` lies ``margin`` (times
    :func:`replication._jitter.margin_scale`) inside ``[low, high]`` (``None``: that side
    unbounded); a value exactly at the margin passes. A zero margin checks nothing unless
    ``at_zero``. Under ``REPLICATION_GUARD_LOG`` a guard that does not hold is logged instead
    (:func:`replication._jitter.guard_failed`)."""
    margin = float(margin) * margin_scale()
    lo, hi = -np.inf if low is None else low, np.inf if high is None else high
    tol = 1e-12 * max(1.0, abs(value))
    if (margin or at_zero) and not lo + margin - tol <= value <= hi - margin + tol and guard_failed(
            {"what": what, "value": value, "bound": text, "margin": margin, "distance": min(value - lo, hi - value)}):
        raise ValueError(f"{what} {value:.4g} {problem.format(margin=margin, text=text)}")


_IN_BRACKET = ("is within {margin:g} of an edge of its bracket {text}: another machine's rounding can move it across; "
               "show it with another step or a declared bound")


def bracket(value, width: float, *, margin: float = 0.0, what: str = "the value") -> str:
    """The ``width``-wide bracket that holds ``value`` (``bracket(13.86, 1) == "13-14"``).

    For means whose last digits depend on rounding (counts of a solver that stops at an iteration
    limit from a far start): a machine with other rounding moves the printed text only if the value
    crosses an edge, so the value is checked to lie ``margin`` (its measured spread between
    machines) inside the bracket; ``ValueError`` otherwise.
    """
    value, width = float(value), float(width)
    if not (np.isfinite(value) and width > 0):
        raise ValueError(f"need a finite value and a positive width, got {value}, {width}")
    k = np.floor(value / width + 1e-9)
    text = f"{k * width:g}-{(k + 1) * width:g}"
    _guard(value, k * width, (k + 1) * width, margin, what, text, _IN_BRACKET)
    return text


#: Runs by which a machine's rounding moves a count of runs whose outcome is chaotic (which
#: far-start SLSQP runs fail, which basin a Newton start falls into): one or two runs between the
#: machines tried (scripts/spread.py; the portability issue's machines). The guard of a share of
#: such runs (:func:`share_range`'s ``margin``) is this many runs.
ROUNDING_RUNS = 2


def declared_bound(value, low=None, high=None, *, margin, what: str = "the value", fmt: str = "g") -> str:
    """A bound declared in advance for a quantity that rounding moves, as text, once ``value`` is
    checked to lie at least ``margin`` inside it.

    The text is made from the constants ``low`` and ``high`` only (``"600-700"``, ``"at most 0.4"``,
    ``"at least 13"``), never from ``value``: a machine whose rounding moves ``value`` by less than
    ``margin`` prints the same text. ``margin`` is the measured machine-to-machine spread of
    ``value`` with room to spare (``scripts/spread.py`` measures it; ``docs/reproducing.md``, "What
    strict nbval compares"). For a quantity that is a chaotic function of its inputs (runs stopped
    by an iteration limit, which runs end on which local minimum) this is the stable statement about
    it; a bracket chosen from the value (:func:`bracket`) flips where the value sits near an edge.

    >>> declared_bound(13.6, 10, margin=1), declared_bound(0.27, high=0.4, margin=0.05)
    ('at least 10', 'at most 0.4')
    >>> declared_bound(620, 550, 700, margin=20)
    '550-700'
    >>> declared_bound(0.37, high=0.4, margin=0.05, what="the bound")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: the bound 0.37 is not at least 0.05 inside its declared bound (at most 0.4): ...
    """
    value = float(value)
    if low is None and high is None:
        raise ValueError("declare low, high or both")
    if not (np.isfinite(value) and float(margin) >= 0):
        raise ValueError(f"need a finite value and a margin >= 0, got {value}, {margin}")
    if low is not None and high is not None:
        text = f"{low:{fmt}}-{high:{fmt}}" if low >= 0 else f"{low:{fmt}} to {high:{fmt}}"
    else:
        text = f"at least {low:{fmt}}" if high is None else f"at most {high:{fmt}}"
    _guard(value, low, high, margin, what, text, "is not at least {margin:g} inside its declared bound ({text}): "
           "measure its spread and declare a wider one", at_zero=True)
    return text


def share_range(p, step: float = 0.05, *, margin: float = 0.0, what: str = "the share") -> str:
    """A share of runs as the ``step``-wide bracket that holds it (``"80-85 %"``), or ``"none"`` /
    ``"all"``.

    For counts of runs whose outcome depends on rounding (a solver stopped at an iteration limit):
    one run more or less on another machine then moves the printed text only if it crosses a
    bracket's edge; ``margin`` (a share: the runs a machine's rounding moves, divided by the runs)
    is the room the share must keep from both edges (``ValueError`` otherwise).
    """
    p = float(p)
    if not 0.0 <= p <= 1.0:
        raise ValueError(f"a share must be in [0, 1], got {p}")
    if p == 0.0:
        return "none"
    if p == 1.0:
        return "all"
    k = int(np.floor(p / step + 1e-9))
    low, high = k * step, min((k + 1) * step, 1.0)
    text = f"{100 * low:.0f}-{100 * high:.0f} %"
    _guard(p, low, high, margin, what, text, _IN_BRACKET)  # 0 and 1 are edges too: "none" and "all"
    return text


def wilson_interval(k, n, level: float = 0.95):
    """Wilson score interval ``(low, high)`` of a share ``k / n`` (counts of independent runs).

    Unlike ``k / n +- z SE`` it stays inside [0, 1] and is not empty at ``k = 0`` or ``k = n``.
    """
    import statistics

    k, n = int(k), int(n)
    if n < 1 or not 0 <= k <= n:
        raise ValueError(f"need 0 <= k <= n and n >= 1, got k={k}, n={n}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")
    z = statistics.NormalDist().inv_cdf(0.5 + level / 2)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def poisson_upper(k, exposure: float, level: float = 0.95) -> float:
    """One-sided upper ``level`` bound on a rate from ``k`` events in ``exposure`` (exact:
    ``chi^2_{2(k+1)}`` quantile / 2; for ``k = 0`` at 95 % it is ``3.0 / exposure``)."""
    from scipy.stats import chi2

    k = int(k)
    if k < 0 or not exposure > 0:
        raise ValueError(f"need k >= 0 and a positive exposure, got k={k}, exposure={exposure}")
    return float(chi2.ppf(level, 2 * (k + 1)) / 2.0 / exposure)


def radius_deg(cov, level: float = 0.95) -> float:
    """The ``level`` quantile of ``|w|`` (degrees) for ``w ~ N(0, cov)`` (radians).

    ``|w|^2`` is a weighted sum of chi-square variables; Welch-Satterthwaite matches it with ``a
    chi^2_nu`` (``a = sum l^2 / sum l``, ``nu = (sum l)^2 / sum l^2`` over the eigenvalues ``l`` of
    ``cov``), whose quantile comes from the Wilson-Hilferty cube-root normal approximation (within 1
    % for ``nu >= 1``).
    """
    lam = np.clip(np.linalg.eigvalsh(cov), 0.0, None)
    total, squares = float(lam.sum()), float((lam ** 2).sum())
    if not math.isfinite(total) or not math.isfinite(squares):
        return math.inf
    if not total > 0:
        return 0.0
    a, nu = squares / total, total ** 2 / squares
    return math.degrees(math.sqrt(a * chi2_quantile(level, nu)))


def chi2_quantile(level: float, dof: float) -> float:
    """The ``level`` quantile of ``chi^2_dof`` (Wilson-Hilferty; ``dof`` need not be an integer)."""
    z = _normal_quantile(level)
    return dof * (1.0 - 2.0 / (9.0 * dof) + z * math.sqrt(2.0 / (9.0 * dof))) ** 3


@functools.lru_cache(maxsize=8)
def _normal_quantile(level: float) -> float:
    return statistics.NormalDist().inv_cdf(level)
