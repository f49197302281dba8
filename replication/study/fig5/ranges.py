"""The growth ratio over motion ranges, and a two-step method that stops short (notebook 04, section
4).

Where both methods converge (SQP from the identity at the certified minimum of (8), the two-step
iteration run to its limit), how much faster the two-step error grows with the sensor noise depends
on the motions: the ledger's first two motion distributions do not span it. And the mirror image of
:mod:`.stop_short`: a two-step method stopped at the paper's 50 iterations with small motions, where
it has not converged, beside the same SQP. :func:`range_sweep` runs both on one set of problems per
motion range (the two-step variants share SQP's runs); :func:`range_table` shows it.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ...core.so3 import angle_between_deg, frobenius_error
from ...core.solvers import ReplicationWarning, chordal_optimal, sqp, two_step
from ..simulation import noise_bound_for_angle_deg, simulate
from .sweep import AT_MINIMUM_DEG, _interval, resilience

__all__ = ["CONVERGED", "range_sweep", "range_table"]

#: The two-step label of the runs iterated to the limit (``iterations="auto"``: to convergence, or
#: the closed-form limit beyond 1000 iterations).
CONVERGED = "to its limit"


def range_sweep(levels, n_runs: int, seed: int, rng: np.random.Generator, *, ranges: dict, stop_short: dict,
                init=None, noise_distribution: str = "uniform", camera_noise_deg: float = 1.0,
                sqp_iterations: int = 50, n_boot: int = 2000):
    """Both methods over motion ranges: the two-step method to its limit everywhere, and stopped
    early where asked.

    Level ``k`` of range ``r`` draws ``n_runs`` problems with seed ``seed + k`` (as
    :func:`noise_sweep`: the ranges share their noise draws). SQP (analytic, at most
    ``sqp_iterations``) runs once per level and serves every two-step variant; an SQP run counts as
    converged within :data:`AT_MINIMUM_DEG` of the certified minimiser.

    Parameters
    ----------
    levels : sequence of float
        Sensor-noise levels (deg); the growth ratio is between the first and the last.
    ranges : dict
        label -> ``motion_angle_range_deg`` of :func:`replication.study.simulation.simulate`.
    stop_short : dict
        label of a range -> iterations at which a second two-step variant stops (e.g. ``{"0-30 deg":
        50}``).
    rng : numpy.random.Generator
        Bootstrap draws of :func:`resilience`, row after row.

    Returns
    -------
    (per_level, growth)
        As :func:`sweep_grid`'s (``per_level`` sorted, ``growth`` in the order of ``ranges``), index
        ``(motions, two-step)`` (``two-step``: :data:`CONVERGED` or ``"<n> iterations"``).
    """
    unknown = [k for k in stop_short if k not in ranges]
    if unknown:
        raise ValueError(f"stop_short names ranges {unknown} that are not in ranges {list(ranges)}")
    results = {}
    for label, motions in ranges.items():
        variants = {CONVERGED: "auto", **({f"{stop_short[label]} iterations": int(stop_short[label])}
                                          if label in stop_short else {})}
        sweeps = {v: {} for v in variants}
        for k, level in enumerate(levels):
            sim = simulate(seed + k, n_runs, motion_angle_range_deg=motions, noise_distribution=noise_distribution,
                           noise_camera=noise_bound_for_angle_deg(camera_noise_deg),
                           noise_sensor=noise_bound_for_angle_deg(float(level)))
            with warnings.catch_warnings():  # the stopped two-step and SQP's cap are what is measured
                warnings.simplefilter("ignore", ReplicationWarning)
                opt = sqp(sim.A, sim.B, max_iterations=sqp_iterations, init=init)
                ours = {v: two_step(sim.A, sim.B, iterations=it, init=init, history=False)
                        for v, it in variants.items()}
                best = chordal_optimal(sim.A, sim.B)  # small motions: R0 poorly determined, said once per sweep here
            at_min = angle_between_deg(opt.R, best.R) <= AT_MINIMUM_DEG
            for v, res in ours.items():
                sweeps[v][float(level)] = {"two_step": frobenius_error(res.R, sim.R0),
                                           "sqp": frobenius_error(opt.R, sim.R0), "sqp_at_minimum": at_min}
        for v in variants:
            results[(label, v)] = resilience(sweeps[v], rng, n_boot=n_boot)
    names = ["motions", "two-step"]
    per_level = pd.concat({k: v[0] for k, v in results.items()}, names=names + ["sensor noise (deg)"]).sort_index()
    growth = pd.DataFrame({k: v[1] for k, v in results.items()}).T
    growth.index.names = names
    return per_level, growth


def range_table(per_level: pd.DataFrame, growth: pd.DataFrame, *, low: float = 1.0) -> pd.DataFrame:
    """One text row per (motions, two-step): SQP's runs off the minimum, the two-step / SQP error
    ratio at ``low`` and the growth ratio, each ``"r [low, high]"`` (95 % bootstrap), or ``"-"``
    where SQP left the minimum."""
    at_low = per_level.xs(low, level=-1)
    out = pd.DataFrame({
        "SQP runs off the minimum": growth["sqp_failed_share"].map(lambda p: f"{100 * p:.0f} %"),
        f"two-step / SQP at {low:g} deg": at_low.apply(
            lambda r: _interval(r["ratio"], r["ratio_low"], r["ratio_high"]), axis=1),
        "growth ratio": growth.apply(lambda r: _interval(r["ratio"], r["low"], r["high"]), axis=1)})
    return out.loc[growth.index]
