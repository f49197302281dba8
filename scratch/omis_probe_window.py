"""First-window sensor model on the red team's online misalignment case (seeds from argv)."""
import sys
import warnings
import numpy as np
sys.path.insert(0, "/work/wt-rt6/scratch/rt6")
from probe_online import BIAS, make
from replication.rig.streams import GyroStream, OrientationStream
from replication.rig.online_bias import _start

mu = float(sys.argv[1])
T = np.eye(3) + mu * np.array([[0, 1, 0], [1, 0, 1], [0, 1, 0]])
for seed in map(int, sys.argv[2:]):
    cam, g = make(seed)
    g = GyroStream(g.t, (g.omega - BIAS) @ T.T + BIAS, "gyro")
    k = cam.t <= cam.t[0] + 20.0
    kg = g.t <= g.t[0] + 21.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m, eff, reason = _start(OrientationStream(cam.t[k], cam.R[k]), GyroStream(g.t[kg], g.omega[kg]), 1.0, 0.2, 0.5)
    print(seed, "scale", np.round(m.scale, 4), m.scale_resolved, "mu", np.round(m.misalignment, 4),
          m.misalignment_resolved, np.round(m.misalignment_ci95, 4).tolist(), "eff", np.round(eff, 3),
          None if reason is None else reason.check)
