"""The online estimator (issue 16): per-pair update cost, replay rate, and memory against the recording's length.

Targets: median update <= 20 us and >= 50 000 pairs/s in a replay on 2 cores; memory constant in the length.

Run: python benchmarks/bench_online.py
"""
import tracemalloc

import numpy as np

from replication.live_study import update_costs
from replication.online import OnlineCalibrator
from replication.simulation import simulate

if __name__ == "__main__":
    for n in (2000, 20000):
        c = update_costs(n, seed=1)
        print(f"{n:6d} pairs: one update median {c['median_us']:.1f} us (p99 {c['p99_us']:.0f} us); "
              f"replay {c['replay_pairs_per_s']:,.0f} pairs/s")
    print("peak memory of the calibrator against the number of pairs fed (tracemalloc):")
    sim = simulate(2, 1, n_motions=1000)
    for n in (1000, 10000, 100000):
        oc = OnlineCalibrator(cusum_h=1e12)
        tracemalloc.start()
        for k in range(n // 1000):
            oc.update_many(sim.A[0], sim.B[0])  # states are not kept: only the calibrator's own memory counts
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        print(f"  {n:7d} pairs: peak {peak / 1e3:.0f} kB (update_many's list of states for 1000 pairs included)")
