"""What every notebook shares: one setup call, and writers for ``results/``.

``setup()`` fixes print precision and plot style (the notebooks' first code cell).
``save_table`` writes CSV + Markdown to ``results/tables/``; ``save_figure``
writes PNG to ``results/figures/``. ``$REPLICATION_RESULTS_DIR`` overrides
``results/`` (the test suite points it at a temporary folder).
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["setup", "results_dir", "save_table", "save_figure", "best_of"]

#: Digits printed by numpy and pandas in the notebooks (keeps stored outputs stable).
PRINT_DIGITS = 4


def setup() -> None:
    """Fix numpy/pandas print precision and the matplotlib style (inline PNG, fixed size)."""
    import matplotlib.pyplot as plt

    np.set_printoptions(precision=PRINT_DIGITS, suppress=True, linewidth=110)
    pd.set_option("display.precision", PRINT_DIGITS)
    pd.set_option("display.width", 120)
    pd.set_option("display.max_columns", 20)
    plt.rcParams.update(
        {
            "figure.figsize": (7.0, 4.0),
            "figure.dpi": 90,
            "savefig.dpi": 120,
            "axes.grid": True,
            "grid.alpha": 0.3,
            "font.size": 10,
            "svg.hashsalt": "replication",
        }
    )
    try:  # inline figures as PNG only
        from IPython import get_ipython

        ip = get_ipython()
        if ip is not None:
            ip.run_line_magic("config", "InlineBackend.figure_formats = ['png']")
    except ImportError:  # pragma: no cover - IPython is a dependency
        pass


def results_dir() -> Path:
    """``results/`` of this project, or ``$REPLICATION_RESULTS_DIR``."""
    env = os.environ.get("REPLICATION_RESULTS_DIR")
    return Path(env) if env else Path(__file__).resolve().parent.parent / "results"


def save_table(df: pd.DataFrame, name: str, *, floatfmt: str = ".4g") -> None:
    """Write ``df`` as ``results/tables/<name>.csv`` and ``<name>.md``.

    Returns nothing, so that a notebook cell ending in it shows no (machine-dependent) path.
    """
    out = results_dir() / "tables"
    out.mkdir(parents=True, exist_ok=True)
    csv = out / f"{name}.csv"
    df.to_csv(csv)
    flat = df.copy()
    if isinstance(flat.columns, pd.MultiIndex):  # ("ours_right", "mean") -> "ours_right mean"
        flat.columns = [" ".join(str(part) for part in col) for col in flat.columns]
    flat = flat.reset_index() if any(name is not None for name in flat.index.names) else flat
    (out / f"{name}.md").write_text(flat.to_markdown(floatfmt=floatfmt, index=False) + "\n")


def save_figure(fig, name: str) -> None:
    """Write ``fig`` as ``results/figures/<name>.png`` (returns nothing, like :func:`save_table`)."""
    out = results_dir() / "figures"
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.png"
    fig.savefig(path, bbox_inches="tight", metadata={"Software": None})


def best_of(fn, repeat: int = 7) -> float:
    """Smallest wall time (s) of ``repeat`` calls of ``fn()`` (the timing cells and ``benchmarks/``)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)
