"""The online estimator: per-pair update cost, replay rate, and memory against the recording's
length.

Targets: mean cost of a single-pair ``update()`` <= 50 us over 20 000 pairs (>= 20 000 pairs/s
single-threaded; issue 38, point 2), best of ``--runs`` runs (the machine is shared: the load
average is printed; the CPU time of the process is printed beside the wall time); memory bounded
whatever the length (the running sums are O(1); the repeat filter remembers at most
``online_events.DUPLICATE_MEMORY`` distinct pairs, about 0.3 kB each).

Run: OPENBLAS_NUM_THREADS=1 python benchmarks/bench_online.py [--runs 5] [--memory]
"""
import argparse
import os
import time
import tracemalloc

from replication.rig.online import OnlineCalibrator
from replication.rig.online_events import DUPLICATE_MEMORY
from replication.study.live_study import update_costs
from replication.study.simulation import simulate


def mean_update_us(n: int = 20000, runs: int = 5, seed: int = 1) -> tuple[float, float]:
    """Best over ``runs`` of the mean wall and CPU time (us) of ``n`` single-pair ``update()``
    calls."""
    sim = simulate(seed, 1, n_motions=n)
    A, B = sim.A[0], sim.B[0]
    OnlineCalibrator().update_many(A[:2000], B[:2000])  # warm-up: every code path once
    best_wall = best_cpu = float("inf")
    for _ in range(runs):
        oc = OnlineCalibrator()
        wall, cpu = time.perf_counter(), time.process_time()
        for a, b in zip(A, B):
            oc.update(a, b)
        best_wall = min(best_wall, (time.perf_counter() - wall) / n * 1e6)
        best_cpu = min(best_cpu, (time.process_time() - cpu) / n * 1e6)
    return best_wall, best_cpu


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--memory", action="store_true")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    wall, cpu = mean_update_us(runs=args.runs)
    print(f"20000 single-pair updates, best of {args.runs}: mean {wall:.1f} us wall ({1e6 / wall:,.0f} pairs/s), "
          f"{cpu:.1f} us CPU (target <= 50 us); load average {load:.1f} (then {os.getloadavg()[0]:.1f}) on "
          f"{os.cpu_count()} cores")
    for n in (2000, 20000):
        c = update_costs(n, seed=1)
        print(f"{n:6d} pairs: one update median {c['median_us']:.1f} us, mean {c['mean_us']:.1f} us (p99 "
              f"{c['p99_us']:.0f} us); replay {c['replay_pairs_per_s']:,.0f} pairs/s")
    if args.memory:
        print(f"peak memory of the calibrator against the number of distinct pairs fed (tracemalloc; the repeat "
              f"filter remembers at most {DUPLICATE_MEMORY:,}):")
        for n in (1000, 10000, 100000):
            oc = OnlineCalibrator()
            tracemalloc.start()
            for k in range(n // 1000):
                sim = simulate(100 + k, 1, n_motions=1000)  # distinct pairs: repeats would not be added
                oc.update_many(sim.A[0], sim.B[0])  # states are not kept: only the calibrator's own memory counts
                del sim
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            print(f"  {n:7d} pairs: peak {peak / 1e6:.1f} MB (one batch of 1000 simulated pairs and its states "
                  f"included)")
