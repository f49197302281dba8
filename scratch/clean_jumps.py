"""False jumps on clean synthetic rigs (noisy_rig: camera 0.05 and 0.5 deg noise, gyro bias 0.05 rad/s),
both rules (the residual one against the true R0, offset 0). Seeds 96000-96099."""
import numpy as np

from replication.rig.camera_jumps import camera_jumps, residual_jumps
from replication.rig.streams import integrate_gyro
from replication.testing import RIG_R0, noisy_rig

for cam_deg in (0.05, 0.5):
    first = second = 0
    for seed in range(96000, 96100):
        camera, gyro = noisy_rig(seed, 60.0, cam_deg, 0.0035)
        oriented = integrate_gyro(gyro)
        first += bool(camera_jumps(camera, oriented, 0.2))
        second += bool(residual_jumps(camera, oriented, RIG_R0, 0.0))
    print(f"camera noise {cam_deg} deg: recordings with a jump named: rate rule {first}/100, residual rule {second}/100")
