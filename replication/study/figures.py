"""Plot helpers shared by the notebooks (matplotlib; no computation here).

One style per solver (:data:`METHOD_STYLE`, :func:`method_style`): every figure takes a method's
colour from it, by name, so a method's colour never depends on which other methods a figure shows.
"""
from __future__ import annotations

import zlib

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["METHOD_STYLE", "SQP_CONFIG_STYLE", "method_style", "sqp_config_style", "convergence_figure",
           "SWEEP_LABELS", "SWEEP_TITLES", "sweep_figure", "FIG7_STYLE", "fig6_figure", "fig7_figure", "live_figure"]

#: SQP's configurations in notebooks 02 and 04 (:func:`replication.study.fig5.sqp_configs_for`; a
#: stop-short label ``"family: value"`` by its family): SQP's blue, one line style and marker each.
SQP_CONFIG_STYLE = {
    "analytic": {"ls": "-", "marker": "."},
    "finite-difference": {"ls": "--", "marker": "^"},
    "capped": {"ls": ":", "marker": "v"},
    "cost / 100J": {"ls": "-.", "marker": "s"},
    "stopped early": {"ls": ":", "marker": "D"},
    "loose tolerance": {"ls": ":", "marker": "x"},
    "eq. (8) / 100J, stopped early": {"ls": ":", "marker": "P"},
}
_PAPER = {"ls": "-", "lw": 2.0}
_BASELINE = {"ls": "--", "lw": 1.2}
#: One colour per method, reused in every figure, keyed by the registered solver names
#: (:func:`replication.core.solvers.available`) and by the paper's names of its three methods, which
#: keep the colours of the paper's Fig. 7 (``R^r`` cyan, ``R^l`` magenta, SQP blue): ``ours_right``
#: is ``two_step_right``, ``ours_left`` ``two_step_left``, ``optimization`` ``sqp``. An OpenCV
#: wrapper takes a light shade of the method it wraps. SQP's configurations (notebook 02) are SQP:
#: its blue, told apart by line style and marker.
METHOD_STYLE = {
    "two_step_right": {"color": "c", **_PAPER, "label": "two_step_right (ours, $R^r$)"},
    "two_step_left": {"color": "m", **_PAPER, "label": "two_step_left (ours, $R^l$)"},
    "sqp": {"color": "b", **_BASELINE, "label": "sqp (SLSQP)"},
    "chordal_optimal": {"color": "tab:green", **_BASELINE},
    "andreff": {"color": "tab:gray", **_BASELINE},
    "robust": {"color": "tab:olive", **_BASELINE},
    "park_martin": {"color": "tab:orange", **_BASELINE},
    "opencv_park": {"color": "#ffbb78", **_BASELINE},
    "tsai_lenz": {"color": "tab:brown", **_BASELINE},
    "opencv_tsai": {"color": "#c49c94", **_BASELINE},
    "horaud_dornaika": {"color": "tab:purple", **_BASELINE},
    "opencv_horaud": {"color": "#c5b0d5", **_BASELINE},
    "ours_right": {"color": "c", "label": "ours, $R^r$"},
    "ours_left": {"color": "m", "label": "ours, $R^l$"},
    "optimization": {"color": "b", "label": "SQP (SLSQP)"},
    "optimization_projected": {"color": "b", "ls": "--", "label": "SQP, iterate projected"},
    "optimization (analytic)": {"color": "b", **SQP_CONFIG_STYLE["analytic"], "label": "SQP, analytic gradients"},
    "optimization (finite-difference)": {"color": "b", **SQP_CONFIG_STYLE["finite-difference"],
                                         "label": "SQP, finite differences"},
    "optimization (capped)": {"color": "b", **SQP_CONFIG_STYLE["capped"], "label": "SQP, capped (30 it., ftol 1e-6)"},
    "optimization (per-pair cost)": {"color": "b", **SQP_CONFIG_STYLE["cost / 100J"], "label": "SQP, cost (8) / 2J"},
}

#: Colours left for methods :data:`METHOD_STYLE` does not know: none of them is a known method's.
_SPARE = ("gold", "crimson", "teal", "sienna", "darkkhaki", "hotpink", "darkslategray", "lime")
_SPARE_MARKERS = ("x", "+", "1", "2", "3", "4")


