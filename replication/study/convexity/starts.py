"""Newton on SO(3) from many starts against the certified global minimiser of (8) (notebook 06,
section 4): every end point judged with :mod:`.hessian`'s derivatives, the non-global minima counted
with Wilson intervals over brackets and shown as the notebook shows them, and why those counts are
brackets: the basins interleave finely."""
from __future__ import annotations

import numpy as np
import pandas as pd

from ...core.checks import check_rotation_matrices
from ...core.handeye import kronecker_operator
from ...core.so3 import angle_between_deg, matrix_from_rotation_vector
from ...core.solvers import chordal_optimal
from ...core.solvers.certificate import chordal_newton
from ...core.stats import wilson_interval
from .counts import _bracket_counts, _ceil, _floor, bracket_interval
from .hessian import cost_derivatives_on_so3

__all__ = ["NONGLOBAL_TOL", "STATIONARY_TOL", "newton_from_starts", "nonglobal_summary", "nonglobal_view",
           "basin_sensitivity"]

#: A Newton end point whose cost (8) exceeds the certified global minimum by more than
#: ``NONGLOBAL_TOL * J`` is a non-global minimum (the costs of the two kinds differ by tens;
#: rounding is about ``1e-14 J``).
NONGLOBAL_TOL = 1e-9
#: A point is stationary when its Riemannian gradient of (8) is at most this times ``J``.
STATIONARY_TOL = 1e-8


def newton_from_starts(A, B, starts, *, max_iterations: int = 100) -> pd.DataFrame:
    """Riemannian Newton on SO(3) (:func:`~replication.core.solvers.certificate.chordal_newton`)
    from ``starts``, each end point judged against the certified global minimiser of (8); one row
    per (start, problem).

    Parameters
    ----------
    A, B : array_like, shape (N, J, 3, 3)
    starts : array_like, shape (N, 3, 3) or (S, N, 3, 3)
        One start per problem, or ``S`` starts per problem.
    max_iterations : int

    Returns
    -------
    pandas.DataFrame
        Columns ``start``, ``problem``, ``cost`` (eq. (8) at the end point), ``global cost`` (the
        certified minimum), ``certified`` (the global minimum is certified), ``non-global``
        (``cost`` above the minimum by more than :data:`NONGLOBAL_TOL` ``* J``), ``gradient / J``,
        ``hessian min / J`` (smallest eigenvalue of the Riemannian Hessian,
        :func:`cost_derivatives_on_so3`), ``strict`` (gradient at most :data:`STATIONARY_TOL` ``*
        J`` and that eigenvalue positive: a strict local minimum), ``angle to global (deg)``,
        ``midpoint sigma2`` (second singular value of the midpoint of the end point and the global
        minimiser: 0 for a half-turn twin, whose midpoint ``R n n^T`` has rank one, 1 at the
        minimiser itself).
    """
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    starts = check_rotation_matrices(starts, "starts")
    if A.ndim != 4 or starts.shape[-3] != A.shape[0] or starts.ndim not in (3, 4):
        raise ValueError(f"need A, B of shape (N, J, 3, 3) and starts (N, 3, 3) or (S, N, 3, 3), got {A.shape}, "
                         f"{starts.shape}")
    starts = starts[None] if starts.ndim == 3 else starts
    J = A.shape[-3]
    best = chordal_optimal(A, B)
    R = chordal_newton(kronecker_operator(A, B), starts, max_iterations=max_iterations)[0]
    cost, gradient, hessian = cost_derivatives_on_so3(A, B, R)
    grad_j = np.linalg.norm(gradient, axis=-1) / J
    hmin_j = np.linalg.eigvalsh(0.5 * (hessian + np.swapaxes(hessian, -1, -2)))[..., 0] / J
    mid_sigma2 = np.linalg.svd(0.5 * (R + best.R), compute_uv=False)[..., 1]
    S, N = starts.shape[:2]
    frame = pd.DataFrame({
        "start": np.repeat(np.arange(S), N), "problem": np.tile(np.arange(N), S),
        "cost": cost.ravel(), "global cost": np.tile(best.cost, S), "certified": np.tile(best.global_optimum, S),
        "non-global": (cost > best.cost + NONGLOBAL_TOL * J).ravel(),
        "gradient / J": grad_j.ravel(), "hessian min / J": hmin_j.ravel(),
        "strict": ((grad_j <= STATIONARY_TOL) & (hmin_j > 0)).ravel(),
        "angle to global (deg)": angle_between_deg(R, best.R).ravel(), "midpoint sigma2": mid_sigma2.ravel(),
    })
    return frame


