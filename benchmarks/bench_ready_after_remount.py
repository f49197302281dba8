"""How long the online estimator stays ``ready`` while wrong after a re-mount, and how often it
withdraws ``ready`` without any change.

Wrong means farther from the current mounting than the target (0.5 deg). Re-mounts of 0.5, 1 and 2
deg about a random axis, at two noise levels, over ``--runs`` seeded runs each, seeds ``[SEED,
set-up, noise index, step index, run]`` for runs ``--first`` .. ``--first + --runs - 1`` (tune on
one range, confirm on a disjoint one):

* pairs: 600 independent pairs of :func:`replication.study.live_study.pair_stream` (pair residual
  RMS 0.3 or 1 deg, motions of 5-60 deg), then 1200 after the re-mount (a case of 1800 was
  reported); counted in pairs;
* seconds (``--live``): a live replay (:func:`replication.rig.live.replay`, 1 s pairs, camera 20 Hz,
  gyro 200 Hz) of a 150 s synthetic rig re-mounted at 70 s (camera / gyro noise 0.3 deg / 0.3 deg/s
  or 1 deg / 1 deg/s); counted in seconds (the pairs' time spans while ready and wrong);
* no change: the same streams without the re-mount; a false withdrawal is a pair not ready after the
  first ready one.

Prints the median and 90th percentile over the runs and the share of runs with any (Wilson 95 %
interval). Usage: python benchmarks/bench_ready_after_remount.py [--runs 50] [--first 0] [--seed 33]
[--live]
"""
import argparse

import numpy as np

from replication.core import so3
from replication.core.stats import wilson_interval
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.study.live_study import pair_stream
from replication.testing import rig_streams

STEPS_DEG = (0.5, 1.0, 2.0)
PAIR_NOISE_DEG = (0.3, 1.0)
LIVE_NOISE = ((0.3, 0.3), (1.0, 1.0))
TARGET_DEG = 0.5
BEFORE, AFTER = 600, 1200


def _axis(rng):
    axis = rng.normal(size=3)
    return axis / np.linalg.norm(axis)


def wrong_pairs(step_deg, noise_deg, rng) -> tuple[int, int]:
    """``(pairs ready while wrong after the re-mount, pairs not ready after the first ready one
    before it)``; a step of 0: no change (every not-ready pair after the first ready one is a false
    withdrawal)."""
    R0 = so3.random_rotations(rng, ())
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(step_deg) * _axis(rng))
    A1, B1 = pair_stream(rng, BEFORE, R0, noise_deg=noise_deg)
    A2, B2 = pair_stream(rng, AFTER, R1, noise_deg=noise_deg)
    states = OnlineCalibrator(target_deg=TARGET_DEG).update_many(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
    ready = np.array([s.ready for s in states])
    first = int(np.argmax(ready)) if ready.any() else len(ready)
    end = BEFORE if step_deg else len(states)
    withdrawn = int(np.sum(~ready[first:end]))
    wrong = sum(1 for s in states[BEFORE:] if s.ready and so3.angle_between_deg(s.R, R1) > TARGET_DEG)
    return wrong, withdrawn


def wrong_seconds(step_deg, noise, rng) -> tuple[float, float]:
    """As :func:`wrong_pairs` on a live replay, in seconds."""
    R0, camera, gyro, _ = rig_streams(150.0, rng=rng, camera_noise_deg=noise[0], gyro_noise_deg_s=noise[1])
    R = so3.matrix_from_rotation_vector(np.radians(step_deg) * _axis(rng))
    rows = replay(camera, gyro, OnlineCalibrator(target_deg=TARGET_DEG), reference=R0,
                  remount=(70.0, R) if step_deg else None, diagnose=False)
    t = rows["t"].to_numpy()
    span = np.diff(np.concatenate([[t[0] - 1.0], t]))
    ready = rows["ready"].to_numpy(bool)
    first = int(np.argmax(ready)) if ready.any() else len(ready)
    before = (np.arange(len(t)) >= first) & (t < 70.0 if step_deg else np.ones(len(t), bool))
    withdrawn = float(span[before & ~ready].sum())
    after = t >= 70.0 + 1.05  # pairs wholly after the re-mount
    wrong = after & ready & (rows["error_deg"].to_numpy() > TARGET_DEG)
    return (float(span[wrong].sum()) if step_deg else 0.0), withdrawn


def _line(label, values, unit):
    v = np.asarray(values, dtype=float)
    k = int(np.sum(v > 0))
    low, high = wilson_interval(k, len(v))
    return (f"{label}: median {np.median(v):.3g} {unit}, p90 {np.percentile(v, 90):.3g}, max {v.max():.3g}; runs with "
            f"any {k}/{len(v)} [{low:.2f}, {high:.2f}]")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--seed", type=int, default=33)
    parser.add_argument("--live", action="store_true")
    args = parser.parse_args()
    runs = range(args.first, args.first + args.runs)
    print(f"ready while more than {TARGET_DEG} deg off after a re-mount; {args.runs} runs each, seeds "
          f"[{args.seed}, set-up, noise, step, run], runs {args.first}..{args.first + args.runs - 1}")
    setups = [("pairs", wrong_pairs, PAIR_NOISE_DEG, "pairs")] + (
        [("live", wrong_seconds, LIVE_NOISE, "s")] if args.live else [])
    for s, (name, fn, noises, unit) in enumerate(setups):
        for i, noise in enumerate(noises):
            for j, step in enumerate((0.0,) + STEPS_DEG):
                out = [fn(step, noise, np.random.default_rng([args.seed, s, i, j, run])) for run in runs]
                if step:
                    print(_line(f"{name}, noise {noise}, re-mount {step} deg, ready while wrong", [o[0] for o in out],
                                unit), flush=True)
                print(_line(f"{name}, noise {noise}, {'before the re-mount' if step else 'no change'}, false "
                            f"withdrawals", [o[1] for o in out], unit), flush=True)
