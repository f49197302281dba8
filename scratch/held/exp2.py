import sys, numpy as np
from replication.testing import misaligned_rig
from replication.rig.gyro_model import axes_matrix
from replication.rig.streams import GyroStream
from replication.rig import sensor_model as sm
from replication.rig.gyro_held import held_report
from replication.core.so3 import angle_between_deg
for secs in (10.0, 15.0):
    for seed in range(71000, 71006):
        R0, camera, gyro, _ = misaligned_rig(seed, 0.0, seconds=secs)
        T = axes_matrix(np.zeros(3), [0.015] * 3); bias = np.array([0.03, -0.02, 0.04])
        g = GyroStream(gyro.t, (gyro.omega - bias) @ T.T + bias, "gyro")
        m = sm.estimate_sensor_model(camera, g)
        f = held_report(m)
        print(secs, seed, f["held_terms"], round(f["held_R0_deg"], 3), float(angle_between_deg(m.R, R0)), flush=True)
