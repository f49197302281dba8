"""Loaders, calibrate() and the calibrate CLI; the shared real recordings are used where present."""
import json
import re
import subprocess
import sys

import numpy as np
import pytest

from replication import calibrate
from replication.cli import main
from replication.core import so3
from replication.rig import realdata as rd
from replication.rig.datafile import MEAN_MAX_DEG, ColumnCountError, DataFileError, read_table
from replication.rig.live import LiveRig
from replication.rig.online import OnlineCalibrator
from replication.rig.poses import calibrate_poses
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import rig_motion

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


IMU_NS = ["#timestamp [ns],wx,wy,wz,ax,ay,az", "1520530308181901469,0.1,0.2,0.3,0,0,9.8",
          "1520530308186917469,0.1,0.2,0.3,0,0,9.8", "1520530308191933469,0.1,0.2,0.3,0,0,9.8"]


@pytest.mark.parametrize("unit, digits", [("s", 9), ("ms", 6), ("us", 3)])
def test_a_csv_in_another_unit_is_read_with_its_unit(tmp_path, unit, digits):
    """A gyro CSV written in seconds (float stamps) or ms / us reads as the ns file does, given its
    unit (the option the refusal names)."""
    t_ns = [int(line.split(",")[0]) for line in IMU_NS[1:]]
    lines = [IMU_NS[0]] + [f"{t // 10**digits}.{t % 10**digits:0{digits}d}," + line.split(",", 1)[1]
                           for t, line in zip(t_ns, IMU_NS[1:])]
    path = write(tmp_path, "imu.csv", lines)
    ns = rd.load_stream(write(tmp_path, "ns.csv", IMU_NS), "gyro")
    for read in (rd.load_stream(path, "gyro", time_unit=unit), rd.load_euroc_imu(path, time_unit=unit)):
        np.testing.assert_allclose(read.t, ns.t, rtol=0, atol=1e-6)
    with pytest.raises(ValueError, match=r"imu.csv, line 2, column 1: the time stamp [^ ]* has a fraction: not "
                                         r"nanoseconds.*--sensor-time-unit s\) reads it"):
        rd.load_stream(path, "gyro")


def test_a_csv_stamp_with_a_fraction_is_refused_as_ns_and_an_integral_one_is_not(tmp_path):
    """The fraction rule at its boundary: ``...469.0`` is a count of ns, ``...469.5`` is not."""
    whole = [IMU_NS[0]] + [line.replace(",", ".0,", 1) for line in IMU_NS[1:]]
    assert len(rd.load_stream(write(tmp_path, "whole.csv", whole), "gyro", time_unit="ns").t) == 3
    half = [IMU_NS[0], "1000.0,0,0,0,0,0,9.8", "6000.5,0,0,0,0,0,9.8"]
    with pytest.raises(ValueError, match="half.csv, line 3, column 1: the time stamp [^ ]* has a fraction"):
        rd.load_stream(write(tmp_path, "half.csv", half), "gyro")
    mocap = write(tmp_path, "gt.csv", ["1.5,0,0,0,1,0,0,0", "1.55,0,0,0,1,0,0,0"])
    with pytest.raises(ValueError, match="gt.csv, line 1, column 1: the time stamp [^ ]* has a fraction"):
        rd.load_stream(mocap, "orientation")
    np.testing.assert_allclose(rd.load_stream(mocap, "orientation", time_unit="s").t, [1.5, 1.55])


def test_an_unknown_time_unit_is_refused_for_any_file(tmp_path):
    with pytest.raises(ValueError, match=r"time_unit must be one of .* got 'min'"):
        rd.load_stream(write(tmp_path, "ns.csv", IMU_NS), "gyro", time_unit="min")


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

# --------------------------------------------------------------------------------------------------
# Dataset files as shipped: EuRoC's 17-column ground truth, time stamps repeated with another pose
# (refused naming the option that reads them, or kept first / last / averaged and counted), messages
# with plain numbers (never numpy's ``np.float64(...)``).


