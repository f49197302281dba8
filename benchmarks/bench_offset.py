"""The clock-offset estimate: sub-grid accuracy, the bootstrap interval's width and coverage, peak
margins, run time.

* TUM-VI room1 (ORB-SLAM3 mono camera, raw gyro integrated) and EuRoC MH01 run A (ORB-SLAM3 mono
  camera, ground truth): the gyro's (ground truth's) time stamps are shifted by off-grid offsets
  (the issue's five and a dozen uniform in +-20 ms); the error of each is ``estimate(shifted) -
  estimate(unshifted) - shift``, before (the 0.5 ms fine grid's maximum, the computation of before)
  and after (the refined offset), with the 95 % interval of
  :func:`replication.rig.association.offset_analysis` on each shifted stream;
* coverage of that interval over synthetic rigs (the rig of ``tests/rig/test_association.py``, 30 s)
  with independent noise on the camera's poses and the gyro, each with an injected off-grid offset:
  the share of intervals holding it, with a Wilson 95 % interval on the share;
* the peak margin on the recordings and on a periodic motion, at the default search (+-0.2 s) and a
  wider one;
* the run time of ``offset_analysis`` (200 replicates), ``estimate_time_offset`` and the search of
  before.

Usage: python benchmarks/bench_offset.py [--quick] [--margins]   (needs the real recordings; prints
figures, asserts nothing; --margins: only the peak margins)
"""
import argparse
import time

import numpy as np

from replication.core import so3
from replication.rig import offset_search, realdata
from replication.rig.association import estimate_time_offset, offset_analysis
from replication.rig.calibration import _gap_free_window
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import RIG_R0, rig_streams

ISSUE_MS = (0.13, 0.37, 1.71, 2.29, -3.43)


def old_search(camera, sensor, max_offset=0.2, resolution=0.5e-3):
    """The search of before (10 ms grid, then the ``resolution`` grid; its maximum), for timing and
    'before'."""
    t, cam = offset_search.overlap(camera, sensor, max_offset)
    coarse = np.arange(-max_offset, max_offset + 1e-12, 0.01)
    best = coarse[np.argmax(offset_search.correlations(cam, sensor, t, coarse))]
    fine = np.clip(np.arange(best - 0.01, best + 0.01 + 1e-12, resolution), -max_offset, max_offset)
    return float(fine[np.argmax(offset_search.correlations(cam, sensor, t, fine))])


def recordings():
    """``{name: (camera, shift -> sensor)}``."""
    d, e = realdata.data_root() / "tumvi_room1_orbslam3mono", realdata.data_root() / "euroc_mh01_orbslam3"
    gyro = realdata.load_euroc_imu(d / "imu0_data.csv")
    gt = realdata.load_tum_trajectory(e / "gt_body_MH_01_easy_tum.txt")
    return {
        "TUM-VI room1, raw gyro": (realdata.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt"),
                                   lambda s: integrate_gyro(GyroStream(gyro.t + s, gyro.omega, "gyro"))),
        "EuRoC MH01 run A, ground truth": (realdata.load_tum_trajectory(e / "orbslam3_mono_cam0_traj_runA.txt"),
                                           lambda s: OrientationStream(gt.t + s, gt.R, "ground truth")),
    }


def injection(name, camera, shifted, shifts):
    base_old, base_new = old_search(camera, shifted(0.0)), estimate_time_offset(camera, shifted(0.0))[0]
    print(f"\n{name}: unshifted {1e3 * base_new:+.4f} ms (grid {1e3 * base_old:+.1f} ms); error = estimate(shifted) "
          "- estimate(unshifted) - shift")
    print("   shift (ms)   before (ms)   after (ms)   95 % interval - estimate (ms)   width (ms)")
    before, after, widths = [], [], []
    for s in shifts:
        sensor = shifted(s)
        found = offset_analysis(camera, sensor)
        before.append(old_search(camera, sensor) - base_old - s)
        after.append(found.offset_s - base_new - s)
        lo, hi = found.ci95_s
        widths.append(hi - lo)
        print(f"   {1e3 * s:+9.3f}   {1e3 * before[-1]:+10.4f}   {1e3 * after[-1]:+10.5f}   "
              f"[{1e3 * (lo - found.offset_s):+.3f}, {1e3 * (hi - found.offset_s):+.3f}]{'':17s}{1e3 * widths[-1]:.3f}")
    b, a = 1e3 * np.abs(before), 1e3 * np.abs(after)
    print(f"   |error| before: max {b.max():.4f} ms, median {np.median(b):.4f} ms; after: max {a.max():.5f} ms, "
          f"median {np.median(a):.5f} ms; interval width median {1e3 * np.median(widths):.3f} ms "
          f"({1e3 * min(widths):.3f}-{1e3 * max(widths):.3f})")


