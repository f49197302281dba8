import sys
sys.path.insert(0, "tests/rig")
import numpy as np
from test_online_bias import _scaled_rig
from replication.rig.online_bias import _start
from replication.rig.streams import GyroStream, OrientationStream
_, camera, gyro = _scaled_rig(seconds=30.0)
for span in (20.0, 30.0):
    k = camera.t <= camera.t[0] + span
    m, eff, r = _start(OrientationStream(camera.t[k], camera.world_from_body[k]), gyro, 1.0, 0.2, 0.01)
    print(span, np.round(eff, 4), m.misalignment_resolved, m.misalignment, None if r is None else r.check)
