"""The live front end and the command line's online path: the batch options honoured, short recordings handled,
the usual input mistakes named online, ready at the pair's formation time, and the online results in the report."""
import json

import jsonschema
import numpy as np
import pandas as pd
import pytest

from replication.__main__ import main
from replication.core import so3
from replication.rig.live import LiveRig, replay
from replication.rig.online import OnlineCalibrator
from replication.rig.streams import GyroStream, OrientationStream
from replication.study.simulation import rig_streams

SCHEMA = json.loads((__import__("pathlib").Path(__file__).resolve().parent.parent / "docs"
                     / "calibration_report.schema.json").read_text())


@pytest.fixture(scope="module")
def rig():
    return rig_streams(90.0, rng=np.random.default_rng(7), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)


def _summary(camera, sensor, R0=None, **kw):
    rows = replay(camera, sensor, OnlineCalibrator(), reference=R0, **kw)
    return rows, rows.attrs["summary"]


def _fails(summary):
    return {r["check"]: r["message"] for r in summary["verdict"]["reasons"] if r["level"] == "fail"}


@pytest.mark.parametrize("kwargs, message", [
    ({"interval": 0}, "interval must be > 0"), ({"max_offset": -1}, "max_offset must be > 0"),
    ({"offset": float("nan")}, "offset must be a finite number"), ({"stride": 0}, "stride must be >= 1"),
    ({"offset_window": 1.2}, "offset_window must exceed 2 max_offset"), ({"correct_offset": "no"}, "correct_offset"),
    ({"on_pair": 3}, "on_pair must be callable"), ({"diagnose": 1}, "diagnose must be True or False"),
])
def test_live_rig_parameters_are_validated_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        LiveRig(OnlineCalibrator(), **kwargs)
    with pytest.raises(ValueError, match="calibrator must be an OnlineCalibrator"):
        LiveRig(object())


def test_a_gyro_and_an_orientation_sensor_do_not_mix(rig):
    live = LiveRig(OnlineCalibrator(), offset=0.0)
    live.add_gyro(0.0, np.zeros(3))
    with pytest.raises(ValueError, match="this rig's sensor gives gyro samples"):
        live.add_orientation(0.1, np.eye(3))


def test_clean_rig_is_ready_at_the_pairs_formation_time(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera, gyro, R0)
    first = rows.index[rows["ready"]][0]
    assert summary["ready"] and summary["ready_at_s"] == pytest.approx(rows.loc[first, "t_seen"] - camera.t[0])
    assert summary["ready_at_s"] >= 20.0 > summary["ready_pair_end_s"]  # the first pairs wait for the offset window
    assert summary["verdict"]["level"] == "ok" and summary["events"] == [] and rows["error_deg"].iloc[-1] < 0.05
    assert rows[["qw", "radius_deg", "error_deg"]].iloc[:9].isna().all().all()  # no estimate yet: empty, not identity
    assert rows[["qw", "radius_deg", "error_deg"]].iloc[9:].notna().all().all()


def test_a_short_recording_is_paired_at_its_end(rig):
    """15 s of both streams, shorter than the 20 s offset window: the offset is estimated when the streams end."""
    R0, camera, gyro, _ = rig
    keep = gyro.t < 16.0
    rows, summary = _summary(camera.between(0.0, 15.0), GyroStream(gyro.t[keep], gyro.omega[keep], "gyro"), R0)
    assert 12 <= len(rows) <= 15 and summary["clock_offset_s"] == pytest.approx(0.0, abs=1e-3)
    assert summary["note"] is None and rows["t_seen"].min() >= 15.0  # formed when the streams ended


def test_a_too_short_recording_says_why_and_forms_no_pair(rig):
    R0, camera, gyro, _ = rig
    rows, summary = _summary(camera.between(0.0, 0.3), gyro, R0)
    assert len(rows) == 0 and not summary["ready"] and "no clock offset" in summary["note"]


def test_the_max_offset_and_keep_clock_options_are_honoured(rig):
    R0, camera, gyro, _ = rig
    late = GyroStream(gyro.t + 3.0, gyro.omega, "gyro")  # the sensor clock 3 s ahead
    rows, summary = _summary(camera, late, R0, max_offset=4.0)
    assert summary["clock_offset_s"] == pytest.approx(3.0, abs=1e-3) and summary["ready"]
    rows, summary = _summary(camera, late, R0, max_offset=4.0, correct_offset=False)
    assert summary["clock_offset_s"] == pytest.approx(3.0, abs=1e-3) and not summary["ready"]
    assert "offset_left_ms" in {r["check"] for r in summary["verdict"]["reasons"]}
    rows, summary = _summary(camera, late, R0)  # the default search (0.2 s) cannot find it: said, never ready
    assert not rows["ready"].any() and "offset_at_bound" in _fails(summary)


