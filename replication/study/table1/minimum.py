"""Two measurements of notebook 03 on seeds no other study uses.

* :func:`sqp_cap_shares`: SQP (analytic, eq. (8) as printed) from the far start with SLSQP's default
  cap of 100 iterations as well as the paper's 50: one run to the larger cap, read at each (SLSQP's
  path does not depend on its cap), so "does not converge" is scoped to the cap it holds at.
* :func:`minimum_study`: the two-step iterates' cost (8) against the certified minimum of (8) on
  fresh problems: the ratio at iteration 10 (``cost_to_zero``'s lower end, with its interval) and
  the runs in which the certified minimiser costs less than both ``R^r`` and ``R^l``
  (``either_minimises``); :func:`either_minimises_record` builds that claim's record from the
  notebook's settings and the fresh problems.
"""
from __future__ import annotations

import warnings

import numpy as np

from ...core.so3 import frobenius_error
from ...core.solvers import ReplicationWarning, chordal_optimal, sqp, two_step
from ...core.stats import ROUNDING_RUNS, declared_bound, paired_ratio_ci, wilson_interval
from ..ledger import check_evidence
from ..simulation import simulate
from .study import FAIL, bracket_ci

__all__ = ["COST_RTOL", "CAP_BOUND", "sqp_cap_shares", "cap_shares_text", "minimiser_cheaper", "minimum_study",
           "either_minimises_record"]

#: The certified minimiser "costs less" than an iterate when its cost is below the iterate's by more
#: than this relative amount (rounding of the cost (8) is about 1e-15 relative).
COST_RTOL = 1e-9


def sqp_cap_shares(problems, *, init=None, caps=(50, 100), fail: float = FAIL) -> dict:
    """SQP's failure share at each iteration cap: one run to ``max(caps)``, its projected iterate
    read at each cap.

    Returns ``{cap: share of runs whose projected iterate at that cap is more than fail from R0}``
    and ``"n"``.
    """
    caps = sorted(int(c) for c in caps)
    if not caps or caps[0] < 1:
        raise ValueError(f"caps must be positive iteration counts, got {caps}")
    with warnings.catch_warnings():  # the failures are what is counted
        warnings.simplefilter("ignore", ReplicationWarning)
        res = sqp(problems.A, problems.B, max_iterations=caps[-1], init=init)
    out = {cap: float((frobenius_error(res.history.projected[:, cap - 1], problems.R0) > fail).mean()) for cap in caps}
    out["n"] = len(problems.R0)
    return out


#: The declared bound (share of runs) of far-start SQP's failures with SLSQP's default cap of 100
#: iterations: 68 and 70 % on the two new seed sets (300 runs each), which runs fail moving with the
#: machine's rounding (kept :data:`~replication.core.stats.ROUNDING_RUNS` runs inside it).
CAP_BOUND = (0.6, 0.75)


def cap_shares_text(shares: dict, *, bound=CAP_BOUND, step: float = 0.1) -> str:
    """``"80-90 % [75, 93] of 300 at 50 iterations, 60-75 % [54, 80] at 100"``:
    :func:`sqp_cap_shares` in words, the share at the smaller cap as its ``step`` bracket, at the
    larger as the declared ``bound``, each with the Wilson 95 % interval covering every count it
    allows; ``ValueError`` if either share is within :data:`~replication.core.stats.ROUNDING_RUNS`
    runs of its edges."""
    n = int(shares["n"])
    small, large = sorted(k for k in shares if k != "n")
    declared_bound(shares[large], *bound, margin=ROUNDING_RUNS / n, what=f"SQP's failure share at {large} "
                          "iterations")
    lo, hi = wilson_interval(int(np.ceil(bound[0] * n)), n)[0], wilson_interval(int(np.floor(bound[1] * n)), n)[1]
    return (f"{bracket_ci(shares[small], n, step)} of {n} at {small} iterations, {100 * bound[0]:.0f}-"
            f"{100 * bound[1]:.0f} % [{100 * lo:.0f}, {100 * hi:.0f}] at {large}")


