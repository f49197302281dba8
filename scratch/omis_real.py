"""TUM-VI room1 (ORB-SLAM3 mono cam0, raw imu0 gyro, Kalibr reference) replayed online, as recorded
and with the gyro's axes made non-orthogonal (T = I + mu on xy, xz, yz; red team 6's real case).
Prints ready, the final error to Kalibr, the radius, the track's ready rows beyond the floor and
the radius, and the misalignment keys. Run with PYTHONPATH=<the code to test>."""
import sys
import warnings

import numpy as np

import replication.rig.realdata as rd
from replication.rig.live import replay
from replication.rig.online import OnlineCalibrator
from replication.rig.streams import GyroStream

FLOOR = 0.343
tum = rd.data_root() / "tumvi_room1_orbslam3mono"
cam = rd.load_tum_trajectory(tum / "orbslam3_mono_cam0_traj.txt")
imu, ref = rd.load_euroc_imu(tum / "imu0_data.csv"), rd.load_reference(tum / "camchain.yaml")
for mu in map(float, sys.argv[1:]):
    T = np.eye(3) + mu * (np.ones((3, 3)) - np.eye(3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = replay(cam, GyroStream(imu.t, imu.omega @ T.T, "gyro"), OnlineCalibrator(), reference=ref)
    s = rows.attrs["summary"]
    r = rows[rows["ready"].astype(bool)]
    print(f"mu {mu}: ready {s['ready']} at {s['ready_at_s']}, err {rows['error_deg'].iloc[-1]:.3f} radius "
          f"{s['radius_deg']:.3f}; rows {len(rows)} ready {len(r)} ready&err>floor {(r['error_deg'] > FLOOR).sum()} "
          f"ready&err>radius {(r['error_deg'] > r['radius_deg']).sum()}; reasons "
          f"{[(x['check'], x['level']) for x in s['verdict']['reasons']]}; mis {s.get('gyro_misalignment')} "
          f"ci {s.get('gyro_misalignment_ci95')} R0 deg {s.get('gyro_misalignment_R0_deg')} joint "
          f"{s.get('gyro_bias_R0_deg')}", flush=True)
