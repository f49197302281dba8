"""The unstated settings of Table I (``notebooks/03_table1_monte_carlo.ipynb``, section 2): the
two-step method over a grid of motions, starts, noise distributions and half-step orders against the
paper's Table I, the closest settings again on fresh seeds, and what the paper's printed table
itself allows (its three decimals taken as a bound).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .. import paper
from ..simulation import SimulatedProblems, simulate
from .table import EARLY, NEGLIGIBLE, PRINTED_HALF_UNIT, iterate_errors, table1, versus_paper

__all__ = ["HALF_STEP_ORDERS", "PRINTED_ORDER", "paper_two_step_means", "two_step_means", "sensitivity_grid",
           "fresh_mismatch", "paper_left_farther", "paper_settled"]

#: The order of the two half-steps as the paper prints it: eq. (14) (``R^r_n`` from ``R^l_{n-1}``),
#: then eq. (15).
PRINTED_ORDER = "(14) then (15)"
#: The two orders of the half-steps (label -> ``reversed_halves`` of :func:`iterate_errors`).
HALF_STEP_ORDERS = {PRINTED_ORDER: False, "(15) then (14)": True}


def paper_two_step_means(reference: pd.DataFrame | None = None) -> pd.DataFrame:
    """The paper's mean two-step errors: index iteration, columns ``ours_right``, ``ours_left``."""
    reference = paper.load_table1() if reference is None else reference
    return reference["mean"].unstack()[["ours_right", "ours_left"]]


def two_step_means(problems: SimulatedProblems, start, paper_means: pd.DataFrame, *, reversed_halves: bool = False,
                   half_unit: float = PRINTED_HALF_UNIT, early=EARLY):
    """Mean errors of ``R^r`` and ``R^l`` at the paper's iterations, their mismatch with Table I,
    and how many early cells agree with it.

    Parameters
    ----------
    problems : SimulatedProblems
    start : None or array_like, shape (3, 3) or (n_runs, 3, 3)
        Start of the two-step method (``None``: identity).
    paper_means : DataFrame
        :func:`paper_two_step_means`.
    reversed_halves : bool
        The half-steps in the other order (:func:`iterate_errors`).
    half_unit : float
        The paper's rounding: a printed mean ``p`` stands for anything in ``[p - half_unit, p +
        half_unit)``.
    early : sequence of int
        The iterations whose cells are checked for agreement.

    Returns
    -------
    (means, mismatch, agreeing)
        ``means``: the ``"mean"`` part of :func:`table1` (index iteration, one column per side).
        ``mismatch = mean over iterations n and sides s of |log(ours[n, s] / p[n, s])|``, ``p`` the
        value the paper's rounding allows nearest to ours (0: equal means up to rounding; ``log 2 =
        0.69``: a factor 2 on average). ``agreeing``: how many of the ``2 len(early)`` early cells
        agree with the paper's Table I within :data:`~replication.study.table1.Z_AGREE`
        rounding-aware standard errors (:func:`versus_paper`).
    """
    tab = table1(iterate_errors(problems, init=start, with_sqp=False, reversed_halves=reversed_halves))
    means = tab.xs("mean", axis=1, level=1)
    ours = means[["ours_right", "ours_left"]]
    nearest = ours.clip(paper_means - half_unit, paper_means + half_unit)
    agreeing = int(versus_paper(tab, half_unit=half_unit).loc[list(early), "verdict"].eq("agrees").sum())
    return means, float(np.mean(np.abs(np.log(ours / nearest)))), agreeing


def _left_closer(means: pd.DataFrame, early) -> dict:
    """``{n: R^l closer than R^r}`` for each early iteration ``n`` whose ``R^r`` mean is above twice
    its value at the last iteration (still far from the floor)."""
    floor = means["ours_right"].iloc[-1]
    return {n: bool(means.loc[n, "ours_left"] < means.loc[n, "ours_right"]) for n in early
            if means.loc[n, "ours_right"] > 2 * floor}


