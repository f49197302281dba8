"""Uncertainty of the verdicts: standard errors, paired bootstrap intervals, comparisons in standard errors.

Every interval takes an explicit :class:`numpy.random.Generator`, so a notebook's numbers are seeded.
"""
from __future__ import annotations

import functools
import math
import statistics

import numpy as np

__all__ = ["mean_se", "paired_ratio_ci", "z_score", "format_ci", "share_range", "bracket", "wilson_interval",
           "poisson_upper", "radius_deg"]


def mean_se(x, axis=0):
    """Mean and its standard error ``std / sqrt(n)`` (``ddof=1``) along ``axis``."""
    x = np.asarray(x, dtype=float)
    n = x.shape[axis]
    if n < 2:
        raise ValueError(f"need at least 2 values for a standard error, got {n}")
    return x.mean(axis=axis), x.std(axis=axis, ddof=1) / np.sqrt(n)


def paired_ratio_ci(a, b, rng: np.random.Generator, *, n_boot: int = 2000, level: float = 0.95):
    """``mean(a) / mean(b)`` and its percentile bootstrap interval, resampling the pairs ``(a_i, b_i)`` together.

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


def bracket(value, width: float) -> str:
    """The ``width``-wide bracket that holds ``value`` (``bracket(13.86, 1) == "13-14"``).

    For means whose last digits depend on rounding (counts of a solver that stops at an iteration limit from a
    far start): a machine with other rounding moves the printed text only if the value crosses an edge.
    """
    value, width = float(value), float(width)
    if not (np.isfinite(value) and width > 0):
        raise ValueError(f"need a finite value and a positive width, got {value}, {width}")
    k = np.floor(value / width + 1e-9)
    return f"{k * width:g}-{(k + 1) * width:g}"


def share_range(p, step: float = 0.05) -> str:
    """A share of runs as the ``step``-wide bracket that holds it (``"80-85 %"``), or ``"none"`` / ``"all"``.

    For counts of runs whose outcome depends on rounding (a solver stopped at an iteration limit): one run more
    or less on another machine then moves the printed text only if it crosses a bracket's edge.
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
    return f"{100 * low:.0f}-{100 * high:.0f} %"


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
    """One-sided upper ``level`` bound on a rate from ``k`` events in ``exposure`` (exact: ``chi^2_{2(k+1)}``
    quantile / 2; for ``k = 0`` at 95 % it is ``3.0 / exposure``)."""
    from scipy.stats import chi2

    k = int(k)
    if k < 0 or not exposure > 0:
        raise ValueError(f"need k >= 0 and a positive exposure, got k={k}, exposure={exposure}")
    return float(chi2.ppf(level, 2 * (k + 1)) / 2.0 / exposure)


def radius_deg(cov, level: float = 0.95) -> float:
    """The ``level`` quantile of ``|w|`` (degrees) for ``w ~ N(0, cov)`` (radians).

    ``|w|^2`` is a weighted sum of chi-square variables; Welch-Satterthwaite matches it with ``a chi^2_nu``
    (``a = sum l^2 / sum l``, ``nu = (sum l)^2 / sum l^2`` over the eigenvalues ``l`` of ``cov``), whose quantile
    comes from the Wilson-Hilferty cube-root normal approximation (within 1 % for ``nu >= 1``).
    """
    lam = np.clip(np.linalg.eigvalsh(cov), 0.0, None)
    total, squares = float(lam.sum()), float((lam ** 2).sum())
    if not math.isfinite(total) or not math.isfinite(squares):
        return math.inf
    if not total > 0:
        return 0.0
    a, nu = squares / total, total ** 2 / squares
    z = _normal_quantile(level)
    q = nu * (1.0 - 2.0 / (9.0 * nu) + z * math.sqrt(2.0 / (9.0 * nu))) ** 3  # chi^2_nu quantile
    return math.degrees(math.sqrt(a * q))


@functools.lru_cache(maxsize=8)
def _normal_quantile(level: float) -> float:
    return statistics.NormalDist().inv_cdf(level)
