"""Per-calibration cost of the two-step method (single and batched) and of SQP, on the same data.

Usage: python benchmarks/bench_solvers.py [--runs 1000] [--iterations 50]
Prints absolute times and ratios; nothing is asserted (figures go to environment.md).
The paper (Sec. III-A): two-step "less than 0.05 second", SQP "about 2 seconds" per calibration.
Two modes of the two-step method: the paper's protocol (a fixed count, every iterate projected and recorded;
target for 1000 x 50: <= 0.25 s) and the default ``iterations="auto"`` (run to the limit, final estimate only).
"""
import argparse
import warnings

import numpy as np

from replication.notebook import best_of
from replication.simulation import simulate
from replication.solvers import ReplicationWarning, sqp, two_step


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--iterations", type=int, default=50)
    parser.add_argument("--sqp-runs", type=int, default=200, help="runs timed for SQP (it loops in Python)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", ReplicationWarning)
    sim = simulate(0, args.runs)
    n_it = args.iterations
    single = best_of(lambda: two_step(sim.A[0], sim.B[0], iterations=n_it), 20)
    batched = best_of(lambda: two_step(sim.A, sim.B, iterations=n_it), 5)
    auto_single = best_of(lambda: two_step(sim.A[0], sim.B[0]), 20)
    auto_batched = best_of(lambda: two_step(sim.A, sim.B), 5)
    its = two_step(sim.A, sim.B).n_iterations
    k = min(args.sqp_runs, args.runs)
    sqp_total = best_of(lambda: sqp(sim.A[:k], sim.B[:k], max_iterations=n_it), 2)
    per_sqp = sqp_total / k
    print(f"data: {args.runs} simulated problems, J = {sim.A.shape[1]}, {n_it} iterations, both sides,")
    print("      per-iteration projections and costs recorded")
    print(f"two-step, one problem per call : {1e3 * single:8.3f} ms per calibration")
    print(f"two-step, {args.runs} problems in one call: {batched:8.3f} s total, "
          f"{1e3 * batched / args.runs:8.4f} ms per calibration")
    print(f"two-step, iterations='auto', one problem per call: {1e3 * auto_single:8.3f} ms per calibration")
    print(f"two-step, iterations='auto', {args.runs} problems in one call: {auto_batched:8.3f} s total "
          f"({1e3 * auto_batched / args.runs:8.4f} ms per calibration; iterations median {np.median(its):.0f}, "
          f"max {its.max()})")
    print(f"SQP (SLSQP), per problem ({k} timed): {1e3 * per_sqp:8.3f} ms per calibration")
    print(f"ratio SQP / two-step single  : {per_sqp / single:8.1f}")
    print(f"ratio SQP / two-step batched : {per_sqp / (batched / args.runs):8.1f}")


if __name__ == "__main__":
    main()
