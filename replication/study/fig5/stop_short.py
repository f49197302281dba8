"""SQPs that stop short of the minimum of eq. (8), as the paper's Table I SQP does, each matched to
Table I.

The paper's Table I SQP ends at 0.015 at iteration 50, less accurate than its two-step method's
0.009, while in every setting of :mod:`.sweep` the certified minimiser of eq. (8) is the more
accurate: that SQP stopped short of the minimiser. :func:`match_to_table1` builds such SQPs (stopped
early, a loose tolerance), each with one knob matched to Table I on its own problems, for
:func:`replication.study.fig5.sweep_grid` to run with ``all_runs=True``; :func:`matching_display`
shows the matching.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ...core.so3 import frobenius_error
from ...core.solvers import ReplicationWarning, sqp, two_step
from ...core.stats import mean_se
from ..simulation import simulate

__all__ = ["MAX_MISMATCH", "match_to_table1", "matching_display"]


#: A stop-short SQP counts as matched to Table I when its mean error is within this factor of Table
#: I's.
MAX_MISMATCH = 1.25


def match_to_table1(seed: int, n_runs: int, target: float, *, motions: dict, starts: dict, noise: dict,
                    families: dict, iterations: int = 50, max_mismatch: float = MAX_MISMATCH):
    """SQPs that stop short of the minimum of eq. (8), each tuned to Table I's SQP error at
    iteration 50.

    The problems are Table I's (the paper's noise bound 0.02 on both sides: :func:`simulate`'s
    defaults), drawn with seed ``seed`` for every motion distribution and noise distribution. In
    each, every family's knob is set to the value of its grid whose mean error ``||R - R0||_F`` over
    the ``n_runs`` problems is closest to ``target`` on a log scale; the family is *matched* there
    if that mean is within a factor ``max_mismatch`` of ``target`` (a start from which SQP fails,
    say, matches with no value).

    Parameters
    ----------
    seed, n_runs : int
    target : float
        Table I's SQP mean error at iteration 50.
    motions, starts, noise : dict
        As for :func:`sweep_grid`.
    families : dict
        name -> dict with ``start`` (a label of ``starts``), ``knob`` (``"max_iterations"``: SQP
        stopped after that many iterations, read from one run's history; or an option of
        :func:`replication.core.solvers.sqp` such as ``"ftol"``, one run per value), ``grid`` (the
        knob's values, increasing), ``options`` (other options of ``sqp``, e.g. ``{"cost": 1 /
        2000}``) and ``text`` (a format of the knob's value, e.g. ``"{:g} iterations"``; the label
        is ``"name: text"``).
    iterations : int
        The iteration limit of SQP for the other knobs, and the two-step method's iterations.
    max_mismatch : float

    Returns
    -------
    (matching, configs, keys)
        ``matching``: index ``(family, motions, noise)``; columns ``knob``, ``value`` (its chosen
        value), ``SQP mean``, ``SQP SE``, ``SQP SD``, ``mean below`` / ``mean above`` (the mean
        errors at the neighbouring grid values, NaN at the ends), ``two-step mean`` (same problems
        and start), ``matched`` and ``label``. ``configs``: label -> ``("analytic", options)`` of
        the matched rows, for :func:`sweep_grid`; ``keys``: their rows ``(motions, start, noise,
        label)``, to run with ``variants_for=variants_of(keys)``.
    """
    rows, configs, keys = {}, {}, []
    for m_name, m_range in motions.items():
        for n_name, dist in noise.items():
            sim = simulate(seed, n_runs, motion_angle_range_deg=m_range, noise_distribution=dist)
            for name, fam in families.items():
                init, options = starts[fam["start"]], dict(fam.get("options") or {})
                knob, grid = fam["knob"], list(fam["grid"])
                with warnings.catch_warnings():  # stopping short is the point
                    warnings.simplefilter("ignore", ReplicationWarning)
                    if knob == "max_iterations":
                        res = sqp(sim.A, sim.B, max_iterations=int(max(grid)), init=init, **options)
                        errors = [frobenius_error(res.history.projected[:, int(k) - 1], sim.R0) for k in grid]
                    else:
                        errors = [frobenius_error(sqp(sim.A, sim.B, max_iterations=iterations, init=init,
                                                      **{**options, knob: value}).R, sim.R0) for value in grid]
                    ours = two_step(sim.A, sim.B, iterations=iterations, init=init, history=False)
                means = np.array([e.mean() for e in errors])
                best = int(np.argmin(np.abs(np.log(means / target))))
                value = grid[best]
                label = f"{name}: {fam['text'].format(value)}"
                matched = bool(np.exp(abs(np.log(means[best] / target))) <= max_mismatch)
                m, se = mean_se(errors[best])
                rows[(name, m_name, n_name)] = {
                    "knob": knob, "value": value, "SQP mean": m, "SQP SE": se, "SQP SD": errors[best].std(ddof=1),
                    "mean below": means[best - 1] if best > 0 else np.nan,
                    "mean above": means[best + 1] if best + 1 < len(grid) else np.nan,
                    "two-step mean": frobenius_error(ours.R, sim.R0).mean(), "matched": matched, "label": label}
                if matched:
                    configs[label] = ("analytic", {**options, knob: value})
                    keys.append((m_name, fam["start"], n_name, label))
    matching = pd.DataFrame(rows).T
    matching.index.names = ["family", "motions", "noise"]
    return matching, configs, keys


def matching_display(matching: pd.DataFrame, target: float) -> pd.DataFrame:
    """:func:`match_to_table1`'s table as text: the SQP chosen, its mean error ``± SE`` and SD
    against ``target``, the means at the neighbouring knob values (the match is bracketed where they
    lie on either side), and the two-step method's mean on the same problems."""
    def row(r):
        m = r["SQP mean"]
        if not r["matched"]:
            return pd.Series({"SQP (matched knob)": f"no match (best: {r['label'].split(': ')[-1]})",
                              "SQP mean ± SE": f"{m:.2f}", "SQP SD": "-", "neighbours": "-",
                              "two-step mean": f"{r['two-step mean']:.4f}"})
        nb = " / ".join("-" if pd.isna(v) else f"{v:.4f}" for v in (r["mean below"], r["mean above"]))
        return pd.Series({"SQP (matched knob)": r["label"].split(": ")[-1],
                          "SQP mean ± SE": f"{m:.4f} ± {r['SQP SE']:.4f}", "SQP SD": f"{r['SQP SD']:.3f}",
                          "neighbours": nb, "two-step mean": f"{r['two-step mean']:.4f}"})

    out = matching.apply(row, axis=1)
    out.columns.name = f"Table I: {target:.3f}"
    return out
