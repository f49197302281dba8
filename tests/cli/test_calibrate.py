"""The ``calibrate`` command (``replication/cli/calibrate.py``): its options reach the library."""
import re

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


def test_a_gyro_csv_in_seconds_is_refused_naming_the_option_that_then_reads_it(tmp_path, capsys):
    """Float-second stamps in an EuRoC-format gyro CSV: refused as ns (exit 2) naming
    ``--sensor-time-unit s``, which reads them to the R0 of the same file in ns."""
    import json

    from replication.rig.streams import GyroStream, OrientationStream
    from replication.testing import rig_streams, write_euroc_imu, write_tum_trajectory

    _, camera, gyro, _ = rig_streams(30.0, rng=np.random.default_rng(5), camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    epoch = 1520530308.0
    write_tum_trajectory(tmp_path / "cam.txt", OrientationStream(camera.t + epoch, camera.R, "c"))
    write_euroc_imu(tmp_path / "ns.csv", GyroStream(gyro.t + epoch, gyro.omega, "g"))
    lines = (tmp_path / "ns.csv").read_text().splitlines()
    seconds = [lines[0]] + [f"{int(t) // 10**9}.{int(t) % 10**9:09d},{rest}"
                            for t, rest in (line.split(",", 1) for line in lines[1:])]
    (tmp_path / "s.csv").write_text("\n".join(seconds) + "\n")

    def run(sensor, *extra):
        return main(["calibrate", "--camera", str(tmp_path / "cam.txt"), "--sensor", str(tmp_path / sensor),
                     "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", "--out", str(tmp_path / f"{sensor}.json"),
                     *extra])

    assert run("s.csv") == 2
    assert re.search(r"the time stamp [0-9.]+ has a fraction: not nanoseconds", capsys.readouterr().err)
    assert run("s.csv", "--sensor-time-unit", "s") == 0 and run("ns.csv") == 0
    R = [np.array(json.loads((tmp_path / f"{name}.json").read_text())["R0_camera_from_sensor"])
         for name in ("s.csv", "ns.csv")]
    assert so3.rotation_angle_deg(R[0].T @ R[1]) < 1e-3
