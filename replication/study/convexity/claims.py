"""The ledger record of ``convex_problem`` (notebook 06, section 4), built from the found and the
fresh seeds' tables, its numbers checked first (:func:`~replication.study.ledger.check_evidence`):
its checks, its evidence and its uncertainty, one function each."""
from __future__ import annotations

import pandas as pd

from ...core.stats import ROUNDING_RUNS, declared_bound
from ..ledger import check_evidence
from .counts import _ceil, _floor, count_text

__all__ = ["convex_problem_record"]


def _check_convex_problem(convexity, random_starts, many_starts, outliers) -> tuple[dict, dict]:
    """The checks of :func:`convex_problem_record` (its ``Raises``); the outlier problems where
    Newton stops on a non-global minimum, and the outlier problems, per seed set."""
    claim = "convex_problem"
    check_evidence((convexity["PSD"] == convexity["problems"]).all(), claim,
                   "the Hessian of (8) in vec(R) PSD in every problem (a convex quadratic cost)")
    for name, rows in (("one random start", random_starts), ("several starts", many_starts)):
        check_evidence(set(rows.index.get_level_values(0)) == {"found", "fresh"}, claim,
                       f"{name}: rows on the found and on the fresh seeds, got {list(rows.index)}")
        check_evidence(rows["all certified"].all(), claim, f"{name}: every global minimum certified")
        check_evidence((rows["strict"] == rows["non-global"]).all() and (rows["half-turn"] == rows["non-global"]).all(),
                       claim, f"{name}: every non-global end point a strict local minimum, a half-turn from the "
                       f"global one (strict {list(rows['strict'])}, half-turn {list(rows['half-turn'])} of "
                       f"{list(rows['non-global'])})")
        check_evidence((rows["cost min"] > 10 * rows["global cost max"]).all(), claim,
                       f"{name}: the non-global minima cost more than 10 times the global minimum")
        shares = rows["non-global"] / rows["runs"]
        check_evidence(((shares > 0.25) & (shares < 0.75)).all(), claim,
                       f"{name}: a start ends on a non-global minimum in 25-75 % of runs, got {list(shares.round(3))}")
    check_evidence((many_starts["problems with one"] == many_starts["problems"]).all()
                   and (many_starts["fewest starts on one"] >= 2).all(), claim,
                   "with several starts, every problem has a non-global minimum, found by at least 2 starts")
    stuck = {k: int(t["Newton alone on a non-global minimum"].sum()) for k, t in outliers.items()}
    n_out = {k: int(t["problems"].sum()) for k, t in outliers.items()}
    check_evidence(set(outliers) == {"found", "fresh"} and all(stuck.values())
                   and all((t["of them strict"] == t["Newton alone on a non-global minimum"]).all()
                           and (t["certified global"] == t["problems"]).all() for t in outliers.values()), claim,
                   f"outliers: non-global strict minima on the found and the fresh seeds, every answer certified "
                   f"(got {stuck})")
    return stuck, n_out


def _convex_evidence(convexity, rs, ms, outliers, stuck, n_out, n_starts) -> str:
    """The evidence of :func:`convex_problem_record` (``rs``, ``ms``: its random and many
    starts)."""
    noisy = convexity[convexity["smallest / J (min)"] > 1e-9]
    hessian = ", ".join(
        ([f"smallest eigenvalue {_floor(noisy['smallest / J (min)'].min(), 4):.4f}-"
          f"{_ceil(noisy['smallest / J (max)'].max(), 4):.4f} J with the paper's noise"] if len(noisy) else [])
        + (["0 to rounding noise-free, where vec(R0) is a null vector"] if len(noisy) < len(convexity) else []))
    noise_labels = " and ".join(dict.fromkeys(rs.index.get_level_values(1)))
    if rs["share"].nunique() == 1:
        single = (f"{rs['share'].iloc[0]} of {int(rs['runs'].iloc[0])} problems in each set ({noise_labels}, on the "
                  f"found and on the fresh seeds)")
    else:
        single = (f"{' and '.join(rs.loc['found', 'share'])} of {int(rs['runs'].iloc[0])} problems ({noise_labels}; "
                  f"fresh seeds: {' and '.join(rs.loc['fresh', 'share'])})")
    bad = pd.concat([rs, ms])
    out = outliers["found"]
    out_rows = out[out["Newton alone on a non-global minimum"] > 0]
    return (
        f"the constraint set SO(3), eqs. (9)-(10), is not convex, and with it the problem; the cost (8) alone is a "
        f"convex quadratic in vec(R) (its 9x9 Hessian 2 sum_j L_j^T L_j is positive semi-definite in all "
        f"{int(convexity['problems'].sum())} problems: {hessian}). Newton on SO(3) from a random start ends on a "
        f"non-global "
        f"local minimum in {single} and in {ms.loc['found', 'share']} of {int(ms['runs'].iloc[0])} runs with "
        f"{n_starts} starts on each of {int(ms['problems'].iloc[0])} problems (fresh: {ms.loc['fresh', 'share']}), "
        f"where every problem has at least one (found by at least 2 of its {n_starts} starts); these shares are "
        f"this Newton's (which basin a start falls into depends on the optimiser: a referee's other local "
        f"optimisers, issue 36, not run here, found 55-59 %), the existence of the minima is not. Every one is a "
        f"strict "
        f"local minimum (smallest eigenvalue of the Riemannian Hessian at least "
        f"{_floor(bad['hessian min / J'].min(), 2):.2f} J, "
        f"gradient below {_ceil(bad['gradient max / J'].max() * 1e9, 0):.0f}e-9 J) and a half-turn twin of the "
        f"global minimiser, {_floor(bad['angle min (deg)'].min(), 0):.0f}-180 deg from it: the midpoint of the two is "
        f"R n n^T up to sigma_2 <= {_ceil(bad['midpoint sigma2 max'].max(), 2):.2f} (rank one, not a rotation); they "
        f"cost at least {_floor(bad['cost min'].min(), 0):.0f} where the global minimum is at most "
        f"{_ceil(bad['global cost max'].max(), 2):.2f}. With outlier pairs Newton from the relaxed start stops on a "
        f"non-global strict minimum in {stuck['found']} of {n_out['found']} problems (fresh seeds: {stuck['fresh']} "
        f"of {n_out['fresh']}; up to {out_rows['their excess cost (max, %)'].max():.0f} % above the minimum, at least "
        f"{out_rows['their angle to the global minimiser (min deg)'].min():.0f} deg away). A convex cost on a convex "
        f"set has no non-global local minimum: SO(3) is what makes (8)-(10) non-convex")


