"""What every notebook shares: one setup call, and writers for ``results/``.

``setup()`` fixes print precision and plot style (the notebooks' first code cell).
``save_table`` writes CSV + Markdown to ``results/tables/``; ``save_figure``
writes PNG to ``results/figures/`` and shows it in the notebook as that PNG, whatever
the matplotlib backend (``MPLBACKEND=Agg``, common in CI, shows nothing by itself).
``$REPLICATION_RESULTS_DIR`` overrides ``results/`` (the test suite points it at a
temporary folder). Files are written to a temporary name and renamed, never half-written.
"""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

from .._io import PROJECT_ROOT, png_bytes, write_atomic

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
    return Path(env) if env else PROJECT_ROOT / "results"


def save_table(df: pd.DataFrame, name: str, *, floatfmt: str = ".4g") -> None:
    """Write ``df`` as ``results/tables/<name>.csv`` and ``<name>.md``.

    Returns nothing, so that a notebook cell ending in it shows no (machine-dependent) path.
    """
    out = results_dir() / "tables"
    out.mkdir(parents=True, exist_ok=True)
    flat = df.copy()
    if isinstance(flat.columns, pd.MultiIndex):  # ("ours_right", "mean") -> "ours_right mean"
        flat.columns = [" ".join(str(part) for part in col) for col in flat.columns]
    flat = flat.reset_index() if any(name is not None for name in flat.index.names) else flat
    write_atomic(out / f"{name}.csv", df.to_csv().encode())
    write_atomic(out / f"{name}.md", (flat.to_markdown(floatfmt=floatfmt, index=False) + "\n").encode())


def save_figure(fig, name: str) -> None:
    """Write ``fig`` as ``results/figures/<name>.png`` and show that PNG in the notebook; close
    ``fig``.

    Returns nothing, like :func:`save_table`. The figure is displayed explicitly (an
    ``image/png`` output) and closed, so the stored output is the same with the inline
    backend and with ``MPLBACKEND=Agg``.
    """
    import matplotlib.pyplot as plt

    out = results_dir() / "figures"
    out.mkdir(parents=True, exist_ok=True)
    png = png_bytes(fig)
    write_atomic(out / f"{name}.png", png)
    plt.close(fig)
    try:
        from IPython import get_ipython
        from IPython.display import Image, display
    except ImportError:  # pragma: no cover - IPython is a dependency
        return
    if get_ipython() is not None:
        display(Image(data=png, format="png"))


def best_of(fn, repeat: int = 7) -> float:
    """Smallest wall time (s) of ``repeat`` calls of ``fn()`` (the timing cells and
    ``benchmarks/``)."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)
