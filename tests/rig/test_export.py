"""Export into the ecosystem's files (:mod:`replication.rig.export`,
:mod:`replication.rig.vioformats`) and those files as references.

Round trips against the real files of both rigs (Kalibr camchain, OpenVINS ``%YAML:1.0`` chains,
Basalt's JSON, ORB-SLAM3 settings); only the rotation and the offset change, every other value and
comment stays; ``cv2.FileStorage`` still reads the OpenCV-style files; the offset's sign: a gyro
clock shifted by a known amount gives that amount in each file, under each tool's own name and unit.
"""
import argparse
import difflib
import json
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from conftest import _REFERENCES, BASALT, CAMCHAIN, I16, _angle, needs_real, needs_real_ea
from replication.cli.export import run as export_command
from replication.core import so3
from replication.rig.calibration import calibrate
from replication.rig.datafile import DataFileError
from replication.rig.export import (
    ExportWarning,
    TranslationNotEstimatedWarning,
    export_calibration,
    read_report,
)
from replication.rig.realdata import data_root, load_reference
from replication.rig.vioformats import format_number, read_vio_file
from replication.testing import RIG_R0, rig_streams

R_TRUE = RIG_R0
FILE_FORMATS = ("kalibr", "openvins", "basalt", "orbslam3")


def _rig(offset, seconds=30.0):
    """A 20 Hz camera and a rigid 200 Hz gyro (raw rates) whose clock reads ``offset`` s ahead of
    the camera's."""
    return rig_streams(seconds, offset=offset)[1:3]


def _report(R=R_TRUE, d=0.0123456789, level="ok", kind="GyroStream"):
    return {"R0_camera_from_sensor": np.asarray(R).tolist(), "time_offset_s": d,
            "verdict": {"level": level, "reasons": [] if level == "ok" else [{"level": level, "message": "m"}]},
            "inputs": {"sensor": {"kind": kind, "source": "imu.csv"}}}


_BASES = Path(tempfile.mkdtemp(prefix="export_bases_"))


def _export(report, to, **kw):
    """Export into ``_base``'s file of that tool unless a base is given."""
    if to != "ros2":
        kw.setdefault("base", _base(_BASES, to))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TranslationNotEstimatedWarning)
        return export_calibration(report, to, **kw)


def _written(tmp_path, export, name):
    path = tmp_path / name
    export.write(path)
    return path


# ------------------------------------------------------------------------------------------------
# numbers and files


@pytest.mark.parametrize("to, needs", [
    ("kalibr", "camera_model, intrinsics, distortion_model, distortion_coeffs, resolution and rostopic"),
    ("openvins", "distortion_model, distortion_coeffs, intrinsics and resolution"),
    ("basalt", "value0.intrinsics, resolution, calib_accel_bias, calib_gyro_bias, imu_update_rate, accel_noise_std, "
               "gyro_noise_std, accel_bias_std, gyro_bias_std and vignette"),
    ("orbslam3", "Camera.type, the camera's intrinsics"),
])
def test_without_a_base_a_file_is_refused_naming_what_the_tools_loader_needs(to, needs):
    """No tool loads a file holding only the extrinsic (Basalt's loader: 10 required fields
    missing): refused, with the fields a base must provide and the way out (--base, or ros2 for the
    rotation alone)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # refused before any warning
        with pytest.raises(ValueError, match=f"--to {to} needs --base: .* loads no file without ") as info:
            export_calibration(_report(level="warning"), to)
    assert needs in str(info.value) and "--to ros2" in str(info.value)


def _base(tmp_path, to):
    """A small base file of each tool, two cameras where the tool has several (identity
    rotations)."""
    path = tmp_path / f"base_{to}.{'json' if to == 'basalt' else 'yaml'}"
    pose = {"px": 0.1, "py": 0.2, "pz": 0.3, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": 1.0}
    path.write_text({"kalibr": KALIBR_BASE, "openvins": "%YAML:1.0\n" + KALIBR_BASE.replace("T_cam_imu", "T_imu_cam"),
                     "basalt": json.dumps({"value0": {"T_imu_cam": [pose, {**pose, "px": -0.1}],
                                                      "cam_time_offset_ns": 0}}, indent=4),
                     "orbslam3": '%YAML:1.0\nFile.version: "1.0"\n' + ORB_MATRIX}[to])
    return path


KALIBR_BASE = """# my rig, calibrated 2026-11-30
cam0:
  T_cam_imu:  # keep this comment
  - [1.0, 0.0, 0.0, 0.1]
  - [0.0, 1.0, 0.0, -0.2]
  - [0.0, 0.0, 1.0, 0.3]
  - [0.0, 0.0, 0.0, 1.0]
  intrinsics: [190.9, 190.9, 254.9, 256.8]
  timeshift_cam_imu: -0.5
cam1:
  T_cam_imu:
  - [1.0, 0.0, 0.0, 0.7]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