def test_the_stride_is_honoured(rig):
    R0, camera, gyro, _ = rig
    every, _ = _summary(camera, gyro, R0, diagnose=False)
    second, summary = _summary(camera, gyro, R0, stride=2, diagnose=False)
    assert len(second) == pytest.approx(len(every) / 2, abs=1) and summary["pairs_formed"] >= len(every) - 1


@pytest.mark.parametrize("mistake, check, named", [
    ("camera inverted", "input_mistake", "camera_from_world"),
    ("gyro in deg/s", "input_mistake", "gyro rates in deg/s read as rad/s"),
    ("sensor inverted", "input_mistake", "sensor_from_world"),
    ("rig at rest", "motion_median_deg", "barely moves"),
])
def test_the_usual_mistakes_are_named_online_and_never_ready(rig, mistake, check, named):
    R0, camera, gyro, sensor = rig
    inv = lambda s: OrientationStream(s.t, np.swapaxes(s.world_from_body, -1, -2), s.source)  # noqa: E731
    rest = OrientationStream(camera.t, np.broadcast_to(np.eye(3), camera.R.shape), "camera")
    cases = {"camera inverted": (inv(camera), gyro),
             "gyro in deg/s": (camera, GyroStream(gyro.t, np.degrees(gyro.omega), "gyro")),
             "sensor inverted": (camera, inv(sensor)),
             "rig at rest": (rest, GyroStream(gyro.t, np.zeros_like(gyro.omega), "gyro"))}
    rows, summary = _summary(*cases[mistake], R0)
    assert not rows["ready"].any() and summary["verdict"]["level"] == "fail"
    assert named in _fails(summary)[check]


def test_cli_online_writes_its_results_into_the_report_and_figure(tmp_path, rig, capsys):
    R0, camera, gyro, _ = rig
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(camera.R)
    np.savetxt(cam_file, np.column_stack([camera.t + 1e3, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]]),
               fmt="%.9f")
    late = gyro.t + 1e3 + 2.0  # a 2 s clock offset: only found with --max-offset
    np.savetxt(imu_file, np.column_stack([np.round(late * 1e9), gyro.omega, np.zeros((len(gyro.t), 3))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    out, track, fig = tmp_path / "r.json", tmp_path / "track.csv", tmp_path / "fig.png"
    code = main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro",
                 "--max-offset", "3", "--online", "--track", str(track), "--out", str(out), "--plot", str(fig),
                 "--bootstrap", "20", "--quiet"])
    text = capsys.readouterr().out
    assert code == 0 and "events: none" in text and "alarms at []" not in text
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    online = report["online"]
    assert online["ready"] and online["clock_offset_s"] == pytest.approx(2.0, abs=1e-3)
    assert online["ready_at_s"] == pytest.approx(float(text.split("after the camera's")[0].split(",")[-1].split()[0]),
                                                 abs=0.05)
    assert "own noise only" in online["radius_covers"] and online["verdict"]["level"] == "ok"
    rows = pd.read_csv(track)
    assert rows["qw"].iloc[:9].isna().all() and rows["ready"].iloc[-1] and fig.stat().st_size > 10_000


def test_cli_online_on_a_short_recording_writes_the_report(tmp_path, rig):
    R0, camera, gyro, _ = rig
    cam = camera.between(0.0, 15.0)
    cam_file, imu_file, out = tmp_path / "cam.txt", tmp_path / "imu.csv", tmp_path / "r.json"
    q = so3.quaternion_from_matrix(cam.R)
    np.savetxt(cam_file, np.column_stack([cam.t + 1e3, np.zeros((len(cam.t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    keep = gyro.t < 16.0
    np.savetxt(imu_file, np.column_stack([np.round((gyro.t[keep] + 1e3) * 1e9), gyro.omega[keep],
                                          np.zeros((keep.sum(), 3))]), fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    code = main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro",
                 "--online", "--out", str(out), "--bootstrap", "0", "--quiet", "--accept"])
    assert code == 0
    online = json.loads(out.read_text())["online"]
    assert 12 <= online["pairs"] <= 15 and online["clock_offset_s"] == pytest.approx(0.0, abs=1e-3)  # 14; -0.1 ms
