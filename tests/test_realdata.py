"""Loaders, calibrate() and the calibrate CLI; the shared real recordings are used where present."""
import json
import subprocess
import sys

import numpy as np
import pytest

from replication import calibrate
from replication.core import so3
from replication.rig import realdata as rd
from replication.rig.poses import calibrate_poses
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro

HAVE_REAL = rd.real_data_available()
needs_real = pytest.mark.skipif(not HAVE_REAL, reason="real recordings absent: run 'python -m replication "
                                "fetch-data DEST' and set REPLICATION_REAL_DATA=DEST (or provide ../shared/data/real)")

TUM_LINES = [
    "# t tx ty tz qx qy qz qw",
    "1520530313249735680.0 0 0 0 0 0 0 1",
    "1520530313299737600.0 0 0 0 0.0087265 0 0 0.9999619",
    "1520530313349738752.0 0 0 0 0.0174524 0 0 0.9998477",
]


def write(tmp_path, name, lines):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n")
    return path


def test_tum_trajectory_reads_nanoseconds_and_world_from_body(tmp_path):
    s = rd.load_tum_trajectory(write(tmp_path, "t.txt", TUM_LINES))
    np.testing.assert_allclose(np.diff(s.t), [0.050002, 0.050001], atol=1e-6)
    np.testing.assert_allclose(so3.rotation_angle_deg(s.R), [0, 1, 2], atol=1e-4)


@pytest.mark.parametrize("line, message", [
    ("1520530313399738752.0 0 0 0 0 0 1", r"line 5: expected 8 columns"),
    ("1520530313399738752.0 0 0 0 0 0 x 1", r"line 5, column 7 \('qz'\): not a number: 'x'"),
    ("1520530313399738752.0 0 0 0 0 0 nan 1", r"line 5, column 7 \('qz'\): NaN or inf"),
    ("1520530313299737600.0 0 0 0 0 0 0 1", r"line 5, column 1 \('t'\): timestamp not after"),
    ("1520530313399738752.0 0 0 0 0 0 0 2", r"line 5: quaternion norm 2 is not 1"),
])
def test_malformed_trajectory_lines_are_named(tmp_path, line, message):
    path = write(tmp_path, "bad.txt", TUM_LINES + [line])
    with pytest.raises(ValueError, match=rf"bad.txt, {message}"):
        rd.load_tum_trajectory(path)


def test_repeated_lines_are_dropped_only_on_request(tmp_path):
    path = write(tmp_path, "rep.txt", TUM_LINES + [TUM_LINES[-1]])
    with pytest.raises(ValueError, match="timestamp not after"):
        rd.load_tum_trajectory(path)
    assert len(rd.load_tum_trajectory(path, drop_repeated=True).t) == 3


def test_imu_in_degrees_per_second_is_refused(tmp_path):
    lines = ["#timestamp [ns],wx,wy,wz,ax,ay,az", "1000,0.1,0.2,0.3,0,0,9.8", "6000,57.3,0,0,0,0,9.8"]
    with pytest.raises(ValueError, match=r"imu.csv, line 3: angular rate 57.3 rad/s exceeds .* deg/s"):
        rd.load_euroc_imu(write(tmp_path, "imu.csv", lines))


