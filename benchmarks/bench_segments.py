"""The segment test (replication.rig.segments) inside calibrate: one verdict at every interval,
false alarms, clock jumps, cost.

1. lost tracking: a synthetic rig (bench_changepoint's: camera 20 Hz, gyro 200 Hz, smooth three-axis
   motion) whose camera frame wanders for a stretch (a random walk of WANDER_DEG per 10 s about each
   camera axis during the first LOST_S seconds, back to the true frame at LOST_S and still
   afterwards: a SLAM frame lost and re-found, its R0 off by a varying rotation then), calibrated at
   intervals 0.5, 1 and 2 s: the share of seeds with the same verdict at the three intervals (Wilson
   95 %), the verdicts, the share where a segment is named, the angle to the true R0 with
   ``use="consistent"``;
2. false alarms: rigs without a wander (bench_changepoint's CONFIGS without a gyro bias): the share
   where a segment is named as disagreeing (a verdict reason), and where the segments' omnibus test
   is significant;
3. clock jumps of several sizes half-way (JUMPS_MS), and none with samples lost (a gap, the clock
   unchanged): detection and false alarms (replication.rig.clock.clock_segments as calibrate calls
   it);
4. time: calibrate against the segment test alone.

Run: python benchmarks/bench_segments.py [N] [BASE]     (tuning seeds: 40 0; fresh: 40 50000) Runs
against whatever ``replication`` is importable (PYTHONPATH=/path/to/another/checkout for today's
calibrate).
"""
import sys
import time
import warnings

import numpy as np
from bench_changepoint import CONFIGS, R0, rig, wilson

from replication.core import so3
from replication.rig.calibration import calibrate
from replication.testing import camera_lost
from replication.testing import clock_jumped as jumped
from replication.testing import samples_lost as lost_samples

WANDER_DEG, LOST_S, SECONDS = 1.0, 46.0, 180.0
INTERVALS = (0.5, 1.0, 2.0)


def lost_rig(seed: int, wander_deg: float = WANDER_DEG, lost_s: float = LOST_S, seconds: float = SECONDS):
    """bench_changepoint's rig (camera 0.05 deg, gyro 0.005 rad/s) whose camera frame wanders during
    [0, lost_s)."""
    camera, gyro = rig(seed, seconds, 0.05, 0.005)
    return camera_lost(camera, np.random.default_rng(10 ** 6 + seed), wander_deg, lost_s), gyro


def _cal(camera, sensor, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, sensor, n_bootstrap=50, diagnose=False, **kw)


def lost_tracking(seeds):
    same, named, levels, angles = 0, 0, {}, []
    for s in seeds:
        cam, gyro = lost_rig(s)
        rs = [_cal(cam, gyro, interval=iv) for iv in INTERVALS]
        v = tuple(r.verdict.level for r in rs)
        levels[v] = levels.get(v, 0) + 1
        same += len(set(v)) == 1
        seg = getattr(rs[1], "segments", None)
        named += bool(seg and seg.get("run") and seg["disagreeing"])
        if seg is not None:
            rc = _cal(cam, gyro, use="consistent")
            angles.append((float(so3.angle_between_deg(rs[1].R, R0)), float(so3.angle_between_deg(rc.R, R0))))
    n = len(seeds)
    print(f"1. lost tracking ({WANDER_DEG:g} deg per 10 s for the first {LOST_S:g} s of {SECONDS:g} s), seeds "
          f"{seeds[0]}..{seeds[-1]}: the same verdict at {INTERVALS}: {wilson(same, n)}; verdicts {levels}; a "
          f"segment named (interval 1): {wilson(named, n)}")
    if angles:
        a = np.array(angles)
        print(f"   angle to the true R0, all pairs: median {np.median(a[:, 0]):.3f} max {a[:, 0].max():.3f} deg; "
              f"use='consistent': median {np.median(a[:, 1]):.3f} max {a[:, 1].max():.3f} deg")


def false_alarms(seeds):
    configs = [c for c in CONFIGS if c[3] == 0.0]
    named, omnibus, worse = 0, 0, 0
    for k, s in enumerate(seeds):
        secs, cam_deg, gyro_noise, bias = configs[k % len(configs)]
        r = _cal(*rig(s, secs, cam_deg, gyro_noise, bias))
        seg = getattr(r, "segments", None) or {}
        named += bool(seg.get("run") and seg["disagreeing"])
        omnibus += bool(seg.get("run") and seg["significant"])
        worse += r.verdict.level != "ok"
    n = len(seeds)
    print(f"2. no wander ({len(configs)} settings), seeds {seeds[0]}..{seeds[-1]}: a segment named "
          f"{wilson(named, n)}; omnibus significant {wilson(omnibus, n)}; verdict not ok {wilson(worse, n)}")


JUMPS_MS = (1.0, 2.5, 5.0, 10.0, 30.0, 100.0)
LOST_SAMPLES = (1, 4, 20, 40)


def clock_jumps(seeds):
    try:
        from replication.rig.clock import clock_segments, jump_candidates
    except ImportError:
        print("3. clock jumps: no clock_segments here")
        return
    from replication.rig.streams import integrate_gyro

    print(f"3. clock jumps half-way on 60 s rigs (camera 0.05 deg, gyro 0.005 rad/s), seeds {seeds[0]}..{seeds[-1]}:")
    for ms in JUMPS_MS:
        found, size_err = 0, []
        for s in seeds:
            camera, gyro = rig(s, 60, 0.05, 0.005)
            sensor = integrate_gyro(jumped(gyro, 30.0, ms / 1e3))
            _, jumps = clock_segments(camera, sensor, gaps=jump_candidates(sensor.t, 0.2), seed=s)
            found += bool(jumps)
            size_err += [abs(j.size_s - ms / 1e3) for j in jumps]
        err = f"; |size error| max {1e3 * max(size_err):.3f} ms" if size_err else ""
        print(f"   jump {ms:g} ms: found {wilson(found, len(seeds))}{err}")
    for count in LOST_SAMPLES:
        alarms = 0
        for s in seeds:
            camera, gyro = rig(s, 60, 0.05, 0.005)
            sensor = integrate_gyro(lost_samples(gyro, 30.0, count))
            alarms += bool(clock_segments(camera, sensor, gaps=jump_candidates(sensor.t, 0.2), seed=s)[1])
        print(f"   no jump, {count} samples lost at 30 s ({5 * count} ms): a jump named {wilson(alarms, len(seeds))}")


def timing(seed: int = 0):
    from replication.rig.association import motion_pairs
    from replication.rig.streams import integrate_gyro

    cam, gyro = lost_rig(seed)
    t0 = time.perf_counter()
    r = _cal(cam, gyro)
    t1 = time.perf_counter()
    try:
        from replication.rig.segments import segment_test
    except ImportError:
        print(f"4. time: calibrate {t1 - t0:.2f} s (no segment test here)")
        return
    A, B, t = motion_pairs(cam, integrate_gyro(gyro), 1.0, offset=r.time_offset_s)
    t2 = time.perf_counter()
    for _ in range(5):
        segment_test(A, B, t, block=20)
    print(f"4. time ({SECONDS:g} s rig, {len(A)} pairs): calibrate {t1 - t0:.2f} s (n_bootstrap 50); the segment "
          f"test alone {(time.perf_counter() - t2) / 5:.3f} s")


def main(n: int = 40, base: int = 0):
    seeds = list(range(base, base + n))
    lost_tracking(seeds)
    false_alarms(seeds)
    clock_jumps(seeds)
    timing(base)


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:3]))
