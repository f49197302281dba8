"""The real recordings (notebook 07's TUM-VI and EuRoC): verdict, clock profile choice and jumps with this branch."""
import warnings
import numpy as np
from replication.core.so3 import angle_between_deg
from replication.rig import realdata
from replication.rig.calibration import calibrate
warnings.simplefilter("ignore")
D = "/work/shared/data/real/"
T = D + "tumvi_room1_orbslam3mono/"
E = D + "euroc_mh01_orbslam3/"
runs = [("TUM-VI", realdata.load_tum_trajectory(T + "orbslam3_mono_cam0_traj.txt"), realdata.load_euroc_imu(T + "imu0_data.csv")),
        ("EuRoC", realdata.load_tum_trajectory(E + "orbslam3_mono_cam0_traj_runA.txt"),
         realdata.load_tum_trajectory(E + "gt_body_MH_01_easy_tum.txt"))]
for name, cam, sen in runs:
    r = calibrate(cam, sen, n_bootstrap=30)
    p = r.segments["clock_profile"]
    print(name, r.verdict.level, [x.check for x in r.verdict.reasons], "choice", None if p is None else p["choice"],
          None if p is None else {k: round(v, 1) for k, v in p["chi2"].items()}, None if p is None else round(p["ratio_drift"], 1),
          "jumps", r.segments["clock_jumps"], flush=True)