def method_style(name: str) -> dict:
    """Line style of method ``name`` (``color``, ``label``: the name unless :data:`METHOD_STYLE`
    gives one, maybe ``ls``, ``lw``, ``marker``), the same in every figure.

    A name :data:`METHOD_STYLE` does not know (a solver registered by a user) gets a colour and
    marker chosen from its name alone (CRC-32), among colours no known method uses, so it never
    changes another method's colour; two unknown names may share one (their labels tell them apart).
    Every solver this package registers has its own entry (tested).

    >>> method_style("two_step_right")["color"], method_style("ours_right")["color"]
    ('c', 'c')
    """
    if name in METHOD_STYLE:
        return {"label": name, **METHOD_STYLE[name]}
    h = zlib.crc32(name.encode())
    return {"color": _SPARE[h % len(_SPARE)], "marker": _SPARE_MARKERS[h // len(_SPARE) % len(_SPARE_MARKERS)],
            "ls": "-.", "lw": 1.2, "label": name}


def sqp_config_style(label: str) -> dict:
    """Style of an SQP configuration of notebook 04 (:data:`SQP_CONFIG_STYLE`, a stop-short label by
    its family): SQP's colour; an unknown configuration gets a dash-dot line and a ``*`` marker."""
    style = SQP_CONFIG_STYLE.get(label) or SQP_CONFIG_STYLE.get(label.split(": ")[0], {"ls": "-.", "marker": "*"})
    return {"color": METHOD_STYLE["sqp"]["color"], **style}


def convergence_figure(curves: dict, *, ylabel: str, title: str, logy: bool = True, ax=None):
    """One line per method: ``curves[name]`` is a 1-D array over iterations 1..N (on ``ax`` if
    given)."""
    fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
    for name, values in curves.items():
        values = np.asarray(values)
        ax.plot(np.arange(1, len(values) + 1), values, **{"marker": ".", **method_style(name)})
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


#: Axis labels of the sweeps in :mod:`replication.study.baselines`.
SWEEP_LABELS = {
    "noise_deg": "noise bound on each rotation (deg)",
    "n_motions": "number of motion pairs J",
    "motion_amplitude_deg": "largest motion angle (deg)",
    "outlier_fraction": "fraction of outlier pairs",
}
#: Panel titles of the sweeps (what varies; the rest as in our default simulation).
SWEEP_TITLES = {
    "noise_deg": "against the noise",
    "n_motions": "against the number of motion pairs",
    "motion_amplitude_deg": "against the motion amplitude",
    "outlier_fraction": "against outlier pairs",
}


_LEGEND_IN = 0.8  # inches below the sweep panels for their shared legend


def sweep_figure(sweeps, *, metric: str = "mean_deg", ylabel: str = "mean error to $R_0$ (deg)"):
    """One panel per sweep parameter, one line per solver in its :func:`method_style`; ``sweeps`` is
    :func:`replication.study.baselines.sweep` output.

    With ``metric="mean_deg"`` each point has its 95 % interval of the mean, ``± 1.96 sd_deg /
    sqrt(n_solved)`` (log scale: one that reaches 0 runs off the bottom of the axis); each panel's
    title says how many problems each point averages (``n_solved``: fewer where a solver returned no
    rotation).
    """
    params = list(dict.fromkeys(sweeps["parameter"]))
    ncols = 2
    nrows = -(-len(params) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(11, 3.6 * nrows + _LEGEND_IN), squeeze=False)
    methods = list(dict.fromkeys(sweeps["method"]))
    bars = metric == "mean_deg"
    for k, (ax, param) in enumerate(zip(axes.flat, params)):
        part = sweeps[sweeps["parameter"] == param]
        shown = []  # the means and the interval ends that do not reach 0: they set the axis
        for method in methods:
            line = part[part["method"] == method]
            y = line[metric].to_numpy(float)
            style = {"marker": ".", **method_style(method)}
            if bars:
                half = 1.96 * line["sd_deg"].to_numpy(float) / np.sqrt(line["n_solved"].to_numpy(float))
                ax.errorbar(line["value"], y, yerr=[np.minimum(half, 0.999 * y), half], capsize=2, elinewidth=0.8,
                            **style)
                shown += [y + half, (y - half)[half < y]]
            else:
                ax.plot(line["value"], y, **style)
            shown.append(y)
        n = part["n_solved"]
        each = f"N = {n.max()}" if n.min() == n.max() else f"N = {n.min()}-{n.max()}"
        ax.set_title(f"({chr(97 + k)}) {SWEEP_TITLES.get(param, param)}: {each} problems per point", fontsize=10)
        ax.set_xlabel(SWEEP_LABELS.get(param, param))
        ax.set_ylabel(ylabel + ("\n(bars: 95 % interval of the mean;\nrunning off the bottom: reaches 0)" if bars
                                else ""), fontsize=9)
        ax.set_yscale("log")
        shown = np.concatenate(shown)
        shown = shown[np.isfinite(shown) & (shown > 0)]
        if len(shown):
            ax.set_ylim(shown.min() / 1.5, shown.max() * 1.5)
    for ax in list(axes.flat)[len(params):]:
        fig.delaxes(ax)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, _LEGEND_IN / (3.6 * nrows + _LEGEND_IN), 1, 1))
    return fig