#: EuRoC's state_groundtruth_estimate0/data.csv header, as shipped.
GT_HEADER = ("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
             "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
             "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]")
MOCAP_HEADER = "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"
#: numpy's reprs: never in a message
NUMPY_REPR = re.compile(r"np\.(float|int|bool|str)|array\(")


def _rotations(n, step_deg=1.0):
    return so3.matrix_from_rotation_vector(np.radians(step_deg) * np.outer(np.arange(n), [0.3, -0.5, 0.8]))


def _gt_rows(n=6, columns=17, t0=1403636580838555648, step=5_000_000):
    q = so3.quaternion_from_matrix(_rotations(n))
    rows = []
    for k in range(n):
        extra = [0.1 * k, -0.2, 0.8, -0.003172, 0.021267, 0.078502, -0.025266, 0.136696, 0.075593][:columns - 8]
        rows.append([t0 + k * step, 4.6 + 0.01 * k, -1.7, 0.7, *q[k], *extra])
    return rows


def _line(row):
    return ",".join(str(int(v)) if i == 0 else f"{v:.9f}" for i, v in enumerate(row))


def _write(path, header, rows):
    path.write_text("\n".join([header] + [r if isinstance(r, str) else _line(r) for r in rows]) + "\n")
    return path


def test_euroc_ground_truth_17_columns_is_read_as_shipped_and_equals_its_first_8(tmp_path):
    rows = _gt_rows()
    full = rd.load_euroc_mocap(_write(tmp_path / "data.csv", GT_HEADER, rows))
    eight = rd.load_euroc_mocap(_write(tmp_path / "mocap.csv", MOCAP_HEADER, [r[:8] for r in rows]))
    np.testing.assert_array_equal(full.t, eight.t)
    np.testing.assert_allclose(full.R, eight.R, atol=1e-12)
    np.testing.assert_allclose(full.R, _rotations(6), atol=1e-8)
    assert rd.load_stream(tmp_path / "data.csv").t.size == 6  # the CLI's router: a .csv orientation file


@pytest.mark.parametrize("columns, expected", [(9, "8 or 17"), (16, "8 or 17"), (18, "8 or 17"), (7, "8 or 17")])
def test_other_column_counts_are_refused_naming_both_accepted(tmp_path, columns, expected):
    rows = [r + [0.0] * max(0, columns - 17) for r in _gt_rows(columns=min(columns, 17))]
    rows = [r[:columns] for r in rows]
    with pytest.raises(ColumnCountError, match=rf"line 2: expected {expected} columns \(t\[ns\], p_xyz, q_wxyz"):
        rd.load_euroc_mocap(_write(tmp_path / "x.csv", GT_HEADER, rows))


@pytest.mark.parametrize("first, then", [(17, 8), (8, 17)])
def test_a_file_keeps_one_column_count(tmp_path, first, then):
    rows = _gt_rows()
    mixed = [r[:first] for r in rows[:3]] + [r[:then] for r in rows[3:]]
    with pytest.raises(ColumnCountError, match=rf"line 5: expected {first} columns .*got {then}"):
        rd.load_euroc_mocap(_write(tmp_path / "m.csv", GT_HEADER, mixed))


def test_a_gyro_file_is_not_read_as_ground_truth_nor_the_reverse(tmp_path):
    path = _write(tmp_path / "data.csv", GT_HEADER, _gt_rows())
    with pytest.raises(ColumnCountError, match=r"expected 7 columns .*got 17"):
        rd.load_euroc_imu(path)


def _repeated(tmp_path, angle_deg, *, verbatim=False, name="rep.csv"):
    """A 17-column file whose 4th line repeats the 3rd's time stamp with a pose turned by
    ``angle_deg``."""
    rows = _gt_rows()
    twin = list(rows[2])
    if not verbatim:
        R = so3.matrix_from_rotation_vector(np.radians(angle_deg) * np.array([0.0, 0.0, 1.0])) @ _rotations(6)[2]
        twin[4:8] = so3.quaternion_from_matrix(R)
    return _write(tmp_path / name, GT_HEADER, rows[:3] + [twin] + rows[3:]), rows


