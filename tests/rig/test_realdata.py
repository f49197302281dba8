"""The loaders of real recordings and references (``replication/rig/realdata.py``): formats,
malformed lines named, dataset files as shipped (EuRoC's 17 columns, repeated time stamps by
policy), ORB-SLAM3's stereo settings, a missing data folder naming ``fetch-data``; the shared real
recordings are used where present (``needs_real``, which the command's
end-to-end tests in tests/cli/test_calibrate.py import with the files below)."""
import numpy as np
import pytest

from conftest import GT_HEADER, NUMPY_REPR, TUM_LINES, _write, needs_real, write
from replication.core import so3
from replication.rig import realdata as rd
from replication.rig.datafile import MEAN_MAX_DEG, ColumnCountError, DataFileError


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


@needs_real
def test_reference_loaders_match_the_published_numbers():
    root = rd.data_root()
    euroc = rd.load_reference(root / "euroc_mh01_orbslam3" / "euroc_cam0_sensor.yaml")
    np.testing.assert_allclose(euroc[0], [0.0148655429818, 0.999557249008, -0.0257744366974], atol=1e-12)  # R_BS^T
    tabb = rd.load_reference(root / "tabb_rwhe_ds1" / "transformations.txt")
    np.testing.assert_allclose(tabb[0], [0.997365, -0.0725279, 0.00171889], atol=1e-5)
    assert len(rd.load_tabb_camera_poses(root / "tabb_rwhe_ds1" / "cali.txt")) == 88


# --------------------------------------------------------------------------------------------------
# Dataset files as shipped: EuRoC's 17-column ground truth, time stamps repeated with another pose
# (refused naming the option that reads them, or kept first / last / averaged and counted), messages
# with plain numbers (never numpy's ``np.float64(...)``).


MOCAP_HEADER = "#timestamp [ns], p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []"


def _rotations(n, step_deg=1.0):
    return so3.matrix_from_rotation_vector(np.radians(step_deg) * np.outer(np.arange(n), [0.3, -0.5, 0.8]))


def _gt_rows(n=6, columns=17, t0=1403636580838555648, step=5_000_000):
    q = so3.quaternion_from_matrix(_rotations(n))
    rows = []
    for k in range(n):
        extra = [0.1 * k, -0.2, 0.8, -0.003172, 0.021267, 0.078502, -0.025266, 0.136696, 0.075593][:columns - 8]
        rows.append([t0 + k * step, 4.6 + 0.01 * k, -1.7, 0.7, *q[k], *extra])
    return rows


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


def test_going_back_in_time_is_not_a_repeat_and_says_so_with_plain_numbers(tmp_path):
    rows = _gt_rows()
    rows[3][0] = rows[1][0]
    with pytest.raises(DataFileError) as err:
        rd.load_euroc_mocap(_write(tmp_path / "b.csv", GT_HEADER, rows), repeated="mean")
    assert "go back in time" in str(err.value) and not NUMPY_REPR.search(str(err.value))


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


def test_missing_data_names_the_command(tmp_path):
    with pytest.raises(FileNotFoundError, match="python -m replication fetch-data DEST"):
        rd.data_root(tmp_path / "nowhere")


@needs_real
def test_stereo_rectification_rotation_of_the_euroc_run():
    cfg = rd.load_orbslam3_stereo(rd.data_root() / "euroc_mh01_orbslam3" / "orbslam3_Stereo_EuRoC.yaml")
    from replication.core.so3 import rotation_angle_deg
    assert abs(float(rotation_angle_deg(cfg.rectification_rotation())) - 0.620) < 0.002  # the shared README's


def test_stereo_settings_errors_name_the_entry(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text('%YAML:1.0\nCamera.type: "PinHole"\nCamera1.fx: 1.0\n')
    with pytest.raises(ValueError, match="entry 'Camera1.cx' missing"):
        rd.load_orbslam3_stereo(path)
    path.write_text('%YAML:1.0\nCamera.type: "KannalaBrandt8"\n')
    with pytest.raises(ValueError, match="only 'PinHole'"):
        rd.load_orbslam3_stereo(path)
    with pytest.raises(FileNotFoundError, match="no such file"):
        rd.load_orbslam3_stereo(tmp_path / "none.yaml")