R0 = RIG_R0


def noisy_rig(offset, camera_noise_deg, gyro_noise, rng, seconds=30.0):
    """The rig of ``tests/rig/test_association.py``: camera poses (20 Hz, noise in deg per axis) and
    the integrated gyro (200 Hz, noise in rad/s per sample) whose clock reads ``offset`` s ahead."""
    _, camera, gyro, _ = rig_streams(seconds, offset=offset,
                                     camera_noise_deg=lambda n: rng.normal(scale=np.radians(camera_noise_deg), size=n),
                                     gyro_noise_deg_s=lambda n: rng.normal(scale=gyro_noise, size=n))
    return camera, integrate_gyro(gyro)


def wilson(k, n, z=1.959964):
    """Wilson score interval of a binomial share ``k / n``."""
    p, den = k / n, 1 + z * z / n
    centre, half = (p + z * z / (2 * n)) / den, z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return centre - half, centre + half


def coverage(runs, camera_noise_deg, gyro_noise, *, seconds=30.0, block_s=1.0, seed=2024):
    rng = np.random.default_rng(seed)
    hits, widths, errors = 0, [], []
    for k in range(runs):
        truth = rng.uniform(-0.02, 0.02)
        found = offset_analysis(*noisy_rig(truth, camera_noise_deg, gyro_noise, rng, seconds), seed=k, block_s=block_s)
        lo, hi = found.ci95_s
        hits += lo <= truth <= hi
        widths.append(hi - lo)
        errors.append(found.offset_s - truth)
    lo, hi = wilson(hits, runs)
    print(f"   camera {camera_noise_deg} deg, gyro {gyro_noise} rad/s, {seconds:.0f} s, blocks {block_s} s: "
          f"{hits}/{runs} = {hits / runs:.3f} (Wilson 95 % {lo:.3f}-{hi:.3f}); width median "
          f"{1e3 * np.median(widths):.2f} ms; error sd {1e3 * np.std(errors):.2f} ms "
          f"(3.92 sd = {3.92e3 * np.std(errors):.2f} ms), mean {1e3 * np.mean(errors):+.2f} ms")


def periodic(freq_hz=3.0, seconds=60.0, aperiodic=0.0):
    """A single-axis oscillation at ``freq_hz`` (the angular speed repeats every ``1 / (2 freq_hz)``
    s), times ``aperiodic`` times the rig's three-axis motion."""
    axis = so3.matrix_from_rotation_vector(np.array([0.3, 0.2, 0.1]))

    def world_from_camera(t):
        slow = so3.matrix_from_rotation_vector(aperiodic * np.stack([0.9 * np.sin(0.7 * t),
                                                                     0.8 * np.sin(0.45 * t + 1.0),
                                                 0.7 * np.cos(0.3 * t)], -1))
        return slow @ axis @ so3.matrix_from_rotation_vector(np.stack([0.6 * np.sin(2 * np.pi * freq_hz * t), 0 * t,
                                                                       0 * t], -1)) @ axis.T

    t_cam, t_sensor = np.arange(0.0, seconds, 0.05), np.arange(-3.0, seconds + 3.0, 0.01)
    return (OrientationStream(t_cam, world_from_camera(t_cam), "camera"),
            OrientationStream(t_sensor, world_from_camera(t_sensor) @ R0, "sensor"))


