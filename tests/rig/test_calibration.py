"""calibrate judges its own answer (``replication/rig/calibration.py``, end to end through
``calibrate`` and ``calibrate_poses``): bad input ends in a clear error, a correct answer, or a
warning / fail verdict naming the cause. None is silent. The command line's own tests:
tests/cli/test_calibrate.py.

Most cases use a synthetic rig whose R0 is known: a camera trajectory at 20 Hz and, rigidly
attached, a gyro at 200 Hz (or an orientation sensor at 100 Hz), 60 s of smooth three-axis motion.
The real recordings (TUM-VI) check ``calibrate`` end to end.
"""
import json
import math
import re
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from conftest import SCHEMA, T0, _nan_like, _poses, _random_rotation, _reasons, _rig, _turned, needs_real
from replication.cli import main
from replication.core import so3
from replication.rig import realdata as rd
from replication.rig.association import offset_in_words
from replication.rig.calibration import OverlapError, _same_stream, calibrate
from replication.rig.poses import calibrate_poses
from replication.rig.quality import THRESHOLDS
from replication.rig.report import RADIUS_COVERS
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import RIG_R0, rig_streams, write_euroc_imu, write_tum_trajectory

R0 = RIG_R0


def _q_reordered(stream, order):
    q = so3.quaternion_from_matrix(stream.world_from_body)[:, order]
    return OrientationStream(stream.t, so3.matrix_from_quaternion(q), stream.source)


def _fast(**kw):
    return {"n_bootstrap": 30, "reference": R0, **kw}


# -------------------------------------------------------------------------- the good case and cases

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


# --------------------------------------------------------------------------------------- time units

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


# ----------------------------------------------------------------------------------- bad parameters

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


# ------------------------------------------------------------------------------- the verdict itself


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


# ----------------------------------------------------------------------------- the campaign's cases


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
    """A line dropped, times shifted by a nanosecond, orientations a little less than 1e-4 rad
    apart: the same recording, refused naming how many samples coincide; a little more than the
    tolerances: a sensor of its own."""
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
    import replication.rig.solve_and_judge as est

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


# ----------------------------------------------------------------- one door for every solver answer


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


@pytest.mark.parametrize("factor, finer, coarser", [
    (1e9, "nanoseconds read as seconds", "seconds read as nanoseconds"),
    (1e6, "microseconds read as seconds, or nanoseconds read as milliseconds",
     "milliseconds read as nanoseconds, or seconds read as microseconds"),
    (1e3, "milliseconds read as seconds, or microseconds read as milliseconds, or nanoseconds read as microseconds",
     "microseconds read as nanoseconds, or seconds read as milliseconds, or milliseconds read as microseconds")])
def test_camera_and_gyro_stamps_in_different_units_are_refused_naming_the_units(rig, factor, finer, coarser):
    """Every pair of units ``factor`` apart is named (a CSV's microseconds read as nanoseconds
    look like seconds read as milliseconds), and the option that reads the file: with its unit where
    one pair fits."""
    camera, gyro, _ = rig
    t0 = 1000.0  # absolute stamps, as a recording has: the camera's in another unit
    late = OrientationStream((camera.t + t0) * factor, camera.R, "c")
    gyro = GyroStream(gyro.t + t0, gyro.omega, "g")
    about = re.escape(f"{factor:.0e}")
    option = "--camera-time-unit " + ("ns" if factor == 1e9 else "with the file's unit")
    with pytest.raises(ValueError, match=rf"a factor of about {about}: the camera file's time stamps are likely in "
                                         rf"another unit than they were read in, one {about} times finer "
                                         rf"\({finer}\); {option} reads it \(TUM trajectories and EuRoC"):
        calibrate(late, gyro, n_bootstrap=0)
    early = OrientationStream(camera.t + t0, camera.R, "c")  # and the other way round: the gyro's in seconds / unit
    slow = GyroStream((gyro.t + t0) / factor, gyro.omega * factor, "g")
    option = "--sensor-time-unit " + ("s" if factor == 1e9 else "with the file's unit")
    with pytest.raises(ValueError, match=rf"the sensor file's time stamps .* {about} times coarser \({coarser}\); "
                                         rf"{option} reads it"):
        calibrate(early, slow, n_bootstrap=0)


