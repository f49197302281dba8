"""The batched small-matrix kernels (issue 26): each kernel against the LAPACK call it replaces, every solver against
one ``cv2.calibrateHandEye`` call before and after, the paper's 1000 x 50 history, and where the time goes.

Usage: python benchmarks/bench_kernels.py [--reps 7] [--runs 2000] [--single-calls 50]
"Before" is the same code inside :func:`replication.core.kernels.lapack_reference` (one LAPACK call per matrix, as
before the kernels); "after" the default. Every figure is the median over ``--reps`` interleaved repetitions (before,
after, the cv2 call, in turn), with the range (min-max) beside it; ratios are taken within a repetition. Nothing is
asserted (figures go to environment.md). Targets (issue 26): each kernel >= 10x the LAPACK call on the same batch;
closed forms >= 40x one cv2 call batched; chordal_optimal (certified) >= 30x; two_step (auto) >= 15x; the 1000 x 50
history <= 0.1 cv2 calls per problem.
"""
import argparse
import cProfile
import pstats
import time
import warnings

import numpy as np
from bench_baselines import bare_cv2_call

from replication.core import kernels
from replication.core.checks import check_matrices, det3
from replication.core.kernels import eigvalsh3, lapack_reference, polar_factor, rotation_violation, solve3
from replication.core.so3 import random_rotations
from replication.core.solvers import ReplicationWarning, solve, two_step
from replication.study.simulation import simulate

SOLVERS = ["park_martin", "horaud_dornaika", "andreff", "tsai_lenz", "chordal_optimal", "two_step_right"]


