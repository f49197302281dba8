"""The two-step gains (over step+drift, over the others) per case, calibrate's profile. Run: tune2.py CASE BASE N"""
import sys, warnings
import numpy as np
from gen import make, cal
from probe_clock import gyro_step_nogap
from replication.rig.streams import GyroStream
from replication.testing import noisy_rig, clock_stepped, clock_drifting
case, base, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
for seed in range(base, base + n):
    if case.startswith("gen"):
        camera, gyro = make(seed, seconds=60.0, bias=(0.03, -0.02, 0.04))
    else:
        camera, gyro = noisy_rig(seed, 60.0, 0.05, 0.005, bias_rad_s=0.05)
    if case.endswith("two"):
        gyro = gyro_step_nogap(gyro_step_nogap(gyro, 40, 30), 20, 20)
    elif case.endswith("two10"):
        gyro = gyro_step_nogap(gyro_step_nogap(gyro, 40, 10), 20, 10)
    elif case.endswith("one30"):
        gyro = gyro_step_nogap(gyro, 30, 30)
    elif case.endswith("one10d100"):
        gyro = clock_drifting(gyro_step_nogap(gyro, 30, 10), 100.0, 30.0)
    elif case.endswith("one30d200"):
        gyro = clock_drifting(gyro_step_nogap(gyro, 30, 30), 200.0, 30.0)
    r = cal(camera, gyro, n_bootstrap=0)
    p = r.segments["clock_profile"]
    c = p["chi2"]; W = len(p["t_s"])
    s2 = max(1, c["two steps"] / (W - 6))
    g_csr = (c["step and drift"] - c["two steps"]) / s2
    g_oth = (min(c["one offset"], c["drift"], c["drift that bends"], c["step"]) - c["two steps"]) / s2
    g_step = (c["step"] - c["two steps"]) / s2
    import numpy as _n; from replication.rig.clock import _fits; f = _fits(_n.array(p["t_s"]), _n.array(p["offset_s"]), 1 / _n.array(p["se_s"]) ** 2); sz = _n.round(1e3 * _n.diff(f[-1][1][1]), 1).tolist(); sz1 = round(1e3 * float(_n.diff(f[-2][1][1])[0]), 1)
    print(case, seed, sz1, sz, f"g_csr {g_csr:.1f} g_step {g_step:.1f} g_oth {g_oth:.1f} s2 {s2:.1f}", len(r.segments["clock_jumps"]), flush=True)