def _convex_uncertainty(rs, ms, stuck, n_out, sensitivity) -> str:
    """The uncertainty of :func:`convex_problem_record`: the shares as brackets, bounded by
    ``sensitivity``."""
    scale, changed, perturbed = sensitivity
    bad = pd.concat([rs, ms])
    return (
        "Hessian eigenvalues, strictness, angles and costs: exact (deterministic) for each problem and minimum found; "
        "shares of runs: 10 % (one start) and 5 % (several) brackets, bounds, because turning every start by "
        f"{scale:g} rad changes the outcome of "
        f"{declared_bound(100 * changed / perturbed, high=2, margin=100 * ROUNDING_RUNS / perturbed)} % of {perturbed} "
        "starts "
        "(a bound; basins interleave finely, and a machine's rounding does the same), with 95 % Wilson intervals "
        "over each bracket's ends: one start "
        + ", ".join(f"[{100 * r['share low']:.0f}, {100 * r['share high']:.0f}] %" for _, r in rs.iterrows())
        + ", several " + ", ".join(f"[{100 * r['share low']:.0f}, {100 * r['share high']:.0f}] %"
                                   for _, r in ms.iterrows())
        + "; every problem with a non-global minimum: "
        + ", ".join(f"{seeds} {count_text(r['problems with one'], r['problems'])}" for seeds, r in ms.iterrows())
        + f"; every non-global end point strict and a half-turn: Wilson lower end at least "
        f"{100 * _floor(min(bad['strict low'].min(), bad['half-turn low'].min()), 3):.1f} % (at each bracket's lower "
        f"count); outliers: " + ", ".join(f"{k} {count_text(stuck[k], n_out[k])}" for k in ("found", "fresh")))


def convex_problem_record(convexity: pd.DataFrame, random_starts: pd.DataFrame, many_starts: pd.DataFrame,
                          outliers: dict, *, n_starts: int, sensitivity: tuple, section: str, setting: str) -> dict:
    """The ledger record of ``convex_problem`` (notebook 06, section 4): the keyword arguments of
    :func:`replication.study.ledger.record`.

    Parameters
    ----------
    convexity : DataFrame
        One row of :func:`cost_convexity` per problem set (index: label).
    random_starts : DataFrame
        One row of :func:`nonglobal_summary` per ``(seeds, noise)``, seeds ``"found"`` and
        ``"fresh"`` (one random start per problem).
    many_starts : DataFrame
        Likewise, ``n_starts`` starts per problem (index: seeds).
    outliers : dict
        ``{"found": table, "fresh": table}`` of :func:`outlier_certificate_study`.
    n_starts : int
    sensitivity : (scale, changed, runs)
        :func:`basin_sensitivity`'s perturbation (radians), its count and the starts perturbed.
    section, setting : str

    Raises
    ------
    ValueError
        (:func:`~replication.study.ledger.check_evidence`) the numbers do not bear the verdict
        ``fails``: a Hessian of (8) in ``vec(R)`` that is not PSD, a share of random starts on a
        non-global minimum outside 25-75 % on the found or the fresh seeds, a non-global end point
        that is not a strict local minimum or not a half-turn from the global one, a problem without
        one among its starts or one found by fewer than 2, an uncertified global minimum, or no
        outlier problem where Newton stops on a non-global minimum, on either seed set.
    """
    claim = "convex_problem"
    stuck, n_out = _check_convex_problem(convexity, random_starts, many_starts, outliers)
    evidence = _convex_evidence(convexity, random_starts, many_starts, outliers, stuck, n_out, n_starts)
    uncertainty = _convex_uncertainty(random_starts, many_starts, stuck, n_out, sensitivity)
    return {"claim": claim, "verdict": "fails", "evidence": evidence, "uncertainty": uncertainty, "setting": setting,
            "section": section}
