"""A raw gyro's bias and the clock's drift estimated with R0.

Synthetic rigs (:func:`biased_rig`: the smooth three-axis motion of ``rig_streams``, 40 s, camera
noise 0.05 deg, gyro noise 0.2 deg/s per sample at 200 Hz, a clock offset drawn in +-20 ms), over
``--runs`` seeded runs per set (seeds ``[SEED, set, run]``):

* bias: each axis drawn in +-0.1 rad/s, half the runs with a 3 s rest at the start; the bias error
  per axis (median and 95th percentile of its absolute value), how often each axis's 95 % interval
  holds the truth (3 axes per run; Wilson 95 % interval), how often the halves' test fires (false
  alarms: the bias is constant) and the reason with it, how often the drift (0 here) is resolved,
  and R0's error with and without the bias model (``calibrate``);
* drift: 0, 50 and 200 ppm with a bias: how often the drift is resolved, how often the verdict's
  drift reason fires;
* time: ``calibrate`` with and without the model on the same input (median of the runs of the first
  set);
* scale (``--scale-runs``): the x axis reading 5 %, 1 % and 0 % high (60 s): the verdict, the
  ``gyro_scale`` reason, R0's error and how far R0 would move with the scale left at 1 (seeds
  ``[SEED, 10 + set, run]``);
* misalignment (``--misalignment-runs``): the gyro reading ``T omega + b``, ``T = I + N(mu)`` with
  the three symmetric off-diagonal terms ``mu`` of 2 %, 0.5 % and 0 % (random signs; 40 s; seeds
  ``--misalignment-seed`` + run, each a ``default_rng(seed)``): the verdict, the
  ``gyro_misalignment`` reason, any false reason, R0's error and how far R0 would move with the
  terms left at 0;
* drift coverage (``--coverage-runs``): no drift, 15, 40 and 60 s: how often the drift's 95 %
  interval excludes 0 (nominal 0.05; seeds ``[SEED, 20 + set, run]``);
* real (``--real``): TUM-VI room1's raw gyro and EuRoC MH01's ground-truth body orientation turned
  into rates with the issue's bias [-0.001, 0.020, 0.079] rad/s added (the raw imu0 file is not in
  the shared data), against the monocular ORB-SLAM3 camera: R0 with and without the model against
  both published calibrations.

Usage: python benchmarks/bench_sensor_model.py [--runs 200] [--seed 3400] [--real] [--scale-runs 30]
[--coverage-runs 150] [--misalignment-runs 24 --misalignment-seed 72000]
"""
import argparse
import time
import warnings

import numpy as np

from replication import testing
from replication.core.so3 import angle_between_deg, rotation_vector_from_matrix
from replication.core.stats import wilson_interval
from replication.rig.calibration import calibrate
from replication.rig.sensor_model import estimate_sensor_model
from replication.rig.streams import GyroStream
from replication.testing import RIG_R0, rig_streams

R0_TRUE = RIG_R0


def biased_rig(seconds=40.0, *, bias=(0.0, 0.0, 0.0), offset=0.0, ppm=0.0, rest_s=0.0, camera_noise_deg=0.0,
               gyro_noise_deg_s=0.0, rng=None, phase=0.0):
    """``(R0, camera, gyro)``: a camera at 20 Hz and a gyro at 200 Hz (one second beyond it on both
    sides) reading ``omega + bias`` (rad/s), stamped ``t + offset + ppm 1e-6 (t - seconds / 2)``;
    the rig rests for ``rest_s`` seconds, then starts moving over 2 s (the motion of
    :func:`replication.testing.rig_streams`)."""

    R0, camera, gyro, _ = rig_streams(seconds, rng=rng, camera_noise_deg=camera_noise_deg,
                                      gyro_noise_deg_s=gyro_noise_deg_s, phase=phase, offset=offset, bias=bias, ppm=ppm,
                                      rest_s=rest_s)
    return R0, camera, gyro


def _wilson(k, n):
    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} = {k / n:.3f} [{lo:.3f}, {hi:.3f}]"


