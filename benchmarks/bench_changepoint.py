"""The batch change test (replication.rig.changepoint.two_segment_test): its threshold, false
alarms, re-mounts, cost.

1. the tail approximation of the threshold against simulated 3-dimensional Brownian bridges;
2. false alarms without a change on synthetic rigs (a camera at 20 Hz and a gyro at 200 Hz on one
   rigid body, 60 or 135 s of smooth three-axis motion as in tests/rig/test_calibration.py, noise on
   the camera orientations and the gyro at several levels), on one seed set and again on a disjoint
   one, with Wilson 95 % intervals; what a slowly wandering camera frame does (not a change, and not
   white noise); re-mounts on the rigs;
3. the real recordings as recorded (pairs as calibrate forms them: its clock offset, interval 1 s,
   its block);
4. synthetic re-mounts inside the real recordings (at 1/3, 1/2, 2/3 of the recording, about two
   axes, 0.5-5 deg): detections, the split time's error, each side's angle to its mounting (the
   recording's own calibration before, that times the re-mount after), and the verdict the proposed
   sizes give;
5. the run time of the test on TUM-VI's 2700 pairs next to calibrate's.

Run: python benchmarks/bench_changepoint.py [--quick] [--workers N]
"""
import argparse
import os
import time
import warnings
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.stats import binomtest

from replication.core import so3
from replication.rig.association import motion_pairs
from replication.rig.calibration import calibrate
from replication.rig.changepoint import remounted, threshold, two_segment_test
from replication.rig.quality import THRESHOLDS
from replication.rig.realdata import (
    data_root,
    load_euroc_imu,
    load_euroc_mocap,
    load_tum_trajectory,
    real_data_available,
)
from replication.rig.streams import GyroStream, integrate_gyro
from replication.study.live_study import REMOUNT_AXIS
from replication.testing import RIG_R0, rig_pairs
from replication.testing import noisy_rig as rig

WARNING_DEG, FAIL_DEG = THRESHOLDS["remount_deg"]

R0 = RIG_R0
#: In-control rigs: (seconds, camera orientation noise (deg, white per frame), gyro noise (rad/s per
#: 200 Hz sample), gyro bias (rad/s, constant)).
CONFIGS = [(60, 0.02, 0.002, 0.0), (60, 0.1, 0.005, 0.0), (60, 0.0, 0.005, 0.0), (60, 0.3, 0.02, 0.005),
           (135, 0.02, 0.002, 0.0), (135, 0.1, 0.005, 0.0), (135, 0.0, 0.005, 0.0), (135, 0.3, 0.02, 0.005)]


def wilson(k: int, n: int) -> str:
    ci = binomtest(int(k), int(n)).proportion_ci(0.95, method="wilson")
    return f"{k}/{n} = {100 * k / n:.2f} % [{100 * ci.low:.2f}, {100 * ci.high:.2f}] %"