def test_a_repeated_time_stamp_with_another_pose_is_refused_naming_the_option(tmp_path):
    path, _ = _repeated(tmp_path, 2.0)
    with pytest.raises(DataFileError) as err:
        rd.load_euroc_mocap(path)
    text = str(err.value)
    assert err.value.line == 5 and "repeated with a different pose, 2 deg away" in text
    assert "repeated='keep-first', 'keep-last' or 'mean'" in text and "--repeated" in text
    assert "1403636580848555648 = 1403636580848555648" in text and not NUMPY_REPR.search(text)  # the file's digits


def test_a_verbatim_repeat_is_refused_naming_drop_repeated_and_dropped_on_request(tmp_path):
    path, rows = _repeated(tmp_path, 0.0, verbatim=True)
    with pytest.raises(DataFileError, match=r"repeats the previous one exactly; drop_repeated=True"):
        rd.load_euroc_mocap(path)
    tally = {}
    s = rd.load_euroc_mocap(path, drop_repeated=True, tally=tally)
    assert s.t.size == 6 and tally["verbatim_repeats"] == 1 and tally["repeated_timestamps"] == 0


@pytest.mark.parametrize("policy", ["keep-first", "keep-last", "mean"])
def test_repeats_read_by_the_policy_asked_and_counted(tmp_path, policy):
    path, _ = _repeated(tmp_path, 2.0)
    tally = {}
    s = rd.load_euroc_mocap(path, repeated=policy, tally=tally)
    assert s.t.size == 6 and np.all(np.diff(s.t) > 0)
    assert tally["repeated_timestamps"] == 1 and tally["repeated_groups"] == 1
    assert tally["repeated_max_deg"] == pytest.approx(2.0, abs=1e-5)
    expected = {"keep-first": 0.0, "keep-last": 2.0, "mean": 1.0}[policy]
    assert so3.angle_between_deg(s.R[2], _rotations(6)[2]) == pytest.approx(expected, abs=1e-5)
    others = np.delete(np.arange(6), 2)
    np.testing.assert_allclose(s.R[others], _rotations(6)[others], atol=1e-8)


def test_mean_of_a_group_takes_quaternion_signs_into_account(tmp_path):
    """q and -q are one rotation: the mean of a pose and its sign-flipped copy is that pose, not a
    zero vector."""
    rows = _gt_rows()
    twin = list(rows[2])
    twin[4:8] = [-v for v in twin[4:8]]
    path = _write(tmp_path / "s.csv", GT_HEADER, rows[:3] + [twin] + rows[3:])
    s = rd.load_euroc_mocap(path, repeated="mean")
    assert so3.angle_between_deg(s.R[2], _rotations(6)[2]) < 1e-6


def test_tum_trajectory_and_imu_take_the_same_policies(tmp_path):
    lines = ["1.0 0 0 0 0 0 0 1", "1.1 0 0 0 0 0 0.0087265 0.9999619", "1.1 0 0 0 0 0 0.0174524 0.9998477",
             "1.2 0 0 0 0 0 0.0261769 0.9996573"]
    path = tmp_path / "t.txt"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFileError, match=r"line 3.*repeated with a different pose, 1 deg away"):
        rd.load_tum_trajectory(path)
    s = rd.load_tum_trajectory(path, repeated="keep-last")
    assert so3.rotation_angle_deg(s.R[1]) == pytest.approx(2.0, abs=1e-4)
    imu = tmp_path / "imu.csv"
    imu.write_text("#t,w,w,w,a,a,a\n1000,0.1,0,0,0,0,9.8\n1000,0.3,0,0,0,0,9.8\n2000,0.2,0,0,0,0,9.8\n")
    with pytest.raises(DataFileError, match=r"repeated with a different pose; repeated='keep-first'"):
        rd.load_euroc_imu(imu)
    assert rd.load_euroc_imu(imu, repeated="mean").omega[0, 0] == pytest.approx(0.2)


