"""Notebook 07's stream recordings through calibrate (seed 7000, no bootstrap): verdict, reasons,
angle to the reference, the camera jumps and the bias change found. Run with PYTHONPATH set to the
code to measure (this branch, or the base commit exported to /tmp/segcause_base)."""
import warnings

from replication import calibrate
from replication.core.so3 import angle_between_deg
from replication.rig import realdata as rd

ROOT = rd.data_root()
tum, euroc = ROOT / "tumvi_room1_orbslam3mono", ROOT / "euroc_mh01_orbslam3"
tum_cam = rd.load_tum_trajectory(tum / "orbslam3_mono_cam0_traj.txt")
euroc_gt = rd.load_tum_trajectory(euroc / "gt_body_MH_01_easy_tum.txt")
ref = {"t": rd.load_reference(tum / "camchain.yaml"), "e": rd.load_reference(euroc / "euroc_cam0_sensor.yaml")}
runs = {run: rd.load_tum_trajectory(euroc / f"orbslam3_{run}.txt", drop_repeated=True)
        for run in ("mono_cam0_traj_runA", "mono_cam0_traj_runB", "stereo_rectleft_traj_runA")}
STREAMS = {"tum gyro": (tum_cam, rd.load_euroc_imu(tum / "imu0_data.csv"), "t"),
           "tum mocap": (tum_cam, rd.load_euroc_mocap(tum / "mocap0_data.csv"), "t"),
           **{f"euroc {k}": (v, euroc_gt, "e") for k, v in runs.items()}}
for name, (cam, sen, r) in STREAMS.items():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = calibrate(cam, sen, reference=ref[r], n_bootstrap=0, seed=7000)
    seg = res.segments or {}
    print(f"{name}: {res.verdict.level} {[(x.check, x.level) for x in res.verdict.reasons]} "
          f"R {res.R.round(6).tolist()} ref_err {float(angle_between_deg(res.R, ref[r])):.4f} "
          f"jumps {seg.get('camera_jumps')} bias_change {seg.get('bias_change')}", flush=True)