def bias_set(runs, seed, with_calibrate):
    errors, covered, halves, halves_reason, drift_resolved, r0 = [], 0, 0, 0, 0, {True: [], False: []}
    times = {True: [], False: []}
    for k in range(runs):
        rng = np.random.default_rng([seed, 0, k])
        bias = rng.uniform(-0.1, 0.1, 3)
        R0, camera, gyro = biased_rig(bias=bias, offset=rng.uniform(-0.02, 0.02), rest_s=3.0 if k % 2 else 0.0,
                                      camera_noise_deg=0.05, gyro_noise_deg_s=0.2, rng=rng, phase=rng.uniform(0, 6))
        m = estimate_sensor_model(camera, gyro)
        errors.append(m.bias_rad_s - bias)
        covered += int(np.sum((m.bias_ci95_rad_s[:, 0] <= bias) & (bias <= m.bias_ci95_rad_s[:, 1])))
        halves += int(m.bias_changes)
        halves_reason += int(m.bias_changes and m.change_R0_deg > 0.05)
        drift_resolved += int(m.drift_resolved)
        if with_calibrate and k < with_calibrate:
            for on in (True, False):
                t0 = time.perf_counter()
                r = calibrate(camera, gyro, n_bootstrap=50, gyro_bias=on, diagnose=False)
                times[on].append(time.perf_counter() - t0)
                r0[on].append(float(angle_between_deg(r.R, R0)))
    e = np.abs(np.array(errors))
    print(f"bias, {runs} runs (seeds [{seed}, 0, 0..{runs - 1}]), half with a 3 s rest:")
    print("  |error| per axis, median (x, y, z): " + ", ".join(f"{v:.2e}" for v in np.median(e, axis=0))
          + " rad/s; 95th percentile: " + ", ".join(f"{v:.2e}" for v in np.percentile(e, 95, axis=0)))
    print(f"  95 % intervals holding the truth (axes): {_wilson(covered, 3 * runs)}")
    print(f"  halves' test fires (constant bias): {_wilson(halves, runs)}; its reason: {_wilson(halves_reason, runs)}")
    print(f"  drift (0 ppm) resolved: {_wilson(drift_resolved, runs)}")
    if r0[True]:
        n = len(r0[True])
        print(f"  R0 error, calibrate, {n} runs: with the model median {np.median(r0[True]):.4f} deg, max "
              f"{np.max(r0[True]):.4f}; without median {np.median(r0[False]):.3f} deg, max {np.max(r0[False]):.3f}")
        on, off = np.median(times[True]), np.median(times[False])
        print(f"  time of calibrate (n_bootstrap 50, no diagnosis): with the model median {on:.2f} s, without "
              f"{off:.2f} s, ratio {on / off:.2f}")


def drift_set(runs, seed):
    from replication.rig.sensor_verdict import sensor_reasons

    for j, ppm in enumerate((0.0, 50.0, 200.0)):
        resolved = reason = 0
        est = []
        for k in range(runs):
            rng = np.random.default_rng([seed, 1 + j, k])
            _, camera, gyro = biased_rig(bias=rng.uniform(-0.1, 0.1, 3), offset=rng.uniform(-0.02, 0.02), ppm=ppm,
                                         camera_noise_deg=0.05, gyro_noise_deg_s=0.2, rng=rng,
                                         phase=rng.uniform(0, 6), seconds=60.0)
            m = estimate_sensor_model(camera, gyro)
            est.append(m.drift_ppm)
            resolved += int(m.drift_resolved)
            reason += int(any(r.check == "clock_drift" for r in sensor_reasons(m, interval=1.0,
                                                                              motion_median_deg=30.0)))
        print(f"drift {ppm:g} ppm over 60 s, {runs} runs (seeds [{seed}, {1 + j}, k]): median estimate "
              f"{np.median(est):.1f} ppm; resolved {_wilson(resolved, runs)}; the verdict's reason "
              f"{_wilson(reason, runs)}")


def scale_set(runs, seed):
    for j, error in enumerate((0.05, 0.01, 0.0)):
        ok = named = 0
        errors, left = [], []
        for k in range(runs):
            rng = np.random.default_rng([seed, 10 + j, k])
            R0, camera, gyro = biased_rig(seconds=60.0, offset=rng.uniform(-0.02, 0.02), camera_noise_deg=0.05,
                                          gyro_noise_deg_s=0.2, rng=rng, phase=rng.uniform(0, 6))
            omega = gyro.omega * [1.0 + error, 1.0, 1.0] + rng.uniform(-0.1, 0.1, 3)
            r = calibrate(camera, GyroStream(gyro.t, omega, "gyro"), n_bootstrap=50, diagnose=False)
            ok += r.verdict.level == "ok"
            named += any(x.check == "gyro_scale" for x in r.verdict.reasons)
            errors.append(float(angle_between_deg(r.R, R0)))
            left.append(r.sensor_model["sensor_model"]["scale_R0_deg"])
        print(f"scale {error:.0%} high on x, {runs} runs (seeds [{seed}, {10 + j}, k]): ok {_wilson(ok, runs)}; the "
              f"gyro_scale reason {_wilson(named, runs)}; R0 error median {np.median(errors):.3f} deg, max "
              f"{np.max(errors):.3f}; left at 1 R0 would move {np.min(left):.3f}-{np.max(left):.3f} deg")


MISALIGNMENT_BIAS = np.array([0.03, -0.02, 0.04])


def misaligned_rig(seed, size, seconds=40.0):
    """:func:`replication.testing.misaligned_rig` with the gyro bias :data:`MISALIGNMENT_BIAS`."""
    return testing.misaligned_rig(seed, size, seconds, bias=MISALIGNMENT_BIAS)


