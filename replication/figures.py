"""Plot helpers shared by the notebooks (matplotlib; no computation here)."""
from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["METHOD_STYLE", "convergence_figure"]

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
