"""The ``calibrate`` command (``replication/cli/calibrate.py``): its options reach the library."""
import numpy as np
import pytest

from replication.cli import main
from replication.core import so3
from replication.rig import live


@pytest.mark.parametrize("flag, expected", [([], True), (["--no-gyro-bias"], False)])
def test_calibrate_online_passes_the_gyro_bias_switch_to_the_live_rig(tmp_path, monkeypatch, flag, expected):
    seen = {}
    real = live.replay

    def spy(*args, **kwargs):
        seen["gyro_bias"] = kwargs.get("gyro_bias")
        return real(*args, **kwargs)

    monkeypatch.setattr(live, "replay", spy)
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 30.0, 0.05)
    omega = np.column_stack([np.sin(1.3 * t), np.cos(0.7 * t), np.sin(0.9 * t + 1)])
    R = so3.cumulative_product(so3.matrix_from_rotation_vector(omega[:-1] * 0.05))
    R = np.concatenate([np.eye(3)[None], R])
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(R)
    np.savetxt(cam_file, np.column_stack([t + 1e3, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    ts = np.arange(0.0, 30.0, 0.005)
    om = np.column_stack([np.sin(1.3 * ts), np.cos(0.7 * ts), np.sin(0.9 * ts + 1)]) + rng.normal(0, 1e-3, (len(ts), 3))
    np.savetxt(imu_file, np.column_stack([np.round((ts + 1e3) * 1e9), om, np.zeros((len(ts), 3))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro", "--online",
          "--bootstrap", "0", "--quiet", *flag])
    assert seen["gyro_bias"] is expected
