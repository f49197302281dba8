import warnings
from replication.rig import realdata as rd
from replication.rig.calibration import calibrate
d = rd.data_root() / "tumvi_room1_orbslam3mono"
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    r = calibrate(rd.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt"), rd.load_euroc_imu(d / "imu0_data.csv"),
                  reference=rd.load_reference(d / "camchain.yaml"), n_bootstrap=20)
print(r.verdict.level, round(r.reference_error_deg, 4), [x.check for x in r.verdict.reasons])
sm = r.to_dict()
print({k: sm["sensor_model"].get(k) for k in ("held_terms", "held_R0_deg", "triangular_frame_deg", "misalignment_resolved", "scale_resolved")}, sm["gyro_misalignment"])
print("\n".join(l for l in r.summary().splitlines() if "gyro" in l or "R0's" in l))
