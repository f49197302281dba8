"""How long the online estimator stays ``ready`` while wrong after a re-mount (issue 33, point 3).

Wrong means farther from the new mounting than the target (0.5 deg). Two set-ups, each for re-mounts of 0.5, 1 and
2 deg about a random axis, at two noise levels, over ``--runs`` seeded runs each (seeds ``[SEED, noise index, step
index, run]``):

* pairs: 200 independent pairs of :func:`replication.study.live_study.pair_stream` (pair residual RMS 0.2 or 0.5 deg,
  motions of 5-60 deg), then 300 after the re-mount; counted in pairs;
* seconds: a live replay (:func:`replication.rig.live.replay`, 1 s pairs, camera 20 Hz, gyro 200 Hz) of a 150 s
  synthetic rig re-mounted at 70 s (camera / gyro noise 0.05 deg / 0.05 deg/s or 0.2 deg / 0.2 deg/s); counted in
  seconds (the pairs' time spans while ready and wrong).

Prints the median and maximum over the runs and the share of runs with any such pair (Wilson 95 % interval).
Usage: python benchmarks/bench_ready_after_remount.py [--runs 20] [--seed 33]
"""
import argparse

import numpy as np

from replication.core import so3
from replication.core.stats import wilson_interval
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.study.live_study import pair_stream
from replication.study.simulation import rig_streams

STEPS_DEG = (0.5, 1.0, 2.0)
TARGET_DEG = 0.5


def _axis(rng):
    axis = rng.normal(size=3)
    return axis / np.linalg.norm(axis)


def wrong_pairs(step_deg, noise_deg, rng) -> int:
    R0 = so3.random_rotations(rng, ())
    R1 = R0 @ so3.exp_map(np.radians(step_deg) * _axis(rng))
    A1, B1 = pair_stream(rng, 200, R0, noise_deg=noise_deg)
    A2, B2 = pair_stream(rng, 300, R1, noise_deg=noise_deg)
    states = OnlineCalibrator(target_deg=TARGET_DEG).update_many(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
    return sum(1 for s in states[200:] if s.ready and so3.angle_between_deg(s.R, R1) > TARGET_DEG)


def wrong_seconds(step_deg, noise, rng) -> float:
    R0, camera, gyro, _ = rig_streams(150.0, rng=rng, camera_noise_deg=noise[0], gyro_noise_deg_s=noise[1])
    R = so3.exp_map(np.radians(step_deg) * _axis(rng))
    rows = replay(camera, gyro, OnlineCalibrator(target_deg=TARGET_DEG), reference=R0, remount=(70.0, R),
                  diagnose=False)
    after = rows[rows["t"] >= 70.0 + 1.05]  # pairs wholly after the re-mount
    span = np.diff(np.concatenate([[70.0], after["t"].to_numpy()]))
    wrong = (after["ready"] & (after["error_deg"] > TARGET_DEG)).to_numpy()
    return float(span[wrong].sum())


def _line(label, values):
    v = np.asarray(values, dtype=float)
    k = int(np.sum(v > 0))
    low, high = wilson_interval(k, len(v))
    return (f"{label}: median {np.median(v):.3g}, max {v.max():.3g}; runs with any {k}/{len(v)} "
            f"[{low:.2f}, {high:.2f}]")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--seed", type=int, default=33)
    args = parser.parse_args()
    print(f"ready while more than {TARGET_DEG} deg off after a re-mount; {args.runs} runs each, seeds "
          f"[{args.seed}, noise, step, run]")
    for i, noise in enumerate((0.2, 0.5)):
        for j, step in enumerate(STEPS_DEG):
            values = [wrong_pairs(step, noise, np.random.default_rng([args.seed, i, j, run]))
                      for run in range(args.runs)]
            print(_line(f"pairs, noise {noise} deg, re-mount {step} deg (pairs)", values))
    for i, noise in enumerate(((0.05, 0.05), (0.2, 0.2))):
        for j, step in enumerate(STEPS_DEG):
            values = [wrong_seconds(step, noise, np.random.default_rng([args.seed + 1, i, j, run]))
                      for run in range(args.runs)]
            print(_line(f"live replay, camera {noise[0]} deg / gyro {noise[1]} deg/s, re-mount {step} deg (s)",
                        values))
