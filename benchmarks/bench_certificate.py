"""How often chordal_optimal certifies the global minimum of eq. (8), and what the certificate
costs.

Usage: python benchmarks/bench_certificate.py [--runs 1000] For the paper's noise and for 20-40 %
outlier pairs (J = 3, 5, 10, 20), prints the share certified globally, the share the fast Lagrangian
dual settles, the share that needed the semidefinite relaxation (Clarabel), and the time per problem
with and without the certificate. Nothing is asserted (figures go to environment.md). Goal: 100 %
certified, fallback included.
"""
import argparse
import time
import warnings

import numpy as np
import pandas as pd

from replication.core.solvers import ReplicationWarning, chordal_optimal
from replication.study.baselines import corrupt_pairs
from replication.study.simulation import simulate


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    args = parser.parse_args()
    warnings.simplefilter("ignore", ReplicationWarning)
    rows = []
    cases = [(20, 0.0)] + [(J, f) for J in (3, 5, 10, 20) for f in (0.2, 0.3, 0.4)]
    for k, (J, fraction) in enumerate(cases):
        sim = simulate(100 + k, args.runs, n_motions=J)
        B = sim.B if fraction == 0 else corrupt_pairs(sim.B, fraction, np.random.default_rng(k))[0]
        t0 = time.perf_counter()
        res = chordal_optimal(sim.A, B)
        t1 = time.perf_counter()
        chordal_optimal(sim.A, B, certify=False)
        t2 = time.perf_counter()
        rows.append({"J": J, "outliers": fraction, "certified_global_%": 100 * res.global_optimum.mean(),
                     "fast_dual_%": 100 * (res.certificate == "lagrangian").mean(),
                     "relaxation_%": 100 * res.sdp_used.mean(),
                     "us_per_problem": 1e6 * (t1 - t0) / args.runs,
                     "us_without_certificate": 1e6 * (t2 - t1) / args.runs})
    print(f"{args.runs} problems per row (paper's noise, Haar-random motions)")
    print(pd.DataFrame(rows).set_index(["J", "outliers"]).round(2).to_string())


if __name__ == "__main__":
    main()
