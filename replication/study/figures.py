"""Plot helpers shared by the notebooks (matplotlib; no computation here)."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["METHOD_STYLE", "convergence_figure", "SWEEP_LABELS", "sweep_figure", "FIG7_STYLE", "fig6_figure",
           "fig7_figure", "live_figure"]

#: One colour/line style per method, reused in every figure.
METHOD_STYLE = {
    "ours_right": {"color": "tab:cyan", "label": "ours, $R^r$"},
    "ours_left": {"color": "tab:purple", "label": "ours, $R^l$"},
    "optimization": {"color": "tab:blue", "label": "SQP (SLSQP)"},
    "optimization_projected": {"color": "tab:blue", "ls": "--", "label": "SQP, iterate projected"},
    "optimization (analytic)": {"color": "tab:blue", "label": "SQP, analytic gradients"},
    "optimization (finite-difference)": {"color": "tab:orange", "ls": "--", "label": "SQP, finite differences"},
    "optimization (capped)": {"color": "tab:red", "ls": ":", "label": "SQP, capped (30 it., ftol 1e-6)"},
    "optimization (per-pair cost)": {"color": "tab:brown", "ls": "-.", "label": "SQP, cost (8) / 2J"},
}


def convergence_figure(curves: dict, *, ylabel: str, title: str, logy: bool = True, ax=None):
    """One line per method: ``curves[name]`` is a 1-D array over iterations 1..N (on ``ax`` if given)."""
    fig, ax = plt.subplots() if ax is None else (ax.figure, ax)
    for name, values in curves.items():
        values = np.asarray(values)
        ax.plot(np.arange(1, len(values) + 1), values, marker=".", **METHOD_STYLE.get(name, {"label": name}))
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


def sweep_figure(sweeps, *, metric: str = "mean_deg", ylabel: str = "mean error to $R_0$ (deg)"):
    """One panel per sweep parameter, one line per solver; ``sweeps`` is :func:`replication.study.baselines.sweep`
    output."""
    params = list(dict.fromkeys(sweeps["parameter"]))
    ncols = 2
    nrows = -(-len(params) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(11, 3.6 * nrows), squeeze=False)
    methods = list(dict.fromkeys(sweeps["method"]))
    cmap = plt.get_cmap("tab20")
    for ax, param in zip(axes.flat, params):
        part = sweeps[sweeps["parameter"] == param]
        for i, method in enumerate(methods):
            line = part[part["method"] == method]
            style = {"ls": "-", "lw": 2.2} if method.startswith("two_step") else {"ls": "--", "lw": 1.2}
            ax.plot(line["value"], line[metric], marker=".", color=cmap(i), label=method, **style)
        ax.set_xlabel(SWEEP_LABELS.get(param, param))
        ax.set_ylabel(ylabel)
        ax.set_yscale("log")
    for ax in list(axes.flat)[len(params):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return fig


#: Fig. 7's colours as the paper describes them: camera red, sensor frame black,
#: projections cyan / magenta / blue.
FIG7_STYLE = {
    "camera": {"color": "tab:red", "label": "camera (PnP)", "lw": 1.6},
    "sensor_frame": {"color": "black", "label": "sensor frame (uncalibrated)", "lw": 1.0},
    "ours_right": {"color": "c", "label": "projected, ours $R^r$", "lw": 1.0},
    "ours_left": {"color": "m", "label": "projected, ours $R^l$", "lw": 1.0, "ls": "--"},
    "optimization": {"color": "b", "label": "projected, SQP", "lw": 1.0, "ls": ":"},
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
            style = {"color": FIG7_STYLE[method]["color"], "ls": FIG7_STYLE[method].get("ls", "-")}
            ax.plot(part["set"] + 1, part[f"dev_{axis}_deg"], marker="o", ms=4, label=METHOD_STYLE[method]["label"],
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
    """Notebook 08: the online estimate's error to the reference and its stated radius over time, per recording,
    with the moment VINS-Mono's rule declares success (``runs``: :func:`replication.study.live_study.live_run`
    results)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(6.5 * len(runs), 4.2), squeeze=False)
    for ax, (name, (track, vins)) in zip(axes[0], runs.items()):
        ok = track["n_pairs"] >= 10
        ax.semilogy(track["t"][ok], track["error_deg"][ok], label="error to the reference")
        ax.semilogy(track["t"][ok], track["radius_deg"][ok], "--", label="stated 95 % radius")
        for target in targets:
            ax.axhline(target, color="grey", lw=0.6, ls=":")
        if np.isfinite(vins["ready_t"]):
            ax.axvline(vins["ready_t"], color="tab:red", lw=0.8)
            ax.annotate(f"VINS-Mono rule: done,\n{vins['error_at_ready_deg']:.2f} deg off", (vins["ready_t"], 0.9),
                        xycoords=("data", "axes fraction"), fontsize=7, color="tab:red", va="top")
        ax.set_title(name)
        ax.set_xlabel("time since the first camera pose (s)")
        ax.set_ylabel("deg")
        ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    return fig