def test_unknown_policy_is_refused():
    with pytest.raises(ValueError, match=r"repeated must be one of 'refuse', 'keep-first'.*got 'first'"):
        read_table("any.txt", ("t", "x"), repeated="first")


def test_going_back_in_time_is_not_a_repeat_and_says_so_with_plain_numbers(tmp_path):
    rows = _gt_rows()
    rows[3][0] = rows[1][0]
    with pytest.raises(DataFileError) as err:
        rd.load_euroc_mocap(_write(tmp_path / "b.csv", GT_HEADER, rows), repeated="mean")
    assert "go back in time" in str(err.value) and not NUMPY_REPR.search(str(err.value))


def _cli_files(tmp_path, angle_deg):
    """A camera TUM trajectory and a 17-column ground truth of the same rig, the latter with one
    time stamp repeated with a pose ``angle_deg`` away."""
    t = 1403636580.0 + np.arange(0.0, 40.0, 0.05)
    R = rig_motion(t)  # the synthetic rig's motion
    q = so3.quaternion_from_matrix(R)
    cam = tmp_path / "cam.txt"
    np.savetxt(cam, np.column_stack([t, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    Q = R @ so3.matrix_from_rotation_vector(np.array([0.3, -0.2, 0.5]))  # world_from_sensor
    rows = [[int(round(tk * 1e9)), 0.0, 0.0, 0.0, *qk, *([0.0] * 9)] for tk, qk in zip(t,
                                                                                       so3.quaternion_from_matrix(Q))]
    twin = list(rows[100])
    twin[4:8] = so3.quaternion_from_matrix(so3.matrix_from_rotation_vector(np.radians([0.0, 0.0, angle_deg])) @ Q[100])
    gt = _write(tmp_path / "data.csv", GT_HEADER, rows[:101] + [twin] + rows[101:])
    return cam, gt


def test_cli_refuses_repeats_naming_repeated_and_counts_them_when_read(tmp_path, capsys):
    cam, gt = _cli_files(tmp_path, 3.0)
    base = ["calibrate", "--camera", str(cam), "--sensor", str(gt), "--bootstrap", "10", "--quiet"]
    assert main(base) == 2
    err = capsys.readouterr().err
    assert "data.csv, line 103" in err and "--repeated keep-first|keep-last|mean" in err
    out = tmp_path / "r.json"
    assert main(base + ["--repeated", "keep-first", "--out", str(out)]) == 0
    assert "--sensor: 1 lines repeat an earlier line's time stamp (1 time stamps, poses up to 3 deg apart)" in (
        capsys.readouterr().out)
    cli = json.loads(out.read_text())["cli"]
    assert cli["repeated"] == "keep-first"
    assert cli["repeats"]["sensor"]["repeated_timestamps"] == 1
    assert cli["repeats"]["sensor"]["repeated_max_deg"] == pytest.approx(3.0, abs=1e-4)
    assert cli["repeats"]["camera"]["repeated_timestamps"] == 0


def test_cli_names_a_ground_truth_given_as_gyro(tmp_path, capsys):
    cam, gt = _cli_files(tmp_path, 0.0)
    assert main(["calibrate", "--camera", str(cam), "--sensor", str(gt), "--sensor-kind", "gyro", "--quiet"]) == 2
    assert "looks like an orientation stream" in capsys.readouterr().err


def test_refusals_of_time_stamps_carry_no_numpy_reprs():
    """Streams and the live front end refuse time going back; the numbers in their messages are
    plain."""
    t = np.array([0.0, 0.5, 0.5, 1.0])
    messages = []
    for build in (lambda: OrientationStream(t, np.tile(np.eye(3), (4, 1, 1)), "s"),
                  lambda: GyroStream(t, np.zeros((4, 3)), "g")):
        with pytest.raises(ValueError) as err:
            build()
        messages.append(str(err.value))
    live = LiveRig(OnlineCalibrator(), interval=1.0)
    live.add_camera(np.float64(1.0), np.eye(3))
    with pytest.raises(ValueError) as err:
        live.add_camera(np.float64(0.5), np.eye(3))
    messages.append(str(err.value))
    live.add_orientation(np.float64(1.0), np.eye(3))
    with pytest.raises(ValueError) as err:
        live.add_orientation(np.float64(1.0), np.eye(3))
    messages.append(str(err.value))
    with pytest.raises(ValueError) as err:
        live.add_gyro(2.0, np.array([np.nan, 0.0]))
    messages.append(str(err.value))
    assert all(not NUMPY_REPR.search(m) for m in messages), messages
    assert "0.5 after 1.0" in messages[2] and "1.0 after 1.0" in messages[3]


def _rig_streams():
    t = np.arange(0.0, 20.0, 0.05)
    R = so3.matrix_from_rotation_vector(np.stack([np.sin(t), np.cos(0.7 * t), 0.3 * t], axis=-1))
    return OrientationStream(t, R, "c"), OrientationStream(t, R @ so3.matrix_from_rotation_vector(np.array([0.1, 0.2,
                                                                                                            0.3])), "s")


def test_parameter_refusals_show_numpy_scalars_as_plain_numbers():
    """Parameters given as NumPy scalars (read from an array, a config parsed by NumPy): the refusal
    shows the number (``-1.0``), never ``np.float64(-1.0)``."""
    from replication.core.checks import check_number, check_range
    from replication.rig.calibration import calibrate
    from replication.rig.poses import calibrate_poses
    from replication.study.vins_rule import VinsExRotation

    cam, sen = _rig_streams()
    cases = [
        (lambda: check_number("x", np.float64(-1), minimum=0), "x must be > 0, got -1.0"),
        (lambda: check_number("x", np.float64(1.5), integer=True), "got 1.5"),
        (lambda: check_range("x", np.float64(2.0), low=0.0, high=1.0), "got 2.0"),
        (lambda: calibrate(cam, sen, interval=np.float64(-1)), "interval must be > 0, got -1.0"),
        (lambda: calibrate(cam, sen, n_bootstrap=np.int64(-1)), "n_bootstrap must be >= 0, got -1"),
        (lambda: calibrate_poses(cam.R[:8], sen.R[:8], pairs=np.str_("x")), "got 'x'"),
        (lambda: LiveRig(OnlineCalibrator(), max_offset=0.3, offset_window=np.float64(1.5)), "got 1.5"),
        (lambda: VinsExRotation(huber_deg=np.float64(0.0)), "got 0.0"),
    ]
    for build, phrase in cases:
        with pytest.raises(ValueError) as err:
            build()
        assert phrase in str(err.value) and not NUMPY_REPR.search(str(err.value)), str(err.value)


def test_a_sign_flipped_quaternion_under_one_stamp_is_the_same_pose_and_dropped_on_request(tmp_path):
    rows = _gt_rows()
    twin = list(rows[2])
    twin[4:8] = [-v for v in twin[4:8]]
    path = _write(tmp_path / "flip.csv", GT_HEADER, rows[:3] + [twin] + rows[3:])
    with pytest.raises(DataFileError, match=r"repeats the previous one with its quaternion's sign flipped"):
        rd.load_euroc_mocap(path)
    tally = {}
    s = rd.load_euroc_mocap(path, drop_repeated=True, tally=tally)
    assert s.t.size == 6 and tally["verbatim_repeats"] == 1


@pytest.mark.parametrize("angle, refused", [(MEAN_MAX_DEG - 1, False), (MEAN_MAX_DEG + 1, True),
                                            (180.0, True)])
def test_the_mean_of_poses_far_apart_is_refused_naming_the_other_policies(tmp_path, angle, refused):
    path, _ = _repeated(tmp_path, angle)
    if refused:
        with pytest.raises(DataFileError, match=r"deg apart .*their mean is no pose; repeated='keep-first' or"):
            rd.load_euroc_mocap(path, repeated="mean")
    else:
        s = rd.load_euroc_mocap(path, repeated="mean")
        assert so3.angle_between_deg(s.R[2], _rotations(6)[2]) == pytest.approx(angle / 2, abs=1e-5)
    assert rd.load_euroc_mocap(path, repeated="keep-first").t.size == 6