# -------------------------------------------- replicates that are rotations but no solutions (33.1)


def test_batched_replicates_that_are_no_solutions_fail_naming_the_solver(rig, door_solver):
    camera, gyro, _ = rig
    name = door_solver(lambda R, call: _random_rotation(R, call) if call == 1 else R)
    r = calibrate(camera, gyro, method=name, **_fast(diagnose=False))
    reason = _reasons(r)["bootstrap_answers"]
    assert reason.level == "fail" and reason.measured == 30 and f"solver '{name}'" in reason.message
    assert not math.isfinite(r.bootstrap_ci95_deg)


# --------------------------------------------------------------------------------------------------
# The batch verdict's words: every radius saying what it covers, the offset's sign in words (pose
# sets judged by station: tests/rig/test_poses.py and test_solve_and_judge.py).


def test_every_radius_says_what_it_covers(rng):
    R0, camera, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.05)
    r = calibrate(camera, gyro, n_bootstrap=30)
    assert RADIUS_COVERS in r.summary() and r.bootstrap_covers == RADIUS_COVERS
    assert r.bootstrap_resamples.startswith("pairs in moving blocks of")
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["bootstrap_covers"] == RADIUS_COVERS and "not in it" in report["bootstrap_covers"]


@pytest.mark.parametrize("offset, words", [
    (0.0123, "+12.3 ms: the sensor sample stamped t + 12.3 ms matches the camera sample stamped t (sensor clock ahead "
             "of the camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)"),
    (-0.0123, "-12.3 ms: the sensor sample stamped t - 12.3 ms matches the camera sample stamped t (sensor clock "
              "behind the camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)"),
])
def test_the_offset_sign_in_words_in_the_summary(rng, offset, words):
    """The summary states the sign right for both signs (it printed 'ahead' whatever the sign)."""
    assert offset_in_words(offset) == words
    R0, camera, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.02)
    from replication.rig.streams import GyroStream

    # the rates as recorded (bias-free): the bias model moves the offset within its noise, here by
    # 0.01 ms
    r = calibrate(camera, GyroStream(gyro.t + offset, gyro.omega, "gyro"), n_bootstrap=20, gyro_bias=False)
    line = next(x for x in r.summary().splitlines() if x.startswith("time offset"))
    side = "ahead of" if offset > 0 else "behind"
    assert f"sensor clock {side} the camera's by 12.30 ms" in line and "95 % interval" in line
    lo, hi = r.time_offset_ci95_s
    assert lo <= offset <= hi and hi - lo < 2e-3


# ---------------------------------------------------------------------- a change inside a recording

def test_a_remount_inside_a_recording_fails_naming_the_time_and_both_estimates(rng):
    from replication.rig.changepoint import remounted

    R0, camera, gyro, _ = rig_streams(90.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.05)
    step = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))
    r = calibrate(camera, remounted(gyro, 45.0, step), n_bootstrap=20)
    reason = _reasons(r)["remount_deg"]
    assert r.verdict.level == "fail" and reason.level == "fail" and "after 45" in reason.message
    assert "R0 before (" in reason.message and "after (" in reason.message
    c = r.change_test
    assert c["significant"] and abs(c["split_time_s"] - 45.0) < 1.0 and c["angle_deg"] == pytest.approx(2.0, abs=0.05)
    assert so3.angle_between_deg(np.array(c["R0_before"]), R0) < 0.05
    assert so3.angle_between_deg(np.array(c["R0_after"]), R0 @ step) < 0.05
    jsonschema.validate(r.to_dict(), SCHEMA)
    clean = calibrate(camera, gyro, n_bootstrap=20)
    assert "remount_deg" not in _reasons(clean) and clean.change_test["run"] and not clean.change_test["significant"]


