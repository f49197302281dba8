"""Per-calibration cost of the two-step method (single and batched) and of SQP, on the same data.

Usage: python benchmarks/bench_solvers.py [--runs 1000] [--iterations 50] Prints absolute times and
ratios; nothing is asserted (figures go to environment.md). The paper (Sec. III-A): two-step "less
than 0.05 second", SQP "about 2 seconds" per calibration: a ratio over 40 that depends on what is
compared, which the paper does not say. Modes of the two-step method: the paper's protocol
*instrumented* (a fixed count, every iterate projected and costed, as Fig. 3-4 need; target for 1000
x 50: <= 0.25 s), *lean* (the same count, only the final estimate projected) and the default
``iterations="auto"`` (run to the limit); SQP in each variant of ``SQP_VARIANTS`` (analytic
gradients, finite differences, capped). The last block prints every SQP / two-step ratio.
"""
import argparse
import warnings

import numpy as np

from replication.core.solvers import SQP_VARIANTS, ReplicationWarning, sqp, two_step
from replication.study.notebook import best_of
from replication.study.simulation import simulate


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--iterations", type=int, default=50)
    parser.add_argument("--sqp-runs", type=int, default=100, help="runs timed per SQP variant (it loops in Python)")
    args = parser.parse_args()
    warnings.simplefilter("ignore", ReplicationWarning)
    sim = simulate(0, args.runs)
    n_it, n = args.iterations, args.runs
    A1, B1 = sim.A[0], sim.B[0]
    modes = {  # the iteration alone, without the certificate of its answer (certify=False)
        "instrumented": dict(iterations=n_it, certify=False),
        "lean": dict(iterations=n_it, history=False, certify=False),
        "auto": dict(certify=False),
    }
    two = {}
    for name, kw in modes.items():
        two[(name, "single")] = best_of(lambda: two_step(A1, B1, **kw), 20)
        two[(name, "batched")] = best_of(lambda: two_step(sim.A, sim.B, **kw), 5) / n
    its = two_step(sim.A, sim.B, certify=False).iterations
    k = min(args.sqp_runs, n)
    sqp_t = {}
    for variant, options in SQP_VARIANTS.items():
        options = {"max_iterations": n_it, **options}
        sqp_t[variant] = best_of(lambda: sqp(sim.A[:k], sim.B[:k], **options), 2) / k
    print(f"data: {n} simulated problems, J = {sim.A.shape[1]}, {n_it} iterations (two-step fixed modes, SQP cap)")
    for (name, how), t in two.items():
        extra = f" (iterations median {np.median(its):.0f}, max {its.max()})" if name == "auto" else ""
        total = f", {t * n:.3f} s for {n} problems" if how == "batched" else ""
        print(f"two-step {name:12s} {how:7s}: {1e3 * t:8.4f} ms per calibration{total}{extra}")
    for variant, t in sqp_t.items():
        print(f"SQP {variant:17s} (per problem, {k} timed): {1e3 * t:8.3f} ms per calibration")
    print("ratio SQP / two-step (rows: SQP variant; columns: two-step mode, single call / batched):")
    cols = [f"{m} {h}" for m, h in two]
    print(" " * 18 + "".join(f"{c:>22s}" for c in cols))
    for variant, t in sqp_t.items():
        print(f"{variant:18s}" + "".join(f"{t / two[key]:22.1f}" for key in two))


if __name__ == "__main__":
    main()
