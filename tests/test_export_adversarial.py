"""Adversarial inputs to ``python -m replication export`` and ``load_reference`` (replication.rig.export, vioformats,
realdata), written by an independent referee who tried to make them lie: YAML anchors and duplicate keys, files with
both OpenVINS keys, ORB-SLAM3 version and legacy keys, integer OpenCV matrices, camera names out of range, implausible
or mistyped report fields, CRLF and byte-order marks, tabs in JSON, files recognised by content. Each test states the
behaviour the product claims; every one failed before the fixes it guards. No calibration is run."""
import argparse
import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from replication.core import so3
from replication.rig.datafile import DataFileError
from replication.rig.export import ExportWarning, export_calibration, export_command
from replication.rig.realdata import data_root, load_reference, real_data_available
from replication.rig.vioformats import read_vio_file

R = so3.matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))
REAL = data_root() if real_data_available() else Path("/nonexistent")
BASALT = REAL / "euroc_mh01_orbslam3" / "basalt_euroc_ds_calib.json"
CAMCHAIN = REAL / "tumvi_room1_orbslam3mono" / "camchain.yaml"
needs_real = pytest.mark.skipif(not (BASALT.exists() and CAMCHAIN.exists()), reason="real files not available")

I4 = ("  - [1.0, 0.0, 0.0, 0.1]\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n  - [0.0, 0.0, 0.0, 1.0]\n")
I16 = "1.,0.,0.,0.1, 0.,1.,0.,0.2, 0.,0.,1.,0.3, 0.,0.,0.,1."


def _report(d=0.0123456789, level="ok", kind="GyroStream"):
    return {"R0_camera_from_sensor": R.tolist(), "time_offset_s": d,
            "verdict": {"level": level, "reasons": []}, "inputs": {"sensor": {"kind": kind, "source": "imu.csv"}}}


def _export(tmp_path, text, to, name="base.yaml", report=None, **kw):
    base = tmp_path / name
    base.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return export_calibration(report or _report(), to, base=base, **kw)


def _angle(A, B):
    return np.degrees(np.linalg.norm(so3.rotation_vector_from_matrix(np.asarray(A) @ np.asarray(B).T)))


# ------------------------------------------------------------------ silent wrong numbers


def test_anchor_alias_editing_cam1_leaves_cam0_untouched(tmp_path):
    """A row anchored in cam0 and aliased in cam1: exporting cam1 rewrites the anchor, i.e. cam0's row."""
    text = ("cam0:\n  T_cam_imu:\n  - &r0 [1.0, 0.0, 0.0, 0.1]\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n"
            "  - [0.0, 0.0, 0.0, 1.0]\n  timeshift_cam_imu: 0.0\n"
            "cam1:\n  T_cam_imu:\n  - *r0\n  - [0.0, 1.0, 0.0, 0.2]\n  - [0.0, 0.0, 1.0, 0.3]\n"
            "  - [0.0, 0.0, 0.0, 1.0]\n  timeshift_cam_imu: 0.0\n")
    try:
        out = _export(tmp_path, text, "kalibr", camera="cam1").text
    except ValueError:
        return  # refusing an aliased matrix is acceptable
    cam0 = np.array(yaml.safe_load(out)["cam0"]["T_cam_imu"])
    assert cam0[0].tolist() == [1.0, 0.0, 0.0, 0.1], "cam0's row was changed by an export of cam1"


def test_anchor_alias_on_the_offset_of_another_camera(tmp_path):
    text = ("cam0:\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: &t 0.0\n"
            "cam1:\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: *t\n")
    try:
        out = _export(tmp_path, text, "kalibr", camera="cam1").text
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
    """PyYAML (Kalibr's reader) keeps the last duplicate; the export edits the first and reports success."""
    try:
        out = _export(tmp_path, text, "kalibr").text
    except ValueError:
        return  # refusing duplicate keys is acceptable
    doc = yaml.safe_load(out)["cam0"]
    assert _angle(np.array(doc["T_cam_imu"])[:3, :3], R) < 1e-9
    assert doc["timeshift_cam_imu"] == pytest.approx(0.012345679)


def test_openvins_with_both_keys_uses_T_imu_cam_like_openvins(tmp_path):
    """OpenVINS parses T_imu_cam and falls back to T_cam_imu only when it is missing (opencv_yaml_parse.h)."""
    Rz = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # T_imu_cam rotation: R0 = Rz^T
    text = ("%YAML:1.0\ncam0:\n  T_imu_cam:\n  - [0.0, -1.0, 0.0, 0.0]\n  - [1.0, 0.0, 0.0, 0.0]\n"
            "  - [0.0, 0.0, 1.0, 0.0]\n  - [0.0, 0.0, 0.0, 1.0]\n  T_cam_imu:\n" + I4 + "  timeshift_cam_imu: 0.0\n")
    path = tmp_path / "both.yaml"
    path.write_text(text)
    assert _angle(load_reference(path), Rz.T) < 1e-9, "load_reference read T_cam_imu, OpenVINS reads T_imu_cam"
    out = _export(tmp_path, text, "openvins", name="both2.yaml").text
    T_imu_cam = np.array(yaml.safe_load("#" + out[1:])["cam0"]["T_imu_cam"])
    assert _angle(T_imu_cam[:3, :3].T, R) < 1e-9, "the export left the T_imu_cam OpenVINS reads unchanged"


