"""Static pose sets (``replication/rig/poses.py``): ``calibrate_poses`` recovers a known R0 from
noise-free stations."""
from replication.core import so3
from replication.rig.poses import calibrate_poses


def test_calibrate_poses_recovers_R0(rng):
    R0 = so3.random_rotations(rng, ())
    S = so3.random_rotations(rng, 15)  # sensor_from_world
    C = R0 @ S  # camera_from_world = camera_from_sensor sensor_from_world
    res = calibrate_poses(C, S, reference=R0, n_bootstrap=0)
    assert res.reference_error_deg < 1e-10 and res.n_pairs == 105  # noise-free: measured 5e-14
