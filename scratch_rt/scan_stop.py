"""Which noisy_rig seeds name a false step for a 500 ppm drift stopping at 30 s, old code vs new (calibrate)."""
import sys, warnings
import numpy as np
from replication.rig import clock, _oldclock_tmp as old
from replication.rig.calibration import calibrate
from replication.rig.streams import GyroStream
from replication.testing import noisy_rig
new = (clock.offset_profile, clock.merged_jumps)
def run(seed, use_old):
    clock.offset_profile, clock.merged_jumps = (old.offset_profile, old.merged_jumps) if use_old else new
    camera, gyro = noisy_rig(seed, 60.0, 0.05, 0.005, bias_rad_s=0.05)
    g = GyroStream(gyro.t + 500e-6 * (np.minimum(gyro.t, 30.0) - 30.0), gyro.omega, gyro.source)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = calibrate(camera, g, n_bootstrap=0, diagnose=False)
    return [(round(j["time_s"], 1), round(1e3 * j["size_s"], 1)) for j in r.segments["clock_jumps"]]
for s in range(int(sys.argv[1]), int(sys.argv[2])):
    o = run(s, True)
    print(s, "old", o, "new", run(s, False) if o else "-", flush=True)
