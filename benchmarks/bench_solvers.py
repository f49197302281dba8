"""Per-calibration cost of the two-step method (single and batched) and of SQP, on the same data.

Usage: python benchmarks/bench_solvers.py [--runs 1000] [--iterations 50]
Prints absolute times and ratios; nothing is asserted (figures go to environment.md).
The paper (Sec. III-A): two-step "less than 0.05 second", SQP "about 2 seconds" per calibration.
"""
import argparse
import warnings

from replication.notebook import best_of
from replication.simulation import simulate
from replication.solvers import ConvergenceWarning, sqp, two_step


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--iterations", type=int, default=50)
    parser.add_argument("--sqp-runs", type=int, default=200, help="runs timed for SQP (it loops in Python)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", ConvergenceWarning)
    sim = simulate(0, args.runs)
    n_it = args.iterations
    single = best_of(lambda: two_step(sim.A[0], sim.B[0], iterations=n_it), 20)
    batched = best_of(lambda: two_step(sim.A, sim.B, iterations=n_it), 5)
    k = min(args.sqp_runs, args.runs)
    sqp_total = best_of(lambda: sqp(sim.A[:k], sim.B[:k], max_iterations=n_it), 2)
    per_sqp = sqp_total / k
    print(f"data: {args.runs} simulated problems, J = {sim.A.shape[1]}, {n_it} iterations, both sides,")
    print("      per-iteration projections and costs recorded")
    print(f"two-step, one problem per call : {1e3 * single:8.3f} ms per calibration")
    print(f"two-step, {args.runs} problems in one call: {batched:8.3f} s total, "
          f"{1e3 * batched / args.runs:8.4f} ms per calibration")
    print(f"SQP (SLSQP), per problem ({k} timed): {1e3 * per_sqp:8.3f} ms per calibration")
    print(f"ratio SQP / two-step single  : {per_sqp / single:8.1f}")
    print(f"ratio SQP / two-step batched : {per_sqp / (batched / args.runs):8.1f}")


if __name__ == "__main__":
    main()
