"""Calibrations per second of every registered solver, one problem per call and batched, J = 20.

Usage: python benchmarks/bench_baselines.py [--runs 2000] Prints a table (absolute figures and the
ratio to one bare ``cv2.calibrateHandEye`` call, Tsai, 21 poses, measured in the same run); nothing
is asserted (figures go to environment.md). Each figure is the best of a few repeats, through
``solve()`` with default options (validation, observability diagnostics, the two-step method run to
its limit, the global certificate of ``chordal_optimal``, SQP's check against it). Targets, batched
vs the bare cv2 call: closed forms >= 20x, ``chordal_optimal`` with its global certificate >= 4x,
``two_step`` (auto) >= 4x.
"""
import argparse
import warnings

import cv2
import numpy as np
import pandas as pd

from replication.core.solvers import ReplicationWarning, available, solve
from replication.study.notebook import best_of
from replication.study.simulation import simulate

#: Solvers that loop over problems in Python: timed on fewer problems.
LOOPED = {"sqp": 100, "opencv_tsai": 500, "opencv_park": 500, "opencv_horaud": 500}


def bare_cv2_call(A, B):
    """Seconds per ``cv2.calibrateHandEye`` (Tsai) call on the 21 poses whose consecutive motions
    are (A, B)."""
    Hg, Hc = [np.eye(3)], [np.eye(3)]
    for a, b in zip(A, B):
        Hg.append(Hg[-1] @ a.T)
        Hc.append(b @ Hc[-1])
    zeros = [np.zeros((3, 1))] * len(Hg)
    return best_of(lambda: [cv2.calibrateHandEye(Hg, zeros, Hc, zeros, method=cv2.CALIB_HAND_EYE_TSAI)
                            for _ in range(100)], 5) / 100


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--single-calls", type=int, default=100)
    args = parser.parse_args()
    warnings.simplefilter("ignore", ReplicationWarning)
    sim = simulate(0, args.runs)
    cv = bare_cv2_call(sim.A[0], sim.B[0])
    rows = []
    for name in available():
        n = min(LOOPED.get(name, args.runs), args.runs)
        m = min(args.single_calls, n)
        single = best_of(lambda: [solve(name, sim.A[k], sim.B[k]) for k in range(m)], 3) / m
        batched = best_of(lambda: solve(name, sim.A[:n], sim.B[:n]), 3) / n
        rows.append({"solver": name, "single_per_s": 1 / single, "batched_per_s": 1 / batched,
                     "batched_problems": n, "batched_vs_cv2_call": cv / batched})
    df = pd.DataFrame(rows).set_index("solver")
    print(f"{args.runs} simulated problems (the paper's setting), J = {sim.A.shape[1]}; calibrations per second")
    print(f"one bare cv2.calibrateHandEye call (Tsai, 21 poses): {1e3 * cv:.3f} ms ({1 / cv:.0f}/s)")
    print(df.round(1).to_string())


if __name__ == "__main__":
    main()
