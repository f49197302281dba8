"""Plot helpers shared by the notebooks (matplotlib; no computation here)."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["METHOD_STYLE", "convergence_figure", "SWEEP_LABELS", "sweep_figure"]

#: One colour/line style per method, reused in every figure.
METHOD_STYLE = {
    "ours_right": {"color": "tab:cyan", "label": "ours, $R^r$"},
    "ours_left": {"color": "tab:purple", "label": "ours, $R^l$"},
    "optimization": {"color": "tab:blue", "label": "SQP (SLSQP)"},
    "optimization_projected": {"color": "tab:blue", "ls": "--", "label": "SQP, iterate projected"},
}


def convergence_figure(curves: dict, *, ylabel: str, title: str, logy: bool = True):
    """One line per method: ``curves[name]`` is a 1-D array over iterations 1..N."""
    fig, ax = plt.subplots()
    for name, values in curves.items():
        values = np.asarray(values)
        ax.plot(np.arange(1, len(values) + 1), values, marker=".", **METHOD_STYLE.get(name, {"label": name}))
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    return fig


#: Axis labels of the sweeps in :mod:`replication.baselines`.
SWEEP_LABELS = {
    "noise_deg": "noise bound on each rotation (deg)",
    "n_motions": "number of motion pairs J",
    "motion_amplitude_deg": "largest motion angle (deg)",
    "outlier_fraction": "fraction of outlier pairs",
}


def sweep_figure(sweeps, *, metric: str = "mean_deg", ylabel: str = "mean error to $R_0$ (deg)"):
    """One panel per sweep parameter, one line per solver; ``sweeps`` is :func:`replication.baselines.sweep` output."""
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
