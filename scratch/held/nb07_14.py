import warnings, json
import pandas as pd
from replication.rig import realdata as rd
from replication.study.real_study import usual_mistakes, verdict_table
d = rd.data_root() / "tumvi_room1_orbslam3mono"
cam, gyro = rd.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt"), rd.load_euroc_imu(d / "imu0_data.csv")
ref = rd.load_reference(d / "camchain.yaml")
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    t = verdict_table(usual_mistakes(cam, gyro, ref, seed=0))
pd.set_option("display.width", 250); pd.set_option("display.max_colwidth", 120)
[print(i, "|", r.verdict, "|", r.checks) for i, r in t.iterrows()]