def sensitivity_grid(seed: int, n_runs: int, motions: dict, starts: dict, noise: dict, paper_means: pd.DataFrame,
                     *, orders=None, shown=(2, 5, 10, 20, 50), early=EARLY):
    """The two-step method over every (noise distribution, motions, start, half-step order) setting,
    against Table I.

    Each (noise, motions) pair draws ``simulate(seed, n_runs, motion_angle_range_deg=...,
    noise_distribution=...)`` (the same seed everywhere: the settings share their random draws);
    every start and order is run on those problems.

    Parameters
    ----------
    seed, n_runs : int
    motions : dict
        label -> ``motion_angle_range_deg`` (``None``: Haar).
    starts : dict
        label -> start (``None``, a rotation, or one rotation per run).
    noise : dict
        label -> ``noise_distribution``.
    paper_means : DataFrame
        :func:`paper_two_step_means`.
    orders : dict, optional
        label -> ``reversed_halves`` (default: the printed order only, ``{PRINTED_ORDER: False}``).
    shown : sequence of int
        Iterations whose mean ``R^r`` error is reported (columns ``"R^r @<n>"``).
    early : sequence of int
        Iterations checked for agreement and for the order of ``R^l`` and ``R^r``.

    Returns
    -------
    (sens, left_closer)
        ``sens``: index ``(motions, start, noise, half-steps)`` in loop order (noise outermost, then
        motions, start, order); columns the ``R^r`` means, ``mismatch`` and ``early cells agreeing``
        (of ``2 len(early)``; :func:`two_step_means`). ``left_closer``: a bool Series, one entry per
        early cell whose ``R^r`` mean is still above twice its value at iteration 50 (index
        ``(motions, start, noise, half-steps, iteration)``): whether ``R^l``'s mean is below
        ``R^r``'s.
    """
    orders = {PRINTED_ORDER: False} if orders is None else orders
    rows, closer = {}, {}
    for n_name, dist in noise.items():
        for m_name, m_range in motions.items():
            sim_s = simulate(seed, n_runs, motion_angle_range_deg=m_range, noise_distribution=dist)
            for s_name, start in starts.items():
                for o_name, flip in orders.items():
                    means, mismatch, agreeing = two_step_means(sim_s, start, paper_means, reversed_halves=flip)
                    key = (m_name, s_name, n_name, o_name)
                    rows[key] = {**{f"R^r @{n}": means.loc[n, "ours_right"] for n in shown}, "mismatch": mismatch,
                                 "early cells agreeing": agreeing}
                    closer.update({(*key, n): v for n, v in _left_closer(means, early).items()})
    names = ["motions", "start", "noise", "half-steps"]
    sens = pd.DataFrame(rows).T
    sens.index.names = names
    index = pd.MultiIndex.from_tuples(list(closer), names=[*names, "iteration"]) if closer else \
        pd.MultiIndex.from_arrays([[]] * 5, names=[*names, "iteration"])
    return sens, pd.Series(list(closer.values()), index=index, dtype=bool)


def fresh_mismatch(settings, seed: int, n_runs: int, motions: dict, starts: dict, noise: dict,
                   paper_means: pd.DataFrame, *, orders=None, early=EARLY) -> pd.DataFrame:
    """Settings of :func:`sensitivity_grid` again on new problems, one draw per noise distribution.

    Parameters
    ----------
    settings : iterable of (motions label, start label, order label)
    seed, n_runs : int
        The new problems: ``simulate(seed, n_runs, ...)`` per noise distribution.
    motions, starts, noise, paper_means
        As in :func:`sensitivity_grid`.
    orders : dict, optional
        label -> ``reversed_halves`` (default :data:`HALF_STEP_ORDERS`).
    early : sequence of int

    Returns
    -------
    DataFrame
        Index: the settings (levels ``motions``, ``start``, ``half-steps``). Columns ``mismatch``
        (mean over the noise distributions), ``early cells agreeing`` (the most over them), ``R^l
        closer`` and ``early cells`` (summed over them: the early cells above twice the floor, and
        in how many ``R^l`` is the closer).
    """
    orders = HALF_STEP_ORDERS if orders is None else orders
    rows = {}
    for setting in settings:
        m_name, s_name, o_name = setting
        found = [two_step_means(simulate(seed, n_runs, motion_angle_range_deg=motions[m_name],
                                         noise_distribution=dist), starts[s_name], paper_means,
                                reversed_halves=orders[o_name]) for dist in noise.values()]
        closer = [v for means, _, _ in found for v in _left_closer(means, early).values()]
        rows[tuple(setting)] = {"mismatch": float(np.mean([f[1] for f in found])),
                                "early cells agreeing": max(f[2] for f in found), "R^l closer": sum(closer),
                                "early cells": len(closer)}
    out = pd.DataFrame(rows).T
    out.index.names = ["motions", "start", "half-steps"]
    return out.astype({"mismatch": float, "early cells agreeing": int, "R^l closer": int, "early cells": int})


def paper_left_farther(reference: pd.DataFrame | None = None, *, early=EARLY,
                       half_unit: float = PRINTED_HALF_UNIT) -> bool:
    """Is the paper's ``R^l`` farther from ``R0`` than its ``R^r`` at every early iteration,
    whatever its rounding (the printed means differ by more than ``2 half_unit``)?"""
    reference = paper.load_table1() if reference is None else reference
    return all(reference.loc[(n, "ours_left"), "mean"] - reference.loc[(n, "ours_right"), "mean"] > 2 * half_unit
               for n in early)


def paper_settled(reference: pd.DataFrame | None = None, method: str = "ours_right", *, tol: float = NEGLIGIBLE,
                  half_unit: float = PRINTED_HALF_UNIT) -> tuple:
    """The first of Table I's iterations from which the paper's mean stays within ``tol`` of its
    last value, at both ends of what its rounding allows.

    Each printed mean is anywhere within ``half_unit`` of its digits, so a difference of two is
    within ``2 half_unit`` of the printed difference. Returns ``(earliest, latest)``: the settling
    iteration with every difference as small, and as large, as the rounding allows (equal: the
    rounding cannot move it).
    """
    reference = paper.load_table1() if reference is None else reference
    means = reference.xs(method, level="method")["mean"].sort_index()
    dev = (means - means.iloc[-1]).abs().to_numpy()
    iters = list(means.index)

    def first(d):
        off = np.flatnonzero(d > tol)
        return iters[0] if not off.size else iters[int(off[-1]) + 1]
    widest = dev + 2 * half_unit
    widest[-1] = 0.0  # the last value against itself
    return first(np.maximum(dev - 2 * half_unit, 0.0)), first(widest)