def test_missing_files_and_entries(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        rd.load_euroc_mocap(tmp_path / "none.csv")
    with pytest.raises(ValueError, match=r"no camera .cam0. in this kalibr file; it has cam1"):
        rd.load_reference(write(tmp_path, "c.yaml", ["cam1:", "  T_cam_imu: []"]))
    with pytest.raises(ValueError, match=r"header says 3 poses \(need 48 numbers\), found 16"):
        rd.load_tabb_poses(write(tmp_path, "robot.txt", ["3"] + ["1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"]))
    with pytest.raises(FileNotFoundError, match="REPLICATION_REAL_DATA"):
        rd.data_root(tmp_path / "nowhere")


def test_cumulative_product_matches_a_loop(rng):
    R = so3.random_rotations(rng, 37)
    expected, P = [], np.eye(3)
    for r in R:
        P = P @ r
        expected.append(P)
    np.testing.assert_allclose(so3.cumulative_product(R), expected, atol=1e-13)


def test_integrate_gyro_constant_rate():
    t = np.linspace(0.0, 1.0, 201)
    g = GyroStream(t, np.tile([0.0, 0.0, 0.5], (201, 1)))
    Q = integrate_gyro(g).R
    np.testing.assert_allclose(so3.rotation_angle_deg(Q[-1]), np.degrees(0.5), atol=1e-9)
    np.testing.assert_allclose(Q[-1][:2, :2], [[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]], atol=1e-12)


def _synthetic_rig(offset, rng):
    """Camera at 20 Hz and a 200 Hz gyro whose clock reads ``true time + offset``; R0 random."""
    R0 = so3.random_rotations(rng, ())
    fine = np.arange(0.0, 60.0, 1e-3)
    freqs, phases = rng.uniform(0.1, 0.7, (3, 3)), rng.uniform(0, 2 * np.pi, (3, 3))
    w_cam = sum(np.sin(2 * np.pi * freqs[k] * fine[:, None] + phases[k]) for k in range(3))  # rad/s, body frame
    Qc = integrate_gyro(GyroStream(fine, w_cam)).R
    cam_idx = np.arange(0, len(fine), 50)
    camera = OrientationStream(fine[cam_idx], Qc[cam_idx])
    imu_idx = np.arange(0, len(fine), 5)
    gyro = GyroStream(fine[imu_idx] + offset, w_cam[imu_idx] @ R0)  # omega_sensor = R0^T omega_camera
    return R0, camera, gyro


def test_calibrate_recovers_R0_and_the_clock_offset(rng):
    R0, camera, gyro = _synthetic_rig(0.030, rng)
    res = calibrate(camera, gyro, method="chordal_optimal", reference=R0, n_bootstrap=20)
    assert abs(res.time_offset_s - 0.030) <= 1e-3
    assert res.reference_error_deg < 0.02
    uncorrected = calibrate(camera, gyro, correct_offset=False, reference=R0, n_bootstrap=0)
    assert uncorrected.reference_error_deg > 5 * res.reference_error_deg
    report = res.to_dict()
    json.dumps(report)
    assert report["euler_zyx_deg"].keys() == {"yaw", "pitch", "roll"}
    np.testing.assert_allclose(so3.matrix_from_quaternion(res.quaternion_wxyz), res.R, atol=1e-12)


def test_calibrate_poses_recovers_R0(rng):
    R0 = so3.random_rotations(rng, ())
    S = so3.random_rotations(rng, 15)  # sensor_from_world
    C = R0 @ S  # camera_from_world = camera_from_sensor sensor_from_world
    res = calibrate_poses(C, S, reference=R0, n_bootstrap=0)
    assert res.reference_error_deg < 1e-10 and res.n_pairs == 105  # noise-free: measured 5e-14


@needs_real
@pytest.mark.parametrize("method", ["two_step_left", "two_step_right", "chordal_optimal"])
def test_tumvi_raw_gyro_within_0_2_deg_of_kalibr(method):
    d = rd.data_root() / "tumvi_room1_orbslam3mono"
    res = calibrate(rd.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt"), rd.load_euroc_imu(d / "imu0_data.csv"),
                    method=method, reference=rd.load_reference(d / "camchain.yaml"), n_bootstrap=20)
    assert res.reference_error_deg < 0.2
    assert abs(res.time_offset_s) < 0.005


@needs_real
def test_reference_loaders_match_the_published_numbers():
    root = rd.data_root()
    euroc = rd.load_reference(root / "euroc_mh01_orbslam3" / "euroc_cam0_sensor.yaml")
    np.testing.assert_allclose(euroc[0], [0.0148655429818, 0.999557249008, -0.0257744366974], atol=1e-12)  # R_BS^T
    tabb = rd.load_reference(root / "tabb_rwhe_ds1" / "transformations.txt")
    np.testing.assert_allclose(tabb[0], [0.997365, -0.0725279, 0.00171889], atol=1e-5)
    assert len(rd.load_tabb_camera_poses(root / "tabb_rwhe_ds1" / "cali.txt")) == 88


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "replication", "calibrate", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@needs_real
def test_cli_round_trip_on_the_shared_files(tmp_path):
    d = rd.data_root() / "tumvi_room1_orbslam3mono"
    out = _cli("--camera", d / "orbslam3_mono_cam0_traj.txt", "--sensor", d / "imu0_data.csv", "--sensor-kind",
               "gyro", "--method", "two_step_left", "--bootstrap", "20", "--reference", d / "camchain.yaml",
               "--out", tmp_path / "report.json")
    assert out.returncode == 0, out.stderr
    assert "angle to the reference" in out.stdout
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["method"] == "two_step_left" and report["reference_error_deg"] < 0.2
    R = np.array(report["R0_camera_from_sensor"])
    assert so3.angle_between_deg(R, rd.load_reference(d / "camchain.yaml")) < 0.2


def test_cli_rejects_a_malformed_file_and_writes_nothing(tmp_path):
    cam = write(tmp_path, "cam.txt", TUM_LINES + ["1520530313399738752.0 0 0 0 0 0 0"])
    out = _cli("--camera", cam, "--sensor", cam, "--out", tmp_path / "report.json")
    assert out.returncode == 2
    assert "cam.txt, line 5: expected 8 columns" in out.stderr
    assert not (tmp_path / "report.json").exists()


def test_cli_help_explains_the_formats():
    out = _cli("--help")
    assert out.returncode == 0 and "t tx ty tz qx qy qz qw" in out.stdout and "T_cam_imu" in out.stdout
