"""calibrate judges its own answer: bad input across the API and the command line ends in a clear error, a correct
answer, or a warning / fail verdict naming the cause. None is silent.

Most cases use a synthetic rig whose R0 is known: a camera trajectory at 20 Hz and, rigidly attached, a gyro at
200 Hz (or an orientation sensor at 100 Hz), 60 s of smooth three-axis motion. The real recordings (TUM-VI,
EuRoC, Tabb) check the command line end to end.
"""
import json
import math
import re

import jsonschema
import numpy as np
import pytest

from replication.__main__ import main
from replication.core import so3
from replication.rig.calibration import _same_stream, calibrate
from replication.rig.datafile import DataFileError
from replication.rig.poses import calibrate_poses
from replication.rig.quality import EXIT_FAIL, Evidence, judge
from replication.rig.realdata import data_root, real_data_available
from replication.rig.streams import GyroStream, OrientationStream
from replication.study import lab
from replication.testing import write_euroc_imu, write_tum_trajectory

SCHEMA = json.loads((__import__("pathlib").Path(__file__).resolve().parent.parent / "docs"
                     / "calibration_report.schema.json").read_text())
R0 = so3.matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))


def _world_from_camera(t, phase=0.0):
    w = np.stack([0.9 * np.sin(0.7 * t + phase), 0.8 * np.sin(0.45 * t + 1.0 + phase), 0.7 * np.cos(0.3 * t + phase)],
                 axis=-1)
    return so3.matrix_from_rotation_vector(w)


def _rig(seconds=60.0, phase=0.0):
    t_cam = np.arange(0.0, seconds, 0.05)
    camera = OrientationStream(t_cam, _world_from_camera(t_cam, phase), "camera")
    t_imu = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = _world_from_camera(t_imu, phase) @ R0  # world_from_sensor: v_cam = R0 v_sensor
    rel = np.swapaxes(Q[:-1], -1, -2) @ Q[1:]
    omega = so3.rotation_vector_from_matrix(rel) / 0.005  # body rates over each step, stamped at its midpoint
    gyro = GyroStream(0.5 * (t_imu[1:] + t_imu[:-1]), omega, "gyro")
    sensor = OrientationStream(t_imu[::2], Q[::2], "sensor")
    return camera, gyro, sensor


@pytest.fixture(scope="module")
def rig():
    return _rig()


def _q_reordered(stream, order):
    q = so3.quaternion_from_matrix(stream.world_from_body)[:, order]
    return OrientationStream(stream.t, so3.matrix_from_quaternion(q), stream.source)


def _fast(**kw):
    return {"n_bootstrap": 30, "reference": R0, **kw}


def _reasons(result):
    return {r.check: r for r in result.verdict.reasons}


# ------------------------------------------------------------------------------------------- the good case and cases

def test_clean_rig_is_ok_and_right(rig):
    camera, gyro, sensor = rig
    for s in (gyro, sensor):
        r = calibrate(camera, s, **_fast())
        assert r.verdict.level == "ok", r.verdict.lines()
        assert r.reference_error_deg < 0.05


def test_clock_offset_beyond_the_search_fails_at_the_bound(rig):
    camera, gyro, _ = rig
    late = GyroStream(gyro.t + 10.0, gyro.omega, "gyro")
    camera = OrientationStream(camera.t + 10.0 - 5.0, camera.R, "camera")  # overlap kept, clocks 5 s apart
    r = calibrate(camera, late, **_fast())
    reasons = _reasons(r)
    assert r.verdict.level == "fail" and reasons["offset_at_bound"].level == "fail"
    assert "raise max_offset" in reasons["offset_at_bound"].message


def test_a_large_clock_offset_inside_the_search_is_found(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, GyroStream(gyro.t + 0.5, gyro.omega, "gyro"), max_offset=0.8, **_fast())
    assert r.verdict.level == "ok" and abs(r.time_offset_s - 0.5) < 2e-3 and r.reference_error_deg < 0.1


def test_gyro_from_an_unrelated_segment_fails_on_the_correlation(rig):
    camera, _, _ = rig
    _, other, _ = _rig(phase=2.0)
    r = calibrate(camera, other, **_fast())
    assert r.verdict.level == "fail" and _reasons(r)["offset_correlation"].measured < 0.5


@pytest.mark.parametrize("order, name", [([1, 2, 3, 0], "(x, y, z, w) order read as (w, x, y, z)"),
                                         ([3, 0, 1, 2], "(w, x, y, z) order read as (x, y, z, w)")])
def test_camera_quaternion_order_is_named(rig, order, name):
    camera, gyro, _ = rig
    r = calibrate(_q_reordered(camera, order), gyro, **_fast())
    mistake = _reasons(r)["input_mistake"]
    assert r.verdict.level == "fail" and "camera file holds quaternions in" in mistake.message
    assert mistake.measured < 0.05  # undone, the residual collapses


def test_sensor_quaternion_order_is_named(rig):
    camera, _, sensor = rig
    r = calibrate(camera, _q_reordered(sensor, [1, 2, 3, 0]), **_fast())
    mistake = _reasons(r)["input_mistake"]
    assert r.verdict.level == "fail" and "sensor file holds quaternions in" in mistake.message


def test_camera_from_world_poses_are_named(rig):
    camera, gyro, _ = rig
    inverted = OrientationStream(camera.t, np.swapaxes(camera.R, -1, -2), "camera")
    r = calibrate(inverted, gyro, **_fast())
    assert r.verdict.level == "fail" and "camera_from_world poses" in _reasons(r)["input_mistake"].message


