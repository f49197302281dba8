"""Time and peak memory of the three costs bounded by the "calibrate that judges its own answer"
issue.

* ``robust`` (MSAC + IRLS) through its public door at J = 1e4, 1e5, 1e6 pairs (30 % outliers);
* one ``cv2.calibrateHandEye`` call against the number of poses N (the wrappers refuse more than
  ``replication.core.solvers.opencv.MAX_PAIRS`` pairs);
* ``estimate_time_offset`` at ``max_offset`` 0.2, 2 and 30 s on a synthetic stream of TUM-VI room1's
  size (2800 camera poses at 20 Hz, a 200 Hz gyro integrated).

Usage: python benchmarks/bench_bounded.py [--quick] Every figure comes from a fresh subprocess:
``peak`` is tracemalloc's peak during the call (NumPy allocations included, inputs excluded),
``maxrss`` the process's resident-set high-water mark (inputs, interpreter and libraries included).
Nothing is asserted.
"""
import argparse
import json
import subprocess
import sys
import time

import numpy as np

METHODS = ("CALIB_HAND_EYE_TSAI", "CALIB_HAND_EYE_PARK", "CALIB_HAND_EYE_HORAUD")


def robust_problem(J: int, *, outliers: float = 0.3, noise_deg: float = 0.5, seed: int = 0):
    """``(R0, A, B)``: Haar camera motions, sensor motions ``R0^T A R0`` with noise, a share
    replaced at random."""
    from replication.core import so3
    from replication.study.baselines import corrupt_pairs

    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    A = so3.random_rotations(rng, J)
    B = so3.matrix_from_rotation_vector(rng.normal(size=(J, 3)) * np.radians(noise_deg)) @ (R0.T @ A @ R0)
    return R0, A, corrupt_pairs(B, outliers, rng)[0]  # the same draws as notebook 06's outlier sweep


def tumvi_like(seconds: float = 140.0, camera_hz: float = 20.0, gyro_hz: float = 200.0, offset: float = 0.0123,
               seed: int = 5):
    """``(R0, camera, sensor)``: camera stream and integrated gyro of one rig, sensor clock late by
    ``offset``.

    The attitude follows smooth sines as in ``tests/study/test_real_study.py::synthetic_rig`` plus
    faster terms; the gyro's body rates are central differences of the sensor attitude, integrated
    by :func:`replication.rig.streams.integrate_gyro`.
    """
    from replication.core import so3
    from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro

    R0 = so3.random_rotations(np.random.default_rng(seed), ())

    def attitude(t):
        w = np.stack([np.sin(0.7 * t) + 0.2 * np.sin(3.1 * t), np.sin(0.45 * t + 1.0) + 0.15 * np.cos(2.3 * t),
                      np.cos(0.3 * t) + 0.1 * np.sin(4.1 * t)], axis=-1)
        return so3.matrix_from_rotation_vector(w)

    tc = np.arange(0.0, seconds, 1.0 / camera_hz)
    tg = np.arange(-1.0, seconds + 1.0, 1.0 / gyro_hz)
    Q = attitude(np.concatenate([tg[:1] - 1 / gyro_hz, tg, tg[-1:] + 1 / gyro_hz]) - offset) @ R0
    # body rate at tg (central)
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-2], -1, -2) @ Q[2:]) * (0.5 * gyro_hz)
    return R0, OrientationStream(tc, attitude(tc), "camera"), integrate_gyro(GyroStream(tg, omega, "gyro"))