def margins():
    d, e = realdata.data_root() / "tumvi_room1_orbslam3mono", realdata.data_root() / "euroc_mh01_orbslam3"
    tumvi = realdata.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt")
    mocap = realdata.load_euroc_mocap(d / "mocap0_data.csv")
    gt = realdata.load_tum_trajectory(e / "gt_body_MH_01_easy_tum.txt")
    cases = {
        "TUM-VI raw gyro": (tumvi, integrate_gyro(realdata.load_euroc_imu(d / "imu0_data.csv"))),
        "TUM-VI mocap": (tumvi, mocap),
        "TUM-VI mocap, longest gap-free stretch": (_gap_free_window(tumvi, mocap, 2.0), mocap),
        "EuRoC MH01 run A": (realdata.load_tum_trajectory(e / "orbslam3_mono_cam0_traj_runA.txt"), gt),
        "EuRoC MH01 run B": (realdata.load_tum_trajectory(e / "orbslam3_mono_cam0_traj_runB.txt",
                                                          drop_repeated=True), gt),
        "synthetic rig (three axes, 40 s)": noisy_rig(0.0, 0.0, 0.0, np.random.default_rng(0), 40.0),
        "periodic 3 Hz (speed period 167 ms)": periodic(3.0),
        "periodic 1.3 Hz (speed period 385 ms)": periodic(1.3),
        "periodic 3 Hz times 0.3 x the rig's motion": periodic(3.0, aperiodic=0.3),
        "periodic 3 Hz times 1.0 x the rig's motion": periodic(3.0, aperiodic=1.0),
        "periodic 3 Hz times 2.0 x the rig's motion": periodic(3.0, aperiodic=2.0),
    }
    print(f"\npeak margin (correlation at the peak - highest coarse local maximum farther than "
          f"{1e3 * offset_search.PEAK_SEPARATION_S:.0f} ms, refined if within "
          f"{offset_search.RIVAL_REFINED_WITHIN:g} on "
          "the coarse curve; NaN: none in the search):")
    for name, (camera, sensor) in cases.items():
        row = []
        for max_offset in (0.2, 0.5, 1.0, 2.0):
            f = offset_analysis(camera, sensor, max_offset=max_offset, n_bootstrap=0)
            row.append(f"+-{max_offset:g} s: {f.peak_margin:.4f}"
                       + (f" (r {f.correlation:.4f} vs {f.second_peak_correlation:.4f} at "
                          f"{1e3 * f.second_peak_offset_s:+.0f} ms)" if np.isfinite(f.peak_margin) else ""))
        print(f"   {name}: " + "; ".join(row))


def timing(repeats):
    print(f"\nrun time (fastest / median of {repeats} runs; other processes on the machine inflate the median):")
    for name, (camera, shifted) in recordings().items():
        sensor = shifted(0.0)
        sensor.at(sensor.t[:1])  # the interpolator is built once per stream, outside the timing
        cases = {"search of before": lambda: old_search(camera, sensor),
                 "estimate_time_offset": lambda: estimate_time_offset(camera, sensor),
                 "offset_analysis, 200 replicates": lambda: offset_analysis(camera, sensor),
                 "offset_analysis, no replicates": lambda: offset_analysis(camera, sensor, n_bootstrap=0)}
        out = []
        for label, call in cases.items():
            seconds = []
            for _ in range(repeats):
                start = time.perf_counter()
                call()
                seconds.append(time.perf_counter() - start)
            out.append(f"{label} {min(seconds):.3f} / {np.median(seconds):.3f} s")
        print(f"   {name} ({len(camera.t)} camera times): " + "; ".join(out))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer shifts, coverage runs and repeats")
    parser.add_argument("--margins", action="store_true", help="only the peak margins")
    args = parser.parse_args(argv)
    if args.margins:
        return margins()
    rng = np.random.default_rng(7)
    random_ms = rng.uniform(-20.0, 20.0, 12)
    shifts = 1e-3 * np.concatenate([ISSUE_MS, [] if args.quick else random_ms])
    for name, (camera, shifted) in recordings().items():
        injection(name, camera, shifted, shifts)
    print("\ncoverage of the 95 % interval, synthetic rig, an off-grid offset uniform in +-20 ms per run:")
    runs = 40 if args.quick else 200
    coverage(runs, 0.05, 0.01)
    coverage(runs // 2, 0.05, 0.01, seconds=60.0)
    coverage(runs // 2, 0.01, 0.002)
    margins()
    timing(2 if args.quick else 7)


if __name__ == "__main__":
    main()
