"""The simulated lab (``replication.study.lab``): the generator, Table II's statistics, the
committed recordings, and the loader's rejection of malformed files. The chain: test_lab_chain.py
and test_lab_fastchain.py; the studies: test_lab_study.py."""
import dataclasses
import json

import numpy as np
import pandas as pd
import pytest

from conftest import SMALL_LAB
from replication.rig.datafile import DataFileError
from replication.study import lab

SMALL = SMALL_LAB


# ----------------------------------------------------------------------------- the generator

def test_switching_a_source_off_keeps_every_other_draw():
    a, b = lab.simulate_lab(SMALL), lab.simulate_lab(SMALL.without("pixel noise"))
    pd.testing.assert_frame_equal(a.static_imu, b.static_imu)
    assert not np.allclose(a.static_markers.to_numpy(), b.static_markers.to_numpy())
    c = lab.simulate_lab(SMALL.without("magnetometer errors"))
    pd.testing.assert_frame_equal(a.static_markers, c.static_markers)
    np.testing.assert_array_equal(a.static_imu[lab.ACC_COLUMNS], c.static_imu[lab.ACC_COLUMNS])
    with pytest.raises(ValueError, match="unknown error source"):
        SMALL.without("gremlins")
    assert all(getattr(SMALL.exact(), f) in (0.0, (0.0, 0.0, 0.0)) for s in lab.SOURCES.values() for f in s)


def test_parts_of_a_source_switch_off_separately():
    s = lab.LabSettings()
    noise_off, cal_off = s.without("magnetometer noise"), s.without("magnetometer calibration errors")
    assert noise_off.mag_noise_ut == 0 and noise_off.mag_hard_iron_ut == s.mag_hard_iron_ut
    assert cal_off.mag_noise_ut == s.mag_noise_ut and cal_off.mag_soft_iron == 0 and cal_off.mag_misalignment_deg == 0
    with pytest.raises(ValueError, match="unknown error source"):
        s.without("magnetometer")


def test_dynamic_trial_that_loses_the_wand_is_refused():
    with pytest.raises(ValueError, match="wand leaves the image"):
        lab.simulate_lab(dataclasses.replace(SMALL, dynamic_amplitude_deg=(40.0, 30.0, 40.0)))


# ----------------------------------------------------------------------------- files

def test_committed_recordings_are_the_generator_output():
    """data/lab is what simulate_lab() writes (to the written precision)."""
    loaded, fresh = lab.load_lab(), lab.simulate_lab()
    assert loaded.rig == json.loads(json.dumps(fresh.rig))
    np.testing.assert_allclose(loaded.truth["camera_from_sensor"], fresh.truth["camera_from_sensor"], atol=1e-11)
    for name in ("static_imu", "static_markers", "dynamic_imu", "dynamic_markers"):
        a, b = getattr(loaded, name), getattr(fresh, name)
        assert list(a.columns) == list(b.columns) and len(a) == len(b)
        np.testing.assert_allclose(a.to_numpy(float), b.to_numpy(float), atol=6e-4, err_msg=name)


def test_write_then_load_round_trip(lab_recording):
    rec = lab.load_lab(lab_recording)
    assert (sorted(rec.static_imu["set"].unique()) == [0, 1]
            and rec.static_imu.groupby("set")["pose"].nunique().min() == 4)
    assert not list(lab_recording.glob("*.tmp"))
    res = lab.run_lab(rec)
    assert set(res.table2.index.get_level_values("method")) == {"optimization", "ours_right", "ours_left",
                                                                "sensor_frame"}


def _edit_csv(path, fn):
    lines = path.read_text().splitlines()
    fn(lines)
    path.write_text("\n".join(lines) + "\n")


def _set_cell(line_no, column, value):
    def fn(lines):
        header = lines[0].split(",")
        cells = lines[line_no - 1].split(",")
        cells[header.index(column)] = value
        lines[line_no - 1] = ",".join(cells)
    return fn


def _scale_columns(columns, factor):
    def fn(lines):
        header = lines[0].split(",")
        for i in range(1, len(lines)):
            cells = lines[i].split(",")
            for c in columns:
                cells[header.index(c)] = repr(float(cells[header.index(c)]) * factor)
            lines[i] = ",".join(cells)
    return fn