def misalignment_set(runs, seed):
    for size in (0.02, 0.005, 0.0):
        ok = named = other = 0
        errors, left = [], []
        for k in range(runs):
            R0, camera, gyro, _ = misaligned_rig(seed + k, size)
            r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
            ok += r.verdict.level == "ok"
            named += any(x.check == "gyro_misalignment" for x in r.verdict.reasons)
            other += any(x.check != "gyro_misalignment" for x in r.verdict.reasons)
            errors.append(float(angle_between_deg(r.R, R0)))
            left.append(r.sensor_model["sensor_model"]["misalignment_R0_deg"])
        print(f"misalignment terms {size:.1%}, {runs} runs (seeds {seed}-{seed + runs - 1}): ok {_wilson(ok, runs)}; "
              f"the gyro_misalignment reason {_wilson(named, runs)}; another reason {_wilson(other, runs)}; R0 error "
              f"median {np.median(errors):.3f} deg, max {np.max(errors):.3f}; left at 0 R0 would move "
              f"{np.min(left):.3f}-{np.max(left):.3f} deg")


def coverage_set(runs, seed):
    for j, seconds in enumerate((15.0, 40.0, 60.0)):
        excluded = 0
        for k in range(runs):
            rng = np.random.default_rng([seed, 20 + j, k])
            _, camera, gyro = biased_rig(seconds, bias=rng.uniform(-0.1, 0.1, 3), offset=rng.uniform(-0.02, 0.02),
                                         camera_noise_deg=0.05, gyro_noise_deg_s=0.2, rng=rng,
                                         phase=rng.uniform(0, 6))
            excluded += int(estimate_sensor_model(camera, gyro).drift_resolved)
        print(f"no drift, {seconds:.0f} s, {runs} runs (seeds [{seed}, {20 + j}, k]): the drift's interval excludes 0 "
              f"in {_wilson(excluded, runs)} (nominal 0.05)")


def real():
    from replication.rig import realdata

    root = realdata.data_root()
    tum, euroc = root / "tumvi_room1_orbslam3mono", root / "euroc_mh01_orbslam3"
    cases = {}
    cam = realdata.load_tum_trajectory(tum / "orbslam3_mono_cam0_traj.txt")
    gyro = realdata.load_euroc_imu(tum / "imu0_data.csv")
    refs = (realdata.load_reference(tum / "camchain.yaml"),
            realdata.load_reference(tum / "basalt_tumvi_512_eucm_calib.json"))
    cases["TUM-VI room1, raw gyro"] = (cam, gyro, refs)
    cam = realdata.load_tum_trajectory(euroc / "orbslam3_mono_cam0_traj_runA.txt")
    gt = realdata.load_tum_trajectory(euroc / "gt_body_MH_01_easy_tum.txt")
    w = rotation_vector_from_matrix(np.swapaxes(gt.R[:-1], -1, -2) @ gt.R[1:]) / np.diff(gt.t)[:, None]
    w = w + np.array([-0.001, 0.020, 0.079]) + np.random.default_rng(34).normal(0, 1.7e-4 * np.sqrt(200), w.shape)
    refs = (realdata.load_reference(euroc / "euroc_cam0_sensor.yaml"),
            realdata.load_reference(euroc / "basalt_euroc_eucm_calib.json"))
    cases["EuRoC MH01, ground truth as rates + the issue's bias"] = (cam, GyroStream(0.5 * (gt.t[1:] + gt.t[:-1]), w,
                                                                                      "euroc rates"), refs)
    for name, (cam, gyro, refs) in cases.items():
        for on in (False, True):
            t0 = time.perf_counter()
            r = calibrate(cam, gyro, reference=np.stack(refs), gyro_bias=on)
            dt = time.perf_counter() - t0
            e1, e2 = r.reference_errors_deg
            bias = r.sensor_model.get("gyro_bias_rad_s") if r.sensor_model else None
            print(f"{name}, bias model {'on ' if on else 'off'}: {r.verdict.level}, to the dataset's {e1:.3f} deg, "
                  f"to Basalt's {e2:.3f} deg (floor {r.reference_disagreement_deg:.3f}), radius "
                  f"{r.bootstrap_ci95_deg:.3f} deg, bias {None if bias is None else np.round(bias, 4).tolist()}, "
                  f"{dt:.1f} s; reasons: {[x.check for x in r.verdict.reasons]}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--seed", type=int, default=3400)
    parser.add_argument("--calibrate-runs", type=int, default=20)
    parser.add_argument("--drift-runs", type=int, default=50)
    parser.add_argument("--real", action="store_true")
    parser.add_argument("--scale-runs", type=int, default=0)
    parser.add_argument("--coverage-runs", type=int, default=0)
    parser.add_argument("--misalignment-runs", type=int, default=0)
    parser.add_argument("--misalignment-seed", type=int, default=72000)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    if args.real:
        real()
    if args.scale_runs:
        scale_set(args.scale_runs, args.seed)
    if args.misalignment_runs:
        misalignment_set(args.misalignment_runs, args.misalignment_seed)
    if args.coverage_runs:
        coverage_set(args.coverage_runs, args.seed)
    if args.runs:
        bias_set(args.runs, args.seed, args.calibrate_runs)
    if args.drift_runs:
        drift_set(args.drift_runs, args.seed)


if __name__ == "__main__":
    main()
