"""Clock cases: steps (sensor with/without gap, camera), two steps, step+drift, drift that stops, repeated samples.
Per case: verdict counts, clock_jump named (count), jumps' times/sizes/clocks, drift named, R0 error, lies."""
import sys
from collections import Counter

import numpy as np

from gen import FLOOR, W, cal, err, make
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import samples_lost

BIAS = (0.03, -0.02, 0.04)


def gyro_step_nogap(g, at, ms):  # samples lost, stamps even: sensor clock steps by ms without a skip
    k = int(round(ms / 5.0))
    i = np.searchsorted(g.t, at)
    om = np.concatenate([g.omega[:i], g.omega[i + k:]])
    return GyroStream(g.t[:len(om)], om, "gyro")


def gyro_step_gap(g, at, ms):  # clock jumps ahead: stamps skip
    return GyroStream(np.where(g.t >= at, g.t + ms * 1e-3, g.t), g.omega, "gyro")


def cam_step(c, at, ms):  # camera clock jumps ahead (skip in camera stamps)
    return OrientationStream(np.where(c.t >= at, c.t + ms * 1e-3, c.t), c.world_from_body, "camera")


def cam_step_nogap(c, at, ms):  # camera loses frames, stamps on evenly (50 ms per frame)
    k = int(round(ms / 50.0))
    i = np.searchsorted(c.t, at)
    R = np.concatenate([c.world_from_body[:i], c.world_from_body[i + k:]])
    return OrientationStream(c.t[:len(R)], R, "camera")


def drift_stops(g, ppm, stop, seconds):
    t = g.t
    s = t + ppm * 1e-6 * (np.minimum(t, stop) - 0.5 * seconds)
    return GyroStream(s, g.omega, "gyro")


def repeated(g, every):  # each every-th sample repeated (same stamp + same value), as a driver may
    idx = np.sort(np.r_[np.arange(len(g.t)), np.arange(0, len(g.t), every)])
    return GyroStream(g.t[idx], g.omega[idx], "gyro")


def repeated_new_stamp(g, every):  # a sample value repeated with the next stamp (a stale read)
    om = g.omega.copy()
    om[1::every] = om[0:-1:every][:len(om[1::every])]
    return GyroStream(g.t, om, "gyro")


S = 60.0
CASES = {
    "clean": lambda c, g: (c, g),
    "cam skip 50ms mid": lambda c, g: (cam_step(c, 30, 50), g),
    "cam skip 30ms mid": lambda c, g: (cam_step(c, 30, 30), g),
    "sens samples lost 50ms mid": lambda c, g: (c, samples_lost(g, 30, 10)),
    "sens gap 3ms mid": lambda c, g: (c, gyro_step_gap(g, 30, 3)),
    "sens gap 8ms mid": lambda c, g: (c, gyro_step_gap(g, 30, 8)),
    "sens lost 50ms + step nogap 20ms @30": lambda c, g: (c, samples_lost(gyro_step_nogap(g, 30, 20), 30, 10)),
    "sens nogap 5ms mid": lambda c, g: (c, gyro_step_nogap(g, 30, 5)),
    "sens nogap 10ms mid": lambda c, g: (c, gyro_step_nogap(g, 30, 10)),
    "sens nogap 30ms mid": lambda c, g: (c, gyro_step_nogap(g, 30, 30)),
    "sens nogap 50ms start(3s)": lambda c, g: (c, gyro_step_nogap(g, 3, 50)),
    "sens nogap 50ms end(57s)": lambda c, g: (c, gyro_step_nogap(g, 57, 50)),
    "sens gap 20ms mid": lambda c, g: (c, gyro_step_gap(g, 30, 20)),
    "sens gap 50ms start(2s)": lambda c, g: (c, gyro_step_gap(g, 2, 50)),
    "cam skip 20ms mid": lambda c, g: (cam_step(c, 30, 20), g),
    "cam skip 50ms end(58s)": lambda c, g: (cam_step(c, 58, 50), g),
    "cam lostframe 50ms mid": lambda c, g: (cam_step_nogap(c, 30, 50), g),
    "two steps 20ms@20 -20ms@40": lambda c, g: (c, gyro_step_nogap(gyro_step_gap(g, 40, -20), 20, 20)),
    "two steps nogap 20@20 30@40": lambda c, g: (c, gyro_step_nogap(gyro_step_nogap(g, 40, 30), 20, 20)),
    "step nogap 20ms + 100ppm": lambda c, g: (c, gyro_step_nogap(drift_stops(g, 100, 1e9, S), 30, 20)),
    "drift 200ppm stops@30": lambda c, g: (c, drift_stops(g, 200, 30, S)),
    "drift 500ppm stops@30": lambda c, g: (c, drift_stops(g, 500, 30, S)),
    "drift 300ppm steady": lambda c, g: (c, drift_stops(g, 300, 1e9, S)),
    "repeated every 10": lambda c, g: (c, repeated(g, 10)),
    "stale value every 5": lambda c, g: (c, repeated_new_stamp(g, 5)),
}
def main():
    start = int(sys.argv[1]) if len(sys.argv) > 1 else 6000
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 10
    only = sys.argv[3:] or list(CASES)
    for name in only:
        levels, checks, lies, errs, jumps = Counter(), Counter(), 0, [], []
        for seed in range(start, start + n):
            c0, g0 = make(seed, seconds=S, bias=BIAS)
            try:
                c, g = CASES[name](c0, g0)
                r = cal(c, g)
            except Exception as ex:  # noqa: BLE001
                levels["raised:" + type(ex).__name__ + ":" + str(ex)[:80]] += 1
                continue
            d = r.to_dict()
            e = err(r)
            errs.append(e)
            levels[r.verdict.level] += 1
            for x in r.verdict.reasons:
                checks[x.check] += 1
            lies += r.verdict.level == "ok" and e > FLOOR
            js = (d.get("segments") or {}).get("clock_jumps") or []
            jumps.append([(round(j["time_s"], 1), round(1e3 * j["size_s"], 1), j["clock"], j["found_by"]) for j in js])
            if seed == start:
                print("  e.g.", name, r.verdict.level, [(x.check, x.message[:220]) for x in r.verdict.reasons],
                      "drift ppm", d.get("clock_drift_ppm"), d.get("clock_drift_ci95_ppm"), flush=True)
        print(f"{name:28s} {dict(levels)} lies {W(lies, n)} R0err med {np.median(errs) if errs else float('nan'):.3f} max {max(errs) if errs else float('nan'):.3f} "
              f"checks {dict(checks)}\n     jumps {jumps[:6]}", flush=True)


if __name__ == "__main__":
    main()
