"""The batched small-matrix kernels: each kernel against the LAPACK call it replaces, every solver
against one ``cv2.calibrateHandEye`` call before and after, the paper's 1000 x 50 history, and where
the time goes.

Usage: python benchmarks/bench_kernels.py [--reps 7] [--runs 2000] [--single-calls 50] [--parts
kernels solvers ...]
       python benchmarks/bench_kernels.py --compare-with /tmp/base  (every ratio, base commit and
       this tree alternating; the issue 38 table: ``git archive <base> | tar -x -C /tmp/base``
       first)
"Before" is the same code inside :func:`replication.core.kernels.lapack_reference` (one LAPACK call
per matrix, as before the kernels); "after" the default. Every figure is the median over ``--reps``
interleaved repetitions (before, after, the cv2 call, in turn), with the range (min-max) beside it;
ratios are taken within a repetition. Nothing is asserted (figures go to environment.md). Targets:
each kernel >= 10x the LAPACK call on the same batch; closed forms >= 40x one cv2 call batched;
chordal_optimal (certified) >= 30x; two_step (auto) >= 15x; the 1000 x 50 history <= 0.1 cv2 calls
per problem.
"""
import argparse
import cProfile
import json
import os
import pstats
import subprocess
import sys
import time
import warnings

import numpy as np
from bench_baselines import bare_cv2_call

from replication.core.checks import check_matrices, det3
from replication.core.so3 import random_rotations
from replication.core.solvers import ReplicationWarning, solve, two_step
from replication.study.simulation import simulate

SOLVERS = ["park_martin", "horaud_dornaika", "andreff", "tsai_lenz", "chordal_optimal", "two_step_right"]


