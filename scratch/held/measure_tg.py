"""Row 3 before/after: triangular T_g (rt6 probe_batch.tg on probe_online.make, 60 s). Usage: measure_tg.py M PAIRS START N
PAIRS: upper (xy, xz, yz) or xy; run from rt6/ with PYTHONPATH=<worktree>."""
import sys
import warnings
from collections import Counter

ARGS, sys.argv = sys.argv[1:], sys.argv[:1]  # probe_online reads sys.argv at import
sys.path.insert(0, "/work/wt-rt6/scratch/rt6")
from probe_batch import tg  # noqa: E402
from probe_online import make  # noqa: E402
from replication.core.so3 import angle_between_deg  # noqa: E402
from replication.rig.calibration import calibrate  # noqa: E402
from replication.core.stats import wilson_interval  # noqa: E402
from replication.testing import RIG_R0  # noqa: E402

FLOOR = 0.343


def W(k, n):
    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} [{lo:.2f},{hi:.2f}]"

m, which, start, n = float(ARGS[0]), ARGS[1], int(ARGS[2]), int(ARGS[3])
pairs = ((0, 1), (0, 2), (1, 2)) if which == "upper" else ((0, 1),)
lev, chk, lie, named, gaps = Counter(), Counter(), 0, 0, []
for seed in range(start, start + n):
    cam, gyro = tg(m, pairs)(*make(seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = calibrate(cam, gyro, n_bootstrap=50, diagnose=False)
    e = float(angle_between_deg(r.R, RIG_R0))
    tri = r.to_dict()["sensor_model"]["triangular_frame_deg"]["upper"]
    checks = [x.check for x in r.verdict.reasons]
    lev[r.verdict.level] += 1
    lie += r.verdict.level == "ok" and e > FLOOR
    named += "gyro_triangular_frame" in checks
    gaps.append(abs(tri - e))
    for x in checks:
        chk[x] += 1
    print(f"  seed {seed}: {r.verdict.level} err {e:.3f} triangular(upper) {tri:.3f} {checks}", flush=True)
print(f"T_g {m} {which} {start}+{n}: {dict(lev)} ok&err>floor {W(lie, n)} triangular named {W(named, n)} "
      f"|angle - err| max {max(gaps):.3f} reasons {dict(chk)}", flush=True)
