"""A camera frame that wanders: events, restarts and ``ready`` of the online estimator.

A live replay (:func:`replication.rig.live.replay`, 1 s pairs) of a synthetic 600 s rig whose
camera_from_sensor turns by 2 deg about a fixed axis, uniformly over the recording, at three noise
levels (camera / gyro 0.05 deg / 0.05 deg/s, 0.02 / 0.02, 0.01 / 0.01), over ``--runs`` seeded runs
each (seeds ``[SEED, noise index, run]``). Prints, per level, the runs whose events are exactly one
``drift`` (Wilson 95 % interval), the most restarts in a run, the median estimated rate against the
true one, the median share of pairs ready, and the pairs ready while more than the target (0.5 deg)
off.

Usage: python benchmarks/bench_drift.py [--runs 20] [--seed 404]
"""
import argparse

import numpy as np

from replication.core import so3
from replication.core.stats import wilson_interval
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.rig.streams import OrientationStream
from replication.testing import rig_streams

SECONDS, TOTAL_DEG, AXIS = 600.0, 2.0, np.array([0.6, 0.0, 0.8])


def run(noise, rng):
    R0, camera, gyro, _ = rig_streams(SECONDS, rng=rng, camera_noise_deg=noise[0], gyro_noise_deg_s=noise[1])
    phi = np.radians(TOTAL_DEG) * camera.t / SECONDS
    C = camera.world_from_body @ R0 @ so3.matrix_from_rotation_vector(-np.outer(phi, AXIS)) @ R0.T
    oc = OnlineCalibrator()
    rows = replay(OrientationStream(camera.t, C, "camera"), gyro, oc, diagnose=False)
    truth = [R0 @ so3.matrix_from_rotation_vector(np.radians(TOTAL_DEG) * t / SECONDS * AXIS) for t in rows["t"]]
    q = rows[["qw", "qx", "qy", "qz"]].to_numpy()
    wrong = sum(1 for k, ready in enumerate(rows["ready"]) if ready
                and so3.angle_between_deg(so3.matrix_from_quaternion(q[k]), truth[k]) > 0.5)
    events = rows.attrs["summary"]["events"]
    rate = next((e["rate_deg_s"] for e in events if e["kind"] == "drift"), None)
    return [e["kind"] for e in events], int(rows["alarm"].sum()), rate, float(rows["ready"].mean()), wrong


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--seed", type=int, default=404)
    args = parser.parse_args()
    print(f"{TOTAL_DEG} deg over {SECONDS:g} s (true rate {TOTAL_DEG / SECONDS:.4g} deg/s); {args.runs} runs each, "
          f"seeds [{args.seed}, noise, run]")
    for i, noise in enumerate(((0.05, 0.05), (0.02, 0.02), (0.01, 0.01))):
        out = [run(noise, np.random.default_rng([args.seed, i, k])) for k in range(args.runs)]
        one = sum(kinds == ["drift"] for kinds, *_ in out)
        low, high = wilson_interval(one, len(out))
        rates = [r for _, _, r, _, _ in out if r is not None]
        print(f"camera {noise[0]} deg / gyro {noise[1]} deg/s: one drift event and nothing else in {one}/{len(out)} "
              f"[{low:.2f}, {high:.2f}]; restarts at most {max(o[1] for o in out)}; median rate "
              f"{np.median(rates):.4g} deg/s; median share ready {np.median([o[3] for o in out]):.2f}; pairs ready "
              f"while > 0.5 deg off: {sum(o[4] for o in out)}")
