"""Old rule (one step against one ramp and one offset) vs new (the ramps that bend, two steps) on the same rigs:
the profile's windows do not depend on the rule, so the old decision is recomputed from the report's windows.
Run from benchmarks/: python ../scratch_rt/compare.py CASES BASE N"""
import sys
import numpy as np
sys.path.insert(0, ".")
sys.path.insert(0, "../scratch_rt")
from bench_clock import case
from bench_changepoint import wilson
from replication.rig import clock
from gen import cal, make
from probe_clock import cam_step, drift_stops, gyro_step_nogap

def gen_case(name, seed):
    camera, gyro = make(seed, seconds=60.0, bias=(0.03, -0.02, 0.04))
    if name == "gen_two":
        gyro = gyro_step_nogap(gyro_step_nogap(gyro, 40, 30), 20, 20)
    elif name == "gen_stop":
        gyro = drift_stops(gyro, 500, 30, 60.0)
    elif name == "gen_cam20":
        camera = cam_step(camera, 30, 20)
    elif name == "gen_clean":
        pass
    return cal(camera, gyro, n_bootstrap=0)

def old_named(r):
    gap = any(j["found_by"] == "gap" for j in r.segments["clock_jumps"])
    p = r.segments["clock_profile"]
    if p is None:
        return gap
    t, d, se = (np.array(p[k]) for k in ("t_s", "offset_s", "se_s"))
    c0, c1, _, _, _, (c2, (_, means)), _ = clock._fits(t, d, 1 / se ** 2)
    scale = max(1.0, c2 / max(len(t) - 4, 1))
    old = gap or (min(c1 - c2, c0 - c2) / scale > 40 and abs(means[1] - means[0]) > 2e-3)
    ck = clock._fits(t, d, 1 / se ** 2)[3]
    return old, [old and (gap or (ck - c2) / scale > a * 40) for a in SHARES]

SHARES = (0.0, 0.1, 0.25, 0.5)
cases, base, n = sys.argv[1].split(","), int(sys.argv[2]), int(sys.argv[3])
for name in cases:
    old = new = two = 0
    alt = np.zeros(len(SHARES), int)
    for s in range(base, base + n):
        r = gen_case(name, s) if name.startswith("gen") else case(name, s)
        js = r.segments["clock_jumps"]
        o, a = old_named(r)
        old += o
        alt += a
        new += bool(js)
        two += len(js) == 2
    print(f"{name:10s} seeds {base}-{base + n - 1}: clock_jump old {wilson(old, n)}, new {wilson(new, n)}, two jumps {two}; old rule and over the bend by share * 40: "
          + ", ".join(f"{sh}: {k}/{n}" for sh, k in zip(SHARES, alt)),
          flush=True)
