"""The ecosystem's calibration files as read (``replication/rig/vioformats.py``, through
``load_reference``): recognised by content whatever their name, legacy keys, tabs and rounded
quaternions read, every file that holds no camera-IMU extrinsic refused naming why, only 4x4
matrices, numbers written to round-trip; the two published references of each real rig apart by
the reference floor."""
import math
import re

import numpy as np
import pytest

from conftest import _REFERENCES, BASALT, CAMCHAIN, I16, _angle, needs_real, needs_real_ea
from replication.core import so3
from replication.rig.datafile import DataFileError
from replication.rig.realdata import data_root, load_reference
from replication.rig.vioformats import format_number, read_vio_file


def test_numbers_round_trip_and_always_carry_a_dot():
    for x in (1e-05, -0.1, 0.9995250378696743, 123456789.0, 5e-324):
        text = format_number(x)
        assert "." in text and float(text) == x
    assert format_number(1e-05) == "1.0e-05"
    import yaml

    assert isinstance(yaml.safe_load(format_number(1e-05)), float)  # YAML 1.1 reads a bare 1e-05 as text
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError, match="non-finite"):
            format_number(bad)



@pytest.mark.parametrize("text, message", [
    ("sensor_type: imu\nT_BS:\n  rows: 4\n  cols: 4\n  data: [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]\n",
     "sensor.yaml of sensor_type 'imu', not 'camera'"),
    ("T_BS:\n  rows: 4\n  cols: 4\n  data: [1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]\n", "sensor_type None, not 'camera'"),
    ("%YAML:1.0\nCamera1.fx: 458.6\nORBextractor.nFeatures: 1000\n", "ORB-SLAM3 settings without IMU.T_b_c1"),
    ("cam0:\n  intrinsics: [1, 2, 3, 4]\n", "no camera-IMU extrinsic found"),
    ("cam0:\n  T_cam_imu: [[1, 0], [0, 1]]\n", r"cam0.T_cam_imu is not a 4x4 matrix"),
    ("cam0:\n  T_cam_imu:\n  - [2, 0, 0, 0]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n", "rotation"),
    ('{"value0": {"intrinsics": []}}', "not a Basalt calibration"),
    ('{"value0": {"T_imu_cam": [{"qx": 0, "qy": 0, "qz": 0, "qw": 1.0011}]}}', "norm 1.0011, not within 0.001 of 1"),
    ("cam0:\n  T_cam_imu: [[1, 0,\n", "not valid YAML/JSON"),
])
def test_reference_files_that_are_not_camera_imu_extrinsics_are_refused(tmp_path, text, message):
    path = tmp_path / ("f.json" if text.startswith("{") else "f.yaml")
    path.write_text(text)
    with pytest.raises(DataFileError, match=message):
        load_reference(path)



@pytest.mark.parametrize("rows, cols, ok", [(4, 4, True), (3, 4, False), (4, 3, False), (4, 5, False), (5, 4, False)])
def test_only_a_4x4_matrix_is_read_or_written(tmp_path, rows, cols, ok):
    listed = "".join(f"  - [{', '.join('1.0' if r == c else '0.0' for c in range(cols))}]\n" for r in range(rows))
    data = ", ".join("1.0" if r == c else "0.0" for r in range(rows) for c in range(cols))
    for name, text in (("k.yaml", f"cam0:\n  T_cam_imu:\n{listed}"),
                       ("o.yaml", f"%YAML:1.0\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: {rows}\n"
                                  f"   cols: {cols}\n   dt: f\n   data: [{data}]\n")):
        path = tmp_path / name
        path.write_text(text)
        if ok:
            assert np.abs(load_reference(path) - np.eye(3)).max() == 0
        else:
            with pytest.raises(DataFileError, match="is not a 4x4 matrix"):
                load_reference(path)



def test_euroc_sensor_yaml_without_sensor_type_is_not_taken_for_a_camera(tmp_path):
    path = tmp_path / "sensor.yaml"
    path.write_text("T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0,\n"
                    "         0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\nrate_hz: 200\n")
    with pytest.raises(DataFileError):
        load_reference(path)



@needs_real_ea
def test_a_camchain_named_txt_is_recognised_by_content(tmp_path):
    """Claim (7): recognised by content; a .txt camchain is read as Tabb's file ('a line starting
    with Z')."""
    path = tmp_path / "camchain.txt"
    path.write_text(CAMCHAIN.read_text())
    assert _angle(load_reference(path), load_reference(CAMCHAIN)) < 1e-12



def test_legacy_orbslam3_tbc_is_not_called_vision_only(tmp_path):
    path = tmp_path / "legacy.yaml"
    path.write_text(f"%YAML:1.0\nCamera.fx: 1.0\nTbc: !!opencv-matrix\n   rows: 4\n   cols: 4\n   dt: f\n"
                    f"   data: [{I16}]\n")
    assert _angle(load_reference(path), np.eye(3)) < 1e-12  # read: ORB-SLAM3's legacy key, same meaning
    assert read_vio_file(path).format == "orbslam3"



@needs_real_ea
def test_valid_json_indented_with_tabs_is_read(tmp_path):
    path = tmp_path / "tabs.json"
    path.write_text(BASALT.read_text().replace("    ", "\t"))
    assert _angle(load_reference(path), load_reference(BASALT)) < 1e-12



@needs_real_ea
def test_basalt_quaternion_within_the_documented_norm_tolerance_is_read(tmp_path):
    """docs/conventions.md: stored quaternions must have a norm within 1e-3 of 1; Basalt's check is
    1e-6."""
    text = re.sub(r'("q[xyzw]": )(-?[0-9.]+)', lambda m: m.group(1) + f"{float(m.group(2)):.5f}",
                  BASALT.read_text())
    path = tmp_path / "b5.json"
    path.write_text(text)
    assert _angle(load_reference(path), load_reference(BASALT)) < 0.01



@needs_real
def test_the_two_published_references_of_each_rig_disagree_by_the_reference_floor():
    """Kalibr's (the dataset's) and Basalt's calibrations of cam0: 0.343 deg apart on EuRoC (both of
    Basalt's camera models), 0.034 deg on TUM-VI; OpenVINS' files repeat the dataset's (0 deg)."""
    floors = {"euroc_mh01_orbslam3": 0.343, "tumvi_room1_orbslam3mono": 0.034}
    for folder, names in _REFERENCES.items():
        R = [load_reference(data_root() / folder / n) for n in names]
        assert so3.angle_between_deg(R[0], R[1]) < 1e-6
        for other in R[2:]:
            assert abs(so3.angle_between_deg(R[0], other) - floors[folder]) < 0.0015, folder