def _edit_rig(key, value):
    def fn(path):
        rig = json.loads(path.read_text())
        if value is None:
            del rig[key]
        else:
            rig[key] = value
        path.write_text(json.dumps(rig))
    return fn


CSV_CASES = {
    "missing column": ("static_imu.csv", lambda ls: ls.__setitem__(0, ls[0].replace("mag_z", "mag_w")),
                       r"static_imu.csv, line 1: missing column\(s\) \['mag_z'\]"),
    "not a number": ("static_markers.csv", _set_cell(5, "u3", "abc"),
                     r"static_markers.csv, line 5, column 'u3': not a number: 'abc'"),
    "NaN": ("dynamic_imu.csv", _set_cell(7, "gyr_y", "nan"),
            r"dynamic_imu.csv, line 7, column 'gyr_y': NaN, empty or inf"),
    "empty cell": ("static_imu.csv", _set_cell(9, "acc_z", ""),
                   r"static_imu.csv, line 9, column 'acc_z': NaN, empty or inf"),
    "time goes back": ("dynamic_markers.csv", _set_cell(4, "t", "0.0"),
                       r"dynamic_markers.csv, line 4, column 't': timestamp 0 is not after the previous line's 0.04"),
    "pose out of order": ("static_imu.csv", _set_cell(3, "pose", "7"),
                          r"static_imu.csv, line 4, column 'pose': pose 0 follows pose 7"),
    "fractional set": ("static_markers.csv", _set_cell(2, "set", "0.5"),
                       r"static_markers.csv, line 2, column 'set': must be a non-negative integer"),
    "accelerometer in g": ("static_imu.csv", _scale_columns(lab.ACC_COLUMNS, 1 / lab.GRAVITY),
                           r"static_imu.csv, column 'acc_x': median accelerometer norm 1.0\d*; "
                           r"expected about 9.80665 m/s\^2 \(data in g\?\)"),
    "gyro in deg/s": ("dynamic_imu.csv", _scale_columns(lab.GYR_COLUMNS, 57.29578),
                      r"dynamic_imu.csv, column 'gyr_x': integrating the gyroscope .* \(data in deg/s\?\)"),
    "gyro beyond range": ("dynamic_imu.csv", _set_cell(3, "gyr_z", "40.0"),
                          r"dynamic_imu.csv, line 3, column 'gyr_z': 40 is outside the sensor's range .* not deg/s"),
    "magnetometer in gauss": ("static_imu.csv", _scale_columns(lab.MAG_COLUMNS, 0.01),
                              r"static_imu.csv, column 'mag_x': median magnetometer norm .*gauss"),
    "pixel outside image": ("static_markers.csv", _set_cell(6, "v8", "481.5"),
                            r"static_markers.csv, line 6, column 'v8': pixel 481.5 is outside the image \(0..480\)"),
}


@pytest.mark.parametrize("case", sorted(CSV_CASES))
def test_loader_rejects_malformed_csv(lab_dir, case):
    name, edit, message = CSV_CASES[case]
    _edit_csv(lab_dir / name, edit)
    with pytest.raises(ValueError, match=message):
        lab.load_lab(lab_dir)


RIG_CASES = {
    "missing key": (_edit_rig("wand_points", None), r"rig.json: missing key\(s\) \['wand_points'\]"),
    "camera matrix shape": (_edit_rig("camera_matrix", [[450, 0, 320], [0, 450, 240]]),
                            r"'camera_matrix' must have shape \(3, 3\)"),
    "coplanar wand": (_edit_rig("wand_points", [[x, y, 0.0] for x in (-1, 0, 1) for y in (-1, 0, 1)]), r"coplanar"),
    "wand in mm": (_edit_rig("wand_points", (lab.WAND_POINTS * 1000).tolist()), r"expected metres, not mm"),
    "units": (_edit_rig("units", {**lab.UNITS, "gyr": "deg/s"}), r"key 'units' must be"),
    "distortion": (_edit_rig("dist_coeffs", [0.1, 0.2, 0.3]), r"4, 5, 8, 12 or 14"),
    "not json": (lambda p: p.write_text('{"camera_matrix": [1, 2,\n'), r"rig.json, line 2, column 1: not valid JSON"),
}