def test_sensor_from_world_poses_are_named(rig):
    camera, _, sensor = rig
    r = calibrate(camera, OrientationStream(sensor.t, np.swapaxes(sensor.R, -1, -2), "s"), **_fast())
    assert r.verdict.level == "fail" and "sensor_from_world poses" in _reasons(r)["input_mistake"].message


def test_gyro_in_deg_per_s_is_named(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, GyroStream(gyro.t, np.degrees(gyro.omega), "gyro"), **_fast())
    assert r.verdict.level == "fail" and "deg/s read as rad/s" in _reasons(r)["input_mistake"].message


def test_accelerometer_columns_read_as_gyro_fail(rig):
    camera, gyro, _ = rig
    acc = np.array([0.1, -0.2, 9.81]) + 0.05 * np.sin(gyro.t)[:, None]
    r = calibrate(camera, GyroStream(gyro.t, acc, "acc as gyro"), **_fast())
    assert r.verdict.level == "fail" and "offset_correlation" in _reasons(r)


def test_slow_gyro_fails_on_its_rate(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, GyroStream(gyro.t[::100], gyro.omega[::100], "2 Hz"), **_fast())
    reasons = _reasons(r)
    assert r.verdict.level == "fail" and reasons["gyro_samples_per_interval"].level == "fail"
    assert reasons["gyro_rate_hz"].measured == pytest.approx(2.0, rel=0.01)


def test_pairs_across_a_gyro_gap_are_dropped_and_said(rig):
    camera, gyro, _ = rig
    keep = (gyro.t < 20.0) | (gyro.t > 35.0)
    r = calibrate(camera, GyroStream(gyro.t[keep], gyro.omega[keep], "gap"), **_fast())
    gap = _reasons(r)["gap_share_dropped"]
    assert gap.level == "warning" and "pairs spanned a gap" in gap.message
    assert r.reference_error_deg < 0.05  # the answer is right: the pairs across the gap are gone
    assert r.n_pairs < 0.8 * calibrate(camera, gyro, n_bootstrap=0).n_pairs


def test_pairs_ending_in_an_orientation_gap_are_dropped(rig):
    camera, _, sensor = rig
    keep = (sensor.t < 20.0) | (sensor.t > 30.0)
    r = calibrate(camera, OrientationStream(sensor.t[keep], sensor.R[keep], "gap"), **_fast())
    assert _reasons(r)["gap_share_dropped"].level == "warning" and r.reference_error_deg < 0.05


def test_a_short_overlap_has_no_bootstrap_radius_and_fails(rig):
    camera, gyro, _ = rig
    r = calibrate(camera.between(10.0, 12.5), gyro, **_fast())
    reasons = _reasons(r)
    assert math.isnan(r.bootstrap_ci95_deg) and r.to_dict()["bootstrap_ci95_deg"] is None
    assert reasons["blocks"].level == "fail" and reasons["blocks"].measured < 3  # measured 1.55
    assert (reasons["overlap_intervals"].level == "warning"
            and reasons["overlap_intervals"].measured == pytest.approx(2.5))


def test_nearly_single_axis_motion_warns_with_its_spread():
    t = np.arange(0.0, 60.0, 0.05)
    w = np.stack([np.sin(0.7 * t), 0.003 * np.sin(0.45 * t), 0.003 * np.cos(0.3 * t)], axis=-1)
    Q = so3.matrix_from_rotation_vector(w)
    camera, sensor = OrientationStream(t, Q, "c"), OrientationStream(t, Q @ R0, "s")
    r = calibrate(camera, sensor, n_bootstrap=20)
    assert _reasons(r)["axis_spread_deg"].level == "warning" and r.verdict.level != "ok"


@pytest.mark.filterwarnings("ignore::replication.core.solvers.ConvergenceWarning")
def test_sqp_away_from_the_certified_optimum_fails(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, gyro, method="sqp", max_iterations=2, **_fast(n_bootstrap=0))
    assert r.verdict.level == "fail" and any("LocalMinimumWarning" in x for x in r.warnings)


def test_static_pose_sets_get_a_verdict_and_name_their_pairs(rig):
    camera, _, sensor = rig
    C, S = np.swapaxes(camera.R[::60], -1, -2), np.swapaxes(sensor.at(camera.t[::60]), -1, -2)
    r = calibrate_poses(C, S, reference=R0, n_bootstrap=20)
    assert r.verdict.level == "ok" and r.reference_error_deg < 1e-10  # noise-free: measured 6e-14
    assert "pairs of static poses" in r.summary() and "nan" not in r.summary()


# ------------------------------------------------------------------------------------------- time units

@pytest.mark.parametrize("side, factor", [("sensor", 1e3), ("camera", 1e3), ("sensor", 1e9)])
def test_time_unit_mistakes_on_absolute_clocks_are_named(rig, side, factor):
    camera, gyro, _ = rig
    epoch = 1.5e9  # absolute clocks: a file in another unit does not even overlap
    camera = OrientationStream(camera.t + epoch, camera.R, "camera")
    gyro = GyroStream(gyro.t + epoch, gyro.omega, "gyro")
    if side == "sensor":
        gyro = GyroStream(gyro.t * factor, gyro.omega / factor, "gyro")
    else:
        camera = OrientationStream(camera.t * factor, camera.R, "camera")
    with pytest.raises(ValueError, match=f"the {side} file's time stamps are likely in another unit"):
        calibrate(camera, gyro, n_bootstrap=0)