"""
ORB_MATRIX = ("IMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n   data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, "
              "0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n")


def test_a_kalibr_base_changes_in_three_rotation_rows_and_the_offset_only(tmp_path):
    base = tmp_path / "camchain.yaml"
    base.write_text(KALIBR_BASE)
    with pytest.warns(ExportWarning, match="one camera only: cam0 is changed and cam1 kept as written, so the "
                                           "rotation between cam0 and each of them moves by 148.7 deg"):
        export = export_calibration(_report(), "kalibr", base=base, whole_rig=False)
    changed = [(a, b) for a, b in zip(KALIBR_BASE.splitlines(), export.text.splitlines()) if a != b]
    assert len(export.text.splitlines()) == len(KALIBR_BASE.splitlines()) and len(changed) == 4
    assert export.changed == ("cam0.T_cam_imu rotation", "cam0.timeshift_cam_imu")
    out = read_vio_file(_written(tmp_path, export, "new.yaml"))
    assert np.abs(out.camera_from_sensor("cam0") - R_TRUE).max() < 1e-12
    assert out.doc["cam0"]["T_cam_imu"][0][3] == 0.1 and out.doc["cam0"]["T_cam_imu"][2][3] == 0.3  # translation
    assert out.doc["cam1"] == read_vio_file(base).doc["cam1"] and "# keep this comment" in export.text
    assert out.time_offset_s("cam0") == pytest.approx(0.012345679, abs=1e-15)
    # cam1 has no offset field: it is added at the camera's indentation, the rest untouched
    with pytest.warns(ExportWarning, match="one camera only: cam1 is changed and cam0 kept"):
        export1 = export_calibration(_report(), "kalibr", base=base, camera="cam1", whole_rig=False)
    assert export1.added == ("cam1.timeshift_cam_imu",) and export1.changed == ("cam1.T_cam_imu rotation",)
    out1 = read_vio_file(_written(tmp_path, export1, "new1.yaml"))
    assert out1.time_offset_s("cam1") == pytest.approx(0.012345679) and out1.time_offset_s("cam0") == -0.5
    assert np.abs(out1.camera_from_sensor("cam0") - np.eye(3)).max() == 0


def test_by_default_the_other_cameras_turn_with_the_one_calibrated(tmp_path):
    """KALIBR_BASE's cameras are both the identity: cam0 set to R_TRUE turns cam1 to R_TRUE too;
    their T_cam_imu translations (the IMU in each camera) stay, and so does every other line."""
    base = tmp_path / "camchain.yaml"
    base.write_text(KALIBR_BASE)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export = export_calibration(_report(), "kalibr", base=base)
    assert export.changed == ("cam0.T_cam_imu rotation", "cam1.T_cam_imu rotation", "cam0.timeshift_cam_imu")
    out = read_vio_file(_written(tmp_path, export, "new.yaml"))
    for cam in ("cam0", "cam1"):
        assert np.abs(out.camera_from_sensor(cam) - R_TRUE).max() < 1e-12
        assert [row[3] for row in out.doc[cam]["T_cam_imu"]] == [row[3] for row in read_vio_file(base).doc[cam][
            "T_cam_imu"]]
    assert "timeshift_cam_imu" not in out.doc["cam1"]  # none to move
    assert any(n.startswith("the rig kept whole: cam1") and "148.7 deg" in n for n in export.notes)


def test_another_cameras_entry_that_cannot_turn_is_named_with_the_way_out(tmp_path):
    """The rig's correction reaches every camera: one whose entry cannot be edited (a merge key, a
    matrix that is not a rotation) stops the export naming that camera and --one-camera; with
    --one-camera it goes through."""
    base = tmp_path / "camchain.yaml"
    for cam1 in ("cam1:\n  <<: *b\n  T_cam_imu:\n", "cam1:\n  T_cam_imu:\n  - [2.0, 0.0, 0.0, 0.7]\n"):
        text = KALIBR_BASE.split("cam1:\n  T_cam_imu:\n")
        base.write_text("b: &b\n  intrinsics: [1, 2, 3, 4]\n" + text[0] + cam1 + text[1].split("\n", 1)[1])
        with pytest.raises(DataFileError, match=r"cam1.*\(the rig's other cameras, cam1, turn with cam0; --one-camera "
                                                r"edits cam0 only\)"):
            export_calibration(_report(), "kalibr", base=base)
        with pytest.warns(ExportWarning, match="one camera only"):
            one = export_calibration(_report(), "kalibr", base=base, whole_rig=False)
        assert np.abs(read_vio_file(_written(tmp_path, one, "o.yaml")).camera_from_sensor() - R_TRUE).max() < 1e-12


def test_kalibrs_other_per_camera_offsets_move_by_the_same_amount(tmp_path):
    base = tmp_path / "camchain.yaml"
    base.write_text(KALIBR_BASE + "  timeshift_cam_imu: -0.25\n")  # cam1's, 0.25 s after cam0's -0.5
    out = read_vio_file(_written(tmp_path, export_calibration(_report(d=0.1), "kalibr", base=base), "n.yaml"))
    assert out.time_offset_s("cam0") == pytest.approx(0.1, abs=1e-15)
    assert out.time_offset_s("cam1") - out.time_offset_s("cam0") == pytest.approx(0.25, abs=1e-15)  # was 0.25 apart
    with pytest.warns(ExportWarning, match="one camera only"):
        one = export_calibration(_report(d=0.1), "kalibr", base=base, whole_rig=False)
    assert read_vio_file(_written(tmp_path, one, "o.yaml")).time_offset_s("cam1") == -0.25
    base.write_text(KALIBR_BASE)  # cam1 has none: added there, cam0's -0.5 kept (no old value to move it by)
    added = export_calibration(_report(d=0.1), "kalibr", base=base, camera="cam1")
    out = read_vio_file(_written(tmp_path, added, "a.yaml"))
    assert (out.time_offset_s("cam1"), out.time_offset_s("cam0")) == (pytest.approx(0.1, abs=1e-15), -0.5)
    assert added.added == ("cam1.timeshift_cam_imu",) and any("cam0's offsets are left as they were" in n
                                                               for n in added.notes)


def test_a_static_pose_report_leaves_the_files_offset_as_it_was(tmp_path):
    base = tmp_path / "camchain.yaml"
    base.write_text(KALIBR_BASE)
    export = export_calibration(_report(d=None), "kalibr", base=base)
    assert read_vio_file(_written(tmp_path, export, "n.yaml")).time_offset_s() == -0.5
    assert "cam0.timeshift_cam_imu" not in export.changed and any("left as it was" in n for n in export.notes)
    # a static-pose report written before time_offset_s became null carries 0.0: not a measurement
    # either
    for d in (0.0, 0.0042, None):
        report = {**_report(d=d), "inputs": {"sensor": {"kind": "static poses", "samples": 10}}}
        export = export_calibration(report, "kalibr", base=base)
        assert read_vio_file(_written(tmp_path, export, "s.yaml")).time_offset_s() == -0.5, d
        assert any("left as it was" in n for n in export.notes)
        assert any("comes from static poses, which have no clock" in n for n in export.notes) == (d is not None)
    # a gyro report's 0.0 is a measurement: written
    export = export_calibration(_report(d=0.0), "kalibr", base=base)
    assert read_vio_file(_written(tmp_path, export, "g.yaml")).time_offset_s() == 0.0


@pytest.mark.parametrize("offset", ["null", "0.0"])
def test_a_hand_made_static_pose_report_keeps_kalibrs_timeshift_through_the_command(tmp_path, offset):
    """Issue 33: the report of static poses (calibrate --poses) has no clock; before, its 0.0
    overwrote the user's timeshift_cam_imu of 0.0042. Null (the schema now) and 0.0 (older reports)
    both leave it, and the command says so; a gyro report's number is written."""
    R = np.asarray(R_TRUE).tolist()
    report, base, out = tmp_path / "robot.json", tmp_path / "camchain-imucam.yaml", tmp_path / "new.yaml"
    poses = '{"kind": "static poses", "samples": 12}'
    report.write_text(f'{{"R0_camera_from_sensor": {json.dumps(R)}, "time_offset_s": {offset}, "verdict": {{"level": '
                      f'"ok", "reasons": []}}, "inputs": {{"camera": {poses}, "sensor": {poses}}}}}')
    base.write_text(KALIBR_BASE.replace("timeshift_cam_imu: -0.5", "timeshift_cam_imu: 0.0042"))
    done = subprocess.run([sys.executable, "-m", "replication", "export", str(report), "--to", "kalibr", "--base",
                           str(base), "--out", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert read_vio_file(out).time_offset_s("cam0") == 0.0042 and "timeshift_cam_imu: 0.0042" in out.read_text()
    assert "note: no clock offset was estimated (static poses): the file's offset is left as it was" in done.stderr
    assert "timeshift" not in done.stderr.splitlines()[0]  # "kalibr: changed ..." names the rotations only
    assert np.abs(read_vio_file(out).camera_from_sensor() - R_TRUE).max() < 1e-12
    gyro = json.loads(report.read_text())
    gyro["inputs"] = {"sensor": {"kind": "GyroStream", "source": "imu0.csv"}}
    gyro["time_offset_s"] = 0.0
    report.write_text(json.dumps(gyro))
    done = subprocess.run([sys.executable, "-m", "replication", "export", str(report), "--to", "kalibr", "--base",
                           str(base)], capture_output=True, text=True)
    assert done.returncode == 0 and "timeshift_cam_imu: 0.0\n" in done.stdout  # measured: written


def test_ros2_is_a_static_transform_publisher_command_of_the_cameras_pose_in_the_imu_frame():
    from scipy.spatial.transform import Rotation

    with pytest.warns(TranslationNotEstimatedWarning, match="put your measured translation in --x --y --z") as said:
        export = export_calibration(_report(), "ros2", parent_frame="imu0", child_frame="cam0_optical")
    assert not any("--base" in str(w.message) for w in said)  # which ros2 refuses
    command = export.text.splitlines()[-1].split()
    assert command[:4] == ["ros2", "run", "tf2_ros", "static_transform_publisher"]
    value = {command[i][2:]: command[i + 1] for i in range(4, len(command), 2)}
    assert (value["frame-id"], value["child-frame-id"]) == ("imu0", "cam0_optical")
    assert [float(value[k]) for k in ("x", "y", "z")] == [0.0, 0.0, 0.0]
    q = [float(value[k]) for k in ("qx", "qy", "qz", "qw")]
    assert np.abs(Rotation.from_quat(q).as_matrix() - R_TRUE.T).max() < 1e-12  # p_imu = R p_cam
    assert any("t_imu = t_cam + d" in n for n in export.notes)
    with pytest.raises(ValueError, match="no base file"):
        export_calibration(_report(), "ros2", base="x.yaml")


def test_basalt_keeps_the_files_quaternion_hemisphere(tmp_path):
    base = tmp_path / "calib.json"
    pose = {"px": 0.1, "py": 0.2, "pz": 0.3, "qx": 0.0, "qy": 0.0, "qz": 0.0, "qw": -1.0}
    base.write_text(json.dumps({"value0": {"T_imu_cam": [pose, pose], "cam_time_offset_ns": 7}}, indent=4))
    R = so3.matrix_from_rotation_vector(np.radians([0.0, 0.0, 1.0]))
    with pytest.warns(ExportWarning, match="one camera only"):
        out = json.loads(export_calibration(_report(R=R, d=-2.5e-3), "basalt", base=base, camera="cam1",
                                            whole_rig=False).text)
    assert out["value0"]["T_imu_cam"][1]["qw"] < 0 and out["value0"]["T_imu_cam"][0] == pose
    rig = json.loads(export_calibration(_report(R=R, d=-2.5e-3), "basalt", base=base, camera="cam1").text)
    assert rig["value0"]["T_imu_cam"][0] == rig["value0"]["T_imu_cam"][1] == out["value0"]["T_imu_cam"][1]
    assert out["value0"]["cam_time_offset_ns"] == -2500000
    assert (out["value0"]["T_imu_cam"][1]["px"], out["value0"]["T_imu_cam"][1]["pz"]) == (0.1, 0.3)


# --------------------------------------------------------------------------------------------------
# refusals

def test_a_failed_verdict_is_refused_unless_forced_and_a_warning_is_carried_over():
    with pytest.raises(ValueError, match="verdict is fail .*m.*force"):
        _export(_report(level="fail"), "kalibr")
    with pytest.warns(ExportWarning, match="verdict is fail"):
        _export(_report(level="fail"), "kalibr", force=True)
    with pytest.warns(ExportWarning, match="verdict is warning: warning: m"):
        _export(_report(level="warning"), "kalibr")
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        _export(_report(level="ok"), "kalibr")


def test_an_offset_measured_against_an_orientation_stream_is_flagged():
    with pytest.warns(ExportWarning, match="not the IMU's gyro"):
        _export(_report(kind="OrientationStream"), "basalt")
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        _export(_report(kind="GyroStream"), "basalt")
        _export(_report(kind="OrientationStream", d=None), "basalt")  # no offset exported, nothing to flag
    with pytest.warns(ExportWarning, match="not the IMU's gyro"):  # its note still says to apply the offset
        _export(_report(kind="OrientationStream"), "orbslam3")


@pytest.mark.parametrize("report, message", [
    ({"x": 1}, "not a calibration report"),
    ({**_report(), "R0_camera_from_sensor": (2 * np.eye(3)).tolist()}, "R0_camera_from_sensor"),
    ({**_report(), "time_offset_s": "0.1"}, "time_offset_s must be a number of seconds or null"),
    ({**_report(), "verdict": {"level": "great"}}, "verdict must be an object whose level is ok, warning or fail"),
    ({**_report(d=0.2 + 1e-9), "parameters": {"max_offset_s": 0.2}}, r"beyond the offsets calibrate searched \(\+-0.2"),
    ({**_report(d=1.0 + 1e-9)}, r"beyond the offsets calibrate searched \(\+-1.0 s\): milliseconds"),
])
def test_a_report_that_is_not_one_is_refused(report, message):
    with pytest.raises(ValueError, match=message):
        read_report(report)


def test_an_offset_at_the_search_bound_is_accepted():
    read_report({**_report(d=-0.2), "parameters": {"max_offset_s": 0.2}})
    read_report(_report(d=1.0))


def test_a_bad_report_file_is_named_with_line_and_column(tmp_path):
    path = tmp_path / "r.json"
    path.write_text('{\n  "R0_camera_from_sensor": [1,\n}')
    with pytest.raises(DataFileError, match=r"r.json, line 3, column 1: not valid JSON") as info:
        read_report(path)
    assert (info.value.line, info.value.column) == (3, 1)


def test_a_base_of_another_tool_or_without_the_camera_is_refused(tmp_path):
    base = tmp_path / "camchain.yaml"
    base.write_text(KALIBR_BASE)
    with pytest.raises(DataFileError, match="is a Kalibr file, not Basalt: give a Basalt file as --base, or --to "
                                            "kalibr"):
        export_calibration(_report(), "basalt", base=base)
    with pytest.raises(DataFileError, match="no camera 'cam2' in this kalibr file; it has cam0, cam1"):
        export_calibration(_report(), "kalibr", base=base, camera="cam2")
    with pytest.raises(ValueError, match="to must be one of"):
        export_calibration(_report(), "vins")


# --------------------------------------------------------------------------------------------------
# sign

@pytest.mark.parametrize("shift_ms", (2.29, -12.62))
def test_a_known_gyro_clock_shift_comes_out_in_each_tools_field_and_sign(tmp_path, shift_ms):
    """The gyro's clock reads ``shift`` ahead (its sample stamped t + shift is the camera's at t):
    Kalibr's and OpenVINS' ``timeshift_cam_imu`` (t_imu = t_cam + shift) and Basalt's
    ``cam_time_offset_ns`` (camera time plus it is IMU time) are +shift; the ROS 2 note and
    ORB-SLAM3's (no field) state it with its sign."""
    result = calibrate(*_rig(1e-3 * shift_ms), n_bootstrap=0)
    assert result.verdict.level == "ok"
    for to in ("kalibr", "openvins", "basalt"):
        file = read_vio_file(_written(tmp_path, _export(result, to), f"{to}.{'json' if to == 'basalt' else 'yaml'}"))
        assert abs(1e3 * file.time_offset_s() - shift_ms) < 0.01, (to, file.time_offset_s())
        assert so3.angle_between_deg(file.camera_from_sensor(), R_TRUE) < 1e-4
    orb = _export(result, "orbslam3")
    assert any(f"add d = {1e-3 * shift_ms:.5f}"[:-1] in n for n in orb.notes), orb.notes
    assert f"d = {1e-3 * shift_ms:.5f}"[:-1] in _export(result, "ros2").notes[0]


# --------------------------------------------------------------------------------------------------
# CLI

def test_the_export_command_writes_a_copy_and_says_what_changed(tmp_path):
    report, base, out = tmp_path / "report.json", tmp_path / "camchain.yaml", tmp_path / "new.yaml"
    report.write_text(json.dumps(_report(level="warning")))
    base.write_text(KALIBR_BASE)
    cmd = [sys.executable, "-m", "replication", "export", str(report), "--to", "kalibr", "--base", str(base)]
    done = subprocess.run(cmd + ["--out", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "kalibr: changed cam0.T_cam_imu rotation, cam1.T_cam_imu rotation, cam0.timeshift_cam_imu in new.yaml" in \
        done.stderr and str(tmp_path) not in done.stderr  # file names only
    assert "note: kept from camchain.yaml" in done.stderr and "note: the rig kept whole: cam1" in done.stderr
    assert "warning: ExportWarning: the report's verdict is warning" in done.stderr and base.read_text() == KALIBR_BASE
    assert np.abs(read_vio_file(out).camera_from_sensor() - R_TRUE).max() < 1e-12
    refused = subprocess.run(cmd + ["--out", str(base)], capture_output=True, text=True)
    assert refused.returncode == 2 and "--out is the --base input file" in refused.stderr
    report.write_text(json.dumps(_report(level="fail")))
    failed = subprocess.run(cmd, capture_output=True, text=True)
    assert failed.returncode == 2 and "verdict is fail" in failed.stderr and failed.stdout == ""
    forced = subprocess.run(cmd + ["--force"], capture_output=True, text=True)
    assert forced.returncode == 0 and forced.stdout.startswith("# my rig")  # no --out: standard output
    # one camera only, into cam1 which has no offset: the key is said to be added, and the rig's
    # move is warned
    one = subprocess.run(cmd + ["--force", "--camera", "cam1", "--one-camera"], capture_output=True, text=True)
    assert one.returncode == 0 and "kalibr: changed cam1.T_cam_imu rotation; added cam1.timeshift_cam_imu" in \
        one.stderr and "ExportWarning: one camera only: cam1 is changed" in one.stderr
    bare = subprocess.run(cmd[:-2] + ["--force"], capture_output=True, text=True)  # no --base
    assert bare.returncode == 2 and "error: --to kalibr needs --base" in bare.stderr and bare.stdout == ""


# ------------------------------------------------------------------------------------------------
# real files

def _orbslam3_inertial(folder, tmp_path):
    """ORB-SLAM3's real monocular settings with the visual-inertial block its Monocular-Inertial
    settings carry (``IMU.T_b_c1`` as an ``!!opencv-matrix`` of ``dt: f``), holding the rig's
    published extrinsic."""
    name = {"euroc_mh01_orbslam3": "orbslam3_Monocular_EuRoC.yaml",
            "tumvi_room1_orbslam3mono": "orbslam3_Monocular_TUM-VI.yaml"}[folder]
    T = np.eye(4)
    T[:3, :3] = load_reference(data_root() / folder / _REFERENCES[folder][0]).T
    T[:3, 3] = [-0.0216, -0.0647, 0.0098]
    data = ",\n         ".join(", ".join(format_number(v) for v in row) for row in T)
    path = tmp_path / f"inertial_{name}"
    path.write_text((data_root() / folder / name).read_text() + "\n# Transformation from camera to body-frame (imu)\n"
                    f"IMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n   data: [{data}]\n\n"
                    "IMU.NoiseGyro: 1.7e-4\nIMU.Frequency: 200.0\n")
    return path


def _values(file):
    """Every value of a file as ``{dotted path: value}``."""
    out = {}

    def walk(prefix, v):
        if isinstance(v, dict):
            for k, w in v.items():
                walk(f"{prefix}.{k}", w)
        elif isinstance(v, (list, tuple, np.ndarray)):
            for i, w in enumerate(np.asarray(v, dtype=object).tolist() if isinstance(v, np.ndarray) else v):
                walk(f"{prefix}[{i}]", w)
        else:
            out[prefix] = v
    walk("", file.doc)
    return out


@needs_real
@pytest.mark.parametrize("folder", sorted(_REFERENCES))
@pytest.mark.parametrize("camera", ("cam0", "cam1"))
def test_real_files_round_trip_with_only_the_rotation_and_offset_changed(tmp_path, folder, camera):
    """With ``whole_rig=False``: the one camera's rotation and the offset, nothing else."""
    import cv2

    d = data_root() / folder
    bases = [d / name for name in _REFERENCES[folder][1:]]
    if folder == "tumvi_room1_orbslam3mono":
        bases.append(d / "camchain.yaml")
    if camera == "cam0":
        bases.append(_orbslam3_inertial(folder, tmp_path))
    R = so3.matrix_from_rotation_vector(np.radians([0.3, -0.2,
                                                    0.5])) @ read_vio_file(bases[0]).camera_from_sensor(camera)
    for base in bases:
        before = read_vio_file(base)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ExportWarning)  # one camera only: the rig moves, and says so
            export = export_calibration(_report(R=R, d=-0.0123456789), before.format, base=base, camera=camera,
                                        whole_rig=False)
        after = read_vio_file(_written(tmp_path, export, "out" + base.suffix))
        assert after.format == before.format and after.cameras() == before.cameras()
        assert np.abs(after.camera_from_sensor(camera) - R).max() < 1e-12, base.name
        if before.format != "orbslam3":
            assert after.time_offset_s(camera) == pytest.approx(-0.012345679, abs=1e-15)
        old, new = _values(before), _values(after)
        moved = {k for k in old if old[k] != new.get(k)}
        assert old.keys() <= new.keys() and len(new) - len(old) == (0 if before.time_offset_s(camera) is not None
                                                                      or before.format == "orbslam3" else 1)
        assert 1 <= len(moved) <= 10 and all(("T_" in k or "q" in k or "offset" in k) for k in moved), moved
        if before.format == "basalt":
            assert all(k.startswith(f".value0.T_imu_cam[{camera[3:]}].q") or k.endswith("cam_time_offset_ns")
                       for k in moved)
        added = [ln for ln in difflib.ndiff(before.text.splitlines(), export.text.splitlines()) if ln.startswith("+ ")]
        assert 1 <= len(added) <= 5, (base.name, added)  # three rotation rows (four quaternion lines), the offset
        if before.opencv:
            assert export.text.startswith("%YAML:1.0")
            fs = cv2.FileStorage(str(tmp_path / ("out" + base.suffix)), cv2.FILE_STORAGE_READ)
            assert fs.isOpened()
            fs.release()


#: Both rigs' files with two cameras: Kalibr's camchain (with T_cn_cnm1), OpenVINS' chains
#: (T_imu_cam on EuRoC, T_cam_imu on TUM-VI), Basalt's JSON (two camera models each).
_RIG_FILES = [(f, n) for f, names in _REFERENCES.items() for n in names[1:]] + [("tumvi_room1_orbslam3mono",
                                                                               "camchain.yaml")]


def _camera_to_camera(file, i, j):
    """Camera j's pose in camera i: ``(R_ij, t_ij)`` from each one's stored extrinsic."""
    Ri, Rj = file.camera_from_sensor(i), file.camera_from_sensor(j)
    return Ri @ Rj.T, Ri @ (file.camera_position(j) - file.camera_position(i))


@needs_real
@pytest.mark.parametrize("folder, name", _RIG_FILES)
@pytest.mark.parametrize("camera", ("cam0", "cam1"))
def test_a_two_camera_file_stays_a_rig(tmp_path, folder, name, camera):
    """Issue 35: exporting cam0's (or cam1's) R0 into a stereo file leaves the cam0-cam1 rotation as
    it was to 1e-9 deg and its translation to 1e-12 m (Kalibr's T_cn_cnm1 unchanged byte for byte);
    the calibrated camera gets R0 exactly; one camera only moves the stereo rotation by the whole
    correction, and warns with that angle."""
    base = data_root() / folder / name
    before = read_vio_file(base)
    R = so3.matrix_from_rotation_vector(np.radians([0.12, -0.08, 0.1])) @ before.camera_from_sensor(camera)
    correction = so3.angle_between_deg(R, before.camera_from_sensor(camera))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export = export_calibration(_report(R=R, d=-0.0042), before.format, base=base, camera=camera)
    after = read_vio_file(_written(tmp_path, export, "rig" + base.suffix))
    assert np.abs(after.camera_from_sensor(camera) - R).max() < 1e-12
    (R_old, t_old), (R_new, t_new) = _camera_to_camera(before, "cam0", "cam1"), _camera_to_camera(after, "cam0", "cam1")
    assert so3.angle_between_deg(R_old, R_new) < 1e-9 and np.abs(t_new - t_old).max() < 1e-12
    assert so3.angle_between_deg(after.camera_from_sensor("cam1"), before.camera_from_sensor("cam1")) == \
        pytest.approx(correction, abs=1e-9)  # the other camera turned by the correction too
    if "T_cn_cnm1" in before.doc.get("cam1", {}):
        assert after.doc["cam1"]["T_cn_cnm1"] == before.doc["cam1"]["T_cn_cnm1"]
    other = "cam1" if camera == "cam0" else "cam0"
    assert any(n.startswith(f"the rig kept whole: {other}") for n in export.notes), export.notes
    with pytest.warns(ExportWarning, match=f"one camera only: {camera} is changed and {other} kept as written.* moves "
                                           f"by {correction:.4g} deg"):
        one = export_calibration(_report(R=R, d=-0.0042), before.format, base=base, camera=camera, whole_rig=False)
    R_one, _ = _camera_to_camera(read_vio_file(_written(tmp_path, one, "one" + base.suffix)), "cam0", "cam1")
    assert so3.angle_between_deg(R_one, R_old) == pytest.approx(correction, abs=1e-9)


def test_openvins_takes_one_offset_cam0s_and_orbslam3_needs_its_file_version(tmp_path):
    base = tmp_path / "chain.yaml"
    base.write_text("%YAML:1.0\n" + KALIBR_BASE.replace("T_cam_imu", "T_imu_cam"))
    with pytest.warns(ExportWarning, match="one camera only"):
        export = export_calibration(_report(), "openvins", base=base, camera="cam1", whole_rig=False)
    assert export.changed == ("cam1.T_imu_cam rotation", "cam0.timeshift_cam_imu") and export.added == ()
    assert any("one time offset, cam0's" in n for n in export.notes)
    out = read_vio_file(_written(tmp_path, export, "o.yaml"))
    assert out.doc["cam0"]["timeshift_cam_imu"] == pytest.approx(0.012345679) and "timeshift_cam_imu" not in out.doc[
        "cam1"]
    rig = export_calibration(_report(), "openvins", base=base, camera="cam1")  # cam0 turns and moves with cam1
    assert rig.changed == ("cam1.T_imu_cam rotation", "cam0.T_imu_cam rotation", "cam0.T_imu_cam translation",
                           "cam0.timeshift_cam_imu")
    assert np.abs(out.camera_from_sensor("cam1") - R_TRUE).max() < 1e-12
    matrix = "IMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n   data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, " \
             "0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
    orb = tmp_path / "orb.yaml"
    orb.write_text('%YAML:1.0\nFile.version: "1.0"\n' + matrix)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export_calibration(_report(), "orbslam3", base=orb)
    orb.write_text('%YAML:1.0\nFile.version: "0.9"\n' + matrix)
    with pytest.warns(ExportWarning, match='no File.version: "1.0"'):
        export_calibration(_report(), "orbslam3", base=orb)


def test_crlf_and_a_byte_order_mark_are_given_back_as_found(tmp_path):
    base = tmp_path / "camchain.yaml"
    base.write_bytes(b"\xef\xbb\xbf" + KALIBR_BASE.replace("\n", "\r\n").encode())
    export = export_calibration(_report(), "kalibr", base=base)
    out = _written(tmp_path, export, "new.yaml").read_bytes()
    assert out.startswith(b"\xef\xbb\xbf") and out.count(b"\r\n") == out.count(b"\n") == KALIBR_BASE.count("\n") + 0
    assert np.abs(read_vio_file(tmp_path / "new.yaml").camera_from_sensor() - R_TRUE).max() < 1e-12
    base.write_bytes(KALIBR_BASE.encode())  # LF stays LF, no mark added
    plain = _written(tmp_path, export_calibration(_report(), "kalibr", base=base), "lf.yaml").read_bytes()
    assert b"\r" not in plain and not plain.startswith(b"\xef\xbb\xbf")


def test_an_entry_shared_through_a_yaml_alias_is_not_edited(tmp_path):
    base = tmp_path / "camchain.yaml"
    rows = "\n".join(f"  - [{', '.join('1.0' if c == r else '0.0' for c in range(4))}]" for r in range(4))
    base.write_text(f"cam0:\n  T_cam_imu: &same\n{rows}\ncam1:\n  T_cam_imu: *same\n")
    with pytest.raises(DataFileError, match="shared with another entry through a YAML anchor"):
        export_calibration(_report(), "kalibr", base=base, camera="cam1")
    base.write_text(f"cam0:\n  T_cam_imu: &same\n{rows}\ncam1:\n  T_cam_imu:\n{rows}\n")  # written out: edited
    assert np.abs(read_vio_file(_written(tmp_path, export_calibration(_report(), "kalibr", base=base, camera="cam1"),
                                         "o.yaml")).camera_from_sensor("cam1") - R_TRUE).max() < 1e-12


def test_a_t_imu_cam_file_is_openvins_and_without_its_header_it_is_flagged(tmp_path):
    base = tmp_path / "chain.yaml"
    base.write_text(KALIBR_BASE.replace("T_cam_imu", "T_imu_cam"))
    with pytest.raises(DataFileError, match="is an OpenVINS file, not Kalibr"):
        export_calibration(_report(), "kalibr", base=base)
    with pytest.warns(ExportWarning, match="no %YAML:1.0 header: OpenVINS reads its files with cv::FileStorage"):
        export_calibration(_report(), "openvins", base=base)
    base.write_text("%YAML:1.0\n" + KALIBR_BASE.replace("T_cam_imu", "T_imu_cam"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ExportWarning)
        export_calibration(_report(), "openvins", base=base)


def test_names_from_the_report_and_the_command_line_cannot_add_lines_or_shell_words():
    report = _report()
    report["inputs"]["sensor"]["source"] = "imu.csv\ncam0:\n  T_cam_imu: []"
    text = _export(report, "ros2").text
    assert [ln for ln in text.splitlines() if not ln.startswith("#")] == [text.splitlines()[-1]]
    assert "imu.csv cam0: T_cam_imu: []" in text
    command = _export(report, "ros2", parent_frame="imu; rm -rf ~", child_frame="cam 0").text.splitlines()
    assert len(command) == 2 and command[1].endswith("--frame-id 'imu; rm -rf ~' --child-frame-id 'cam 0'")


@pytest.mark.parametrize("source", ("/home/me/rig/imu0.csv", "C:\\Users\\me\\imu0.csv", "imu0.csv"))
def test_no_folder_reaches_any_output(tmp_path, source):
    """Issue 35: file names only, in the command, the notes and the warnings (the report's sensor
    path and the base's folder are the user's own business)."""
    report = _report(kind="OrientationStream")
    report["inputs"]["sensor"]["source"] = source
    base = _base(tmp_path, "kalibr")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        outputs = [export_calibration(report, "ros2"), export_calibration(report, "kalibr", base=base)]
    said = [e.text for e in outputs] + [n for e in outputs for n in e.notes] + [str(w.message) for w in caught]
    assert any("imu0.csv" in t for t in said) and any("base_kalibr.yaml" in t for t in said)
    for folder in ("/home/me", "Users", str(tmp_path)):
        assert not any(folder in t for t in said), folder


def test_the_export_help_says_what_the_command_now_does():
    import argparse

    from replication.cli.export import add_parser

    parser = argparse.ArgumentParser(prog="replication")
    text = add_parser(parser.add_subparsers()).format_help()
    assert "--one-camera" in text and "stays a rig" in " ".join(text.split())
    assert "without --base a file is refused" in " ".join(text.split()) and "minimal" not in text
    assert "replication/_shipped/docs/conventions.md" in " ".join(text.split())

# --------------------------------------------------------------------------------------------------
# Adversarial inputs to ``python -m replication export`` and ``load_reference``
# (replication.rig.export, vioformats, realdata), written by an independent referee who tried to
# make them lie: YAML anchors and duplicate keys, files with both OpenVINS keys, ORB-SLAM3 version
# and legacy keys, integer OpenCV matrices, camera names out of range, implausible or mistyped
# report fields, CRLF and byte-order marks, tabs in JSON, files recognised by content. Each test
# states the behaviour the product claims; every one failed before the fixes it guards. No
# calibration is run.


R = RIG_R0

I4 = ("  - [1.0, 0.0, 0.0, 0.1]\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n  - [0.0, 0.0, 0.0, 1.0]\n")


def _report_ea(d=0.0123456789, level="ok", kind="GyroStream"):
    return {"R0_camera_from_sensor": R.tolist(), "time_offset_s": d,
            "verdict": {"level": level, "reasons": []}, "inputs": {"sensor": {"kind": kind, "source": "imu.csv"}}}


def _export_ea(tmp_path, text, to, name="base.yaml", report=None, **kw):
    base = tmp_path / name
    base.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return export_calibration(report or _report_ea(), to, base=base, **kw)


# ------------------------------------------------------------------ silent wrong numbers

def test_anchor_alias_editing_cam1_leaves_cam0_untouched(tmp_path):
    """A row anchored in cam0 and aliased in cam1: exporting cam1 rewrites the anchor, i.e. cam0's
    row."""
    text = ("cam0:\n  T_cam_imu:\n  - &r0 [1.0, 0.0, 0.0, 0.1]\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n"
            "  - [0.0, 0.0, 0.0, 1.0]\n  timeshift_cam_imu: 0.0\n"
            "cam1:\n  T_cam_imu:\n  - *r0\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n"
            "  - [0.0, 0.0, 0.0, 1.0]\n  timeshift_cam_imu: 0.0\n")
    try:
        out = _export_ea(tmp_path, text, "kalibr", camera="cam1").text
    except ValueError:
        return  # refusing an aliased matrix is acceptable
    cam0 = np.array(yaml.safe_load(out)["cam0"]["T_cam_imu"])
    assert cam0[0].tolist() == [1.0, 0.0, 0.0, 0.1], "cam0's row was changed by an export of cam1"


def test_anchor_alias_on_the_offset_of_another_camera(tmp_path):
    text = ("cam0:\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: &t 0.0\n"
            "cam1:\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: *t\n")
    try:
        out = _export_ea(tmp_path, text, "kalibr", camera="cam1").text
    except ValueError:
        return
    try:
        doc = yaml.safe_load(out)
    except yaml.YAMLError as err:  # the anchor '&t' lies inside the replaced span: it is deleted, '*t' dangles
        pytest.fail(f"the exported file is not YAML any more: {err}")
    assert doc["cam0"]["timeshift_cam_imu"] == 0.0, "cam0's offset was changed by an export of cam1"


@pytest.mark.parametrize("text", [
    "cam0:\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: 0.0\ncam0:\n  T_cam_imu:\n" + I4
    + "  timeshift_cam_imu: 0.5\n",
    "cam0:\n  timeshift_cam_imu: 0.0\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: 0.5\n",
], ids=["duplicate camera", "duplicate timeshift"])
def test_duplicate_keys_edit_what_yaml_readers_see(tmp_path, text):
    """PyYAML (Kalibr's reader) keeps the last duplicate; the export edits the first and reports
    success."""
    try:
        out = _export_ea(tmp_path, text, "kalibr").text
    except ValueError:
        return  # refusing duplicate keys is acceptable
    doc = yaml.safe_load(out)["cam0"]
    assert _angle(np.array(doc["T_cam_imu"])[:3, :3], R) < 1e-9
    assert doc["timeshift_cam_imu"] == pytest.approx(0.012345679)


def test_openvins_with_both_keys_uses_T_imu_cam_like_openvins(tmp_path):
    """OpenVINS parses T_imu_cam and falls back to T_cam_imu only when it is missing
    (opencv_yaml_parse.h)."""
    Rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # T_imu_cam rotation: R0 = Rz^T
    text = ("%YAML:1.0\ncam0:\n  T_imu_cam:\n  - [0.0, -1.0, 0.0, 0.0]\n  - [1.0, 0.0, 0.0, 0.0]\n"
            "  - [0.0, 0.0, 1.0, 0.0]\n  - [0.0, 0.0, 0.0, 1.0]\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: 0.0\n")
    path = tmp_path / "both.yaml"
    path.write_text(text)
    assert _angle(load_reference(path), Rz.T) < 1e-9, "load_reference read T_cam_imu, OpenVINS reads T_imu_cam"
    out = _export_ea(tmp_path, text, "openvins", name="both2.yaml").text
    T_imu_cam = np.array(yaml.safe_load("#" + out[1:])["cam0"]["T_imu_cam"])
    assert _angle(T_imu_cam[:3, :3].T, R) < 1e-9, "the export left the T_imu_cam OpenVINS reads unchanged"


def test_orbslam3_unquoted_file_version_is_warned(tmp_path):
    """ORB-SLAM3 uses IMU.T_b_c1 only if File.version is the *string* "1.0" (System.cc:
    node.isString())."""
    text = ("%YAML:1.0\nFile.version: 1.0\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n"
            f"   data: [{I16}]\n")
    (tmp_path / "o.yaml").write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        export_calibration(_report_ea(), "orbslam3", base=tmp_path / "o.yaml")
    assert any(issubclass(w.category, ExportWarning) and "File.version" in str(w.message) for w in caught)


def test_opencv_integer_matrix_does_not_truncate_the_rotation(tmp_path):
    import cv2

    text = ("%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: i\n"
            "   data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n")
    try:
        out = _export_ea(tmp_path, text, "orbslam3").text
    except ValueError:
        return  # refusing dt: i is acceptable
    (tmp_path / "out.yaml").write_text(out)
    fs = cv2.FileStorage(str(tmp_path / "out.yaml"), cv2.FILE_STORAGE_READ)
    M = fs.getNode("IMU.T_b_c1").mat()
    assert _angle(M[:3, :3].astype(float).T, R) < 1e-3, f"cv2 reads {M[:3, :3].tolist()}"


@needs_real_ea
@pytest.mark.parametrize("camera", ["cam-1", "cam-2", "cam2", "camx"])
def test_basalt_camera_name_is_checked_without_an_offset(tmp_path, camera):
    """With time_offset_s null the camera is never checked: cam-1 edits the last camera, cam-2 the
    first."""
    with pytest.raises(DataFileError, match="no camera"):
        _export_ea(tmp_path, BASALT.read_text(), "basalt", name="b.json", report=_report_ea(d=None), camera=camera)


@needs_real_ea
@pytest.mark.parametrize("d", [True, 12.3], ids=["boolean true", "ms written as s (beyond max_offset_s)"])
def test_an_implausible_time_offset_in_a_report_is_refused(tmp_path, d):
    report = _report_ea(d=d)
    report["parameters"] = {"max_offset_s": 0.2}
    with pytest.raises(ValueError):
        _export_ea(tmp_path, CAMCHAIN.read_text(), "kalibr", report=report)


# ------------------------------------------------------------------ claims: warnings, byte for byte

@pytest.mark.parametrize("to", ["ros2", "orbslam3"])
def test_offset_against_an_orientation_stream_is_warned_for_every_target(tmp_path, to):
    """Claim (4): ros2 and orbslam3 tell the user to add d to the stamps, without the
    ExportWarning."""
    base = None
    if to == "orbslam3":
        base = tmp_path / "orb.yaml"
        base.write_text(f"%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n"
                        f"   dt: f\n   data: [{I16}]\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        export_calibration(_report_ea(kind="OrientationStream"), to, base=base)
    assert any(issubclass(w.category, ExportWarning) for w in caught)


@needs_real_ea
@pytest.mark.parametrize("variant", ["crlf", "bom"])
def test_byte_for_byte_with_crlf_or_bom(tmp_path, variant):
    """Claim (1): everything but the changed numbers stays byte for byte."""
    src = CAMCHAIN.read_bytes()
    data = src.replace(b"\n", b"\r\n") if variant == "crlf" else b"\xef\xbb\xbf" + src
    out = _export_ea(tmp_path, data, "kalibr").text.encode("utf-8")
    if variant == "crlf":  # one line added (timeshift_cam_imu), every line ending CRLF
        assert out.count(b"\r\n") == data.count(b"\r\n") + 1 == out.count(b"\n")
    else:
        assert out.startswith(b"\xef\xbb\xbf")


# ------------------------------------------------------------------ clear errors (no traceback)

def _cli(tmp_path, report, to="kalibr", base=None, camera="cam0"):
    rpath = tmp_path / "report.json"
    rpath.write_text(json.dumps(report))
    args = argparse.Namespace(report=str(rpath), to=to, base=None if base is None else str(base), camera=camera,
                              out=str(tmp_path / "out.txt"), parent_frame="imu_link",
                              child_frame="camera_optical_frame", force=False)
    return export_command(args)


@pytest.mark.parametrize("field,value", [("verdict", "ok"), ("verdict", ["ok"]), ("inputs", "x"),
                                         ("verdict", {"level": "warning", "reasons": "bad"})])
def test_a_malformed_report_field_is_a_clear_error_not_a_traceback(tmp_path, field, value):
    report = _report_ea()
    report[field] = value
    assert _cli(tmp_path, report) == 2


@pytest.mark.parametrize("text", [
    "%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 2\n   cols: 6\n   dt: f\n"
    "   data: [1.,0.,0.,0.1,0.,1., 0.,0.2,0.,0.,1.,0.3]\n",
    "0:\n  T_cam_imu:\n" + I4,
], ids=["opencv-matrix 2x6", "integer camera key"])
def test_odd_bases_are_clear_errors_not_tracebacks(tmp_path, text):
    (tmp_path / "b.yaml").write_text(text)
    to = "orbslam3" if "T_b_c1" in text else "kalibr"
    assert _cli(tmp_path, _report_ea(), to=to, base=tmp_path / "b.yaml") == 2