def test_orbslam3_unquoted_file_version_is_warned(tmp_path):
    """ORB-SLAM3 uses IMU.T_b_c1 only if File.version is the *string* "1.0" (System.cc: node.isString())."""
    text = ("%YAML:1.0\nFile.version: 1.0\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n"
            f"   data: [{I16}]\n")
    (tmp_path / "o.yaml").write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        export_calibration(_report(), "orbslam3", base=tmp_path / "o.yaml")
    assert any(issubclass(w.category, ExportWarning) and "File.version" in str(w.message) for w in caught)


def test_opencv_integer_matrix_does_not_truncate_the_rotation(tmp_path):
    import cv2

    text = ("%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: i\n"
            "   data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n")
    try:
        out = _export(tmp_path, text, "orbslam3").text
    except ValueError:
        return  # refusing dt: i is acceptable
    (tmp_path / "out.yaml").write_text(out)
    fs = cv2.FileStorage(str(tmp_path / "out.yaml"), cv2.FILE_STORAGE_READ)
    M = fs.getNode("IMU.T_b_c1").mat()
    assert _angle(M[:3, :3].astype(float).T, R) < 1e-3, f"cv2 reads {M[:3, :3].tolist()}"


@needs_real
@pytest.mark.parametrize("camera", ["cam-1", "cam-2", "cam2", "camx"])
def test_basalt_camera_name_is_checked_without_an_offset(tmp_path, camera):
    """With time_offset_s null the camera is never checked: cam-1 edits the last camera, cam-2 the first."""
    with pytest.raises(DataFileError, match="no camera"):
        _export(tmp_path, BASALT.read_text(), "basalt", name="b.json", report=_report(d=None), camera=camera)


@needs_real
@pytest.mark.parametrize("d", [True, 12.3], ids=["boolean true", "ms written as s (beyond max_offset_s)"])
def test_an_implausible_time_offset_in_a_report_is_refused(tmp_path, d):
    report = _report(d=d)
    report["parameters"] = {"max_offset_s": 0.2}
    with pytest.raises(ValueError):
        _export(tmp_path, CAMCHAIN.read_text(), "kalibr", report=report)


def test_euroc_sensor_yaml_without_sensor_type_is_not_taken_for_a_camera(tmp_path):
    path = tmp_path / "sensor.yaml"
    path.write_text("T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,\n"
                    "         0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\nrate_hz: 200\n")
    with pytest.raises(DataFileError):
        load_reference(path)


# ------------------------------------------------------------------ claims: warnings, byte for byte


@pytest.mark.parametrize("to", ["ros2", "orbslam3"])
def test_offset_against_an_orientation_stream_is_warned_for_every_target(tmp_path, to):
    """Claim (4): ros2 and orbslam3 tell the user to add d to the stamps, without the ExportWarning."""
    base = None
    if to == "orbslam3":
        base = tmp_path / "orb.yaml"
        base.write_text(f"%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n"
                        f"   dt: f\n   data: [{I16}]\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        export_calibration(_report(kind="OrientationStream"), to, base=base)
    assert any(issubclass(w.category, ExportWarning) for w in caught)


@needs_real
@pytest.mark.parametrize("variant", ["crlf", "bom"])
def test_byte_for_byte_with_crlf_or_bom(tmp_path, variant):
    """Claim (1): everything but the changed numbers stays byte for byte."""
    src = CAMCHAIN.read_bytes()
    data = src.replace(b"\n", b"\r\n") if variant == "crlf" else b"\xef\xbb\xbf" + src
    out = _export(tmp_path, data, "kalibr").text.encode("utf-8")
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
    report = _report()
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
    assert _cli(tmp_path, _report(), to=to, base=tmp_path / "b.yaml") == 2


@needs_real
def test_a_camchain_named_txt_is_recognised_by_content(tmp_path):
    """Claim (7): recognised by content; a .txt camchain is read as Tabb's file ('a line starting with Z')."""
    path = tmp_path / "camchain.txt"
    path.write_text(CAMCHAIN.read_text())
    assert _angle(load_reference(path), load_reference(CAMCHAIN)) < 1e-12


def test_legacy_orbslam3_tbc_is_not_called_vision_only(tmp_path):
    path = tmp_path / "legacy.yaml"
    path.write_text(f"%YAML:1.0\nCamera.fx: 1.0\nTbc: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n"
                    f"   data: [{I16}]\n")
    assert _angle(load_reference(path), np.eye(3)) < 1e-12  # read: ORB-SLAM3's legacy key, same meaning
    assert read_vio_file(path).format == "orbslam3"


@needs_real
def test_valid_json_indented_with_tabs_is_read(tmp_path):
    path = tmp_path / "tabs.json"
    path.write_text(BASALT.read_text().replace("    ", "\t"))
    assert _angle(load_reference(path), load_reference(BASALT)) < 1e-12


@needs_real
def test_basalt_quaternion_within_the_documented_norm_tolerance_is_read(tmp_path):
    """docs/conventions.md: stored quaternions must have a norm within 1e-3 of 1; Basalt's check is 1e-6."""
    text = re.sub(r'("q[xyzw]": )(-?[0-9.]+)', lambda m: m.group(1) + f"{float(m.group(2)):.5f}",
                  BASALT.read_text())
    path = tmp_path / "b5.json"
    path.write_text(text)
    assert _angle(load_reference(path), load_reference(BASALT)) < 0.01