def test_time_unit_mistake_on_relative_clocks_fails_naming_it(rig):
    camera, _, sensor = rig
    slow = OrientationStream(sensor.t * 1e3, sensor.R, "sensor in ms")  # overlaps the camera's 0..60 s
    r = calibrate(camera, slow, n_bootstrap=0)
    assert r.verdict.level == "fail" and "the sensor file's time stamps are likely" in _reasons(r)["time_unit"].message


def test_lab_recording_with_times_in_ms_is_refused(lab_dir):
    path = lab_dir / "dynamic_imu.csv"
    lines = path.read_text().splitlines()
    out = [lines[0]] + [",".join([f"{1e3 * float(x.split(',')[0]):.3f}"] + x.split(",")[1:]) for x in lines[1:]]
    path.write_text("\n".join(out) + "\n")
    with pytest.raises(DataFileError, match="look like ms") as err:
        lab.load_lab(lab_dir)
    assert err.value.column == "t"


# ------------------------------------------------------------------------------------------- bad parameters

@pytest.mark.parametrize("kwargs, message", [
    ({"interval": 0.0}, "interval must be > 0"),
    ({"interval": -1.0}, "interval must be > 0"),
    ({"interval": float("nan")}, "interval must be a finite number"),
    ({"interval": "1"}, "interval must be a finite number"),
    ({"stride": 0}, "stride must be >= 1"),
    ({"stride": 1.5}, "stride must be a finite integer"),
    ({"n_bootstrap": -1}, "n_bootstrap must be >= 0"),
    ({"n_bootstrap": 2.5}, "n_bootstrap must be a finite integer"),
    ({"max_offset": 0.0}, "max_offset must be > 0"),
    ({"max_offset": float("inf")}, "max_offset must be a finite number"),
    ({"seed": -3}, "seed must be >= 0"),
    ({"method": "nope"}, "unknown solver 'nope'"),
    ({"reference": np.eye(4)}, "4x4 transform; pass its rotation block"),
    ({"reference": 2 * np.eye(3)}, "reference is not a rotation matrix"),
    ({"reference": np.eye(2)}, "reference must be a 3x3 rotation"),
])
def test_bad_parameters_are_refused_before_any_work(rig, kwargs, message, monkeypatch):
    camera, gyro, _ = rig
    import replication.rig.calibration as cal

    monkeypatch.setattr(cal, "offset_analysis", lambda *a, **k: pytest.fail("work started"))
    with pytest.raises(ValueError, match=message):
        calibrate(camera, gyro, **kwargs)


@pytest.mark.parametrize("camera, sensor", [("not a stream", "gyro"), ("camera", np.zeros((10, 3)))])
def test_streams_of_the_wrong_type_are_refused(rig, camera, sensor):
    streams = {"camera": rig[0], "gyro": rig[1]}
    with pytest.raises(ValueError, match="camera must be an OrientationStream"):
        calibrate(streams.get(camera, camera) if isinstance(camera, str) else camera,
                  streams.get(sensor, sensor) if isinstance(sensor, str) else sensor)


# ------------------------------------------------------------------------------------------- the verdict itself

def test_judge_levels_and_thresholds():
    good = Evidence(n_pairs=100, residual_median_deg=0.2, motion_median_deg=30.0, bootstrap_deg=0.1,
                    axis_spread_deg=10.0, offset_s=0.0, offset_correlation=0.99, max_offset_s=0.2,
                    offset_resolution_s=5e-4, blocks=100, overlap_s=100.0, interval_s=1.0)
    assert judge(good).level == "ok" and judge(good).reasons == ()
    import dataclasses

    warn = judge(dataclasses.replace(good, offset_correlation=0.8))
    assert warn.level == "warning" and warn.reasons[0].threshold == 0.9
    fail = judge(dataclasses.replace(good, bootstrap_deg=7.0, warnings=("AccuracyWarning",)))
    assert fail.level == "fail" and {r.check for r in fail.reasons} == {"bootstrap_deg", "solver_warning"}


def test_report_is_strict_json_and_valid_against_the_schema(rig):
    camera, gyro, _ = rig
    r = calibrate(camera.between(10.0, 11.6), gyro, n_bootstrap=0)  # NaN bootstrap, a fail verdict
    text = json.dumps(r.to_dict(), allow_nan=False)  # raises on NaN / inf
    report = json.loads(text)
    jsonschema.validate(report, SCHEMA)
    assert report["verdict"]["level"] == "fail" and report["package"]["name"] == "replication"
    assert "sensor sample stamped t + d" in report["time_offset_convention"]
    assert report["parameters"]["n_bootstrap"] == 0 and report["inputs"]["sensor"]["kind"] == "GyroStream"


def test_diagnostic_figure_has_every_panel(rig, tmp_path):
    camera, gyro, _ = rig
    r = calibrate(camera, gyro, n_bootstrap=20)
    fig = r.plot(tmp_path / "r.png")
    titles = [ax.get_title() for ax in fig.axes]
    for key in ("(a) angular speed", "(b) clock offset", "(c) per-pair residual", "(e) bootstrap", "(f) verdict"):
        assert any(t.startswith(key) for t in titles), titles
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"


# ------------------------------------------------------------------------------------------- the command line