@pytest.mark.parametrize("case", sorted(RIG_CASES))
def test_loader_rejects_malformed_rig(lab_dir, case):
    edit, message = RIG_CASES[case]
    edit(lab_dir / "rig.json")
    with pytest.raises(ValueError, match=message):
        lab.load_lab(lab_dir)


def test_loader_rejects_protocol_violations(lab_dir):
    with pytest.raises(ValueError, match=r"set 0, pose 0 is held for 5.2 s, less than min_static_seconds = 6"):
        lab.load_lab(lab_dir, min_static_seconds=6.0)
    with pytest.raises(ValueError, match=r"set 0 has 4 static orientations, fewer than min_poses = 5"):
        lab.load_lab(lab_dir, min_poses=5)
    _edit_csv(lab_dir / "static_markers.csv",
              lambda ls: ls.__setitem__(slice(None), [l for l in ls if not l.startswith("1,3,")]))
    with pytest.raises(ValueError, match=r"\(set, pose\) \(1, 3\) appears only in static_imu.csv"):
        lab.load_lab(lab_dir)


TRUTH_CASES = {  # the value written on line 2 (after '  "camera_from_sensor": ', column 25), the message
    "twice a rotation": ("[[2, 0, 0], [0, 2, 0], [0, 0, 2]]", r"is not a rotation matrix .*\|\|R\^T R - I\|\|_F"),
    "a reflection": ("[[1, 0, 0], [0, 1, 0], [0, 0, -1]]", r"reflection|det"),
    "not 3 x 3": ("[[1, 0, 0], [0, 1, 0]]", r"must be a 3 x 3 rotation matrix, got shape \(2, 3\)"),
    "a stack": ("[[[1, 0, 0], [0, 1, 0], [0, 0, 1]]]", r"must be a 3 x 3 rotation matrix, got shape \(1, 3, 3\)"),
}


@pytest.mark.parametrize("case", sorted(TRUTH_CASES))
def test_loader_refuses_a_truth_that_is_not_a_rotation(lab_dir, case):
    value, message = TRUTH_CASES[case]
    path = lab_dir / "truth.json"
    lines = path.read_text().splitlines()
    assert lines[1].startswith('  "camera_from_sensor": [[')
    lines[1] = f'  "camera_from_sensor": {value},'
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFileError, match=r"truth.json, line 2, column 25: key 'camera_from_sensor' " + message):
        lab.load_lab(lab_dir)


def test_loader_reports_a_missing_file(lab_dir):
    (lab_dir / "dynamic_markers.csv").unlink()
    with pytest.raises(FileNotFoundError, match="dynamic_markers.csv: no such file"):
        lab.load_lab(lab_dir)


def _table2_rms(rec):
    return lab.run_lab(rec).table2["rms_deg"].to_numpy()


@pytest.mark.parametrize("noisy", [True, False])
def test_table2_is_rounding_sensitive_only_without_accelerometer_and_magnetometer_noise(noisy):
    """Madgwick's correction is a normalised gradient step: with noise-free accelerometer and
    magnetometer its direction is set by rounding, so a 1e-13 relative change of the IMU data moves
    Table II; with noise it does not."""
    settings = dataclasses.replace(SMALL, dynamic_seconds=10.0)
    if not noisy:
        settings = settings.without("accelerometer errors", "magnetometer errors")
    assert settings.noise_free_dynamic_attitude is not noisy
    rec = lab.simulate_lab(settings)
    imu = rec.dynamic_imu.copy()
    cols = lab.GYR_COLUMNS + lab.ACC_COLUMNS + lab.MAG_COLUMNS
    imu[cols] = imu[cols] * (1.0 + 1e-13)
    change = np.abs(_table2_rms(rec) - _table2_rms(dataclasses.replace(rec, dynamic_imu=imu))).max()
    if noisy:
        assert change < 1e-8
    else:
        assert change > 1e-6


def test_lab_recording_with_times_in_ms_is_refused(lab_dir):
    path = lab_dir / "dynamic_imu.csv"
    lines = path.read_text().splitlines()
    out = [lines[0]] + [",".join([f"{1e3 * float(x.split(',')[0]):.3f}"] + x.split(",")[1:]) for x in lines[1:]]
    path.write_text("\n".join(out) + "\n")
    with pytest.raises(DataFileError, match="look like ms") as err:
        lab.load_lab(lab_dir)
    assert err.value.column == "t"
