"""Coverage of the station radius on static pose sets whose stations repeat: ``N`` distinct stations
each given ``r`` times, either identical copies or re-measured with fresh noise, the share of runs
whose error is within the stated 95 % radius with its Wilson 95 % interval; runs without a radius (a
resample refused: the verdict says so) are counted apart. ``--old`` counts every station as distinct
(the bootstrap before the repeats were drawn as one).

Run: python benchmarks/bench_station_repeats.py FIRST_SEED LAST_SEED N r identical|remeasured
[--old] (0.5 s per run at N = 8, r = 3; found on seeds 0-199, confirmed on 1000-1199.)
"""
import sys
import warnings

import numpy as np

from replication.core import so3
from replication.core.stats import wilson_interval
from replication.rig import poses


def _stations(rng, N, noise_deg=0.3):
    R0, W = so3.random_rotations(rng, ()), so3.random_rotations(rng, ())
    S = so3.random_rotations(rng, N, angle_range_deg=(5.0, 60.0))
    sd = np.radians(noise_deg) / np.sqrt(3)
    C = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ (R0 @ S @ W)
    return R0, C, so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ S, sd


def main(first, last, N, r, mode, old=False):
    if old:
        poses.repeated_stations = lambda C, S, within: np.arange(len(C))
    hits = none = ok = 0
    for seed in range(first, last + 1):
        rng = np.random.default_rng(seed)
        R0, C, S, sd = _stations(rng, N)
        if mode == "identical":
            C, S = np.tile(C, (r, 1, 1)), np.tile(S, (r, 1, 1))
        else:
            C = np.concatenate([C] + [so3.matrix_from_rotation_vector(rng.normal(0, sd,
                                                                                 (N, 3))) @ C for _ in range(r - 1)])
            S = np.concatenate([S] + [so3.matrix_from_rotation_vector(rng.normal(0, sd,
                                                                                 (N, 3))) @ S for _ in range(r - 1)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = poses.calibrate_poses(C, S, n_bootstrap=200, seed=seed, diagnose=False)
        none += not np.isfinite(res.bootstrap_ci95_deg)
        hits += float(so3.angle_between_deg(res.R, R0)) <= res.bootstrap_ci95_deg
        ok += res.verdict.level == "ok"
    n = last - first + 1
    lo, hi = wilson_interval(hits, n)
    given = "no run has a radius" if none == n else "of those with a radius {} of {} = {:.3f} [{:.3f}, {:.3f}]".format(
        hits, n - none, hits / (n - none), *wilson_interval(hits, n - none))
    print(f"N = {N} x {r} {mode}{' (old bootstrap)' if old else ''}, seeds {first}-{last}: covered {hits} of {n} = "
          f"{hits / n:.3f} [{lo:.3f}, {hi:.3f}]; no radius in {none}; {given}; verdict ok in {ok}")


if __name__ == "__main__":
    a = sys.argv[1:]
    main(int(a[0]), int(a[1]), int(a[2]), int(a[3]), a[4], old="--old" in a)
