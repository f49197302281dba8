"""Coverage of the batch radii in simulation, where R0 is known: the share of runs whose error is
within the stated 95 % bootstrap radius, with its Wilson 95 % interval (the runs are independent).

* streams (``calibrate``): a synthetic rig (``replication.testing.rig_streams``: camera at 20 Hz,
  gyro at 200 Hz, smooth three-axis motion) with Gaussian noise on every camera orientation and
  every gyro sample; the moving-block bootstrap over the pairs (blocks of one pairing interval);
* static pose sets (``calibrate_poses``): stations with independent noise on both attitudes; the
  station bootstrap (every pair between two drawn stations), against resampling the pairs one by one
  (what it replaced).

Run: python benchmarks/bench_batch_coverage.py [runs]   (about 10 minutes at the default 100 runs
per setting)
"""
import sys
import time
import warnings

import numpy as np

from replication.core import so3
from replication.core.motions import prepare_motions
from replication.core.stats import wilson_interval
from replication.rig.calibration import calibrate
from replication.rig.poses import calibrate_poses, pose_pairs
from replication.rig.solve_and_judge import block_indices, bootstrap_replicates
from replication.testing import rig_streams


def _share(hits):
    low, high = wilson_interval(sum(hits), len(hits))
    return f"{np.mean(hits):.3f} [{low:.3f}, {high:.3f}] ({sum(hits)} of {len(hits)})"


def streams(runs, seconds, camera_noise_deg, gyro_noise_deg_s, seed):
    hits, radius, error = [], [], []
    for k in range(runs):
        rng = np.random.default_rng([seed, k])
        R0 = so3.random_rotations(rng, ())
        _, camera, gyro, _ = rig_streams(seconds, R0=R0, rng=rng, camera_noise_deg=camera_noise_deg,
                                         gyro_noise_deg_s=gyro_noise_deg_s, phase=rng.uniform(0, 6))
        r = calibrate(camera, gyro, n_bootstrap=100, seed=k)
        err = float(so3.angle_between_deg(r.R, R0))
        hits.append(err <= r.bootstrap_ci95_deg)
        radius.append(r.bootstrap_ci95_deg)
        error.append(err)
    return hits, float(np.median(radius)), float(np.median(error))


def stations(runs, N, noise_deg, seed):
    station_hits, pair_hits = [], []
    for k in range(runs):
        rng = np.random.default_rng([seed, k])
        R0, W = so3.random_rotations(rng, ()), so3.random_rotations(rng, ())
        S = so3.random_rotations(rng, N, angle_range_deg=(5.0, 60.0))
        C = R0 @ S @ W
        sd = np.radians(noise_deg) / np.sqrt(3)
        C = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ C
        S = so3.matrix_from_rotation_vector(rng.normal(0, sd, (N, 3))) @ S
        r = calibrate_poses(C, S, n_bootstrap=100, seed=k)
        err = float(so3.angle_between_deg(r.R, R0))
        station_hits.append(err <= r.bootstrap_ci95_deg)
        motions = prepare_motions(*pose_pairs(C, S))
        R_boot = bootstrap_replicates(motions, "chordal_optimal", {},
                                      block_indices(np.random.default_rng(k), motions.J, 1, 100), progress=False)
        pair_hits.append(err <= float(np.percentile(so3.angle_between_deg(R_boot, r.R), 95)))
    return station_hits, pair_hits


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    print(f"streams: {runs} runs per setting, 60 s, interval 1 s, moving-block bootstrap (100 replicates)")
    for cam, gyr in ((0.05, 0.05), (0.2, 0.2), (0.5, 0.1)):
        start = time.perf_counter()
        hits, radius, error = streams(runs, 60.0, cam, gyr, seed=int(100 * cam + 10 * gyr))
        print(f"  camera noise {cam} deg, gyro noise {gyr} deg/s: coverage {_share(hits)}; median radius "
              f"{radius:.4f} deg, median error {error:.4f} deg ({time.perf_counter() - start:.0f} s)")
    print(f"static pose sets: {runs} runs per setting, 100 replicates")
    for N, noise in ((20, 0.3), (40, 0.3), (88, 0.2)):
        start = time.perf_counter()
        st, pr = stations(runs, N, noise, seed=N)
        print(f"  {N} stations, {noise} deg per attitude: stations {_share(st)}; pairs one by one {_share(pr)} "
              f"({time.perf_counter() - start:.0f} s)")
