"""Calibrations per second of every registered solver, one problem per call and batched, J = 20.

Usage: python benchmarks/bench_baselines.py [--runs 2000]
Prints a table (absolute figures and the ratio to a per-call cv2.calibrateHandEye);
nothing is asserted (figures go to environment.md). Each figure is the best of a few
repeats, through ``solve()`` (input validation and observability diagnostics included).
Targets from issue 5: batched closed-form solvers >= 10,000/s, chordal_optimal >= 1,000/s,
both faster per calibration than a per-call cv2.calibrateHandEye.
"""
import argparse
import warnings

import pandas as pd

from replication.notebook import best_of
from replication.simulation import simulate
from replication.solvers import ConvergenceWarning, available, solve

#: Solvers that loop over problems in Python: timed on fewer problems.
LOOPED = {"sqp": 100, "opencv_tsai": 500, "opencv_park": 500, "opencv_horaud": 500}


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--single-calls", type=int, default=100)
    args = parser.parse_args()
    warnings.simplefilter("ignore", ConvergenceWarning)
    sim = simulate(0, args.runs)
    rows = []
    for name in available():
        n = min(LOOPED.get(name, args.runs), args.runs)
        m = min(args.single_calls, n)
        single = best_of(lambda: [solve(name, sim.A[k], sim.B[k]) for k in range(m)], 3) / m
        batched = best_of(lambda: solve(name, sim.A[:n], sim.B[:n]), 3) / n
        rows.append({"solver": name, "single_per_s": 1 / single, "batched_per_s": 1 / batched,
                     "batched_problems": n})
    df = pd.DataFrame(rows).set_index("solver")
    cv = df.loc["opencv_tsai", "single_per_s"]
    df["batched_vs_cv2_call"] = df["batched_per_s"] / cv
    print(f"{args.runs} simulated problems (the paper's setting), J = {sim.A.shape[1]}; calibrations per second")
    print(df.round(1).to_string())


if __name__ == "__main__":
    main()
