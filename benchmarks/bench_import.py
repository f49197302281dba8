"""The package face: import time of each layer in a fresh interpreter, and what it loads.

``import replication.core.so3`` should load NumPy only (SciPy's rotations on first use); the loaders
and the lab's recording I/O must not load the solvers or SciPy's optimiser. Each figure is the
median wall time of the import over ``REPEATS`` fresh interpreters; a bare ``import numpy`` is
printed first (most modules pay it).

Run: python benchmarks/bench_import.py
"""
import statistics
import subprocess
import sys

REPEATS = 7
MODULES = ["replication.core.so3", "replication", "replication.core.handeye", "replication.core.motions",
           "replication.rig.streams", "replication.rig.datafile", "replication.study.paper", "replication.rig.realdata",
           "replication.study.lab.recording", "replication.core.solvers", "replication.rig.calibration",
           "replication.study.lab"]
PROBE = ("import time, sys; t = time.perf_counter(); import {m}; dt = time.perf_counter() - t; "
         "print(dt, 'scipy.optimize' in sys.modules, 'replication.core.solvers' in sys.modules, "
         "'scipy' in sys.modules)")


def measure(module):
    runs = [subprocess.run([sys.executable, "-c", PROBE.format(m=module)], capture_output=True, text=True,
                           check=True).stdout.split() for _ in range(REPEATS)]
    return statistics.median(float(r[0]) for r in runs), runs[0][1:]


if __name__ == "__main__":
    floor, _ = measure("numpy")
    print(f"import numpy: {1e3 * floor:.0f} ms (median of {REPEATS} fresh interpreters)")
    print(f"{'module':28s} {'ms':>5s}  {'/ numpy':>7s}  scipy.optimize  solvers  scipy")
    for module in MODULES:
        seconds, (optimize, solvers, scipy) = measure(module)
        print(f"{module:28s} {1e3 * seconds:5.0f}  {seconds / floor:7.1f}  {optimize:>14s}  {solvers:>7s}  {scipy:>5s}")