def nonglobal_summary(runs: pd.DataFrame, *, step: float = 0.05) -> dict:
    """The counts of :func:`newton_from_starts`'s table, with 95 % Wilson intervals.

    Returns
    -------
    dict
        ``runs``, ``non-global`` (count), ``share`` (its ``step`` bracket, a bound: which basin a
        start falls in changes for a few starts with the machine's rounding,
        :func:`basin_sensitivity`), ``share low``, ``share high`` (:func:`bracket_interval`);
        ``problems``, ``problems with one`` (problems where some start ends on a non-global
        minimum), ``fewest starts on one`` (per problem, the fewest starts that end on one: a margin
        against a start changing basin), ``strict`` (non-global end points that are strict local
        minima), ``strict low`` (Wilson lower end of the share strict: at the bracket's lower count
        when all are), ``half-turn`` (non-global end points at least 170 deg from the global
        minimiser) and ``half-turn low`` likewise; ``hessian min / J`` (smallest over the non-global
        end points), ``gradient max / J``, ``angle min (deg)``, ``midpoint sigma2 max``, ``cost
        min`` (cheapest non-global end point), ``global cost max``, ``all certified``.
    """
    bad = runs[runs["non-global"]]
    k, n = len(bad), len(runs)
    text, low, high = bracket_interval(k, n, step)
    per_problem = runs.groupby("problem")["non-global"].sum()
    k_low = max(_bracket_counts(k, n, step)[0], 1) if k else 0
    strict, half = int(bad["strict"].sum()), int((bad["angle to global (deg)"] >= 170).sum())

    def lower(m):  # all of them: the Wilson lower end at the bracket's lower count; else at the count itself
        return wilson_interval(k_low, k_low)[0] if m == k and k else wilson_interval(m, k)[0] if k else 0.0

    return {
        "runs": n, "non-global": k, "share": text, "share low": low, "share high": high,
        "problems": int(runs["problem"].nunique()), "problems with one": int((per_problem > 0).sum()),
        "fewest starts on one": int(per_problem.min()),
        "strict": strict, "strict low": lower(strict), "half-turn": half, "half-turn low": lower(half),
        "hessian min / J": float(bad["hessian min / J"].min()) if k else np.nan,
        "gradient max / J": float(bad["gradient / J"].max()) if k else np.nan,
        "angle min (deg)": float(bad["angle to global (deg)"].min()) if k else np.nan,
        "midpoint sigma2 max": float(bad["midpoint sigma2"].max()) if k else np.nan,
        "cost min": float(bad["cost"].min()) if k else np.nan,
        "global cost max": float(runs["global cost"].max()), "all certified": bool(runs["certified"].all()),
    }


def nonglobal_view(summaries: pd.DataFrame) -> pd.DataFrame:
    """Rows of :func:`nonglobal_summary` as the notebook shows them: the share as its bracket (a
    bound) with the Wilson interval over the bracket's ends, "all" where every non-global end point
    qualifies, minima rounded down and maxima up to the digits shown (a few starts change basin with
    the machine's rounding, and with them the set of minima found)."""
    def every(m, k):
        return "all" if m == k else f"{m} of {k}"

    rows = {}
    for key, r in summaries.iterrows():
        k = r["non-global"]
        rows[key] = {
            "runs": int(r["runs"]), "on a non-global minimum (bound)": r["share"],
            "95 % Wilson over the bracket": f"[{100 * r['share low']:.0f}, {100 * r['share high']:.0f}] %",
            "problems with one": f"{r['problems with one']} of {r['problems']}" if r["runs"] > r["problems"] else "-",
            "strict minima": every(r["strict"], k), "half-turns (>= 170 deg)": every(r["half-turn"], k),
            "angle to the global (min deg)": f"{_floor(r['angle min (deg)'], 0):.0f}",
            "Riemannian Hessian min / J": f"{_floor(r['hessian min / J'], 2):.2f}",
            "midpoint sigma_2 (max)": f"{_ceil(r['midpoint sigma2 max'], 2):.2f}",
            "their cost (min)": f"{_floor(r['cost min'], 0):.0f}",
            "global minimum (max)": f"{_ceil(r['global cost max'], 3):.3f}",
        }
    view = pd.DataFrame(rows).T
    view.index.names = summaries.index.names
    return view


def basin_sensitivity(A, B, starts, *, scale: float, rng: np.random.Generator, repeats: int = 3) -> int:
    """How many starts change outcome (a non-global minimum or the global one) when every start is
    turned by a random rotation of ``scale`` radians: the largest count over ``repeats`` draws.

    The basins of Newton on SO(3) interleave finely, so a perturbation at the level of the machine's
    rounding changes the outcome of a few starts: counts of outcomes are shown as brackets (bounds).
    """
    starts = check_rotation_matrices(starts, "starts")
    base = newton_from_starts(A, B, starts)["non-global"].to_numpy()
    changed = []
    for _ in range(int(repeats)):
        w = rng.normal(size=starts.shape[:-2] + (3,))
        w *= scale / np.linalg.norm(w, axis=-1, keepdims=True)
        moved = newton_from_starts(A, B, starts @ matrix_from_rotation_vector(w))["non-global"].to_numpy()
        changed.append(int(np.sum(moved != base)))
    return max(changed)
