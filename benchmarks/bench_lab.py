"""Simulated lab: time to generate the recordings, load them, run the chain, and
re-execute notebook 05 end to end (target: generation + notebook <= 2 min on 2 cores).

Run: python benchmarks/bench_lab.py
"""
import os
import shutil
import tempfile
import time
from pathlib import Path

from replication.cli.reproduce import execute_notebook
from replication.study.lab import load_lab, run_lab, simulate_lab, write_lab

ROOT = Path(__file__).resolve().parent.parent


def timed(fn):
    start = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - start


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        rec, t_sim = timed(simulate_lab)
        _, t_write = timed(lambda: write_lab(rec, tmp))
        loaded, t_load = timed(lambda: load_lab(tmp))
        _, t_run = timed(lambda: run_lab(loaded))
        # a copy of the notebook, its results in the temporary folder (the committed files stay
        # untouched)
        nb = Path(shutil.copy(ROOT / "notebooks" / "05_table2_experiment.ipynb", tmp))
        os.environ["REPLICATION_RESULTS_DIR"] = str(Path(tmp) / "results")
        t_nb = execute_notebook(nb)
    print(f"simulate_lab      {t_sim:6.2f} s")
    print(f"write_lab         {t_write:6.2f} s")
    print(f"load_lab          {t_load:6.2f} s   (validation included)")
    print(f"run_lab           {t_run:6.2f} s   (PnP, ecompass, 3 solvers x 10 sets, Madgwick, Table II)")
    print(f"notebook 05       {t_nb:6.2f} s   (incl. 16-case ablation and a 5-point sensitivity)")
    total = t_sim + t_write + t_nb
    print(f"generation + notebook: {total:.1f} s = {total / 120:.2f} of the 2 min budget")
