"""The noise sweep of Fig. 5: both methods' errors per sensor-noise level, over a grid of settings.
Theory and measured numbers: ``docs/studies.md``, section ``replication.study.fig5.sweep``."""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ...core.so3 import angle_between_deg, frobenius_error
from ...core.solvers import SQP_VARIANTS, ReplicationWarning, chordal_optimal, sqp, two_step
from ...core.stats import declared_bound, mean_se
from ..simulation import noise_bound_for_angle_deg, simulate

__all__ = ["noise_sweep", "resilience", "AT_MINIMUM_DEG", "sqp_configs_for", "sweep_grid", "summary_table",
           "fig5_figure", "two_step_growth", "ratio_range", "problem_sets", "variants_of", "confirmation_table",
           "span_text", "rounding_bound", "PAPER_ITERATION", "PAPER_LEVEL_DEG"]


#: An SQP answer within this angle of the certified global minimiser of eq. (8) counts as having
#: reached it.
AT_MINIMUM_DEG = 0.01


def noise_sweep(levels, n_runs: int, seed: int, *, motions=None, init=None, noise_distribution: str = "uniform",
                sqp_variant: str = "analytic", sqp_options=None, iterations: int = 50,
                camera_noise_deg: float = 1.0) -> dict:
    """Final errors of both methods at each sensor-noise level (degrees).

    Level ``k`` draws ``n_runs`` problems with seed ``seed + k``. The two-step method runs the
    paper's ``iterations``; SQP (the named variant of ``SQP_VARIANTS``, updated by ``sqp_options``,
    e.g. ``{"cost": 0.0005}``; at most ``iterations``) is projected onto SO(3) at the end.

    Returns
    -------
    dict
        level -> ``{"two_step": (n,) errors of R^r, "sqp": (n,) errors, "sqp_at_minimum": (n,)
        bool}`` (errors ``||R - R0||_F``).
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
            "two_step": frobenius_error(ours.R, sim.R0),
            "sqp": frobenius_error(opt.R, sim.R0),
            "sqp_at_minimum": angle_between_deg(opt.R, best.R) <= AT_MINIMUM_DEG,
        }
    return out


def resilience(sweep: dict, rng: np.random.Generator, *, n_boot: int = 2000,
               all_runs: bool = False) -> tuple[pd.DataFrame, dict]:
    """Per-level statistics and the growth ratio of one :func:`noise_sweep` (see the module notes).

    Parameters
    ----------
    sweep : dict
        :func:`noise_sweep` output.
    rng : numpy.random.Generator
        Bootstrap draws: per level (where a ratio is given), then the resampled problems of the
        lowest and the highest level.
    n_boot : int
    all_runs : bool
        ``False`` (default): ratios only where SQP reached the global minimum in every run (its
        failures stop at points that depend on rounding). ``True``: over all runs, for SQPs meant to
        stop short of the minimum (:func:`match_to_table1`), whose errors are smooth functions of
        the data.

    Returns
    -------
    (per_level, growth)
        ``per_level``: index level; columns ``two_step``, ``two_step_se``, ``sqp_failed`` (runs not
        at the global minimum), ``sqp`` and ``sqp_se`` (NaN where any run failed, unless
        ``all_runs``), ``ratio``, ``ratio_low``, ``ratio_high`` (two-step / SQP, paired bootstrap 95
        %; NaN likewise). ``growth``: ``{"ratio", "low", "high"}`` between the lowest and the
        highest level (NaN if SQP failed in either, unless ``all_runs``), ``{"sqp_failed_share"}``
        over all levels, ``sqp_all_lowest`` / ``sqp_all_highest``: SQP's mean error over *all* runs
        at the lowest and highest level, and the changes of the mean errors from the lowest to the
        highest level with their 95 % bootstrap intervals (the same resampled problems as the growth
        ratio): ``two_step_change`` (``_low``, ``_high``) and ``sqp_change`` (``_low``, ``_high``;
        over all runs, including failed ones).
    """
    levels = sorted(sweep)
    rows = {}
    for level in levels:
        d = sweep[level]
        ours_m, ours_se = mean_se(d["two_step"])
        failed = int((~d["sqp_at_minimum"]).sum())
        row = {"two_step": ours_m, "two_step_se": ours_se, "sqp_failed": failed, "runs": len(d["sqp"])}
        if failed == 0 or all_runs:
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
    i_lo = rng.integers(0, len(lo["sqp"]), size=(int(n_boot), len(lo["sqp"])))
    i_hi = rng.integers(0, len(hi["sqp"]), size=(int(n_boot), len(hi["sqp"])))
    g_ours = hi["two_step"][i_hi].mean(axis=1) - lo["two_step"][i_lo].mean(axis=1)
    g_sqp = hi["sqp"][i_hi].mean(axis=1) - lo["sqp"][i_lo].mean(axis=1)
    for name, method, boot in (("two_step_change", "two_step", g_ours), ("sqp_change", "sqp", g_sqp)):
        growth.update({name: float(hi[method].mean() - lo[method].mean()),
                       f"{name}_low": float(np.percentile(boot, 2.5)),
                       f"{name}_high": float(np.percentile(boot, 97.5))})
    if all_runs or per_level.loc[[levels[0], levels[-1]], "sqp_failed"].sum() == 0:
        ratio = growth["two_step_change"] / growth["sqp_change"]
        growth.update(ratio=ratio, low=np.percentile(g_ours / g_sqp, 2.5), high=np.percentile(g_ours / g_sqp, 97.5))
    else:
        growth.update(ratio=np.nan, low=np.nan, high=np.nan)
    return per_level, growth


#: The settings of notebook 04's grid where the slow SQP variants also run: our defaults and the
#: matched setting.
FULL_SETTINGS = (("Haar", "identity"), ("0-90 deg", "150 deg from R0"))


def sqp_configs_for(motions: str, start: str, noise: str, *, full_noise: str = "uniform in ball",
                    full_settings=FULL_SETTINGS) -> list:
    """The SQP configurations run in one setting of the grid (labels of notebook 04's ``CONFIGS``).

    Analytic SQP everywhere; with noise ``full_noise`` also analytic SQP on eq. (8) / 100J (``"cost
    / 100J"``), and where ``(motions, start)`` is in ``full_settings`` the finite-difference and
    capped variants too.

    Returns
    -------
    list of str
        In this order: ``"analytic"``, ``"cost / 100J"``, ``"finite-difference"``, ``"capped"`` (the
        order in which :func:`sweep_grid` runs them and draws their bootstrap samples).
    """
    variants = ["analytic"]
    if noise == full_noise:
        variants.append("cost / 100J")
        if (motions, start) in full_settings:
            variants += ["finite-difference", "capped"]
    return variants


def sweep_grid(levels, n_runs: int, seed: int, rng: np.random.Generator, *, motions: dict, starts: dict,
               noise: dict, configs: dict, variants_for=sqp_configs_for, n_boot: int = 2000,
               all_runs: bool = False):
    """:func:`noise_sweep` and :func:`resilience` over a grid of settings.

    Loops over ``motions``, then ``starts``, then ``noise``, then ``variants_for(motions label,
    start label, noise label)``; every setting uses the same ``seed`` (level ``k``: ``seed + k``),
    so settings share their problems where their motions and noise distribution agree.

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
    all_runs : bool
        Passed to :func:`resilience` (``True`` for SQPs meant to stop short of the minimum).

    Returns
    -------
    (sweeps, per_level, growth)
        ``sweeps``: ``(motions, start, noise, SQP variant) -> noise_sweep output``. ``per_level``:
        the stacked per-level tables of :func:`resilience`, index ``(motions, start, noise, SQP
        variant, sensor noise (deg))``, sorted. ``growth``: one row per setting (the ``growth``
        dicts), sorted.
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
                    results[key] = resilience(sweeps[key], rng, n_boot=n_boot, all_runs=all_runs)
    names = ["motions", "start", "noise", "SQP variant"]
    per_level = pd.concat({k: v[0] for k, v in results.items()}, names=names + ["sensor noise (deg)"]).sort_index()
    growth = pd.DataFrame({k: v[1] for k, v in results.items()}).T
    growth.index.names = names
    return sweeps, per_level, growth.sort_index()


def problem_sets(sweeps: dict, growth: pd.DataFrame) -> pd.DataFrame:
    """The rows of a grid grouped by the problems they ran on.

    :func:`sweep_grid` gives every setting the same seeds, so rows with the same motions and noise
    distribution ran on the same problems: one problem set, however many SQP configurations and
    starts ran on it. Where they all end at the same point, the rows repeat one measurement.

    Parameters
    ----------
    sweeps : dict
        :func:`sweep_grid`'s ``sweeps``.
    growth : DataFrame
        Its ``growth`` table, the rows to group.

    Returns
    -------
    DataFrame
        Index ``(motions, noise)``, in order of first appearance; columns ``rows`` (how many),
        ``first`` (the first row's key), ``SQP difference`` and ``two-step difference`` (the largest
        difference, run by run at any level, between the errors of any row and the first row's),
        ``growth ratio`` (the first row's, ``"v [low, high]"``) and ``growth ratios of the rows``
        (smallest and largest, ``"a-b"``, or one number where they agree to 2 decimals).
    """
    groups: dict = {}
    for key in growth.index:
        groups.setdefault((key[0], key[2]), []).append(key)
    out = {}
    for pset, keys in groups.items():
        first = keys[0]

        def diff(method, first=first, keys=keys):
            return max(float(np.abs(sweeps[k][lv][method] - sweeps[first][lv][method]).max())
                       for k in keys for lv in sweeps[first])

        g = growth.loc[keys, "ratio"]
        r = growth.loc[first]
        out[pset] = {"rows": len(keys), "first": first, "SQP difference": diff("sqp"),
                     "two-step difference": diff("two_step"),
                     "growth ratio": _interval(r["ratio"], r["low"], r["high"]),
                     "growth ratios of the rows": span_text(g)}
    table = pd.DataFrame(out).T
    table.index.names = ["motions", "noise"]
    return table


def variants_of(keys):
    """``variants_for`` of :func:`sweep_grid` that runs exactly the rows ``keys`` (``(motions,
    start, noise, SQP variant)``), e.g. to run them again on fresh seeds."""
    keys = list(keys)
    return lambda m, s, n: [k[3] for k in keys if k[:3] == (m, s, n)]


def confirmation_table(found: pd.DataFrame, fresh: pd.DataFrame) -> pd.DataFrame:
    """The growth ratio and the changes of the mean errors (lowest to highest level), found against
    fresh seeds.

    ``found`` and ``fresh``: ``growth`` tables of :func:`sweep_grid`; one row per row of ``fresh``.
    Texts ``"v [low, high]"`` (95 % bootstrap); ``"-"`` where no growth ratio is given, and there
    SQP's change as a bound (:func:`rounding_bound`: its failed runs stop at points that depend on
    the machine's rounding).
    """
    def ratio(g):
        return g.apply(lambda r: _interval(r["ratio"], r["low"], r["high"]), axis=1)

    def change(g, name):
        def text(r):
            if name != "two_step_change" and pd.isna(r["ratio"]):
                return rounding_bound(r[name + "_low"], r[name + "_high"])
            return f"{r[name]:.3f} [{r[name + '_low']:.3f}, {r[name + '_high']:.3f}]"
        return g.apply(text, axis=1)

    found = found.loc[fresh.index]
    return pd.DataFrame({"growth ratio (found)": ratio(found), "growth ratio (fresh)": ratio(fresh),
                         "SQP change (found)": change(found, "sqp_change"),
                         "SQP change (fresh)": change(fresh, "sqp_change"),
                         "two-step change (fresh)": change(fresh, "two_step_change")})


#: The declared bound (deg) on the change of a failing SQP's mean error, and the margin its interval
#: ends must keep inside it. Where a failing SQP's runs stop depends on the machine's rounding: such
#: interval ends moved by up to 0.04 deg between machines (OpenBLAS's Sandybridge kernels: 0.2698 ->
#: 0.2879; numpy's AVX2 paths: an end of about 0.26 below 0.25), so an end rounded outwards to 0.1
#: deg flipped; a bound declared in advance does not, and 0.1 is more than twice the largest move
#: seen (the ends here: -0.31 and 0.27, twice the margin inside +-0.6).
FAILING_CHANGE_BOUND_DEG = 0.6
FAILING_CHANGE_MARGIN_DEG = 0.1


def rounding_bound(low: float, high: float) -> str:
    """``"within [-0.6, 0.6]"``: the declared :data:`FAILING_CHANGE_BOUND_DEG`, once ``low`` and
    ``high`` are checked to lie :data:`FAILING_CHANGE_MARGIN_DEG` inside it
    (:func:`replication.core.stats.declared_bound`); a bound that holds on machines that round
    differently, not an interval.

    >>> rounding_bound(-0.13, 0.20)
    'within [-0.6, 0.6]'
    """
    b = FAILING_CHANGE_BOUND_DEG
    declared_bound(low, -b, margin=FAILING_CHANGE_MARGIN_DEG, what="a failing SQP's change, lower end (deg)")
    declared_bound(high, high=b, margin=FAILING_CHANGE_MARGIN_DEG, what="a failing SQP's change, upper end (deg)")
    return f"within [{-b:.1f}, {b:.1f}]"


def _interval(v, lo, hi) -> str:
    return "-" if pd.isna(v) else f"{v:.2f} [{lo:.2f}, {hi:.2f}]"


def summary_table(per_level: pd.DataFrame, growth: pd.DataFrame, *, low: float = 1.0, high: float = 10.0):
    """One text row per setting: SQP's failure share, the two-step / SQP ratio at two levels, the
    growth ratio.

    Ratios are ``"r [low, high]"`` (95 % bootstrap), ``"-"`` where SQP failed (NaN); the failure
    share goes through :func:`replication.core.stats.share_range`.

    Parameters
    ----------
    per_level, growth : DataFrame
        :func:`sweep_grid` output.
    low, high : float
        The levels whose ratios are shown.
    """
    from ...core.stats import share_range

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


#: The paper's points shown in Fig. 5: Table I at its last iteration, whose setting (1 deg noise on
#: both sides) is Fig. 5's lowest level. Fig. 5's own curves are not in the paper's text (its figure
#: is an image we do not have).
PAPER_ITERATION = 50
PAPER_LEVEL_DEG = 1.0


def fig5_figure(per_level: pd.DataFrame, sweeps: dict, levels, panels,
                variants=(("analytic", "-"), ("finite-difference", "--"), ("capped", ":")), *,
                title: str = "Fig. 5 (replicated)", paper: pd.DataFrame | None = None):
    """Fig. 5 replicated: final error against sensor noise, one panel per setting.

    Each panel: the two-step mean error (``R^r``) with ``± 1.96 SE`` error bars (from the
    ``"analytic"`` row of ``per_level``), and each SQP variant's mean error over *all* runs
    (including runs that did not reach the minimum), log scale, in the colours of
    :func:`replication.study.figures.method_style` (SQP's blue for every variant, each with its line
    style and marker); a variant that did not run in a panel's setting is left out of that panel,
    and each panel has its own legend and says how many runs each point averages. With ``paper``,
    the paper's numbers beside ours, never used: Table I's mean ± SD at iteration
    :data:`PAPER_ITERATION` for ``R^r`` and SQP, at :data:`PAPER_LEVEL_DEG` (Table I's noise), as
    stars.

    Parameters
    ----------
    per_level, sweeps
        :func:`sweep_grid` output (of several grids: concatenated / merged).
    levels : sequence of float
    panels : sequence of (title, (motions, start, noise))
    variants : sequence of (SQP variant, line style)
    title : str
    paper : DataFrame, optional
        :func:`replication.study.paper.load_table1`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    from ..figures import method_style, sqp_config_style

    ours = method_style("ours_right")
    fig, axes = plt.subplots(1, len(panels), figsize=(max(12.0, 4.5 * len(panels)), 5.4), sharey=True, squeeze=False)
    for ax, (label, key) in zip(axes[0], panels):
        base = per_level.loc[key + ("analytic",)]
        ax.errorbar(levels, base["two_step"], yerr=1.96 * base["two_step_se"], marker="o", capsize=3,
                    color=ours["color"], label=ours["label"])
        runs = set()
        for variant, style in variants:
            if key + (variant,) not in sweeps:
                continue
            sw = sweeps[key + (variant,)]
            runs |= {len(sw[lv]["sqp"]) for lv in levels}
            ax.plot(levels, [sw[lv]["sqp"].mean() for lv in levels], **{**sqp_config_style(variant), "ls": style},
                    label=f"SQP ({variant}), all runs")
        if paper is not None:
            for method, text, dx in (("ours_right", "$R^r$", -0.12), ("optimization", "SQP", 0.12)):
                row = paper.loc[(PAPER_ITERATION, method)]
                ax.errorbar([PAPER_LEVEL_DEG + dx], [row["mean"]], yerr=[row["std"]], marker="*", ms=11, capsize=3,
                            ls="none", color=method_style(method)["color"], mec="k", mew=0.6,
                            label=f"the paper, {text}: Table I, iteration {PAPER_ITERATION} (mean ± SD)")
        n = f"N = {min(runs)}" + (f"-{max(runs)}" if len(runs) > 1 else "") if runs else ""
        ax.set_title(f"{label}\n{n} runs per point" if n else label, fontsize=9)
        ax.set_xlabel(r"noise on $\Delta R_i$ (deg); noise on $\Delta R_c$ = 1 deg")
        ax.set_yscale("log")
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.16))
    axes[0, 0].set_ylabel(r"final $\|\hat R_0 - R_0\|_F$ (mean; ours $\pm$ 1.96 SE)")
    fig.suptitle(title)
    if paper is not None:
        fig.text(0.5, 0.005, "Stars: the paper's only numbers in Fig. 5's setting (Table I, 1 deg noise on both sides, "
                 "1000 runs), drawn either side of 1 deg; its Fig. 5 curves are not in the paper's text, so they "
                 "are not shown.", ha="center", fontsize=8)
    fig.tight_layout(rect=(0, 0.03 if paper is not None else 0, 1, 1))
    return fig


def two_step_growth(sweeps: dict, keys, *, low: float = 1.0, high: float = 10.0) -> dict:
    """Growth of the two-step mean error between two levels: ``mean(error at high) - mean(error at
    low)``, per key."""
    return {k: sweeps[k][high]["two_step"].mean() - sweeps[k][low]["two_step"].mean() for k in keys}


def ratio_range(per_level: pd.DataFrame, motions: str, start: str = "identity") -> tuple:
    """Smallest and largest two-step / SQP ratio over every level, noise distribution and SQP
    configuration of one (motions, start) setting."""
    ratio = per_level.xs(motions, level="motions").xs(start, level="start")["ratio"]
    return ratio.min(), ratio.max()


def span_text(values, digits: int = 2) -> str:
    """Smallest and largest of ``values`` as ``"a-b"`` (``"a to b"`` where one is negative), or
    ``"a"`` if they agree at ``digits`` decimals."""
    lo, hi = f"{min(values):.{digits}f}", f"{max(values):.{digits}f}"
    return lo if lo == hi else f"{lo} to {hi}" if lo.startswith("-") or hi.startswith("-") else f"{lo}-{hi}"
