"""Notebook 07's usual mistakes (replication.study.real_study.usual_mistakes) on TUM-VI room1:
verdict, reasons, angle to the reference, the camera jumps found. PYTHONPATH: the code to measure."""
import warnings

from replication.core.so3 import angle_between_deg
from replication.rig import realdata as rd
from replication.study.real_study import usual_mistakes

tum = rd.data_root() / "tumvi_room1_orbslam3mono"
ref = rd.load_reference(tum / "camchain.yaml")
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    out = usual_mistakes(rd.load_tum_trajectory(tum / "orbslam3_mono_cam0_traj.txt"),
                         rd.load_euroc_imu(tum / "imu0_data.csv"), ref, seed=7000, n_bootstrap=0)
for name, r in out.items():
    seg = r.segments or {}
    print(f"{name}: {r.verdict.level} {[(x.check, x.level) for x in r.verdict.reasons]} "
          f"err {float(angle_between_deg(r.R, ref)):.4f} jumps {len(seg.get('camera_jumps') or [])} "
          f"bias {seg.get('bias_change') is not None}", flush=True)