def minimiser_cheaper(cost_right, cost_left, minimum) -> np.ndarray:
    """Per run: does the certified minimum cost less than both the last ``R^r`` and the last ``R^l``
    iterate (each by more than :data:`COST_RTOL` relative)? ``cost_right`` / ``cost_left``: ``(n,
    iterations)`` or ``(n,)``."""
    last = [np.asarray(c, dtype=float) for c in (cost_right, cost_left)]
    last = [c[:, -1] if c.ndim == 2 else c for c in last]
    minimum = np.asarray(minimum, dtype=float)
    return (minimum < (1 - COST_RTOL) * last[0]) & (minimum < (1 - COST_RTOL) * last[1])


def minimum_study(seed: int, n_runs: int, rng: np.random.Generator, *, motions_deg=None, init=None,
                  iterations: int = 50) -> dict:
    """The two-step iterates against the certified minimum of (8) on problems ``simulate(seed,
    n_runs, ...)``.

    Returns ``dict``: ``"@10 / minimum"`` (mean cost of ``R^r`` at iteration 10 over the mean
    minimum, with its paired 95 % bootstrap interval from ``rng``: ``(ratio, low, high)``),
    ``"cheaper"`` (runs where the certified minimiser costs less than both last iterates,
    :func:`minimiser_cheaper`), ``"certified"`` (runs whose minimum is certified global) and
    ``"n"``.
    """
    s = simulate(seed, n_runs, motion_angle_range_deg=motions_deg)
    with warnings.catch_warnings():  # the paper's fixed iterations on purpose
        warnings.simplefilter("ignore", ReplicationWarning)
        ours = two_step(s.A, s.B, iterations=iterations, init=init)
    floor = chordal_optimal(s.A, s.B)
    return {"@10 / minimum": paired_ratio_ci(ours.history.cost_right[:, 9], floor.cost, rng),
            "cheaper": int(minimiser_cheaper(ours.history.cost_right, ours.history.cost_left, floor.cost).sum()),
            "certified": int(np.asarray(floor.global_optimum).sum()), "n": n_runs}


def _count(k: int, n: int) -> str:
    low, high = wilson_interval(k, n)
    return f"{k} of {n} [{100 * low:.1f}, {100 * high:.1f}] %"


def either_minimises_record(found: dict, fresh: dict, *, section: str, setting: str) -> dict:
    """The record of ``either_minimises`` ("either R^l or R^r ... minimise the cost function", Sec.
    III-A).

    ``found``: label -> ``(cheaper, certified, n)`` on the notebook's settings
    (:func:`minimiser_cheaper` of their iterates and certified minima); ``fresh``: label ->
    :func:`minimum_study` on new problems. The verdict ``fails`` needs the certified minimiser
    cheaper than both iterates in every run, every minimum certified, on both sets (``ValueError``
    naming the claim otherwise).
    """
    claim = "either_minimises"
    rows = [(label, v) for label, v in found.items()] + [
        (f"{label} (fresh)", (v["cheaper"], v["certified"], v["n"])) for label, v in fresh.items()]
    for label, (cheaper, certified, n) in rows:
        check_evidence(cheaper == n and certified == n, claim,
                       f"the certified minimiser of (8) costs less than both R^r and R^l after 50 iterations in "
                       f"every run of {label} ({cheaper} of {n}; certified global in {certified} of {n})")
    found_text = "; ".join(f"{label} {_count(k, n)}" for label, (k, _, n) in rows[:len(found)])
    fresh_text = "; ".join(f"{label} {_count(k, n)}" for label, (k, _, n) in rows[len(found):])
    return dict(
        claim=claim, verdict="fails",
        evidence="with noise neither minimises (8): after the paper's 50 iterations the certified global minimiser "
                 f"of (8) costs less than both R^r and R^l in every run ({found_text}; on fresh problems "
                 f"{fresh_text}). The iteration converges to the projected top singular vectors of K, a fixed point "
                 "of its own, not a stationary point of (8) (notebook 01, 3d); noise-free both reach cost 0, the "
                 "minimum (notebook 01). Both estimates are accurate (cost_to_zero, table1_final): the claim fails "
                 "on 'minimise', not on 'accurate'",
        uncertainty="95 % Wilson intervals over runs (in brackets); a run counts when the minimum is lower by more "
                    f"than {COST_RTOL:g} relative (far above rounding); every minimum certified global "
                    "(Lagrangian / semidefinite certificate)",
        setting=setting, section=section)
