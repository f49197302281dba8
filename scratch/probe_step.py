"""Bias step 0.02 rad/s at 30 s (mount fixed) and controls: verdict, remount named, R0 error, the
bias change found. Usage: probe_step.py CASE SEED0 N"""
import sys
import warnings

sys.path.insert(0, "/work/wt-rt6/scratch/rt6")
from probe_online import make, step, ramp  # noqa: E402
from replication.core.so3 import angle_between_deg  # noqa: E402
from replication.rig.calibration import calibrate  # noqa: E402
from replication.testing import RIG_R0  # noqa: E402

case, s0, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
fn = {"step": step(0.02), "none": None, "ramp": ramp(0.005), "step05": step(0.05)}[case]
for seed in range(s0, s0 + n):
    cam, gyro = make(seed, bias_fn=fn)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = calibrate(cam, gyro, n_bootstrap=30, diagnose=False)
    checks = [(x.check, x.level) for x in r.verdict.reasons]
    bc = r.segments.get("bias_change") if r.segments else None
    print(f"{case} seed {seed}: {r.verdict.level} err {float(angle_between_deg(r.R, RIG_R0)):.3f} "
          f"remount={'remount_deg' in dict(checks)} segs={'segments_disagree' in dict(checks)} {checks} "
          f"change {bc}", flush=True)