def _seconds(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def _old_rotation_test(R):
    """The rotation test before the fused pass: finiteness, ``||R^T R - I||_F``, ``det R`` in three
    passes."""
    R = check_matrices(R, "R")
    E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
    return np.maximum(np.sqrt(np.einsum("...ab,...ab->...", E, E)), np.abs(det3(R) - 1.0))


def _summary(values, fmt="{:.1f}"):
    v = np.asarray(values)
    return f"{fmt.format(np.median(v))} ({fmt.format(v.min())}-{fmt.format(v.max())})"


def _handeye_4x4(sim):
    """Horaud & Dornaika's 4x4 matrices ``S = sum_j C_j^T C_j`` of the simulated problems."""
    from replication.core.motions import prepare_motions
    from replication.core.so3 import quaternion_from_rotation_vector
    from replication.core.solvers.classic import _multiplication_matrix

    a, b = (quaternion_from_rotation_vector(w) for w in prepare_motions(sim.A, sim.B).rotation_vectors)
    C = _multiplication_matrix(a, "left") - _multiplication_matrix(b, "right")
    return np.einsum("...jki,...jkl->...il", C, C)


def kernel_table(rng, reps, sim):
    """Each kernel against the LAPACK call it replaces, on the same batch."""
    from replication.core.kernels import bottom_eigenvector4, eigvalsh3, polar_factor, rotation_violation, solve3

    history_batch = (random_rotations(rng, 1000 * 100) / np.sqrt(3.0)
                     + 0.02 * rng.normal(size=(100000, 3, 3)))  # 1000 x 50 history: 2 x 50 unit iterates
    near = random_rotations(rng, 51000) + 1e-3 * rng.normal(size=(51000, 3, 3))
    G = rng.normal(size=(51000, 3, 3))
    S = -(G @ np.swapaxes(G, -1, -2) + 20.0 * np.eye(3))  # Newton Hessians of chordal_optimal are like this
    b = rng.normal(size=(51000, 3))
    R = random_rotations(rng, 51000)
    S4 = _handeye_4x4(sim)
    cases = {
        "polar factor, up to sign (history: 100,000)": (lambda: polar_factor(history_batch, "up_to_sign"),
                                                         lambda: polar_factor(history_batch, "up_to_sign",
                                                                              method="lapack")),
        "nearest rotation (51,000 near rotations)": (lambda: polar_factor(near), lambda: polar_factor(near,
                                                                                                    method="lapack")),
        "eigvalsh3 (51,000 Hessians)": (lambda: eigvalsh3(S), lambda: np.linalg.eigvalsh(S)),
        "solve3 (51,000 systems)": (lambda: solve3(S, b), lambda: np.linalg.solve(S, b[..., None])),
        "rotation test (51,000 rotations)": (lambda: rotation_violation(R), lambda: _old_rotation_test(R)),
        f"bottom eigenvector 4x4 (Horaud & Dornaika, {len(S4)})": (lambda: bottom_eigenvector4(S4),
                                                                   lambda: np.linalg.eigh(S4)),
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
    from replication.core import kernels

    e = np.ascontiguousarray(S4.reshape(-1, 16).T)
    e /= np.sqrt(np.einsum("kn,kn->n", e, e))
    sent = np.mean(~(kernels.bottom_eigenvector4_block(e)[1] <= kernels.EIG4_SAFE))
    print(f"  bottom eigenvector 4x4: {100 * sent:.1f} % of the {len(S4)} matrices go to LAPACK (EIG4_SAFE)")


def lapack_9x9_table(sim, reps):
    """What the 9x9 decompositions of K that stay with LAPACK cost per problem, against one cv2
    call."""
    from replication.core.motions import prepare_motions

    K = prepare_motions(sim.A, sim.B).K
    M = 0.5 * (K + np.swapaxes(K, -1, -2))
    n = len(K)
    calls = {"svd of K (observability, two-step limit)": lambda: np.linalg.svd(K),
             "eigh of sym(K) (relaxed start: andreff, chordal)": lambda: np.linalg.eigh(M),
             "eigvalsh of sym(K) (every solve; the certificate's once more)": lambda: np.linalg.eigvalsh(M)}
    times = {name: [] for name in calls}
    cvs = []
    for _ in range(reps):
        cvs.append(bare_cv2_call(sim.A[0], sim.B[0]))
        for name, fn in calls.items():
            times[name].append(_seconds(fn) / n)
    cv = np.median(cvs)
    print(f"\nthe 9x9 LAPACK calls left, per problem ({n} in one call; one cv2 call {1e3 * cv:.3f} ms in this block; "
          f"a ratio of 40 / 30 / 15 allows {1e6 * cv / 40:.1f} / {1e6 * cv / 30:.1f} / {1e6 * cv / 15:.1f} us per "
          f"problem in all):")
    for name, t in times.items():
        print(f"  {name:62s} {_summary(1e6 * np.asarray(t))} us")


def solver_table(sim, reps, n_single):
    """Every solver's ratio to one cv2 call, single and batched, before and after; the 1000 x 50
    history."""
    from replication.core.kernels import lapack_reference

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
            run = lambda: two_step(hist.A, hist.B, iterations=50, certify=False)  # noqa: E731
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


def _best(fn, clock, reps=7):
    """Smallest time of ``reps`` calls of ``fn`` on ``clock`` (``time.perf_counter``: wall;
    ``time.process_time``: this process's CPU time, which other jobs on a shared machine disturb far
    less)."""
    times = []
    for _ in range(reps):
        start = clock()
        fn()
        times.append(clock() - start)
    return min(times)


def _cv2_call(sim, clock):
    """Seconds per bare ``cv2.calibrateHandEye`` (Tsai) call, best of 5 blocks of 100 (as
    ``bare_cv2_call``)."""
    import cv2

    Hg, Hc = [np.eye(3)], [np.eye(3)]
    for a, b in zip(sim.A[0], sim.B[0]):
        Hg.append(Hg[-1] @ a.T)
        Hc.append(b @ Hc[-1])
    zeros = [np.zeros((3, 1))] * len(Hg)
    return _best(lambda: [cv2.calibrateHandEye(Hg, zeros, Hc, zeros, method=cv2.CALIB_HAND_EYE_TSAI)
                          for _ in range(100)], clock, 5) / 100


def ratios_once(n, n_single, reps=7):
    """One process on the code importable now: per solver the ratio to one cv2 call, batched and
    single, each time the best of ``reps`` calls, on the wall clock and on CPU time; the history's
    cv2 calls per problem; the load. Only APIs older than the kernels are used, so a base commit
    runs it."""
    sim, hist = simulate(0, n), simulate(0, 1000)
    for name in SOLVERS:  # warm-up: first-call imports and caches out of the timings
        solve(name, sim.A[:300], sim.B[:300])
        solve(name, sim.A[0], sim.B[0])
    out = {"load": os.getloadavg()[0]}
    for clock, key in ((time.perf_counter, "wall"), (time.process_time, "cpu")):
        cv = _cv2_call(sim, clock)
        row = {"cv2_us": 1e6 * cv}
        for name in SOLVERS:
            t_b = _best(lambda: solve(name, sim.A, sim.B), clock, reps) / n
            t_s = _best(lambda: [solve(name, sim.A[k], sim.B[k]) for k in range(n_single)], clock, reps) / n_single
            row[name] = (cv / t_b, cv / t_s, 1e6 * t_b)
        row["history"] = _best(lambda: two_step(hist.A, hist.B, iterations=50, certify=False), clock, 3) / (1000 * cv)
        out[key] = row
    return out


def compare_with(base, reps, n, n_single):
    """Ratios of the code at ``base`` (e.g. ``git archive 3ece4a3 | tar -x -C /tmp/base``) and of
    this tree in one run: ``reps`` processes each, alternating base / this tree; in each process
    every figure is the best of 7 calls. Prints, per solver, the best ratio over the processes and
    the median (min-max), on the wall clock and on CPU time, the speed-up of this tree's best time
    over the base's, and the load average seen by each process."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    runs = {"base": [], "this tree": []}
    for _ in range(reps):
        for label, root in (("base", base), ("this tree", here)):
            env = dict(os.environ, PYTHONPATH=root)
            cmd = [sys.executable, os.path.abspath(__file__), "--ratios-json", "--runs", str(n),
                   "--single-calls", str(n_single)]
            done = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True, cwd=os.sep)
            runs[label].append(json.loads(done.stdout.splitlines()[-1]))
    loads = [r["load"] for rs in runs.values() for r in rs]
    print(f"base {base} vs this tree {here}: {reps} processes each, alternating; every figure the best of 7 calls in "
          f"its process; batched: {n} problems in one call; single: {n_single} calls of one problem; load average "
          f"{min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores")
    for key, what in (("wall", "wall clock"), ("cpu", "CPU time of the process")):
        cvs = {label: [r[key]["cv2_us"] for r in rs] for label, rs in runs.items()}
        print(f"\n{what}: one cv2 call " + "; ".join(f"{label} {_summary(v, '{:.0f}')} us" for label, v in cvs.items())
              + "\nratio to one cv2 call: best over the processes, then median (min-max)")
        for name in SOLVERS:
            cells = []
            for label, rs in runs.items():
                b = [r[key][name][0] for r in rs]
                single = max(r[key][name][1] for r in rs)
                cells.append(f"{label} batched best {max(b):5.1f}, {_summary(b)}; single {single:.2f}")
            speed = min(r[key][name][2] for r in runs["base"]) / min(r[key][name][2] for r in runs["this tree"])
            print(f"  {name:16s} " + "  |  ".join(cells) + f"  |  speed-up {speed:.2f}x")
        line = "  ".join(f"{label} best {min(r[key]['history'] for r in rs):.3f}, "
                         f"{_summary([r[key]['history'] for r in rs], '{:.3f}')}" for label, rs in runs.items())
        print(f"  history 1000 x 50, cv2 calls per problem: {line}")


#: How the profile's functions are grouped: kernels, LAPACK calls, the rest by module.
GROUPS = {
    "kernels.py": "kernels (polar, eigvalsh3, solve3, rotation test)",
    "_linalg.py": "numpy.linalg (LAPACK: 9x9 SVD/eigh of K, 4x4 eigh, fallbacks)",
    "so3.py": "so3 (rotation_vector_from_matrix, quaternions, SciPy conversions)",
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
    parser.add_argument("--reps", type=int, default=7, help="repetitions; with --compare-with, processes per tree")
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--single-calls", type=int, default=50)
    parser.add_argument("--parts", nargs="+", default=["kernels", "solvers", "lapack9", "shares"],
                        choices=["kernels", "solvers", "lapack9", "shares"], help="which tables (default: all)")
    parser.add_argument("--compare-with", metavar="DIR", help="also time the package tree at DIR (a base commit)")
    parser.add_argument("--ratios-json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.ratios_json:
        warnings.simplefilter("ignore")
        print(json.dumps(ratios_once(args.runs, args.single_calls)))
        return
    if args.compare_with:
        warnings.simplefilter("ignore", ReplicationWarning)
        compare_with(args.compare_with, args.reps, args.runs, args.single_calls)
        return
    warnings.simplefilter("ignore", ReplicationWarning)
    rng = np.random.default_rng(0)
    from replication.core import kernels

    print(f"kernels.MIN_BATCH = {kernels.MIN_BATCH}; the paper's simulated data, J = 20")
    sim = simulate(0, args.runs)
    if "kernels" in args.parts:
        kernel_table(rng, args.reps, sim)
    if "solvers" in args.parts:
        solver_table(sim, args.reps, args.single_calls)
    if "lapack9" in args.parts:
        lapack_9x9_table(sim, args.reps)
    if "shares" in args.parts:
        share_table(sim)


if __name__ == "__main__":
    main()