def test_a_short_recording_says_why_the_change_test_did_not_run(rng):
    R0, camera, gyro, _ = rig_streams(15.0, rng=rng, camera_noise_deg=0.05)
    r = calibrate(camera, gyro, n_bootstrap=0)
    assert not r.change_test["run"] and r.change_test["note"].startswith("not run: ")
    assert "change test: not run" in r.summary()


def test_an_input_mistake_is_not_called_a_remount(rng):
    R0, camera, gyro, _ = rig_streams(60.0, rng=rng, camera_noise_deg=0.05)
    q = so3.quaternion_from_matrix(camera.R)[:, [1, 2, 3, 0]]
    from replication.rig.streams import OrientationStream

    r = calibrate(OrientationStream(camera.t, so3.matrix_from_quaternion(q), "camera"), gyro, n_bootstrap=0)
    assert r.verdict.level == "fail" and "input_mistake" in _reasons(r) and "remount_deg" not in _reasons(r)
    assert r.change_test["sides_fit"] > THRESHOLDS["residual_to_motion"][1]


def _bias_stepped_rig(seed, size=0.02, at=30.0, seconds=60.0):
    """The red team's rig (camera 0.05 deg, gyro 0.2 deg/s, bias (0.03, -0.02, 0.04) rad/s) whose
    gyro bias steps by ``size`` rad/s along (1, -1, 1) at ``at`` s, the mount fixed."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)
    t_cam = np.arange(0.0, seconds, 0.05)
    from replication.testing import rig_motion

    C = rig_motion(t_cam, phase) @ so3.matrix_from_rotation_vector(
        rng.normal(0.0, np.radians(0.05) / np.sqrt(3.0), (len(t_cam), 3)))
    t_imu = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = rig_motion(t_imu, phase) @ R0
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    t = 0.5 * (t_imu[1:] + t_imu[:-1])
    omega = omega + [0.03, -0.02, 0.04] + ((t > at) * size)[:, None] * np.array([1, -1, 1]) / np.sqrt(3)
    omega = omega + rng.normal(0.0, np.radians(0.2), omega.shape)
    return OrientationStream(t_cam, C, "camera"), GyroStream(t, omega, "gyro")


def test_a_gyro_bias_step_is_named_with_its_time_and_size_not_a_remount(monkeypatch):
    """Seed 64000 (red team 6): left in, the step read as a re-mount at 9.2 s (fail); seed 64029:
    the whole's R0 moves by less than gyro_bias_change's floor, but a split's short side still
    took the step for a re-mount."""
    import replication.rig.calibration as cal

    camera, gyro = _bias_stepped_rig(64000)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    reasons = _reasons(r)
    assert "remount_deg" not in reasons and "segments_disagree" not in reasons and r.verdict.level == "warning"
    assert "a step of 1.1" in reasons["gyro_bias_change"].message and "at 30.0 s" in reasons["gyro_bias_change"].message
    assert "not a re-mount" in reasons["gyro_bias_change"].message
    change = r.segments["bias_change"]
    assert change["kind"] == "step" and abs(change["time_s"] - 30.0) <= 0.1
    assert change["size_rad_s"] == pytest.approx(0.02, rel=0.05)
    assert so3.angle_between_deg(r.R, R0) < 0.1
    jsonschema.validate(r.to_dict(), SCHEMA)
    small = calibrate(*_bias_stepped_rig(64029), n_bootstrap=0, diagnose=False)
    assert "remount_deg" not in _reasons(small) and abs(small.segments["bias_change"]["time_s"] - 30.0) <= 0.1
    monkeypatch.setattr(cal, "bias_change_of", lambda *a: None)
    left = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    assert left.segments["bias_change"] is None and "remount_deg" in _reasons(left)  # the wrong cause, left in


def test_use_consistent_drops_nothing_for_a_gyro_bias_step():
    camera, gyro = _bias_stepped_rig(64007)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False, use="consistent")
    assert r.segments["use"]["dropped_s"] == 0.0 and "segments_consistent_part" not in _reasons(r)
    assert "remount_deg" not in _reasons(r) and so3.angle_between_deg(r.R, R0) < 0.1


def test_map_resets_are_named_their_pairs_dropped_and_r0_from_the_rest(rng):
    """The camera's world frame turns 90 deg three times (a SLAM map re-initialised, no time gap):
    named with the times, the pairs spanning them dropped, R0 as without them."""
    _, camera, gyro, _ = rig_streams(60.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    R = np.array(camera.R)
    for k, at in enumerate((15.02, 30.02, 45.02)):
        R[camera.t > at] = so3.matrix_from_rotation_vector(np.radians(90.0) * np.array([np.cos(k), np.sin(k), 0.5])
                                                          / np.hypot(1.0, 0.5)) @ R[camera.t > at]
    r = calibrate(OrientationStream(camera.t, R, "camera"), gyro, n_bootstrap=20)
    reasons = _reasons(r)
    assert set(reasons) <= {"camera_jump"} and r.verdict.level == "warning"
    found = re.findall(r"(\d+\.\d\d) s \((\d+\.\d) deg\)", reasons["camera_jump"].message)
    assert [t for t, _ in found] == ["15.00", "30.00", "45.00"] and all(85 < float(a) < 95 for _, a in found)
    assert "the 60 pairs that span them were dropped" in reasons["camera_jump"].message
    assert [round(j["start_s"], 2) for j in r.segments["camera_jumps"]] == [15.0, 30.0, 45.0]
    assert so3.angle_between_deg(r.R, R0) < 0.05
    jsonschema.validate(r.to_dict(), SCHEMA)
    clean = calibrate(camera, gyro, n_bootstrap=0)
    assert clean.segments["camera_jumps"] == [] and "camera_jump" not in _reasons(clean)


# ------------------------------------------------------------------------------------------------
# handedness

def _rig_from_body_rates(out_of_plane: float, seed: int = 0, seconds: float = 40.0):
    """A camera turning about its x and y axes (and ``out_of_plane`` rad/s about z), a gyro on the
    same body."""
    from replication.rig.streams import GyroStream, OrientationStream

    rng = np.random.default_rng(seed)
    R0 = RIG_R0
    dt = 2e-3
    t = np.arange(-1.0, seconds + 1.0, dt)
    w = np.stack([0.7 * np.sin(0.9 * t), 0.6 * np.sin(1.3 * t + 1.0), out_of_plane * np.sin(0.5 * t + 2.0)], -1)
    C = np.concatenate([np.eye(3)[None], so3.cumulative_product(so3.matrix_from_rotation_vector(w[:-1] * dt))])
    k = np.arange(int(1.0 / dt), int((seconds + 1.0) / dt), 25)  # the camera at 20 Hz
    camera = OrientationStream(t[k], C[k] @ so3.matrix_from_rotation_vector(rng.normal(0, np.radians(0.1) / np.sqrt(3),
                                                                                       (len(k), 3))),
                               "camera")
    Q = C[::2] @ R0  # the gyro at 250 Hz
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / (2 * dt)
    omega += rng.normal(0, np.radians(0.2), omega.shape)
    return R0, camera, GyroStream(t[::2][:-1] + dt, omega, "gyro")


def test_rates_in_one_plane_cannot_show_a_flipped_gyro_axis_and_the_verdict_says_so():
    """Red team: a gyro with one axis's sign flipped and rates in one plane gave ok, radius 0.02
    deg, R0 126 deg off. The flipped gyro is exactly a right-handed one mounted otherwise; both now
    warn, naming the unturned axis."""
    from replication.rig.streams import GyroStream

    R0, camera, gyro = _rig_from_body_rates(0.0)
    normal = R0.T @ np.array([0.0, 0.0, 1.0])  # the camera's z axis in the sensor frame
    for g, n in ((gyro, normal), (GyroStream(gyro.t, gyro.omega * [1.0, 1.0, -1.0], "gyro"), normal * [1, 1, -1])):
        r = calibrate(camera, g, n_bootstrap=0)
        reason = _reasons(r)["mirror_fit_ratio"]
        assert r.verdict.level == "warning" and reason.level == "warning" and reason.measured < 1.5
        assert reason.threshold == THRESHOLDS["mirror_fit_ratio"][0]
        assert "one axis's sign flipped (a left-handed frame" in reason.message
        assert abs(np.dot(r.diagnostics["mirror_normal"], n)) > 0.99  # in the gyro's frame


def test_rates_about_a_third_axis_tell_the_flip_and_leave_no_such_warning():
    R0, camera, gyro = _rig_from_body_rates(0.3)
    r = calibrate(camera, gyro, n_bootstrap=0)
    assert "mirror_fit_ratio" not in _reasons(r) and r.diagnostics["mirror_fit_ratio"] > 10
    assert so3.angle_between_deg(r.R, R0) < 0.2


def test_a_remount_in_the_last_tenth_of_a_recording_fails_and_the_tested_splits_are_said():
    """Red team: a 5 deg re-mount at 55 s of 60 s gave ok (the splits left 15 % on each side)."""
    from replication.rig.calibration import CHANGE_MIN_SHARE
    from replication.rig.changepoint import remounted

    R0, camera, gyro, _ = rig_streams(60, rng=np.random.default_rng(3), camera_noise_deg=0.1, gyro_noise_deg_s=0.2)
    turn = so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5,
                                                                                                           0.81]))
    r = calibrate(camera, remounted(gyro, 55.0, turn), n_bootstrap=0)
    reason = _reasons(r)["remount_deg"]
    assert reason.level == "fail" and 54.0 <= r.change_test["split_time_s"] <= 56.0
    # the last split leaves 5 % of the pairs and 5 blocks (of 1 s) after it: later than 0.15's 51 s
    assert 60.0 * (1 - 0.15) < r.change_test["splits_to_s"] <= 60.0 * (1 - CHANGE_MIN_SHARE)
    assert "a change outside cannot be told" in r.summary()


# ---------------------------------------------------------------------- no clock, no offset


def test_a_stream_report_keeps_its_measured_clock_offset(rng):
    _, camera, gyro, _ = rig_streams(30.0, rng=rng, camera_noise_deg=0.05)
    report = calibrate(camera, gyro, n_bootstrap=0).to_dict()
    jsonschema.validate(report, SCHEMA)
    assert isinstance(report["time_offset_s"], float)


# --------------------------------------------------------------------------------------------------
# Two references: ``calibrate(reference=<two>)`` and ``calibrate --reference A --reference B``
# report the error to each, their disagreement (the reference floor) and which reading applies; one
# reference works as before.


SCHEMA_TR = json.loads((Path(__file__).resolve().parents[2] / "docs" / "calibration_report.schema.json").read_text())


def test_two_references_in_the_result_the_report_and_the_summary(rig_tr):
    R0, camera, gyro = rig_tr
    refs = np.stack([_turned(R0, 0.15), _turned(R0, -0.15)])  # 0.3 deg apart, the estimate between them
    r = calibrate(camera, gyro, n_bootstrap=20, reference=refs)
    e1, e2 = r.reference_errors_deg
    assert r.reference_disagreement_deg == pytest.approx(0.3, abs=1e-9)
    assert r.reference_error_deg == e1 and max(e1, e2) < 0.3  # the first stays the single error
    assert r.reference_reading.startswith("agreement, not accuracy")
    report = json.loads(json.dumps(r.to_dict(), allow_nan=False))
    jsonschema.validate(report, SCHEMA_TR)
    assert report["reference_errors_deg"] == [e1, e2] and report["reference_disagreement_deg"] == pytest.approx(0.3)
    assert report["reference_reading"] == r.reference_reading
    assert np.allclose(report["inputs"]["reference_camera_from_sensor"], refs[0], atol=1e-12)
    assert np.allclose(report["inputs"]["second_reference_camera_from_sensor"], refs[1], atol=1e-12)
    lines = r.summary().split("\n")
    assert f"angle to reference 1: {e1:.3f} deg, to reference 2: {e2:.3f} deg; the references disagree by 0.300 deg " \
           "(the reference floor)" in lines
    assert any(line.startswith("reading: agreement, not accuracy") for line in lines)
    assert not any(line.startswith("angle to the reference:") for line in lines)


def test_one_reference_works_as_before(rig_tr):
    R0, camera, gyro = rig_tr
    r = calibrate(camera, gyro, n_bootstrap=0, reference=_turned(R0, 0.15))
    assert r.reference_errors_deg is None and r.reference_disagreement_deg is None and r.reference_reading is None
    report = r.to_dict()
    jsonschema.validate(json.loads(json.dumps(report)), SCHEMA_TR)
    assert report["reference_errors_deg"] is None and "second_reference_camera_from_sensor" not in report["inputs"]
    assert f"angle to the reference: {r.reference_error_deg:.3f} deg" in r.summary().split("\n")
    assert np.allclose(report["inputs"]["reference_camera_from_sensor"], _turned(R0, 0.15), atol=1e-12)


@pytest.mark.parametrize("second_deg, level", [(0.9, None), (1.1, "warning"), (5.1, "fail")])
def test_the_second_reference_is_judged_as_the_first(rig_tr, second_deg, level):
    R0, camera, gyro = rig_tr
    r = calibrate(camera, gyro, n_bootstrap=0, reference=np.stack([R0, _turned(R0, second_deg, (0.0, 0.6, 0.8))]))
    reasons = {x.check: x for x in r.verdict.reasons}
    assert "reference_error_deg" not in reasons
    if level is None:
        assert "second_reference_error_deg" not in reasons
        return
    reason = reasons["second_reference_error_deg"]
    assert reason.level == level and reason.message.startswith("angle to the second reference ")
    assert r.reference_reading.startswith("closer to reference 1")


def _camchain(path, R):
    T = np.eye(4)
    T[:3, :3] = R
    path.write_text("cam0:\n  T_cam_imu:\n" + "".join(f"  - {row.tolist()}\n" for row in T))
    return path


def test_cli_takes_reference_twice_not_three_times(rig_tr, tmp_path, capsys):
    from replication.rig.streams import GyroStream, OrientationStream

    R0, camera, gyro = rig_tr
    write_tum_trajectory(tmp_path / "cam.txt", OrientationStream(camera.t + 1e3, camera.R, "c"))
    write_euroc_imu(tmp_path / "imu.csv", GyroStream(gyro.t + 1e3, gyro.omega, "g"))
    a, b = _camchain(tmp_path / "a.yaml", _turned(R0, 0.15)), _camchain(tmp_path / "b.yaml", _turned(R0, -0.15))
    base = ["calibrate", "--camera", tmp_path / "cam.txt", "--sensor", tmp_path / "imu.csv", "--sensor-kind", "gyro",
            "--bootstrap", "0", "--quiet"]
    out, fig = tmp_path / "r.json", tmp_path / "r.png"
    assert main([str(x) for x in base + ["--reference", a, "--reference", b, "--out", out, "--plot", fig]]) == 0
    text = capsys.readouterr().out
    assert "angle to reference 1: " in text and "the references disagree by 0.300 deg (the reference floor)" in text
    assert "reading: agreement, not accuracy" in text
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA_TR)
    assert report["files"]["reference"]["sha256"] != report["files"]["reference2"]["sha256"]
    assert report["files"]["reference2"]["camera_entry"] == "cam0"
    assert report["reference_disagreement_deg"] == pytest.approx(0.3, abs=1e-6) and fig.stat().st_size > 1000
    assert main([str(x) for x in base + ["--reference", a, "--out", out]]) == 0  # once: as before
    report = json.loads(out.read_text())
    assert "reference2" not in report["files"] and report["reference_errors_deg"] is None
    assert "angle to the reference: " in capsys.readouterr().out
    assert main([str(x) for x in base + ["--reference", a, "--reference", b, "--reference", a]]) == 2
    assert "--reference given 3 times: at most two (two published calibrations)" in capsys.readouterr().err
    assert main([str(x) for x in base + ["--reference", a, "--reference", tmp_path / "missing.yaml"]]) == 2
    assert "--reference (the second)" in capsys.readouterr().err


def test_figure_states_both_references_and_the_reading(rig_tr):
    import matplotlib.pyplot as plt

    R0, camera, gyro = rig_tr
    r = calibrate(camera, gyro, n_bootstrap=0, reference=np.stack([_turned(R0, 0.15), _turned(R0, -0.15)]))
    fig = r.plot(reference_name="a.yaml and b.yaml")
    text = " ".join(" ".join(t.get_text() for ax in fig.axes for t in ax.texts).split())
    assert "reference 1 (a.yaml): quaternion" in text and "reference 2 (b.yaml): quaternion" in text
    assert f"angle between R0 and it: {r.reference_errors_deg[1]:.3f} deg" in text
    assert "reading: agreement, not accuracy" in text
    plt.close(fig)


# ------------------------------------------------------------------------------ the overlap message
# (the command line's synthetic rig, 40 s on absolute times: tests/conftest.py)

def test_a_max_offset_beyond_the_overlap_is_named_with_durations(cli_rig):
    _, camera, gyro, _ = cli_rig
    from replication.rig.streams import GyroStream, OrientationStream

    cam = OrientationStream(camera.t + T0, camera.R, "camera")
    imu = GyroStream(gyro.t + T0, gyro.omega, "imu")
    with pytest.raises(OverlapError, match=r"the streams overlap by 40\.0 s \(camera 40\.0 s, sensor 42\.0 s long\)"
                       r".*max_offset 30 s is larger than the overlap allows.*\(above [\d.]+ s;") as err:
        calibrate(cam, imu, max_offset=30.0, n_bootstrap=0)
    assert "e+09" not in str(err.value) and "1520" not in str(err.value)  # durations, no absolute times
    bound = float(re.search(r"\(above ([\d.]+) s;", str(err.value)).group(1))
    from replication.rig.offset_search import overlap

    assert len(overlap(cam, imu, bound)[0]) >= 10  # the bound said is the search's: 10 camera samples at it
    with pytest.raises(OverlapError, match="max_offset"):
        calibrate(cam, imu, max_offset=bound + 1.0, n_bootstrap=0)
    assert calibrate(cam, imu, max_offset=2.0, n_bootstrap=0).n_pairs > 0


def test_streams_on_different_clocks_keep_the_start_times_that_show_it(cli_rig):
    _, camera, gyro, _ = cli_rig
    from replication.rig.streams import GyroStream, OrientationStream

    cam = OrientationStream(camera.t, camera.R, "camera")  # relative times
    imu = GyroStream(gyro.t + T0, gyro.omega, "imu")  # absolute times
    with pytest.raises(OverlapError, match=r"the sensor starts 15205\d+\.\d s after the camera ends.*the camera starts "
                       r"at t = 0\.000 s, the sensor at t = 1520529999\.00\d s: their clocks differ"):
        calibrate(cam, imu, n_bootstrap=0)


def test_the_overlap_error_survives_pickling_and_renaming():
    import pickle

    err = OverlapError("{option} 2 s is larger than the overlap")
    assert str(pickle.loads(pickle.dumps(err))) == "max_offset 2 s is larger than the overlap"
    assert str(err.named("--max-offset")) == "--max-offset 2 s is larger than the overlap"
    assert isinstance(err, ValueError)


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


@needs_real
@pytest.mark.parametrize("method", ["two_step_left", "two_step_right", "chordal_optimal"])
def test_tumvi_raw_gyro_within_0_2_deg_of_kalibr(method):
    d = rd.data_root() / "tumvi_room1_orbslam3mono"
    res = calibrate(rd.load_tum_trajectory(d / "orbslam3_mono_cam0_traj.txt"), rd.load_euroc_imu(d / "imu0_data.csv"),
                    method=method, reference=rd.load_reference(d / "camchain.yaml"), n_bootstrap=20)
    assert res.reference_error_deg < 0.2
    assert abs(res.time_offset_s) < 0.005
