"""The online estimator: per-pair update cost, replay rate, and memory against the recording's length.

Targets: median update <= 20 us on 2 cores; memory bounded whatever the length (the running sums are O(1); the
repeat filter remembers at most ``online_events.DUPLICATE_MEMORY`` distinct pairs, about 0.3 kB each).

Run: python benchmarks/bench_online.py
"""
import tracemalloc

from replication.rig.online import OnlineCalibrator
from replication.rig.online_events import DUPLICATE_MEMORY
from replication.study.live_study import update_costs
from replication.study.simulation import simulate

if __name__ == "__main__":
    for n in (2000, 20000):
        c = update_costs(n, seed=1)
        print(f"{n:6d} pairs: one update median {c['median_us']:.1f} us, mean {c['mean_us']:.1f} us (p99 "
              f"{c['p99_us']:.0f} us); replay {c['replay_pairs_per_s']:,.0f} pairs/s")
    print(f"peak memory of the calibrator against the number of distinct pairs fed (tracemalloc; the repeat filter "
          f"remembers at most {DUPLICATE_MEMORY:,}):")
    for n in (1000, 10000, 100000):
        oc = OnlineCalibrator()
        tracemalloc.start()
        for k in range(n // 1000):
            sim = simulate(100 + k, 1, n_motions=1000)  # distinct pairs: repeats would not be added
            oc.update_many(sim.A[0], sim.B[0])  # states are not kept: only the calibrator's own memory counts
            del sim
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        print(f"  {n:7d} pairs: peak {peak / 1e6:.1f} MB (one batch of 1000 simulated pairs and its states included)")
