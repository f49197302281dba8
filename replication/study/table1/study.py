"""The studies of ``notebooks/03_table1_monte_carlo.ipynb``, section by section (the grid over the
unstated settings of its section 2 is :mod:`.grid`): SQP's failures, the scale of eq. (8),
convergence per setting, the counts of runs again on fresh seeds, the cost against its minimum, and
the texts of the notebook's verdicts.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ...core.so3 import angle_between_deg, frobenius_error, orthonormality_residual
from ...core.solvers import ReplicationWarning, chordal_optimal, sqp
from ...core.stats import ROUNDING_RUNS, mean_se, paired_ratio_ci, share_range, wilson_interval
from .. import paper
from ..simulation import simulate
from .table import DIVERGED, FEASIBLE_TOL, convergence_summary, diverting_runs, iterate_errors

__all__ = ["compact", "FAIL", "share_ci", "bracket_ci", "failure_table", "failure_display", "sqp_failures",
           "at_other_minimum", "cost_scale_study", "fresh_seed_counts", "interval_text", "share_text",
           "shown_cost_scales", "convergence_by_setting", "shown_convergence", "cost_against_minimum",
           "diverting_table", "per_setting_text", "sqp_per_setting_text", "scales_text"]

#: A run "fails" when its final error ``||R_hat - R0||_F`` exceeds this (notebook 03, section 4).
FAIL = 0.05


def compact(cmp: pd.DataFrame, reference: pd.DataFrame | None = None) -> pd.DataFrame:
    """One row per iteration: each column's "ours" with its ``z`` (or "infeasible"), beside the
    paper's values.

    Parameters
    ----------
    cmp : DataFrame
        Output of :func:`versus_paper` (index ``(iteration, method)``; it must hold
        ``"ours_right"``).
    reference : DataFrame, optional
        The paper's Table I (:func:`replication.study.paper.load_table1`, the default).

    Returns
    -------
    DataFrame
        Index: iteration. Columns ``"paper ours_right"``, ``"paper optimization"`` (``"mean ±
        std"``), then one column per method: ``"<ours> (z <z>)"`` with ``z`` rounded to an integer,
        or ``cmp``'s "infeasible" text.
    """
    reference = paper.load_table1() if reference is None else reference
    shown = cmp.apply(lambda r: r["ours"] if r["verdict"] == "infeasible" else f"{r['ours']} (z {r['z']:+.0f})",
                      axis=1)
    table = shown.unstack("method")
    table.insert(0, "paper ours_right", cmp.xs("ours_right", level="method")["paper"])
    table.insert(1, "paper optimization", cmp.xs("ours_right", level="method").index.map(
        lambda n: f"{reference.loc[(n, 'optimization'), 'mean']:.3f} ± "
                  f"{reference.loc[(n, 'optimization'), 'std']:.3f}"))
    return table


def share_ci(p, n: int, digits: int = 0) -> str:
    """``"<p>% [<low>, <high>]"``: a share of ``n`` runs with its 95 % Wilson interval, in
    percent."""
    low, high = wilson_interval(int(round(float(p) * n)), n)
    return f"{100 * p:.{digits}f}% [{100 * low:.{digits}f}, {100 * high:.{digits}f}]"


def bracket_ci(p, n: int, step: float = 0.05, *, margin_runs: int = ROUNDING_RUNS) -> str:
    """A share of ``n`` runs that moves with the machine's rounding: its ``step``-wide bracket
    (:func:`~replication.core.stats.share_range`, a bound on this machine's share) and, in brackets,
    a 95 % Wilson interval covering every count in that bracket (the lower end of the smallest, the
    upper of the largest). ``none`` and ``all``: ``"none of <n> [0, <high>]"``, ``"all of <n>
    [<low>, 100]"``. The share must keep ``margin_runs`` runs from the bracket's edges
    (``ValueError`` otherwise: :func:`share_range`'s guard)."""
    p = float(p)
    if p in (0.0, 1.0):
        low, high = wilson_interval(int(round(p * n)), n)
        return (f"{share_range(p, margin=margin_runs / n)} of {n} "
                + (f"[0, {100 * high:.1f}]" if p == 0 else f"[{100 * low:.1f}, 100]"))
    k = int(np.floor(p / step + 1e-9))
    k_min = int(np.ceil(k * step * n - 1e-9))
    k_max = min(int(np.ceil(min((k + 1) * step, 1.0) * n - 1e-9)) - 1, n - 1)
    low, high = wilson_interval(k_min, n)[0], wilson_interval(k_max, n)[1]
    return f"{share_range(p, step, margin=margin_runs / n, what='a share of runs')} [{100 * low:.0f}, {100 * high:.0f}]"


def failure_table(rows: dict, *, fail: float = FAIL) -> pd.DataFrame:
    """Share of runs whose final error exceeds ``fail``, per row and method.

    Parameters
    ----------
    rows : dict
        row label -> ``{method: errors}``; ``errors`` is (n, iterations) (the last column is the
        final error, as :func:`iterate_errors` returns) or (n,) final errors.
    fail : float

    Returns
    -------
    DataFrame
        Index: row labels; columns: the methods in order of first appearance (NaN where a row lacks
        one).
    """
    out = {}
    for label, errors in rows.items():
        out[label] = {m: float(np.mean((e[:, -1] if np.ndim(e) == 2 else np.asarray(e)) > fail))
                      for m, e in errors.items()}
    return pd.DataFrame(out).T


def failure_display(fails: pd.DataFrame, runs) -> pd.DataFrame:
    """:func:`failure_table` as text: each share with its 95 % Wilson interval; SQP's strictly
    between 0 and 1 as brackets.

    Far-start SQP failures depend on where runs stop at their iteration limit (the machine's
    rounding), so an SQP share ``0 < p < 1`` is shown as :func:`bracket_ci` (a bound on this
    machine's share, with an interval covering the bracket); every other share as :func:`share_ci`
    with one decimal, ``n = runs(row, column)``.

    Parameters
    ----------
    fails : DataFrame
        :func:`failure_table`.
    runs : callable
        ``runs(row_label, column) -> n`` runs behind that share.
    """
    return fails.apply(lambda col: [("" if pd.isna(p) else bracket_ci(p, runs(r, col.name))
                                     if col.name.startswith("optimization") and 0 < p < 1
                                     else share_ci(p, runs(r, col.name), 1)) for r, p in zip(fails.index, col)])


def sqp_failures(A, B, R0, *, init=None, max_iterations: int = 50, fail: float = FAIL):
    """Run SQP (analytic gradients) and flag the runs that fail and the runs that stopped at the
    iteration limit.

    Returns
    -------
    (result, failed, at_limit)
        SQP's :class:`~replication.core.solvers.Solution`; ``failed``: final (projected) error
        ``||R - R0||_F > fail``; ``at_limit``: ``iterations >= max_iterations``. Both (n,) bool.
    """
    with warnings.catch_warnings():  # failures are what is being counted
        warnings.simplefilter("ignore", ReplicationWarning)
        res = sqp(A, B, max_iterations=max_iterations, init=init)
    return res, frobenius_error(res.R, R0) > fail, res.iterations >= max_iterations


def at_other_minimum(result, A, B, *, max_iterations: int = 50, min_angle_deg: float = 90.0,
                     rotation_tol: float = 1e-6) -> np.ndarray:
    """Runs where SQP converged to a rotation far from the certified minimiser of eq. (8): another
    local minimum.

    A run counts when SLSQP stopped before ``max_iterations``, its last raw iterate ``X`` is a
    rotation (``||X^T X - I||_F < rotation_tol``) and its answer is more than ``min_angle_deg`` from
    :func:`replication.core.solvers.chordal_optimal`'s.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    final = result.history.iterates[..., -1, :, :]
    on_rotation = np.linalg.norm(np.swapaxes(final, -1, -2) @ final - np.eye(3), axis=(-2, -1)) < rotation_tol
    far_from_min = angle_between_deg(result.R, chordal_optimal(A, B).R) > min_angle_deg
    return (result.iterations < max_iterations) & on_rotation & far_from_min


def cost_scale_study(settings: dict, scales: dict, rng: np.random.Generator, *, n_runs: int = 300,
                     max_iterations: int = 50, fail: float = FAIL, at=(15, 30, 50)):
    """SQP (analytic) on eq. (8) times each factor, per setting: failures, convergence, mean error
    curve.

    SLSQP is not invariant to the scale of its objective; ``cost=s`` minimises ``s`` times eq. (8).

    Parameters
    ----------
    settings : dict
        label -> ``(problems, init)``; the first ``n_runs`` problems are used.
    scales : dict
        name -> factor ``s``.
    rng : numpy.random.Generator
        Bootstrap intervals of :func:`convergence_summary` (default ``n_boot``), drawn in loop order
        (settings outer, scales inner).
    n_runs, max_iterations : int
    fail : float
        Failure threshold on the final raw iterate's error.
    at : sequence of int
        Iterations whose mean error is reported (NaN where a run failed).

    Returns
    -------
    (table, runs)
        ``table``: index ``(setting, "eq. (8) times")``; columns ``failed`` (share), ``below_1pct``
        and ``settled`` with their ``_low``/``_high`` bootstrap bounds, ``mean @<n>``. ``runs``:
        ``(setting, scale) -> (SQP result, (n_runs, iterations) raw-iterate errors)``.
    """
    rows, runs = {}, {}
    with warnings.catch_warnings():  # SQP stops at its iteration limit on purpose; failures are counted
        warnings.simplefilter("ignore", ReplicationWarning)
        for label, (s, init) in settings.items():
            for name, scale in scales.items():
                r = sqp(s.A[:n_runs], s.B[:n_runs], max_iterations=max_iterations, init=init, cost=scale)
                e = frobenius_error(r.history.iterates, s.R0[:n_runs, None])
                runs[(label, name)] = (r, e)
                failed, curve = float(np.mean(e[:, -1] > fail)), e.mean(axis=0)
                cs = convergence_summary({"sqp": e}, rng).loc["sqp"]
                row = {"failed": failed, **{f"{k}{end}": cs[f"{k}{end}"] for k in ("below_1pct", "settled")
                                            for end in ("", "_low", "_high")}}
                row.update({f"mean @{n}": curve[n - 1] if failed == 0 else np.nan for n in at})
                rows[(label, name)] = row
    table = pd.DataFrame(rows).T
    table.index.names = ["setting", "eq. (8) times"]
    return table, runs


def fresh_seed_counts(seed: int, n_runs: int, n_sqp: int, scales: dict, rng: np.random.Generator, *,
                      motions_deg, far_start, near_scales=("as printed", "/ 2J"), far_scales=("as printed", "/ 100J"),
                      bar: float = FAIL, fail: float = FAIL) -> dict:
    """Section 5's counts of runs again, on new problems (root seed ``seed``): the confirmation of
    its shares.

    Two identity-start settings, our defaults (``"defaults"``) and motion angles ``motions_deg``
    (``"0-90 deg, identity start"``): the two-step method on ``n_runs`` runs, SQP (analytic
    gradients) on eq. (8) times each of ``near_scales`` on the first ``n_sqp``; and the matched
    setting (``"matched"``: the same motions from ``far_start``), SQP at each of ``far_scales`` on
    ``n_sqp`` runs.

    Parameters
    ----------
    seed, n_runs, n_sqp : int
    scales : dict
        name -> factor (the notebook's ``SCALES``); ``near_scales`` and ``far_scales`` name some of
        them.
    rng : numpy.random.Generator
        Bootstrap intervals (:func:`cost_scale_study`, :func:`convergence_summary`).
    motions_deg : (float, float)
    far_start : array_like, shape (3, 3)
    near_scales, far_scales : sequence of str
    bar : float
        The error bar of :func:`diverting_table`.
    fail : float
        Failure threshold of :func:`cost_scale_study`.

    Returns
    -------
    dict
        ``seed``, ``n_runs``, ``n_sqp``; ``conv``: :func:`convergence_summary` per identity-start
        setting (index ``(setting, method)``, methods ``"ours_right"`` and ``"optimization
        (analytic)"``: SQP on eq. (8) as printed, ``near_scales[0]``); ``div``:
        :func:`diverting_table` of those settings; ``scales``: :func:`cost_scale_study` of all three
        settings (index ``(setting, "eq. (8) times")``).
    """
    sims = {"defaults": simulate(seed, n_runs),
            "0-90 deg, identity start": simulate(seed, n_runs, motion_angle_range_deg=motions_deg)}
    settings = {label: (s, *iterate_errors(s, with_sqp=False, return_costs=True)) for label, s in sims.items()}
    near, runs = cost_scale_study({label: (s, None) for label, s in sims.items()},
                                  {k: scales[k] for k in near_scales}, rng, n_runs=n_sqp, fail=fail)
    far, _ = cost_scale_study({"matched": (sims["0-90 deg, identity start"], far_start)},
                              {k: scales[k] for k in far_scales}, rng, n_runs=n_sqp, fail=fail)
    conv = pd.concat({label: convergence_summary(
        {"ours_right": e["ours_right"], "optimization (analytic)": runs[(label, near_scales[0])][1]}, rng,
        costs={"ours_right": c["ours_right"],
               "optimization (analytic)": runs[(label, near_scales[0])][0].history.cost})
        for label, (_, e, c) in settings.items()}, names=["setting", "method"])
    div = diverting_table(runs, settings, list(settings), scale_names=near_scales, bar=bar, n_runs=n_sqp)
    return dict(seed=seed, n_runs=n_runs, n_sqp=n_sqp, conv=conv, div=div, scales=pd.concat([near, far]))


def interval_text(row, key: str, caps: dict | None = None, *, iterations: int = 50) -> str:
    """``"<value> [<low>, <high>]"`` of a convergence measure (iterations, bootstrap bounds), or
    "never".

    Parameters
    ----------
    row : Series
        A row of :func:`convergence_summary` or :func:`cost_scale_study` (``key``, ``key_low``,
        ``key_high``).
    key : str
    caps : dict, optional
        Given: "never" also names the iteration budget, ``"never (<caps[method]> iterations)"``,
        with the method the row's name (its last part for a tuple) and ``iterations`` for a method
        not in ``caps``.
    """
    v = row[key]
    if v is None or pd.isna(v):
        if caps is None:
            return "never"
        return f"never ({caps.get(row.name[-1] if isinstance(row.name, tuple) else row.name, iterations)} iterations)"
    return f"{int(v)} [{row[f'{key}_low']:.0f}, {row[f'{key}_high']:.0f}]"


def share_text(row, key: str) -> str:
    """A share as a percentage; far-start SQP (setting "matched...", method "optimization...") as a
    bracket.

    Far-start SLSQP paths change with the machine's rounding: there a share strictly between 0 and 1
    is ``"varies †"`` and 0 or 1 goes through :func:`replication.core.stats.share_range`.
    ``row.name`` is ``(setting, method)``.
    """
    far_sqp = row.name[0].startswith("matched") and row.name[1].startswith("optimization")
    if far_sqp and 0 < row[key] < 1:
        return "varies †"
    return share_range(row[key]) if far_sqp else f"{row[key]:.0%}"


def shown_cost_scales(scales: pd.DataFrame, reference: pd.DataFrame | None = None) -> pd.DataFrame:
    """:func:`cost_scale_study`'s table as text, with the paper's SQP means as a last row
    ``("paper's Table I", "?")``."""
    reference = paper.load_table1() if reference is None else reference
    shown = pd.DataFrame({
        "failed": [share_range(p) if 0 < p < 1 else f"{p:.0%}" for p in scales["failed"]],
        "below 1 %": scales.apply(lambda r: interval_text(r, "below_1pct"), axis=1),
        "settled": scales.apply(lambda r: interval_text(r, "settled"), axis=1),
        **{c: scales[c].map(lambda v: "-" if pd.isna(v) else f"{v:.3f}") for c in ("mean @15", "mean @30", "mean @50")},
    }, index=scales.index)
    shown.loc[("paper's Table I", "?"), :] = ["-", "-", "-"] + [f"{reference.loc[(n, 'optimization'), 'mean']:.3f}"
                                                                for n in (15, 30, 50)]
    return shown


def convergence_by_setting(settings: dict, rng: np.random.Generator, *, caps=None) -> pd.DataFrame:
    """:func:`convergence_summary` of every setting, stacked.

    Parameters
    ----------
    settings : dict
        label -> ``(problems, errors, costs)`` (:func:`iterate_errors` with ``return_costs=True``).
    rng : numpy.random.Generator
        Bootstrap draws, setting after setting.
    caps : dict, optional
        Passed to :func:`convergence_summary`.

    Returns
    -------
    DataFrame
        Index ``(setting, method)``.
    """
    return pd.concat({k: convergence_summary(e, rng, caps=caps, costs=c) for k, (_, e, c) in settings.items()},
                     names=["setting", "method"])


def shown_convergence(conv: pd.DataFrame, caps=None) -> pd.DataFrame:
    """:func:`convergence_by_setting` as text: final error ± SE, iteration intervals, shares of
    runs.

    Final mean errors above :data:`DIVERGED` are "infeasible"; the iteration measures go through
    :func:`interval_text` (with ``caps``), the shares through :func:`share_text`.
    """
    caps = dict(caps or {})
    return pd.DataFrame({
        "final error": conv.apply(lambda r: f"infeasible (mean > {DIVERGED:g})" if not r["final"] <= DIVERGED
                                  else f"{r['final']:.4f} ± {r['final_se']:.4f}", axis=1),
        **{label: conv.apply(lambda r, k=key: interval_text(r, k, caps), axis=1)
           for label, key in (("below 1 %", "below_1pct"), ("converged", "converged"), ("settled", "settled"))},
        **{label: conv.apply(lambda r, k=key: share_text(r, k), axis=1)
           for label, key in (("left SO(3)", "left_SO3"), ("error rises", "error_rises"),
                              ("rises above floor", "rises_above_floor"), ("cost rises", "cost_rises"),
                              ("diverts", "diverts"), ("diverts above floor", "diverts_above_floor"))},
    })


def cost_against_minimum(settings: dict, rng: np.random.Generator, *, method: str = "ours_right",
                         at=(1, 10, 50)):
    """The cost (8) of a method's iterates against the certified minimum of (8), per setting.

    Parameters
    ----------
    settings : dict
        label -> ``(problems, errors, costs)``; ``costs[method]`` is (n, iterations).
    rng : numpy.random.Generator
        Paired bootstrap (:func:`replication.core.stats.paired_ratio_ci`, 2000 draws) of
        ``mean(cost@10) / mean(minimum)`` and then ``mean(cost@last) / mean(minimum)``, per setting
        in order.
    method : str
    at : sequence of int
        Iterations shown as ``"mean ± SE"``.

    Returns
    -------
    (shown, ratios, minima)
        ``shown``: one text row per setting (cost at ``at``, the certified minimum, the two ratios
        with their intervals). ``ratios``: label -> ``{"@10 / @1": mean(cost@10) / mean(cost@1),
        "@10 / minimum": (ratio, low, high), "@50 / minimum": (ratio, low, high)}``. ``minima``:
        label -> the :func:`replication.core.solvers.chordal_optimal` result.
    """
    rows, ratios, minima = {}, {}, {}
    for label, (s, _, c) in settings.items():
        floor = minima[label] = chordal_optimal(s.A, s.B)
        ours = c[method]
        rows[label] = {**{f"cost @{n}": "{:.4f} ± {:.4f}".format(*mean_se(ours[:, n - 1])) for n in at},
                       "certified minimum of (8)": "{:.4f} ± {:.4f}".format(*mean_se(floor.cost))}
        ratios[label] = {"@10 / @1": ours[:, 9].mean() / ours[:, 0].mean(),
                         "@10 / minimum": paired_ratio_ci(ours[:, 9], floor.cost, rng),
                         "@50 / minimum": paired_ratio_ci(ours[:, -1], floor.cost, rng)}
        rows[label].update({k: f"{v[0]:.3f} [{v[1]:.3f}, {v[2]:.3f}]" for k, v in ratios[label].items()
                            if isinstance(v, tuple)})
    return pd.DataFrame(rows).T, ratios, minima


def diverting_table(scale_runs: dict, settings: dict, labels, *, scale_names=("as printed", "/ 2J"),
                    bar: float = 0.05, n_runs: int = 300, method: str = "ours_right") -> pd.DataFrame:
    """Share of runs that "divert" (:func:`diverting_runs`) with one absolute error bar for every
    method.

    Per setting label: SQP at each cost scale (its raw iterates; second column: only iterations
    whose raw iterate is within :data:`FEASIBLE_TOL` of a rotation, where a lower cost (8) means a
    better rotation; third: the error read on the projected iterates, the nearest rotations, against
    the raw iterates' cost), then the two-step method on its first ``n_runs`` runs (always a
    rotation: the columns equal).

    Parameters
    ----------
    scale_runs : dict
        ``(label, scale name) -> (SQP result, errors)`` (:func:`cost_scale_study`).
    settings : dict
        label -> ``(problems, errors, costs)``.
    labels : sequence of str
    scale_names : sequence of str
    bar : float
        ``min_error`` of :func:`diverting_runs`.
    n_runs : int
    method : str

    Returns
    -------
    DataFrame
        Index ``(label, "SQP, eq. (8) <scale>" | "two-step R^r")``; columns ``"diverts, error >
        <bar>"``, ``"... and on a rotation"`` and ``"... read on projected iterates"`` (shares).
    """
    rows = {}
    col, col_rot, col_proj = f"diverts, error > {bar:g}", "... and on a rotation", "... read on projected iterates"
    for label in labels:
        for name in scale_names:
            r, e = scale_runs[(label, name)]
            feasible = orthonormality_residual(r.history.iterates) < FEASIBLE_TOL
            proj = frobenius_error(r.history.projected, settings[label][0].R0[:len(e), None])
            rows[(label, f"SQP, eq. (8) {name}")] = {
                col: diverting_runs(e, r.history.cost, min_error=bar).mean(),
                col_rot: diverting_runs(e, r.history.cost, min_error=bar, feasible=feasible).mean(),
                col_proj: diverting_runs(proj, r.history.cost, min_error=bar).mean()}
        e, c = settings[label][1][method][:n_runs], settings[label][2][method][:n_runs]
        share = diverting_runs(e, c, min_error=bar).mean()
        rows[(label, "two-step R^r")] = {col: share, col_rot: share, col_proj: share}
    return pd.DataFrame(rows).T


def per_setting_text(frames, name: str, key: str, caps=None) -> str:
    """``"<label> <interval>; ..."``: one method's convergence measure in each setting
    (:func:`interval_text`).

    ``frames`` is a sequence of ``(label, convergence_summary frame)``.
    """
    return "; ".join(f"{label} {interval_text(f.loc[name], key, caps)}" for label, f in frames)


def sqp_per_setting_text(frames, sqp_names, key: str, caps=None) -> str:
    """``"<label>: <variant> <interval>, ...; ..."`` for SQP columns ``"optimization
    (<variant>)"``."""
    return "; ".join(f"{label}: " + ", ".join(f"{n[14:-1]} {interval_text(f.loc[n], key, caps)}" for n in sqp_names)
                     for label, f in frames)


def scales_text(scales: pd.DataFrame, label: str, scale_names, key: str = "settled") -> str:
    """``"<scale> <interval>, ..."``: a measure of :func:`cost_scale_study` at each scale for one
    setting."""
    return ", ".join(f"{name} {interval_text(scales.loc[(label, name)], key)}" for name in scale_names)