def _measure(call):
    import resource
    import tracemalloc

    tracemalloc.start()
    start = time.perf_counter()
    out = call()
    seconds = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return out, {"seconds": seconds, "peak_mb": peak / 1e6,
                 "maxrss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3}


def one(kind: str, value: float) -> dict:
    """One measurement (run in a subprocess by :func:`main`)."""
    import warnings

    from replication.core import so3

    warnings.simplefilter("ignore")
    if kind == "opencv":
        return opencv_times(int(value))
    if kind == "robust":
        from replication.core.solvers import solve

        R0, A, B = robust_problem(int(value))
        R, fig = _measure(lambda: solve("robust", A, B))
        fig["error_deg"] = float(so3.angle_between_deg(R, R0))
    else:
        from replication.rig.association import estimate_time_offset

        _, camera, sensor = tumvi_like()
        sensor.at(camera.t[10:12])  # build the interpolator outside the measurement
        (offset, corr), fig = _measure(lambda: estimate_time_offset(camera, sensor, max_offset=value))
        fig.update(offset_ms=1e3 * offset, correlation=corr, camera_poses=len(camera.t), gyro_samples=len(sensor.t))
    return fig


def opencv_times(N: int) -> dict:
    """Seconds of one ``cv2.calibrateHandEye`` call on a chain of N poses, per method, and the
    process's maxrss."""
    import resource

    import cv2

    from replication.core.solvers.opencv import _chain

    _, A, B = robust_problem(N - 1, outliers=0.0, seed=N)
    Hg, Hc = _chain(A, B)
    zeros = [np.zeros((3, 1))] * N
    row = {"N": N}
    for method in METHODS:
        start = time.perf_counter()
        cv2.calibrateHandEye(list(Hg), zeros, list(Hc), zeros, method=getattr(cv2, method))
        row[method] = time.perf_counter() - start
    row["maxrss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3  # OpenCV's own buffers (C++)
    return row


def _subprocess(kind, value):
    out = subprocess.run([sys.executable, __file__, "--one", kind, repr(value)], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="skip J = 1e6, N = 1600 and max_offset = 30 s")
    parser.add_argument("--one", nargs=2, metavar=("KIND", "VALUE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one[0], float(args.one[1]))))
        return
    from replication.core.solvers.msac import MAX_ENUMERATED_PAIRS
    from replication.core.solvers.opencv import MAX_PAIRS

    print(f"robust (public door; MAX_ENUMERATED_PAIRS = {MAX_ENUMERATED_PAIRS}), 30 % outliers, 0.5 deg noise:")
    for J in (10_000, 100_000) + (() if args.quick else (1_000_000,)):
        f = _subprocess("robust", J)
        print(f"  J = {J:>9,}: {f['seconds']:6.2f} s, peak {f['peak_mb']:6.0f} MB, maxrss {f['maxrss_mb']:6.0f} MB, "
              f"error {f['error_deg']:.3f} deg")
    print(f"one cv2.calibrateHandEye call vs poses N (s; the wrappers refuse J > MAX_PAIRS = {MAX_PAIRS} pairs, "
          f"N > {MAX_PAIRS + 1}):")
    print("  " + "".join(f"{m.replace('CALIB_HAND_EYE_', ''):>10}" for m in METHODS) + "   N")
    for N in (50, 100, 200, 400, 800) + (() if args.quick else (1600,)):
        row = _subprocess("opencv", N)
        print("  " + "".join(f"{row[m]:10.3f}" for m in METHODS) + f"   {N:4d}   PARK / N^2 = "
              f"{row[METHODS[1]] / N ** 2 * 1e6:.2f} us, maxrss {row['maxrss_mb']:.0f} MB")
    print("estimate_time_offset on a TUM-VI-sized stream (140 s, camera 20 Hz, gyro 200 Hz integrated):")
    for max_offset in (0.2, 2.0) + (() if args.quick else (30.0,)):
        f = _subprocess("offset", max_offset)
        print(f"  max_offset {max_offset:5.1f} s: {f['seconds']:6.2f} s, peak {f['peak_mb']:5.0f} MB, "
              f"maxrss {f['maxrss_mb']:5.0f} MB, offset {f['offset_ms']:.2f} ms (true 12.30), "
              f"corr {f['correlation']:.6f} ({f['camera_poses']} camera poses, {f['gyro_samples']} gyro samples)")


if __name__ == "__main__":
    main()
