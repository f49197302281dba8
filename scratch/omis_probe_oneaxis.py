"""Online, gyro misaligned (T = I + mu on xy and yz) + bias, motion about one axis until `until` s
then full (red team 6's generator, probe_online.make): the first window cannot resolve the terms.
Usage: omis_probe_oneaxis.py START N MU UNTIL [SECONDS]"""
import sys
import warnings

import numpy as np

sys.path.insert(0, "/work/wt-rt6/scratch/rt6")
from common import FLOOR, W  # noqa: E402
from probe_online import BIAS, make  # noqa: E402
from replication.rig.live import replay  # noqa: E402
from replication.rig.online import OnlineCalibrator  # noqa: E402
from replication.rig.streams import GyroStream  # noqa: E402
from replication.testing import RIG_R0  # noqa: E402

start, n, mu, until = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
seconds = float(sys.argv[5]) if len(sys.argv) > 5 else 60.0
T = np.eye(3) + mu * np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
ready = lies = outr = 0
for seed in range(start, start + n):
    cam, g = make(seed, seconds=seconds, one_axis_until=until)
    g = GyroStream(g.t, (g.omega - BIAS) @ T.T + BIAS, "gyro")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = replay(cam, g, OnlineCalibrator(), reference=RIG_R0, diagnose=False)
    s = rows.attrs["summary"]
    e, r = float(rows["error_deg"].iloc[-1]), bool(s["ready"])
    ready += r
    lies += r and e > FLOOR
    outr += r and e > s["radius_deg"]
    print(f"  seed {seed}: ready {r} err {e:.3f} radius {s['radius_deg']:.3f} reasons "
          f"{[x['check'] for x in s['verdict']['reasons']]} mis {s.get('gyro_misalignment_ci95')}", flush=True)
print(f"mu {mu} one axis until {until}: ready {ready}/{n}; ready&err>floor {W(lies, n)}; ready&err>radius {W(outr, n)}")