#: Fig. 7's colours as the paper describes them: camera red, sensor frame black, projections cyan /
#: magenta / blue (the colours of the three methods in :data:`METHOD_STYLE`).
FIG7_STYLE = {
    "camera": {"color": "tab:red", "label": "camera (PnP)", "lw": 1.6},
    "sensor_frame": {"color": "black", "label": "sensor frame (uncalibrated)", "lw": 1.0},
    "ours_right": {"color": METHOD_STYLE["ours_right"]["color"], "label": "projected, ours $R^r$", "lw": 1.0},
    "ours_left": {"color": METHOD_STYLE["ours_left"]["color"], "label": "projected, ours $R^l$", "lw": 1.0,
                  "ls": "--"},
    "optimization": {"color": METHOD_STYLE["optimization"]["color"], "label": "projected, SQP", "lw": 1.0, "ls": ":"},
}
ANGLES = ("roll", "pitch", "yaw")


def fig6_figure(per_set, *, reference: str = "the true $R_0$"):
    """Fig. 6: each method's ``R0`` estimate over the data sets, as its deviation from a reference.

    ``per_set`` is :attr:`replication.study.lab.LabResult.per_set`: the rotation vector of
    ``R_est R_ref^T`` about the camera's x, y, z axes (deg). (Euler angles would be
    unreadable here: the mounting puts ``R0`` near pitch -90 deg, gimbal lock.)
    """
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4), sharey=True)
    for ax, axis in zip(axes, "xyz"):
        for method, part in per_set.groupby("method", sort=False):
            style = {"color": method_style(method)["color"], "ls": FIG7_STYLE[method].get("ls", "-")}
            ax.plot(part["set"] + 1, part[f"dev_{axis}_deg"], marker="o", ms=4, label=method_style(method)["label"],
                    **style)
        ax.axhline(0.0, color="grey", ls="--", lw=1)
        ax.set_xlabel("data set")
        ax.set_title(f"about camera {axis}")
    axes[0].set_ylabel(f"deviation from {reference} (deg)")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def fig7_figure(traces):
    """Fig. 7: (a) relative roll / pitch / yaw traces; (b) their differences to the camera's.

    ``traces`` is :attr:`replication.study.lab.LabResult.traces`.
    """
    sources = [k for k in FIG7_STYLE if f"{k}_roll" in traces]
    fig, axes = plt.subplots(2, 3, figsize=(12, 6), sharex=True)
    t = traces["t"]
    for j, angle in enumerate(ANGLES):
        for src in sources:
            axes[0, j].plot(t, traces[f"{src}_{angle}"], **FIG7_STYLE[src])
            if src != "camera":
                diff = (traces[f"{src}_{angle}"] - traces[f"camera_{angle}"] + 180.0) % 360.0 - 180.0
                axes[1, j].plot(t, diff, **FIG7_STYLE[src])
        axes[0, j].set_title(f"(a) {angle}")
        axes[1, j].set_title(f"(b) {angle}: minus camera")
        axes[1, j].set_xlabel("time (s)")
    axes[0, 0].set_ylabel("relative attitude (deg)")
    axes[1, 0].set_ylabel("difference (deg)")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig


def live_figure(runs: dict, targets=(0.5, 0.2)):
    """Notebook 08: the online estimate's error to the reference and its stated radius over time,
    per recording, with the moment VINS-Mono's rule declares success (``runs``:
    :func:`replication.study.live_study.live_run` results); each ``"ready"`` target (deg) is a
    labelled dotted line. Points before the 10th pair are left out."""
    fig, axes = plt.subplots(1, len(runs), figsize=(6.5 * len(runs), 4.2), squeeze=False)
    for ax, (name, (track, vins)) in zip(axes[0], runs.items()):
        ok = track["n_pairs"] >= 10
        ax.semilogy(track["t"][ok], track["error_deg"][ok], label="error to the reference")
        ax.semilogy(track["t"][ok], track["radius_deg"][ok], "--", label="stated 95 % radius")
        for target in targets:
            ax.axhline(target, color="grey", lw=0.6, ls=":")
            ax.annotate(f"target {target:g} deg", (1.0, target), xycoords=("axes fraction", "data"),
                        xytext=(-3, 2), textcoords="offset points", ha="right", va="bottom", fontsize=7,
                        color="dimgrey")
        if np.isfinite(vins["ready_t"]):
            ax.axvline(vins["ready_t"], color="tab:red", lw=0.8)
            ax.annotate(f"VINS-Mono rule: done,\n{vins['error_at_ready_deg']:.2f} deg off", (vins["ready_t"], 0.9),
                        xycoords=("data", "axes fraction"), xytext=(3, 0), textcoords="offset points", fontsize=7,
                        color="tab:red", va="top")
        ax.set_title(f"{name}: {int(track['n_pairs'].max())} pairs")
        ax.set_xlabel("time since the first camera pose (s)")
        ax.set_ylabel("angle (deg)")
        ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    return fig
