"""Row 1 before/after: 15 s, symmetric misalignment (gen.make), bias. Usage: measure_short.py CONFIG START N
CONFIG: full (mu 1.5 %), control (mu 0), axis (mu 1.5 %, one-axis wobble 0.1), control_axis."""
import sys
from collections import Counter

import numpy as np

from gen import FLOOR, W, cal, err, make
from replication.rig.streams import GyroStream

BIAS = np.array([0.03, -0.02, 0.04])
CONF = {"full": (0.015, dict(seconds=15.0)), "control": (0.0, dict(seconds=15.0)),
        "axis": (0.015, dict(seconds=15.0, axis="z", wobble=0.1)), "control_axis": (0.0, dict(seconds=15.0, axis="z", wobble=0.1))}
name, start, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
mu, kw = CONF[name]
T = np.eye(3) + mu * (np.ones((3, 3)) - np.eye(3))
lev, chk = Counter(), Counter()
lie = unnamed = held_ok = 0
for seed in range(start, start + n):
    c, g = make(seed, bias=BIAS, **kw)
    r = cal(c, GyroStream(g.t, (g.omega - BIAS) @ T.T + BIAS, "gyro"))
    e, checks = err(r), [x.check for x in r.verdict.reasons]
    d = r.to_dict()["sensor_model"]
    lev[r.verdict.level] += 1
    lie += r.verdict.level == "ok" and e > FLOOR
    unnamed += e > FLOOR and not ({"gyro_misalignment", "gyro_held"} & set(checks))
    for x in checks:
        chk[x] += 1
    print(f"  {name} seed {seed}: {r.verdict.level} err {e:.3f} held_R0 {d.get('held_R0_deg', 0):.2f} "
          f"held {d.get('held_terms')} {checks}", flush=True)
print(f"{name} {start}+{n}: {dict(lev)} ok&err>floor {W(lie, n)} err>floor & neither misalignment nor held named "
      f"{W(unnamed, n)} reasons {dict(chk)}", flush=True)
