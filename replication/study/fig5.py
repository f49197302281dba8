"""Fig. 5: error against sensor noise, the two-step method against SQP (support of ``notebooks/04_noise_sweep.ipynb``).

The paper (Sec. III-A): with the noise on ``Delta R_i`` rising from 1 to 10 deg (1 deg on ``Delta R_c``), the
two-step error grows "much slower than that of the traditional optimization method": it is "more resilient to
the noise". Which SQP, which motions, which start and which noise distribution are not stated, so
:func:`noise_sweep` takes each as a setting, and :func:`resilience` reduces a sweep to what the claim needs,
with uncertainties:

* per level, the two-step error (``R^r``) and SQP's, as means with standard errors;
* SQP runs that do not end at the certified global minimiser of eq. (8) (from a far start SLSQP stops at its
  iteration limit) are counted, not averaged as digits: where such a run stops depends on rounding;
* the ratio two-step / SQP of the mean errors, with a paired bootstrap interval over problems, where SQP reached
  the global minimum in every run of the level;
* the growth ratio ``(two-step error at the top level - at the bottom) / (the same for SQP)``, with a bootstrap
  interval (problems resampled per level, the two methods paired on the same problems): below 1 means the
  two-step error grows more slowly, as the paper claims.

:func:`sweep_grid` runs the notebook's grid of settings (motions x start x noise distribution x SQP
configuration), :func:`summary_table` and :func:`fig5_figure` show it.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ..core.so3 import angle_between_deg, frobenius_error
from ..core.solvers import SQP_VARIANTS, ReplicationWarning, chordal_optimal, sqp, two_step
from ..core.stats import mean_se
from .simulation import noise_bound_for_angle_deg, simulate

__all__ = ["noise_sweep", "resilience", "AT_MINIMUM_DEG", "sqp_configs_for", "sweep_grid", "summary_table",
           "fig5_figure", "two_step_growth", "ratio_range"]

#: An SQP answer within this angle of the certified global minimiser of eq. (8) counts as having reached it.
AT_MINIMUM_DEG = 0.01


def noise_sweep(levels, n_runs: int, seed: int, *, motions=None, init=None, noise_distribution: str = "uniform",
                sqp_variant: str = "analytic", sqp_options=None, iterations: int = 50,
                camera_noise_deg: float = 1.0) -> dict:
    """Final errors of both methods at each sensor-noise level (degrees).

    Level ``k`` draws ``n_runs`` problems with seed ``seed + k``. The two-step method runs the paper's
    ``iterations``; SQP (the named variant of ``SQP_VARIANTS``, updated by ``sqp_options``, e.g.
    ``{"cost": 0.0005}``; at most ``iterations``) is projected onto SO(3) at the end.

    Returns
    -------
    dict
        level -> ``{"two_step": (n,) errors of R^r, "sqp": (n,) errors, "sqp_at_minimum": (n,) bool}``
        (errors ``||R - R0||_F``).
    """
    options = {**SQP_VARIANTS[sqp_variant], **(sqp_options or {})}
    cap = min(int(options.pop("max_iterations", iterations)), iterations)
    out = {}
    for k, level in enumerate(levels):
        sim = simulate(seed + k, n_runs, motion_angle_range_deg=motions, noise_distribution=noise_distribution,
                       noise_camera=noise_bound_for_angle_deg(camera_noise_deg),
                       noise_sensor=noise_bound_for_angle_deg(float(level)))
        with warnings.catch_warnings():  # the fixed protocol and SQP's failures are what is being measured
            warnings.simplefilter("ignore", ReplicationWarning)
            ours = two_step(sim.A, sim.B, iterations=iterations, init=init, history=False)
            opt = sqp(sim.A, sim.B, max_iterations=cap, init=init, **options)
        best = chordal_optimal(sim.A, sim.B)
        out[float(level)] = {
            "two_step": frobenius_error(ours.R_right, sim.R0),
            "sqp": frobenius_error(opt.R, sim.R0),
            "sqp_at_minimum": angle_between_deg(opt.R, best.R) <= AT_MINIMUM_DEG,
        }
    return out


def resilience(sweep: dict, rng: np.random.Generator, *, n_boot: int = 2000) -> tuple[pd.DataFrame, dict]:
    """Per-level statistics and the growth ratio of one :func:`noise_sweep` (see the module notes).

    Returns
    -------
    (per_level, growth)
        ``per_level``: index level; columns ``two_step``, ``two_step_se``, ``sqp_failed`` (runs not at the
        global minimum), ``sqp`` and ``sqp_se`` (NaN where any run failed: their digits depend on rounding),
        ``ratio``, ``ratio_low``, ``ratio_high`` (two-step / SQP, paired bootstrap 95 %; NaN where SQP failed).
        ``growth``: ``{"ratio", "low", "high"}`` between the lowest and the highest level (NaN if SQP failed in
        either), ``{"sqp_failed_share"}`` over all levels, and ``sqp_all_lowest`` / ``sqp_all_highest``: SQP's mean
        error over *all* runs at the lowest and highest level (for bounds only: with failed runs its digits
        depend on rounding).
    """
    levels = sorted(sweep)
    rows = {}
    for level in levels:
        d = sweep[level]
        ours_m, ours_se = mean_se(d["two_step"])
        failed = int((~d["sqp_at_minimum"]).sum())
        row = {"two_step": ours_m, "two_step_se": ours_se, "sqp_failed": failed, "runs": len(d["sqp"])}
        if failed == 0:
            m, se = mean_se(d["sqp"])
            n = len(d["sqp"])
            idx = rng.integers(0, n, size=(int(n_boot), n))
            boot = d["two_step"][idx].mean(axis=1) / d["sqp"][idx].mean(axis=1)
            row.update(sqp=m, sqp_se=se, ratio=ours_m / m, ratio_low=np.percentile(boot, 2.5),
                       ratio_high=np.percentile(boot, 97.5))
        else:
            row.update(sqp=np.nan, sqp_se=np.nan, ratio=np.nan, ratio_low=np.nan, ratio_high=np.nan)
        rows[level] = row
    per_level = pd.DataFrame(rows).T
    per_level.index.name = "sensor noise (deg)"
    lo, hi = sweep[levels[0]], sweep[levels[-1]]
    growth = {"sqp_failed_share": float(per_level["sqp_failed"].sum() / per_level["runs"].sum()),
              "sqp_all_lowest": float(lo["sqp"].mean()), "sqp_all_highest": float(hi["sqp"].mean())}
    if per_level.loc[[levels[0], levels[-1]], "sqp_failed"].sum() == 0:
        i_lo = rng.integers(0, len(lo["sqp"]), size=(int(n_boot), len(lo["sqp"])))
        i_hi = rng.integers(0, len(hi["sqp"]), size=(int(n_boot), len(hi["sqp"])))
        g_ours = hi["two_step"][i_hi].mean(axis=1) - lo["two_step"][i_lo].mean(axis=1)
        g_sqp = hi["sqp"][i_hi].mean(axis=1) - lo["sqp"][i_lo].mean(axis=1)
        ratio = (hi["two_step"].mean() - lo["two_step"].mean()) / (hi["sqp"].mean() - lo["sqp"].mean())
        growth.update(ratio=ratio, low=np.percentile(g_ours / g_sqp, 2.5), high=np.percentile(g_ours / g_sqp, 97.5))
    else:
        growth.update(ratio=np.nan, low=np.nan, high=np.nan)
    return per_level, growth


#: The settings of notebook 04's grid where the slow SQP variants also run: our defaults and the matched setting.
FULL_SETTINGS = (("Haar", "identity"), ("0-90 deg", "150 deg from R0"))


def sqp_configs_for(motions: str, start: str, noise: str, *, full_noise: str = "uniform in ball",
                    full_settings=FULL_SETTINGS) -> list:
    """The SQP configurations run in one setting of the grid (labels of notebook 04's ``CONFIGS``).

    Analytic SQP everywhere; with noise ``full_noise`` also analytic SQP on eq. (8) / 100J (``"cost / 100J"``),
    and where ``(motions, start)`` is in ``full_settings`` the finite-difference and capped variants too.

    Returns
    -------
    list of str
        In this order: ``"analytic"``, ``"cost / 100J"``, ``"finite-difference"``, ``"capped"`` (the order in
        which :func:`sweep_grid` runs them and draws their bootstrap samples).
    """
    variants = ["analytic"]
    if noise == full_noise:
        variants.append("cost / 100J")
        if (motions, start) in full_settings:
            variants += ["finite-difference", "capped"]
    return variants


def sweep_grid(levels, n_runs: int, seed: int, rng: np.random.Generator, *, motions: dict, starts: dict,
               noise: dict, configs: dict, variants_for=sqp_configs_for, n_boot: int = 2000):
    """:func:`noise_sweep` and :func:`resilience` over a grid of settings.

    Loops over ``motions``, then ``starts``, then ``noise``, then ``variants_for(motions label, start label,
    noise label)``; every setting uses the same ``seed`` (level ``k``: ``seed + k``), so settings share their
    problems where their motions and noise distribution agree.

    Parameters
    ----------
    levels : sequence of float
        Sensor-noise levels (deg).
    n_runs, seed : int
    rng : numpy.random.Generator
        Bootstrap draws of :func:`resilience`, setting after setting in loop order.
    motions, starts, noise : dict
        label -> ``motions`` / ``init`` / ``noise_distribution`` of :func:`noise_sweep`.
    configs : dict
        SQP configuration label -> ``(sqp_variant, sqp_options)``.
    variants_for : callable
        ``(motions label, start label, noise label) -> list of configuration labels``.
    n_boot : int

    Returns
    -------
    (sweeps, per_level, growth)
        ``sweeps``: ``(motions, start, noise, SQP variant) -> noise_sweep output``. ``per_level``: the stacked
        per-level tables of :func:`resilience`, index ``(motions, start, noise, SQP variant, sensor noise (deg))``,
        sorted. ``growth``: one row per setting (the ``growth`` dicts), sorted.
    """
    results, sweeps = {}, {}
    for m_name, m_range in motions.items():
        for s_name, start in starts.items():
            for n_name, dist in noise.items():
                for variant in variants_for(m_name, s_name, n_name):
                    key = (m_name, s_name, n_name, variant)
                    base, options = configs[variant]
                    sweeps[key] = noise_sweep(levels, n_runs, seed, motions=m_range, init=start,
                                              noise_distribution=dist, sqp_variant=base, sqp_options=options)
                    results[key] = resilience(sweeps[key], rng, n_boot=n_boot)
    names = ["motions", "start", "noise", "SQP variant"]
    per_level = pd.concat({k: v[0] for k, v in results.items()}, names=names + ["sensor noise (deg)"]).sort_index()
    growth = pd.DataFrame({k: v[1] for k, v in results.items()}).T
    growth.index.names = names
    return sweeps, per_level, growth.sort_index()


def _interval(v, lo, hi) -> str:
    return "-" if pd.isna(v) else f"{v:.2f} [{lo:.2f}, {hi:.2f}]"


def summary_table(per_level: pd.DataFrame, growth: pd.DataFrame, *, low: float = 1.0, high: float = 10.0):
    """One text row per setting: SQP's failure share, the two-step / SQP ratio at two levels, the growth ratio.

    Ratios are ``"r [low, high]"`` (95 % bootstrap), ``"-"`` where SQP failed (NaN); the failure share goes
    through :func:`replication.core.stats.share_range`.

    Parameters
    ----------
    per_level, growth : DataFrame
        :func:`sweep_grid` output.
    low, high : float
        The levels whose ratios are shown.
    """
    from ..core.stats import share_range

    def ratio_at(level):
        return per_level.xs(level, level=-1).apply(lambda r: _interval(r["ratio"], r["ratio_low"], r["ratio_high"]),
                                                   axis=1)

    return pd.DataFrame({
        "SQP not at the global minimum": growth["sqp_failed_share"].map(share_range),
        f"ratio at {low:g} deg": ratio_at(low),
        f"ratio at {high:g} deg": ratio_at(high),
        f"growth ratio {low:g} -> {high:g} deg": growth.apply(lambda r: _interval(r["ratio"], r["low"], r["high"]),
                                                              axis=1),
    })


def fig5_figure(per_level: pd.DataFrame, sweeps: dict, levels, panels,
                variants=(("analytic", "-"), ("finite-difference", "--"), ("capped", ":"))):
    """Fig. 5 replicated: final error against sensor noise, one panel per setting.

    Each panel: the two-step mean error (``R^r``) with ``± 1.96 SE`` error bars (from the ``"analytic"`` row of
    ``per_level``), and each SQP variant's mean error over *all* runs (including runs that did not reach the
    minimum), log scale.

    Parameters
    ----------
    per_level, sweeps
        :func:`sweep_grid` output.
    levels : sequence of float
    panels : sequence of (title, (motions, start, noise))
    variants : sequence of (SQP variant, line style)

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(12, 4.2), sharey=True)
    for ax, (label, key) in zip(axes, panels):
        base = per_level.loc[key + ("analytic",)]
        ax.errorbar(levels, base["two_step"], yerr=1.96 * base["two_step_se"], marker="o", capsize=3,
                    color="tab:cyan", label="ours, $R^r$")
        for variant, style in variants:
            sw = sweeps[key + (variant,)]
            ax.plot(levels, [sw[lv]["sqp"].mean() for lv in levels], ls=style, marker=".",
                    label=f"SQP ({variant}), all runs")
        ax.set_xlabel(r"noise on $\Delta R_i$ (deg); noise on $\Delta R_c$ = 1 deg")
        ax.set_title(label, fontsize=9)
        ax.set_yscale("log")
    axes[0].set_ylabel(r"final $\|\hat R_0 - R_0\|_F$ (mean; ours $\pm$ 1.96 SE)")
    axes[0].legend(fontsize=8)
    fig.suptitle("Fig. 5 (replicated)")
    fig.tight_layout()
    return fig


def two_step_growth(sweeps: dict, keys, *, low: float = 1.0, high: float = 10.0) -> dict:
    """Growth of the two-step mean error between two levels: ``mean(error at high) - mean(error at low)``, per key."""
    return {k: sweeps[k][high]["two_step"].mean() - sweeps[k][low]["two_step"].mean() for k in keys}


def ratio_range(per_level: pd.DataFrame, motions: str, start: str = "identity") -> tuple:
    """Smallest and largest two-step / SQP ratio over every level, noise distribution and SQP configuration of one
    (motions, start) setting."""
    ratio = per_level.xs(motions, level="motions").xs(start, level="start")["ratio"]
    return ratio.min(), ratio.max()