@pytest.fixture(scope="module")
def rig_files(rig, tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    camera, gyro, _ = rig
    shifted = OrientationStream(camera.t + 1e3, camera.R, "c")  # EuRoC-like absolute times
    write_tum_trajectory(d / "cam.txt", shifted)
    write_euroc_imu(d / "imu.csv", GyroStream(gyro.t + 1e3, gyro.omega, "g"))
    write_euroc_imu(d / "imu_deg.csv", GyroStream(gyro.t + 1e3, np.degrees(gyro.omega) / 10, "g"))  # slow deg/s
    return d


def _cli(*args):
    return main(["calibrate", *map(str, args), "--bootstrap", "20", "--quiet"])


def test_cli_ok_writes_a_valid_report_and_figure(rig_files, tmp_path):
    out, fig = tmp_path / "new" / "deeper" / "r.json", tmp_path / "new" / "r.png"
    assert _cli("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu.csv", "--sensor-kind", "gyro",
                "--out", out, "--plot", fig, "--stride", 2, "--seed", 3) == 0
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["files"]["camera"]["sha256"] and report["parameters"]["stride"] == 2
    assert report["parameters"]["seed"] == 3 and fig.stat().st_size > 1000


def test_cli_fail_exits_3_unless_accepted(rig_files, tmp_path, capsys):
    args = ("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu_deg.csv", "--sensor-kind", "gyro")
    assert _cli(*args, "--out", tmp_path / "r.json") == EXIT_FAIL
    captured = capsys.readouterr()
    assert "verdict: FAIL" in captured.out and "exit code 3" in captured.err
    assert json.loads((tmp_path / "r.json").read_text())["verdict"]["level"] == "fail"  # the report is still written
    assert _cli(*args, "--accept") == 0


@pytest.mark.parametrize("extra, message", [
    (("--interval", "0"), "must be > 0"),
    (("--interval", "nan"), "not finite"),
    (("--stride", "0"), "must be >= 1"),
    (("--stride", "1.5"), "not an integer"),
    (("--bootstrap", "-1"), "must be >= 0"),
    (("--max-offset", "-0.1"), "must be > 0"),
    (("--seed", "x"), "not an integer"),
])
def test_cli_bad_numbers_exit_2_naming_the_option(rig_files, extra, message, capsys):
    with pytest.raises(SystemExit, match="^2$"):  # a usage error
        main(["calibrate", "--camera", str(rig_files / "cam.txt"), "--sensor", str(rig_files / "imu.csv"), *extra])
    stderr = capsys.readouterr().err
    assert extra[0] in stderr and message in stderr


@pytest.mark.parametrize("case", ["directory", "under a file", "unknown method", "csv time unit", "empty",
                                  "trailing slash"])
def test_cli_bad_output_or_options_exit_2_before_the_work_leaving_nothing(rig_files, tmp_path, case, capsys,
                                                                          monkeypatch):
    import replication.rig.calibration as cal

    monkeypatch.setattr(cal, "offset_analysis", lambda *a, **k: pytest.fail("work started"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    extra = {"directory": ("--out", tmp_path), "under a file": ("--out", blocker / "r.json"),
             "unknown method": ("--method", "nope"), "csv time unit": ("--sensor-time-unit", "ms"),
             "empty": ("--out", ""), "trailing slash": ("--out", str(tmp_path / "newdir") + "/")}[case]
    sensor_kind = ("--sensor-kind", "gyro")
    assert _cli("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu.csv", *sensor_kind, *extra) == 2
    assert "error:" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.part")) and sorted(p.name for p in tmp_path.iterdir()) == ["file"]


# ------------------------------------------------------------------------------------------- the campaign's cases

def test_inverted_pose_sets_are_named(rig):
    camera, _, sensor = rig
    C, S = np.swapaxes(camera.R[::40], -1, -2), np.swapaxes(sensor.at(camera.t[::40]), -1, -2)
    noise = so3.matrix_from_rotation_vector(np.random.default_rng(2).normal(size=(len(C), 3)) * np.radians(0.1))
    C = noise @ C  # a little camera noise, as on a real robot set
    for name, c, s in (("camera poses inverted", np.swapaxes(C, -1, -2), S),
                       ("robot poses inverted", C, np.swapaxes(S, -1, -2))):
        r = calibrate_poses(c, s, n_bootstrap=0)
        assert r.verdict.level == "fail" and name in _reasons(r)["input_mistake"].message, name
    assert calibrate_poses(C, S, n_bootstrap=0, reference=R0).verdict.level == "ok"
    # both inverted is a consistent problem for another unknown (the world-to-world rotation): the rotations alone
    # cannot show it; a reference does
    both = calibrate_poses(np.swapaxes(C, -1, -2), np.swapaxes(S, -1, -2), n_bootstrap=0, reference=R0)
    assert both.verdict.level == "fail" and "reference_error_deg" in _reasons(both)


def test_a_gyro_with_permuted_axes_fails_against_the_reference(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, GyroStream(gyro.t, gyro.omega[:, [1, 2, 0]], "gyro"), **_fast())
    reason = _reasons(r)["reference_error_deg"]
    assert r.verdict.level == "fail" and "axes permuted" in reason.message and reason.measured > 100


def test_too_few_pairs_fail_even_without_a_bootstrap(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, gyro, stride=300, n_bootstrap=0)
    assert r.n_pairs < 10 and _reasons(r)["n_pairs"].level == "fail"


def test_the_camera_stream_as_sensor_is_refused(rig):
    camera, _, _ = rig
    with pytest.raises(ValueError, match="the sensor stream is the camera stream itself"):
        calibrate(camera, OrientationStream(camera.t, camera.R, "copy"))


def test_a_copy_of_the_camera_stream_as_sensor_is_refused_at_its_tolerances(rig):
    """A line dropped, times shifted by a nanosecond, orientations a little less than 1e-4 rad apart: the same
    recording, refused naming how many samples coincide; a little more than the tolerances: a sensor of its own."""
    from replication.core.so3 import matrix_from_rotation_vector
    from replication.rig.calibration import SAME_SAMPLE_ANGLE_RAD, SAME_SAMPLE_TIME_S

    camera, _, _ = rig
    t, R = camera.t, camera.R
    with pytest.raises(ValueError, match=rf"a copy of it: {len(t) - 1} of the sensor's "
                                         rf"{len(t) - 1} samples are camera"):
        calibrate(camera, OrientationStream(t[1:], R[1:], "copy"))
    turn = matrix_from_rotation_vector(np.array([0.0, 0.0, 0.9 * SAME_SAMPLE_ANGLE_RAD]))
    with pytest.raises(ValueError, match="the sensor stream is the camera stream itself, or a copy of it"):
        calibrate(camera, OrientationStream(t + 0.9 * SAME_SAMPLE_TIME_S, R @ turn, "copy"))
    # just beyond either tolerance, or half of the samples only: not a copy (the calibration runs)
    assert _same_stream(camera,
                        OrientationStream(t, R @ matrix_from_rotation_vector(np.array([0.0, 0.0,
                                                                                       1.1 * SAME_SAMPLE_ANGLE_RAD])),
                                                  "s")) is None
    assert _same_stream(camera, OrientationStream(t + 1.1 * SAME_SAMPLE_TIME_S, R, "s")) is None
    n = len(t)
    half = np.r_[R[: n // 2], R[n // 2:] @ matrix_from_rotation_vector(np.array([0.0, 0.01, 0.0]))]
    assert _same_stream(camera, OrientationStream(t, half, "s")) is not None  # exactly half coincide
    assert _same_stream(camera, OrientationStream(t, np.r_[half[: n // 2 - 1], half[n // 2 - 1:] @
                                                           matrix_from_rotation_vector(np.array([0.0, 0.01,
                                                                                                 0.0]))], "s")) is None


def test_a_degenerate_bootstrap_resample_is_a_reason_not_an_error(rig, monkeypatch):
    camera, gyro, _ = rig
    import replication.rig.estimate as est

    def refuse(*a, **k):
        raise ValueError("degenerate motion: a resample")

    monkeypatch.setattr(est, "bootstrap_replicates", refuse)
    r = calibrate(camera, gyro, n_bootstrap=20)
    assert math.isnan(r.bootstrap_ci95_deg) and "degenerate motion" in _reasons(r)["bootstrap_failed"].message


@pytest.mark.parametrize("side, unit", [("sensor", 1e-3), ("camera", 1e3)])
def test_the_time_unit_reason_blames_the_implausible_stream(rig, side, unit):
    camera, _, sensor = rig
    if side == "sensor":  # a CSV in ms read as ns: its span shrinks to a millisecond or so
        sensor = OrientationStream(sensor.t * unit, sensor.R, "s")
    else:
        camera = OrientationStream(camera.t * unit, camera.R, "c")
    with pytest.raises(ValueError, match=f"the {side} file's time stamps are likely in another unit"):
        calibrate(camera, sensor, n_bootstrap=0)


def test_unknown_or_refused_solver_options_are_named_before_the_work(rig, monkeypatch):
    camera, gyro, _ = rig
    import replication.rig.calibration as cal

    monkeypatch.setattr(cal, "offset_analysis", lambda *a, **k: pytest.fail("work started"))
    with pytest.raises(ValueError, match=r"does not take the option\(s\) \['foo'\]"):
        calibrate(camera, gyro, foo=1)
    with pytest.raises(ValueError, match="refuses the option"):
        calibrate(camera, gyro, method="sqp", max_iterations=-1)


def test_an_offset_kept_in_is_said(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, GyroStream(gyro.t + 0.1, gyro.omega, "gyro"), correct_offset=False, n_bootstrap=0)
    assert _reasons(r)["offset_left_ms"].measured == pytest.approx(100.0, abs=2.0)


# ------------------------------------------------------------------------------------------- real recordings

needs_real = pytest.mark.skipif(not real_data_available(), reason="real recordings not available")


@needs_real
def test_cli_robot_pose_sets_calibrate(tmp_path):
    d = data_root() / "tabb_rwhe_ds1"
    out = tmp_path / "tabb.json"
    assert _cli("--poses", "--camera", d / "cali.txt", "--sensor", d / "robot_cali.txt", "--reference",
                d / "transformations.txt", "--out", out) == 0
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["reference_error_deg"] < 1.0 and report["interval_s"] is None
    assert report["inputs"]["camera"]["kind"] == "static poses"


@needs_real
def test_cli_euroc_with_repeated_lines(tmp_path):
    d = data_root() / "euroc_mh01_orbslam3"
    out = tmp_path / "euroc.json"
    args = ("--camera", d / "orbslam3_mono_cam0_traj_runB.txt", "--sensor", d / "gt_body_MH_01_easy_tum.txt",
            "--reference", d / "euroc_cam0_sensor.yaml", "--out", out)
    assert _cli(*args) == 2  # repeated lines are an error unless dropped
    assert _cli(*args, "--drop-repeated") == 0
    assert json.loads(out.read_text())["reference_error_deg"] < 0.5


@needs_real
@pytest.mark.filterwarnings("ignore::replication.core.solvers.ConvergenceWarning")
def test_cli_sqp_on_tumvi_fails_instead_of_answering_170_deg_off(tmp_path, capsys):
    d = data_root() / "tumvi_room1_orbslam3mono"
    code = _cli("--camera", d / "orbslam3_mono_cam0_traj.txt", "--sensor", d / "imu0_data.csv", "--sensor-kind",
                "gyro", "--method", "sqp", "--bootstrap", "0", "--no-gyro-bias")  # the rates as recorded: SQP's trap
    out = capsys.readouterr().out
    assert code == EXIT_FAIL and "away from the certified optimum of eq. (8)" in out
    assert "use the default method chordal_optimal" in out and "LocalMinimumWarning" not in out.split("R0 (")[0]


@needs_real
def test_cli_two_step_left_on_euroc_names_the_near_single_axis_motion_not_the_warning(tmp_path, capsys):
    """Issue 35.3: README's former example. The verdict says why the iteration hit its cap (sigma_2 / sigma_1 of K
    0.9975 > 0.9863 at axis spread 3.2 deg) and what to do; the class stays in the report's warnings."""
    d = data_root() / "euroc_mh01_orbslam3"
    out = tmp_path / "euroc.json"
    code = _cli("--camera", d / "orbslam3_mono_cam0_traj_runA.txt", "--sensor", d / "gt_body_MH_01_easy_tum.txt",
                "--method", "two_step_left", "--bootstrap", "0", "--out", out)
    text = capsys.readouterr().out
    verdict = text.split("R0 (")[0]
    assert code == 0 and "IterationCapWarning" not in verdict
    assert "sigma_2 / sigma_1 of K 0.997" in verdict and "> 0.9863" in verdict and "camera axis spread 3.2" in verdict
    assert "use the default method chordal_optimal" in verdict
    report = json.loads(out.read_text())
    assert any(w.startswith("IterationCapWarning") for w in report["warnings"])
    (reason,) = [r for r in report["verdict"]["reasons"] if r["check"] == "solver_warning"]
    assert reason["measured"] > reason["threshold"] == pytest.approx(0.98627, abs=1e-5)



# ------------------------------------------------------------------- one door for every solver answer (issue 33, 1)

@pytest.fixture
def door_solver(monkeypatch):
    """``make(answer) -> name``: registers a solver whose core returns ``answer(R, call)`` (``R`` the certified
    minimiser, ``call`` 0 for the calibration's own solve, then 1, 2, ... for each later call: the replicates)."""
    from replication.core.solvers import _registry, register, solver_info

    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    core = solver_info("chordal_optimal").core

    def make(answer):
        calls = []

        def bad(motions):
            calls.append(1)
            return answer(core(motions), len(calls) - 1)

        name = f"door_test_{len(_registry._REGISTRY)}"
        register(name, reference="test: a solver bad on some calls")(bad)
        return name

    return make


def _poses(rig, step=60):
    camera, _, sensor = rig
    return np.swapaxes(camera.R[::step], -1, -2), np.swapaxes(sensor.at(camera.t[::step]), -1, -2)


def _nan_like(R):
    return np.full_like(R, np.nan)


RAW_MESSAGES = ("Non-positive determinant", "R_est contains", "SVD did not converge")


def test_a_solver_returning_2R_on_replicates_is_refused_naming_it_at_every_door(rig, door_solver):
    C, S = _poses(rig)
    camera, gyro, _ = rig
    name = door_solver(lambda R, call: R if call == 0 else 2 * R)
    with pytest.raises(ValueError, match=rf"solver '{name}' returned a matrix that is not a rotation on bootstrap "
                                         r"replicate 0 at batch index \(\): .*det R = 8"):
        calibrate_poses(C, S, method=name, n_bootstrap=20, diagnose=False)
    name = door_solver(lambda R, call: R if call == 0 else 2 * R)  # streams: the replicates come batched
    with pytest.raises(ValueError, match=rf"solver '{name}' returned a matrix that is not a rotation on bootstrap "
                                         r"replicates 0\.\.29 at batch index \(0,\)"):
        calibrate(camera, gyro, method=name, **_fast(diagnose=False))


@pytest.mark.parametrize("what, answer, words", [
    ("reflection", lambda R: -R, r"returned a reflection \(det -1\)"),
    ("nan", _nan_like, r"declared a failure \(NaN\)"),
])
@pytest.mark.parametrize("bad_calls, counted", [((), 0), ((1,), 1), ((1, 5, 7), 3)])
def test_replicates_that_are_no_rotations_fail_naming_the_solver_and_give_no_radius(
        rig, door_solver, what, answer, words, bad_calls, counted):
    """No bad replicate: a radius and no such reason; one bad replicate of 20 (the boundary) already fails."""
    name, r, reason = _bad_replicates(rig, door_solver, lambda R, call: answer(R), bad_calls, counted)
    if reason is not None:
        assert re.search(rf"solver '{name}' {words} on {counted} of 20 bootstrap replicates", reason.message)
        assert r.to_dict()["bootstrap_ci95_deg"] is None


def _bad_replicates(rig, door_solver, answer, bad_calls, counted):
    """A pose-set calibration with a solver giving ``answer(R, call)`` on the calls ``bad_calls`` (the first call is
    the calibration's own solve): without bad calls a radius and no reason; else a ``bootstrap_answers`` fail counting
    them, and no radius. Returns the solver's name, the result and the reason (None without bad calls)."""
    C, S = _poses(rig)
    name = door_solver(lambda R, call: answer(R, call) if call in bad_calls else R)
    r = calibrate_poses(C, S, method=name, n_bootstrap=20, diagnose=False)
    reasons = _reasons(r)
    if not counted:
        assert "bootstrap_answers" not in reasons and math.isfinite(r.bootstrap_ci95_deg)
        return name, r, None
    reason = reasons["bootstrap_answers"]
    assert reason.level == "fail" and r.verdict.level == "fail" and reason.measured == counted
    assert not math.isfinite(r.bootstrap_ci95_deg) and r.diagnostics["bootstrap_rotvec_deg"].size == 0
    return name, r, reason


@pytest.mark.parametrize("answer, words", [(lambda R: -R, r"returned a reflection \(det -1\)"),
                                           (_nan_like, r"declared a failure \(returned NaN\)")])
def test_a_solver_whose_own_answer_is_no_rotation_is_refused_naming_it(rig, door_solver, answer, words):
    C, S = _poses(rig)
    camera, gyro, _ = rig
    for run in (lambda name: calibrate_poses(C, S, method=name, n_bootstrap=20),
                lambda name: calibrate(camera, gyro, method=name, **_fast())):
        name = door_solver(lambda R, call: answer(R))
        with pytest.warns(Warning), pytest.raises(ValueError) as err:
            run(name)
        assert re.search(rf"solver '{name}' {words} on these \d+ pairs: no rotation", str(err.value))
        assert not any(raw in str(err.value) for raw in RAW_MESSAGES)


def test_bootstrap_replicates_without_masks_refuse_non_rotations(rig, door_solver):
    import replication.rig.estimate as est
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    motions = prepare_motions(*pose_pairs(C, S))
    name = door_solver(lambda R, call: -R if call == 2 else R)
    sets = est.block_indices(np.random.default_rng(0), motions.J, 1, 4)
    with pytest.raises(ValueError, match=rf"solver '{name}' returned a reflection \(det -1\) on 1 of 4 bootstrap"):
        est.bootstrap_replicates(motions, name, {}, [s for s in sets])
    R, failed, reflection, unfit = est.bootstrap_replicates(motions, name, {}, [s for s in sets], masks=True)
    assert not reflection.any() and not failed.any()  # calls 4-7: the bad one (call 2) was in the first run


@pytest.mark.parametrize("factor, unit", [(1e9, "nanoseconds"), (1e6, "microseconds"), (1e3, "milliseconds")])
def test_camera_and_gyro_stamps_in_different_units_are_refused_naming_the_units(rig, factor, unit):
    camera, gyro, _ = rig
    t0 = 1000.0  # absolute stamps, as a recording has: the camera's in another unit
    late = OrientationStream((camera.t + t0) * factor, camera.R, "c")
    gyro = GyroStream(gyro.t + t0, gyro.omega, "g")
    about = re.escape(f"{factor:.0e}")
    with pytest.raises(ValueError, match=rf"a factor of about {about}: the camera file's time stamps are likely in "
                                         rf"another unit than they were read in \({unit} read as seconds\)"):
        calibrate(late, gyro, n_bootstrap=0)
    early = OrientationStream(camera.t + t0, camera.R, "c")  # and the other way round: the gyro's in seconds / unit
    slow = GyroStream((gyro.t + t0) / factor, gyro.omega * factor, "g")
    with pytest.raises(ValueError, match=rf"the sensor file's time stamps .* \(seconds read as {unit}\)"):
        calibrate(early, slow, n_bootstrap=0)


# ------------------------------------------------------------- replicates that are rotations but no solutions (33.1)

def _random_rotation(R, call):
    return so3.random_rotations(np.random.default_rng(call), 1)[0] if R.ndim == 2 else so3.random_rotations(
        np.random.default_rng(call), R.shape[0])


@pytest.mark.parametrize("bad_calls, counted", [((), 0), ((1,), 1), ((1, 5, 7), 3)])
def test_replicates_that_are_no_solutions_fail_naming_the_solver_and_give_no_radius(rig, door_solver, bad_calls,
                                                                                    counted):
    """Right on the calibration's own solve, random rotations on some replicates (rotations, so the registry's
    checks pass them): without one, a radius; one of 20 (the boundary) already fails, naming the solver."""
    name, r, reason = _bad_replicates(rig, door_solver, _random_rotation, bad_calls, counted)
    if reason is None:
        return
    assert re.search(rf"solver '{name}' returned an answer that is no solution of its resample on {counted} of 20 "
                     r"bootstrap replicates \(worst: root-mean-square pair residual [\d.]+ deg", reason.message)
    assert "not a solution on resamples" in reason.message and "np." not in reason.message


def test_batched_replicates_that_are_no_solutions_fail_naming_the_solver(rig, door_solver):
    camera, gyro, _ = rig
    name = door_solver(lambda R, call: _random_rotation(R, call) if call == 1 else R)
    r = calibrate(camera, gyro, method=name, **_fast(diagnose=False))
    reason = _reasons(r)["bootstrap_answers"]
    assert reason.level == "fail" and reason.measured == 30 and f"solver '{name}'" in reason.message
    assert not math.isfinite(r.bootstrap_ci95_deg)


def _rms(residual_deg):
    """Cost (8) of the pairs as an angle: the angle whose chordal distance is their root-mean-square one."""
    return float(np.degrees(2 * np.arcsin(np.sqrt(np.mean(np.sin(np.radians(residual_deg) / 2) ** 2)))))


def test_an_outlying_station_drawn_often_does_not_make_the_optimum_a_non_solution(rig):
    """A resample that draws an outlying station several times pulls the least-squares answer off the other
    stations (their median residual grows 6-fold here): it is still the resample's optimum, and not blamed."""
    C, S = _poses(rig)
    rng = np.random.default_rng(2)
    C = C @ so3.matrix_from_rotation_vector(rng.normal(scale=np.radians(0.3), size=(len(C), 3)))
    k = rng.choice(len(C), 1)
    C[k] = C[k] @ so3.matrix_from_rotation_vector(np.radians(30.0) * so3.random_rotations(rng, 1)[:, 0])
    r = calibrate_poses(C, S, n_bootstrap=200, diagnose=False)
    assert "bootstrap_answers" not in _reasons(r) and math.isfinite(r.bootstrap_ci95_deg)


@pytest.mark.parametrize("side", [-1, 1])
def test_a_replicate_is_judged_at_the_factor_times_the_answers_fit_on_the_same_pairs(rig, side):
    """The boundary: a replicate turned from the answer by just less / more than the angle at which its root-mean-square
    residual reaches REPLICATE_FIT_FACTOR times the answer's on the same pairs (noisy poses) is a solution / is not."""
    import replication.rig.estimate as est
    from replication.core.handeye import pair_residual_deg
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    C = C @ so3.matrix_from_rotation_vector(np.random.default_rng(1).normal(scale=np.radians(0.3), size=(len(C), 3)))
    motions = prepare_motions(*pose_pairs(C, S))
    R = calibrate_poses(C, S, n_bootstrap=0, diagnose=False).R
    sets = [np.arange(0, motions.J, 2)]  # a resample: every other pair
    base = _rms(pair_residual_deg(R, motions.A[sets[0]], motions.B[sets[0]]))
    threshold = est.REPLICATE_FIT_FACTOR * base + est.REPLICATE_FIT_FLOOR_DEG

    def turned(angle_deg):
        return so3.matrix_from_rotation_vector(np.radians(angle_deg) * np.array([0.0, 0.0, 1.0])) @ R

    def own(angle_deg):
        return _rms(pair_residual_deg(turned(angle_deg), motions.A[sets[0]], motions.B[sets[0]]))

    lo, hi = 0.0, 90.0  # bisection for the angle where the replicate's median reaches the threshold
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if own(mid) < threshold else (lo, mid)
    angle = hi * (1 + side * 1e-3)
    flags, (mine, full) = est.unfit_replicates(motions, turned(angle)[None], sets, R)
    assert full[0] == pytest.approx(base) and mine[0] == pytest.approx(own(angle))
    assert bool(mine[0] > threshold) is (side > 0) and bool(flags[0]) is (side > 0)


def test_bootstrap_replicates_without_masks_refuse_no_solutions_naming_the_solver(rig, door_solver):
    import replication.rig.estimate as est
    from replication.core.motions import prepare_motions
    from replication.rig.poses import pose_pairs

    C, S = _poses(rig)
    motions = prepare_motions(*pose_pairs(C, S))
    sets = [s for s in est.block_indices(np.random.default_rng(0), motions.J, 1, 4)]
    # calls 0-3: the replicates (call 2 the third), then one solve on all the pairs for the check
    name = door_solver(lambda R, call: _random_rotation(R, call) if call == 2 else R)
    with pytest.raises(ValueError, match=rf"solver '{name}' returned an answer that is no solution of its resample "
                                         r"on 1 of 4 bootstrap replicates"):
        est.bootstrap_replicates(motions, name, {}, sets)
    name = door_solver(lambda R, call: R)
    R_boot, failed, reflection, unfit = est.bootstrap_replicates(motions, name, {}, sets, masks=True)
    assert not (failed.any() or reflection.any() or unfit.any()) and R_boot.shape == (4, 3, 3)


def test_a_solver_that_returns_its_first_answer_on_every_replicate_fails_naming_it(rig, door_solver):
    """A solver that ignores its input (its first answer cached) would give a radius of zero: it fails, named; the
    same pose set with an honest solver keeps its radius, and noise-free data (replicates all equal to the answer,
    as they should be) name nothing."""
    C, S = _poses(rig)
    noisy = C @ so3.matrix_from_rotation_vector(np.random.default_rng(3).normal(scale=np.radians(0.3), size=(len(C),
                                                                                                             3)))
    first = {}
    name = door_solver(lambda R, call: first.setdefault("R", R) if R.ndim == 2 else np.broadcast_to(
        first.setdefault("R", R[0]), R.shape).copy())
    r = calibrate_poses(noisy, S, method=name, n_bootstrap=20, diagnose=False)
    reason = _reasons(r)["bootstrap_answers"]
    assert reason.level == "fail" and f"solver '{name}' returned the answer on all the pairs, unchanged" in (
        reason.message) and "on every one of the 20 bootstrap replicates" in reason.message
    assert not math.isfinite(r.bootstrap_ci95_deg)
    honest = calibrate_poses(noisy, S, n_bootstrap=20, diagnose=False)
    assert "bootstrap_answers" not in _reasons(honest) and honest.bootstrap_ci95_deg > 0
    exact = calibrate_poses(C, S, n_bootstrap=20, diagnose=False)
    assert "bootstrap_answers" not in _reasons(exact) and math.isfinite(exact.bootstrap_ci95_deg)


@pytest.mark.parametrize("turn, frozen", [(0.5, True), (2.0, False)])
def test_replicates_frozen_at_the_bound(rig, door_solver, turn, frozen):
    """Replicates all turned from the answer by half / twice FROZEN_DEG: the answer returned unchanged, or not."""
    import replication.rig.estimate as est

    C, S = _poses(rig)
    noisy = C @ so3.matrix_from_rotation_vector(np.random.default_rng(3).normal(scale=np.radians(0.3), size=(len(C),
                                                                                                             3)))
    first = {}
    step = so3.matrix_from_rotation_vector(np.radians(turn * est.FROZEN_DEG) * np.array([0.0, 0.0, 1.0]))
    name = door_solver(lambda R, call: first.setdefault("R", R) if call == 0 else step @ first["R"])
    r = calibrate_poses(noisy, S, method=name, n_bootstrap=20, diagnose=False)
    assert ("bootstrap_answers" in _reasons(r)) is frozen