def _seconds(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _old_rotation_test(R):
    """The rotation test before the fused pass: finiteness, ``||R^T R - I||_F``, ``det R`` in three passes."""
    R = check_matrices(R, "R")
    E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
    return np.maximum(np.sqrt(np.einsum("...ab,...ab->...", E, E)), np.abs(det3(R) - 1.0))


def _summary(values, fmt="{:.1f}"):
    v = np.asarray(values)
    return f"{fmt.format(np.median(v))} ({fmt.format(v.min())}-{fmt.format(v.max())})"


def kernel_table(rng, reps):
    """Each kernel against the LAPACK call it replaces, on the same batch."""
    history_batch = (random_rotations(rng, 1000 * 100) / np.sqrt(3.0)
                     + 0.02 * rng.normal(size=(100000, 3, 3)))  # 1000 x 50 history: 2 x 50 unit iterates
    near = random_rotations(rng, 51000) + 1e-3 * rng.normal(size=(51000, 3, 3))
    G = rng.normal(size=(51000, 3, 3))
    S = -(G @ np.swapaxes(G, -1, -2) + 20.0 * np.eye(3))  # Newton Hessians of chordal_optimal are like this
    b = rng.normal(size=(51000, 3))
    R = random_rotations(rng, 51000)
    cases = {
        "polar factor, up to sign (history: 100,000)": (lambda: polar_factor(history_batch, "up_to_sign"),
                                                         lambda: polar_factor(history_batch, "up_to_sign",
                                                                              method="lapack")),
        "nearest rotation (51,000 near rotations)": (lambda: polar_factor(near), lambda: polar_factor(near,
                                                                                                    method="lapack")),
        "eigvalsh3 (51,000 Hessians)": (lambda: eigvalsh3(S), lambda: np.linalg.eigvalsh(S)),
        "solve3 (51,000 systems)": (lambda: solve3(S, b), lambda: np.linalg.solve(S, b[..., None])),
        "rotation test (51,000 rotations)": (lambda: rotation_violation(R), lambda: _old_rotation_test(R)),
    }
    print("kernel vs the LAPACK path on the same batch (ms; median (min-max) of interleaved repetitions):")
    for name, (new, old) in cases.items():
        t_new, t_old = [], []
        for _ in range(reps):
            t_old.append(_seconds(old))
            t_new.append(_seconds(new))
        ratio = np.asarray(t_old) / np.asarray(t_new)
        print(f"  {name:46s} LAPACK {_summary(1e3 * np.asarray(t_old))}  kernel "
              f"{_summary(1e3 * np.asarray(t_new))}  speed-up {_summary(ratio)}")


def solver_table(sim, reps, n_single):
    """Every solver's ratio to one cv2 call, single and batched, before and after; the 1000 x 50 history."""
    A, B = sim.A, sim.B
    n = len(A)
    hist = simulate(0, 1000)
    rows = {}
    for _ in range(reps):
        cv = bare_cv2_call(A[0], B[0])
        for name in SOLVERS:
            for when in ("before", "after"):
                def batched():
                    solve(name, A, B)

                def single():
                    for k in range(n_single):
                        solve(name, A[k], B[k])

                if when == "before":
                    with lapack_reference():
                        t_b, t_s = _seconds(batched) / n, _seconds(single) / n_single
                else:
                    t_b, t_s = _seconds(batched) / n, _seconds(single) / n_single
                rows.setdefault((name, when), []).append((cv / t_b, cv / t_s))
        for when in ("before", "after"):
            run = lambda: two_step(hist.A, hist.B, iterations=50)  # noqa: E731
            if when == "before":
                with lapack_reference():
                    t = _seconds(run)
            else:
                t = _seconds(run)
            rows.setdefault(("history 1000 x 50", when), []).append((t, t / (1000 * cv)))
        rows.setdefault(("cv2", ""), []).append((cv, cv))
    cvs = [r[0] for r in rows[("cv2", "")]]
    print(f"\none bare cv2.calibrateHandEye call (Tsai, 21 poses): {_summary(1e3 * np.asarray(cvs), '{:.3f}')} ms")
    print(f"ratio to one cv2 call (median (min-max) of {reps} interleaved repetitions); batched: {n} problems "
          f"in one call; single: {n_single} calls of one problem")
    for name in SOLVERS:
        for when in ("before", "after"):
            r = np.asarray(rows[(name, when)])
            print(f"  {name:16s} {when:6s} batched {_summary(r[:, 0])}  single {_summary(r[:, 1])}")
    for when in ("before", "after"):
        r = np.asarray(rows[("history 1000 x 50", when)])
        print(f"  history 1000 x 50 {when:6s}: {_summary(r[:, 0], '{:.3f}')} s = "
              f"{_summary(r[:, 1], '{:.3f}')} cv2 calls per problem")


#: How the profile's functions are grouped: kernels, LAPACK calls, the rest by module.
GROUPS = {
    "kernels.py": "kernels (polar, eigvalsh3, solve3, rotation test)",
    "_linalg.py": "numpy.linalg (LAPACK: 9x9 SVD/eigh of K, 4x4 eigh, fallbacks)",
    "so3.py": "so3 (log_map, quaternions, SciPy conversions)",
    "checks.py": "validation (checks.py)",
}


def share_table(sim):
    """Share of each group of functions in the batched solve (cProfile, tottime)."""
    print("\nwhere the batched solve spends its time (after; cProfile self time, % of the total):")
    for name in SOLVERS + ["history"]:
        profile = cProfile.Profile()
        if name == "history":
            hist = simulate(0, 1000)
            profile.runcall(two_step, hist.A, hist.B, iterations=50)
        else:
            profile.runcall(solve, name, sim.A, sim.B)
        stats = pstats.Stats(profile).stats
        total = sum(v[2] for v in stats.values())
        shares = {}
        for (path, _, _), v in stats.items():
            group = next((g for k, g in GROUPS.items() if path.endswith(k)), "other (einsum, products, Python)")
            shares[group] = shares.get(group, 0.0) + v[2]
        parts = ", ".join(f"{g.split(' (')[0]} {100 * t / total:.0f}%"
                          for g, t in sorted(shares.items(), key=lambda kv: -kv[1]))
        print(f"  {name:16s} {1e3 * total:7.1f} ms: {parts}")
    print("  groups: " + "; ".join(GROUPS.values()))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--reps", type=int, default=7)
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--single-calls", type=int, default=50)
    args = parser.parse_args()
    warnings.simplefilter("ignore", ReplicationWarning)
    rng = np.random.default_rng(0)
    print(f"kernels.MIN_BATCH = {kernels.MIN_BATCH}; the paper's simulated data, J = 20")
    kernel_table(rng, args.reps)
    sim = simulate(0, args.runs)
    solver_table(sim, args.reps, args.single_calls)
    share_table(sim)


if __name__ == "__main__":
    main()