def bridge_check(n_bridges: int = 50_000, n_steps: int = 1000, seed: int = 0, share: float = 0.15):
    """Quantiles of sup |B|^2 / (lam (1 - lam)) over [share, 1 - share] from simulated bridges,
    beside the approximation."""
    rng = np.random.default_rng(seed)
    lam = np.arange(1, n_steps + 1) / n_steps
    sel = (lam >= share) & (lam <= 1 - share)
    sups = []
    for _ in range(n_bridges // 1000):
        W = np.cumsum(rng.normal(size=(1000, n_steps, 3)), axis=1) / np.sqrt(n_steps)
        Bb = W[:, sel] - lam[sel][None, :, None] * W[:, -1:, :]
        sups.append((np.sum(Bb ** 2, -1) / (lam[sel] * (1 - lam[sel]))).max(1))
    sups = np.concatenate(sups)
    print(f"1. threshold approximation against {n_bridges} simulated bridges ({n_steps} steps, share {share}):")
    for a in (0.1, 0.05, 0.01, 0.001):
        approx = threshold(a, 1e12, share, 1 - share)  # a recording so long that the inflation is known
        print(f"   level {a:g}: simulated {np.quantile(sups, 1 - a):.2f}, approximation {approx:.2f} "
              f"(simulated exceedance of it {np.mean(sups > approx):.4f})")


def _false_alarm_run(args):
    seed, config = args
    A, B, t, block = rig_pairs(*rig(seed, *config))
    r = two_segment_test(A, B, t, block=block)
    return r.significant, r.statistic, r.threshold, r.inflation, r.angle_deg, r.p_value


def false_alarms(seeds, workers: int, label: str):
    print(f"2. false alarms without a change, seeds {seeds[0]}..{seeds[-1]} ({label}):")
    total = 0
    n_all = 0
    with ProcessPoolExecutor(workers) as ex:
        for config in CONFIGS:
            out = np.array(list(ex.map(_false_alarm_run, [(s, config) for s in seeds])), dtype=float)
            k = int(out[:, 0].sum())
            total += k
            n_all += len(out)
            print(f"   {config[0]:4.0f} s, camera {config[1]:.2f} deg, gyro {config[2]:.3f} rad/s, "
                  f"bias {config[3]:.3f}: flagged {wilson(k, len(out))}; p < 0.05 in {np.mean(out[:, 5] < 0.05):.3f}, "
                  f"p < 0.1 in {np.mean(out[:, 5] < 0.1):.3f}; threshold {out[0, 2]:.1f}, "
                  f"inflation median {np.median(out[:, 3]):.2f}, angle median {np.median(out[:, 4]):.3f} "
                  f"max {out[:, 4].max():.3f} deg")
    print(f"   all: flagged {wilson(total, n_all)}")


def _drift_run(args):
    seed, seconds, drift = args
    A, B, t, block = rig_pairs(*rig(seed, seconds, 0.05, 0.005, drift_deg=drift))
    r = two_segment_test(A, B, t, block=block)
    return r.significant, r.angle_deg


def drift(seeds, workers: int):
    print("   not in the claim above: a camera frame that wanders slowly (no re-mount; camera 0.05 deg, gyro 0.005):")
    with ProcessPoolExecutor(workers) as ex:
        for seconds, d in ((135, 0.1), (135, 0.3)):
            out = np.array(list(ex.map(_drift_run, [(s, seconds, d) for s in seeds])), dtype=float)
            print(f"   {seconds} s, drift {d} deg per 10 s: flagged {wilson(int(out[:, 0].sum()), len(out))}; angle "
                  f"median {np.median(out[:, 1]):.3f}, max {out[:, 1].max():.3f} deg, flagged with angle >= "
                  f"{WARNING_DEG} deg: {int(np.sum(out[:, 0].astype(bool) & (out[:, 1] >= WARNING_DEG)))}")


def _power_run(args):
    seed, config, size = args
    R = so3.matrix_from_rotation_vector(np.radians(size) * REMOUNT_AXIS / np.linalg.norm(REMOUNT_AXIS))
    t_r = config[0] * (1 / 3 + seed % 3 / 6)  # at 1/3, 1/2 or 2/3
    A, B, t, block = rig_pairs(*rig(seed, *config, remount=(t_r, R)))
    r = two_segment_test(A, B, t, block=block)
    return (r.significant, r.split_time - t_r, float(so3.angle_between_deg(r.R_before, R0)),
            float(so3.angle_between_deg(r.R_after, R0 @ R)), r.angle_deg)


def power(seeds, workers: int, sizes=(0.5, 1.0, 2.0)):
    print("2b. synthetic re-mounts on the rigs (at 1/3, 1/2 or 2/3 by seed):")
    with ProcessPoolExecutor(workers) as ex:
        for config in (CONFIGS[0], CONFIGS[1], CONFIGS[3], CONFIGS[5], CONFIGS[7]):
            for size in sizes:
                out = np.array(list(ex.map(_power_run, [(s, config, size) for s in seeds])), dtype=float)
                det = out[:, 0].astype(bool)
                err = np.abs(out[det, 1]) if det.any() else np.array([np.nan])
                side = np.maximum(out[:, 2], out[:, 3])
                print(f"   {config[0]:4.0f} s, camera {config[1]:.2f} deg, gyro {config[2]:.3f}, {size:g} deg: "
                      f"detected {int(det.sum())}/{len(out)}; |split error| median {np.nanmedian(err):.2f} "
                      f"max {np.nanmax(err):.2f} s; worse side to its mounting median {np.median(side):.3f} "
                      f"max {side.max():.3f} deg; angle between sides {out[:, 4].min():.2f}-{out[:, 4].max():.2f} deg")


def real_recordings():
    root = data_root()
    tv, eu = root / "tumvi_room1_orbslam3mono", root / "euroc_mh01_orbslam3"
    cam = load_tum_trajectory(tv / "orbslam3_mono_cam0_traj.txt")
    gt = load_tum_trajectory(eu / "gt_body_MH_01_easy_tum.txt")
    return {
        "TUM-VI room1, gyro": (cam, load_euroc_imu(tv / "imu0_data.csv")),
        "TUM-VI room1, mocap": (cam, load_euroc_mocap(tv / "mocap0_data.csv")),
        "EuRoC MH01, run A": (load_tum_trajectory(eu / "orbslam3_mono_cam0_traj_runA.txt", drop_repeated=True), gt),
        "EuRoC MH01, run B": (load_tum_trajectory(eu / "orbslam3_mono_cam0_traj_runB.txt", drop_repeated=True), gt),
    }


def calibrated(camera, sensor, **kw):
    """calibrate's result and its pairs (A, B, start times, block), as calibrate forms them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = calibrate(camera, sensor, **kw)
    oriented = integrate_gyro(sensor) if isinstance(sensor, GyroStream) else sensor
    A, B, t = motion_pairs(camera, oriented, r.interval_s, offset=r.time_offset_s)
    keep = np.isin(t, r.diagnostics["pair_times"])  # calibrate's pairs: those across a stream gap dropped
    return r, A[keep], B[keep], t[keep], max(1, round(r.interval_s / np.median(np.diff(camera.t))))


def verdict(r) -> str:
    if not r.significant:
        return "ok"
    return "fail" if r.angle_deg >= FAIL_DEG else "warning" if r.angle_deg >= WARNING_DEG else "ok (significant)"


def as_recorded(recordings):
    print("3. the real recordings as recorded (calibrate's pairs, interval 1 s):")
    out = {}
    for name, (camera, sensor) in recordings.items():
        t0 = time.perf_counter()
        r, A, B, t, block = calibrated(camera, sensor)
        t_cal = time.perf_counter() - t0
        two_segment_test(A, B, t, block=block)  # warm
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            c = two_segment_test(A, B, t, block=block)
            times.append(time.perf_counter() - t0)
        out[name] = (r, A, B, t, block)
        print(f"   {name}: {len(A)} pairs, block {block}: statistic {c.statistic:.1f}, threshold {c.threshold:.1f} "
              f"(p = {c.p_value:.2g}, inflation {c.inflation:.2f}), significant {c.significant}; split at "
              f"{c.split_time - t[0]:.1f} s of {t[-1] - t[0]:.1f} ({c.n_before} / {c.n_after} pairs), angle "
              f"{c.angle_deg:.3f} deg (noise radius {c.difference_radius_deg:.3f}); verdict by size: {verdict(c)}; "
              f"test {1e3 * np.median(times):.0f} ms (median of 5), calibrate {t_cal:.2f} s")
    return out


def remount_study(recordings, sizes=(0.5, 1.0, 2.0, 5.0), when=(1 / 3, 1 / 2, 2 / 3), axes=None):
    axes = [REMOUNT_AXIS, np.array([0.0, 0.0, 1.0])] if axes is None else axes
    print("4. synthetic re-mounts in the real recordings (each size at 1/3, 1/2, 2/3 about two axes: 6 runs):")
    for name, (camera, sensor) in recordings.items():
        base = calibrated(camera, sensor, n_bootstrap=0, diagnose=False)[0].R
        span = camera.t[-1] - camera.t[0]
        for size in sizes:
            rows = []
            for share in when:
                for axis in axes:
                    R = so3.matrix_from_rotation_vector(np.radians(size) * axis / np.linalg.norm(axis))
                    t_r = camera.t[0] + share * span
                    _, A, B, t, block = calibrated(camera, remounted(sensor, t_r, R), n_bootstrap=0, diagnose=False)
                    c = two_segment_test(A, B, t, block=block)
                    rows.append((c.significant, c.split_time - t_r, float(so3.angle_between_deg(c.R_before, base)),
                                 float(so3.angle_between_deg(c.R_after, base @ R)), c.angle_deg, verdict(c),
                                 c.statistic))
            sig = [r for r in rows if r[0]]
            err = np.array([abs(r[1]) for r in sig]) if sig else np.array([np.nan])
            side = np.array([max(r[2], r[3]) for r in rows])
            verdicts = {v: sum(r[5] == v for r in rows) for v in ("fail", "warning", "ok (significant)", "ok")}
            print(f"   {name}, {size:g} deg: detected {len(sig)}/{len(rows)}; |split error| median "
                  f"{np.nanmedian(err):.2f} max {np.nanmax(err):.2f} s (detected); worse side's angle to its mounting "
                  f"median {np.median(side):.3f} max {side.max():.3f} deg; angle between sides "
                  f"{min(r[4] for r in rows):.2f}-{max(r[4] for r in rows):.2f} deg; statistic "
                  f"{min(r[6] for r in rows):.0f}-{max(r[6] for r in rows):.0f}; verdicts "
                  + ", ".join(f"{v} {n}" for v, n in verdicts.items() if n))


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer bridges and seeds (a smoke run)")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    n_seeds = 20 if args.quick else 200
    bridge_check(n_bridges=5_000 if args.quick else 50_000)
    false_alarms(list(range(n_seeds)), args.workers, "found")
    false_alarms(list(range(10_000, 10_000 + n_seeds)), args.workers, "confirmed on fresh seeds")
    drift(list(range(20_000, 20_000 + n_seeds // 4)), args.workers)
    power(list(range(30_000, 30_000 + n_seeds // 10)), args.workers)
    if real_data_available():
        recordings = real_recordings()
        as_recorded(recordings)
        remount_study(recordings)
    else:
        print("3.-5. skipped: the real recordings are not available (replication.rig.realdata.data_root)")
