"""Counts as notebooks 01 and 06 show them: a count with its Wilson interval, the bracket a count
takes whose last units depend on the machine's rounding (a bound) with the Wilson interval over the
bracket's ends, and minima and maxima rounded outward to the digits shown."""
from __future__ import annotations

import numpy as np

from ...core.stats import ROUNDING_RUNS, share_range, wilson_interval

__all__ = ["count_text", "bracket_interval"]


def _floor(x, digits):
    """``x`` rounded down to ``digits`` decimals (a minimum shown as a lower bound)."""
    return np.floor(x * 10 ** digits + 1e-6) / 10 ** digits + 0.0


def _ceil(x, digits):
    """``x`` rounded up to ``digits`` decimals (a maximum shown as an upper bound)."""
    return np.ceil(x * 10 ** digits - 1e-6) / 10 ** digits + 0.0


def count_text(k, n, level: float = 0.95) -> str:
    """``"k of n (p %, 95 % Wilson interval [low, high] %)"``, one decimal."""
    low, high = wilson_interval(k, n, level)
    return f"{int(k)} of {int(n)} ({100 * k / n:.1f} %, {100 * level:.0f} % Wilson interval [{100 * low:.1f}, " \
           f"{100 * high:.1f}] %)"


def _bracket_counts(k: int, n: int, step: float) -> tuple[int, int]:
    """The counts at the ends of the ``step``-wide bracket of shares that holds ``k / n``."""
    low = int(np.floor(k / n / step + 1e-9) * step * n + 1e-9)
    return low, min(int(round(low + step * n)), n)


def bracket_interval(k, n, step: float = 0.05, level: float = 0.95):
    """A count whose last units depend on the machine's rounding: ``(bracket text, low, high)``.

    The text is the ``step``-wide bracket of the share ``k / n``
    (:func:`~replication.core.stats.share_range`, a bound on the share); ``low``, ``high`` are the
    Wilson interval's lower end at the bracket's lower count and its upper end at the bracket's
    upper count, so a count that moves inside its bracket moves neither.
    """
    k, n = int(k), int(n)
    text = share_range(k / n, step, margin=ROUNDING_RUNS / n, what="a share of starts")
    if k in (0, n):
        low, high = wilson_interval(k, n, level)
        return text, low, high
    lo_count, hi_count = _bracket_counts(k, n, step)
    return text, wilson_interval(lo_count, n, level)[0], wilson_interval(hi_count, n, level)[1]
