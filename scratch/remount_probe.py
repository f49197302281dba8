"""A 2 deg re-mount at 30 s of a 60 s rig with a constant gyro bias (seeds 95000-95009): is it
still named remount_deg, and is a bias change fitted beside it?"""
import sys
import warnings

import numpy as np

from replication.core import so3
from replication.rig.calibration import calibrate
from replication.testing import noisy_rig

step = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))
for seed in range(int(sys.argv[1]), int(sys.argv[1]) + int(sys.argv[2])):
    camera, gyro = noisy_rig(seed, 60.0, 0.05, 0.0035, bias_rad_s=0.05, remount=(30.0, step))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    c = r.change_test
    print(f"seed {seed}: {r.verdict.level} {[(x.check, x.level) for x in r.verdict.reasons]} split "
          f"{c.get('split_time_s', float('nan')):.2f} angle {c.get('angle_deg', float('nan')):.2f} "
          f"bias_change {(r.segments or {}).get('bias_change')}", flush=True)
