"""A raw gyro's bias and the clock's drift estimated with R0."""
import dataclasses
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from conftest import one_axis_rig
from replication.core.so3 import angle_between_deg, matrix_from_rotation_vector, rotation_vector_from_matrix
from replication.rig import sensor_model as sm
from replication.rig.calibration import calibrate
from replication.rig.gyro_model import axes_matrix, critical_value
from replication.rig.sensor_verdict import SENSOR_THRESHOLDS, sensor_reasons
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import RIG_R0, misaligned_rig, rig_streams

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "calibration_report.schema.json").read_text())
BIAS = np.array([0.1, -0.1, 0.07])


def _rig(seed=0, **kw):
    """``(R0, camera, gyro)`` of the synthetic rig (:func:`replication.testing.rig_streams`): 30 s,
    noise on both."""
    rng = np.random.default_rng(seed)
    kw = {"seconds": 30.0, "camera_noise_deg": 0.05, "gyro_noise_deg_s": 0.2, "rng": rng, **kw}
    return rig_streams(**kw)[:3]


@pytest.fixture(scope="module")
def biased():
    R0, camera, gyro = _rig(bias=BIAS, offset=0.012)
    return R0, camera, gyro, sm.estimate_sensor_model(camera, gyro)


def test_bias_of_0_1_rad_s_per_axis_is_recovered_without_a_rest(biased):
    _, _, _, m = biased
    assert not m.start.startswith("rest")
    assert np.all(np.abs(m.bias_rad_s - BIAS) < 3e-4)
    lo, hi = m.bias_ci95_rad_s.T
    assert np.all(hi - lo < 2e-3) and np.all(np.abs(m.bias_rad_s - BIAS) < 1.5 * (hi - lo))  # coverage: the benchmark
    assert abs(m.offset_mid_s - 0.012) < 1e-3 and m.applied


def test_a_rest_is_used_where_there_is_one():
    _, camera, gyro = _rig(seed=1, bias=-BIAS, rest_s=3.0)
    assert sm.rest_periods(gyro) and sm.rest_periods(gyro)[0][0] < 0.0 < sm.rest_periods(gyro)[0][1] - 1.0
    m = sm.estimate_sensor_model(camera, gyro)
    assert m.start.startswith("rest") and np.all(np.abs(m.bias_rad_s + BIAS) < 3e-4)


def test_rest_periods_need_their_length_and_quiet():
    t = np.arange(0.0, 10.0, 0.005)
    w = np.random.default_rng(2).normal(0.0, 0.002, (len(t), 3)) + 0.01
    moving = (t > 3.0) & (t < 6.0)
    w[moving] += np.sin(3 * t[moving])[:, None] * np.array([1.0, 2.0, 3.0])
    found = sm.rest_periods(GyroStream(t, w, "g"))
    assert len(found) == 2 and found[0][0] == 0.0 and 2.5 < found[0][1] <= 3.0 and 6.0 <= found[1][0] < 6.5
    assert found[1][1] == t[-1]
    assert sm.rest_periods(GyroStream(t, w, "g"), min_s=3.5) == [found[1]]  # 4 s long; the first is 3 s


def test_the_bias_jacobian_matches_finite_differences(biased):
    _, camera, gyro, m = biased
    i, k = sm._pairs(camera, gyro.t, 1.0, m.offset_mid_s, 0.2)
    i, k = i[::40], k[::40]
    ti, tk = camera.t[i], camera.t[k]
    A = np.swapaxes(camera.R[k], -1, -2) @ camera.R[i]
    args = (A, ti, tk, 15.0, gyro.t, gyro.omega)
    x = [m.R, m.bias_rad_s, m.offset_mid_s, 1e-5]
    r0, jac = sm._linearise(*x, *args)
    for col, h in ((3, 1e-6), (5, 1e-6), (6, 1e-6), (7, 1e-7), (0, 1e-6)):
        step = np.zeros(8)
        step[col] = h
        y = [x[0] @ matrix_from_rotation_vector(step[:3]), x[1] + step[3:6], x[2] + step[6], x[3] + step[7]]
        numeric = (sm._linearise(*y, *args)[0] - r0) / h
        scale = np.abs(jac[:, :, col]).max()
        assert np.abs(numeric - jac[:, :, col]).max() < 0.02 * scale + 1e-9, col


def test_calibrate_removes_the_bias_and_reports_it(biased):
    R0, camera, gyro, m = biased
    r = calibrate(camera, gyro, n_bootstrap=30)
    assert r.verdict.level == "ok" and angle_between_deg(r.R, R0) < 0.05
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert np.allclose(report["gyro_bias_rad_s"], m.bias_rad_s)
    assert len(report["gyro_bias_ci95_rad_s"]) == 3 and report["sensor_model"]["bias_applied"] is True
    assert report["clock_drift_ci95_ppm"][0] <= 0.0 <= report["clock_drift_ci95_ppm"][1]
    text = r.summary()
    assert "gyro bias (x, y, z), deg/s with 95 % intervals: +5.7" in text and "(removed)" in text
    assert "clock drift:" in text and "not resolved" in text


def test_the_bias_left_in_is_named_as_a_gyro_bias(biased):
    R0, camera, gyro, _ = biased
    r = calibrate(camera, gyro, n_bootstrap=30, gyro_bias=False)
    reasons = {x.check: x for x in r.verdict.reasons}
    assert r.verdict.level == "fail" and angle_between_deg(r.R, R0) > 0.3
    assert reasons["gyro_bias_left"].level == "fail"
    assert "gyro bias not removed" in reasons["gyro_bias_left"].message
    assert "--no-gyro-bias" in reasons["gyro_bias_left"].message
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["sensor_model"]["bias_applied"] is False and report["parameters"]["gyro_bias"] is False


def test_bias_free_data_give_the_same_answer_with_and_without_the_model():
    R0, camera, gyro = _rig(seed=3)
    on, off = (calibrate(camera, gyro, n_bootstrap=30, gyro_bias=flag) for flag in (True, False))
    assert on.verdict.level == off.verdict.level == "ok"
    assert angle_between_deg(on.R, off.R) < 0.01 and angle_between_deg(on.R, R0) < 0.05
    lo, hi = np.array(on.sensor_model["gyro_bias_ci95_rad_s"]).T
    assert np.all((lo <= 0) & (0 <= hi))
    assert off.sensor_model["gyro_bias_rad_s"] is None  # ok without the model: not measured


def test_an_orientation_sensor_has_null_sensor_fields(biased):
    from replication.rig.streams import integrate_gyro

    _, camera, gyro, _ = biased
    report = calibrate(camera, integrate_gyro(GyroStream(gyro.t, gyro.omega - BIAS, "s")), n_bootstrap=0).to_dict()
    assert all(report[k] is None for k in ("gyro_bias_rad_s", "gyro_bias_ci95_rad_s", "clock_drift_ppm",
                                           "clock_drift_ci95_ppm", "sensor_model"))


def test_unrelated_streams_give_no_model_and_say_so(biased):
    _, camera, gyro, _ = biased
    other = GyroStream(gyro.t, np.roll(gyro.omega, 3000, axis=0)[:, [2, 0, 1]] * 0.3 + 0.1, "unrelated")
    with pytest.raises(ValueError, match="angular speeds do not match"):
        sm.estimate_sensor_model(camera, other)
    with pytest.raises(ValueError, match="needs a camera OrientationStream and a GyroStream"):
        sm.estimate_sensor_model(camera, camera)
    r = calibrate(camera, other, n_bootstrap=0, diagnose=False)
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_bias_not_estimated"]
    assert "not estimated" in reason.message and "np.float64" not in reason.message


def test_a_bias_that_changes_half_way_is_named():
    R0, camera, gyro = _rig(seed=4, bias=BIAS)
    w = gyro.omega + np.where(gyro.t[:, None] > 15.0, np.array([0.0, 0.0, 0.02]), 0.0)
    m = sm.estimate_sensor_model(camera, GyroStream(gyro.t, w, "warming"))
    assert m.bias_changes and m.change_R0_deg > SENSOR_THRESHOLDS["gyro_bias_change_R0_deg"][0]
    assert abs(m.halves_rad_s[1, 2] - m.halves_rad_s[0, 2] - 0.02) < 0.004
    (reason,) = [x for x in sensor_reasons(m, interval=1.0, motion_median_deg=30.0) if x.check == "gyro_bias_change"]
    assert "changes over the recording" in reason.message and "temperature" in reason.message


@pytest.mark.parametrize("ppm", [0.0, 50.0, 200.0])
def test_clock_drift_is_estimated_with_its_interval(ppm):
    _, camera, gyro = _rig(seed=5, seconds=60.0, bias=BIAS, offset=-0.01, ppm=ppm)
    m = sm.estimate_sensor_model(camera, gyro)
    lo, hi = m.drift_ci95_ppm
    assert lo <= ppm <= hi and hi - lo < 60.0
    assert m.drift_resolved == (ppm > 0)
    reasons = [x for x in sensor_reasons(m, interval=1.0, motion_median_deg=30.0) if x.check == "clock_drift"]
    assert len(reasons) == (ppm == 200.0)  # 200 ppm over 60 s: 6 ms at the ends of 1 s pairs; 50 ppm: 1.5 ms
    if reasons:
        assert "the sensor clock drifts +" in reasons[0].message and "ppm" in reasons[0].message


def _model(biased, **changes):
    return dataclasses.replace(biased[3], **changes)


def _checks(model, motion, interval=1.0):
    return {x.check: x for x in sensor_reasons(model, interval=interval, motion_median_deg=motion)}


def test_bias_to_motion_at_its_boundary(biased):
    m = _model(biased)
    per_pair = np.degrees(np.linalg.norm(m.bias_rad_s))
    bound = SENSOR_THRESHOLDS["gyro_bias_to_motion"][0]
    assert "gyro_bias_to_motion" not in _checks(m, per_pair / (0.99 * bound))
    above = _checks(m, per_pair / (1.01 * bound))["gyro_bias_to_motion"]
    assert above.level == "warning" and "large gyro bias, removed" in above.message


@pytest.mark.parametrize("ratio, level", [(0.099, None), (0.101, "warning"), (0.299, "warning"), (0.301, "fail")])
def test_bias_left_at_its_boundaries(biased, ratio, level):
    m = _model(biased, applied=False)
    per_pair = np.degrees(np.linalg.norm(m.bias_rad_s))
    found = _checks(m, per_pair / ratio).get("gyro_bias_left")
    assert (found.level if found else None) == level


def test_clock_drift_reason_at_its_boundary(biased):
    bound = SENSOR_THRESHOLDS["clock_drift_share"][0]
    span = biased[3].span_s
    at = bound * 2 * 1.0 / span * 1e6  # ppm whose half change over the span is the bound at 1 s
    for factor, fires in ((0.99, False), (1.01, True)):
        m = _model(biased, drift_ppm=factor * at, drift_ci95_ppm=(factor * at - 5, factor * at + 5))
        assert ("clock_drift" in _checks(m, 30.0)) == fires
    m = _model(biased, drift_ppm=2 * at, drift_ci95_ppm=(-1.0, 4 * at))  # large but not resolved
    assert "clock_drift" not in _checks(m, 30.0)


def test_bias_change_reason_at_its_floor(biased):
    floor = SENSOR_THRESHOLDS["gyro_bias_change_R0_deg"][0]
    changing = dict(change_statistic=50.0, change_threshold=11.34)
    assert "gyro_bias_change" not in _checks(_model(biased, change_R0_deg=0.99 * floor, **changing), 30.0)
    assert "gyro_bias_change" in _checks(_model(biased, change_R0_deg=1.01 * floor, **changing), 30.0)
    assert "gyro_bias_change" not in _checks(_model(biased, change_R0_deg=10 * floor, change_statistic=11.0,
                                                    change_threshold=11.34), 30.0)


def test_a_model_that_does_not_fit_gives_no_reasons(biased):
    m = _model(biased, applied=False, fit_ratio=sm.MAX_FIT_RATIO * 1.01)
    assert sensor_reasons(m, interval=1.0, motion_median_deg=0.1) == []


def test_a_model_that_fits_no_rig_is_not_applied(biased):
    from replication.core.so3 import matrix_from_quaternion, quaternion_from_matrix
    from replication.rig.streams import OrientationStream

    _, camera, gyro, _ = biased
    q = quaternion_from_matrix(camera.world_from_body)[:, [1, 2, 3, 0]]  # quaternions read in the wrong order
    wrong = OrientationStream(camera.t, matrix_from_quaternion(q), "camera")
    r = calibrate(wrong, gyro, n_bootstrap=0, diagnose=False)
    assert r.sensor_model["sensor_model"]["bias_applied"] is False and r.sensor_model["gyro_bias_rad_s"] is None
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_bias_not_estimated"]
    assert "fit no rig" in reason.message and "no bias was removed" in reason.message


def test_the_figure_states_the_bias_and_the_drift(biased):
    from replication.rig.figure import headline

    _, camera, gyro, _ = biased
    _, lines = headline(calibrate(camera, gyro, n_bootstrap=0, diagnose=False))
    assert any(x.startswith("gyro bias (x, y, z), deg/s with 95 % intervals: +5.7") for x in lines)
    assert any(x.startswith("clock drift:") for x in lines)


def _steady_turn(seed=2):
    """A rig turning steadily about z (0.35 rad/s) while it rocks about x and y: the angular speeds
    barely vary."""
    R0, rng = RIG_R0, np.random.default_rng(seed)

    def world_from_camera(t):
        rock = matrix_from_rotation_vector(np.stack([0.5 * np.sin(0.7 * t), 0.4 * np.sin(0.45 * t + 1), 0 * t], -1))
        return matrix_from_rotation_vector(np.stack([0 * t, 0 * t, 0.35 * t], -1)) @ rock

    t_cam, t_imu = np.arange(0, 40, 0.05), np.arange(-1, 41, 0.005)
    C = world_from_camera(t_cam) @ matrix_from_rotation_vector(rng.normal(0, np.radians(0.05) / np.sqrt(3), (len(t_cam),
                                                                                                             3)))
    Q = world_from_camera(t_imu) @ R0
    w = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005 + BIAS + rng.normal(0, np.radians(0.2),
                                                                                         (len(t_imu) - 1, 3))
    return R0, OrientationStream(t_cam, C, "camera"), GyroStream(0.5 * (t_imu[1:] + t_imu[:-1]), w, "gyro")


def test_an_offset_the_pairs_refuse_is_named():
    """The speeds' correlation puts the offset 7.5 ms off on a steady turn (R0 0.23 deg off, ok
    before); the pairs put it within 1 ms of the truth (0; 0.6 ms with the gyro's scale estimated,
    its standard deviation 0.45 ms)."""
    R0, camera, gyro = _steady_turn()
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    reason = {x.check: x for x in r.verdict.reasons}["offset_disagreement"]
    assert r.verdict.level == "warning" and "the pairs fit best with the clock offset at" in reason.message
    assert abs(r.sensor_model["sensor_model"]["offset_mid_s"]) < 1e-3 and abs(r.time_offset_s) > 5e-3


def test_offset_disagreement_at_its_boundary(biased):
    from replication.rig.sensor_verdict import _offsets_disagree

    _, camera, gyro, m = biased
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    assert "offset_disagreement" not in {x.check for x in r.verdict.reasons}
    bound = SENSOR_THRESHOLDS["offset_disagreement_share"][0]
    for factor, fires in ((0.99, False), (1.01, True)):
        shifted = dataclasses.replace(r, time_offset_s=m.offset_mid_s + factor * bound * 1.0)
        assert (_offsets_disagree(m, shifted, 1.0) is not None) == fires
    assert _offsets_disagree(m, dataclasses.replace(r, time_offset_s=m.offset_mid_s + 0.1,
                                                     time_offset_applied=False), 1.0) is None


# --------------------------------------------------------------------------------------------------
# A gyro axis's scale error estimated and named; the intervals' block jackknife.

SCALE_RIG_BIAS = MISALIGNMENT_BIAS = np.array([0.03, -0.02, 0.04])


def _scale_reasons(model):
    return [x for x in sensor_reasons(model, interval=1.0, motion_median_deg=30.0) if x.check == "gyro_scale"]


def _scaled(scale, seed=0, seconds=30.0):
    """``(R0, camera, gyro)``: the noisy rig of :func:`_rig`, its gyro reading ``scale * omega +
    SCALE_RIG_BIAS``."""
    R0, camera, gyro = _rig(seed, seconds=seconds)
    return R0, camera, GyroStream(gyro.t, gyro.omega * np.asarray(scale, float) + SCALE_RIG_BIAS, "gyro")


@pytest.fixture(scope="module")
def five_percent():
    R0, camera, gyro = _scaled([1.05, 1.0, 1.0])
    return R0, camera, gyro, calibrate(camera, gyro, n_bootstrap=20, diagnose=False)


def test_a_5_percent_scale_error_is_estimated_removed_and_named(five_percent):
    R0, _, _, r = five_percent
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    scale, ci = np.array(report["gyro_scale"]), np.array(report["gyro_scale_ci95"], float)
    assert abs(scale[0] - 1.05) < 2e-3 and np.all(np.abs(scale[1:] - 1.0) < 2e-3)
    assert np.all((ci[:, 0] < [1.05, 1, 1]) & ([1.05, 1, 1] < ci[:, 1]))
    assert angle_between_deg(r.R, R0) < 0.05  # 0.67-1.2 deg off with the scale left at 1
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_scale"]
    assert r.verdict.level == "warning" and reason.level == "warning"
    assert "gyro scale error: axis x 1.05" in reason.message and "moves R0 by about" in reason.message
    assert reason.threshold == SENSOR_THRESHOLDS["gyro_scale_error"][0] and abs(reason.measured - 0.05) < 2e-3
    assert report["sensor_model"]["scale_R0_deg"] > 0.343  # left at 1, beyond EuRoC's reference floor
    line = next(x for x in r.summary().splitlines() if x.startswith("gyro scale (x, y, z) with 95 % intervals: "))
    assert float(line.split(": ")[1].split(" ")[0]) == pytest.approx(1.05, abs=2e-3) and line.endswith("(removed)")


def test_clean_gyro_scales_hold_1_and_give_no_reason():
    R0, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=3)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    assert r.verdict.level == "ok" and angle_between_deg(r.R, R0) < 0.05
    ci = np.array(r.sensor_model["gyro_scale_ci95"], float)
    assert np.all((ci[:, 0] < 1.0) & (1.0 < ci[:, 1])) and np.all(ci[:, 1] - ci[:, 0] < 0.005)


def _two_axis_rig(seed=5):
    """A sensor whose rates lie in its x-y plane (its z axis never turns): R0 is determined (the
    axes vary in that plane), z's scale is not."""
    from replication.rig.streams import integrate_gyro

    R0, rng = RIG_R0, np.random.default_rng(seed)
    t = np.arange(-1, 31, 0.005)
    w = np.stack([0.6 * np.sin(0.7 * t), 0.5 * np.sin(0.45 * t + 1.0), 0 * t], -1)
    Q = integrate_gyro(GyroStream(t, w, "truth")).R
    cam = slice(200, len(t) - 200, 10)  # 20 Hz inside the gyro's span
    C = Q[cam] @ R0.T @ matrix_from_rotation_vector(rng.normal(0, np.radians(0.05) / np.sqrt(3), (len(t[cam]), 3)))
    raw = w + SCALE_RIG_BIAS + rng.normal(0, np.radians(0.2), w.shape)
    return R0, OrientationStream(t[cam], C, "camera"), GyroStream(t, raw, "gyro")


def test_an_axis_the_motion_does_not_turn_about_keeps_scale_1_and_says_so():
    R0, camera, gyro = _two_axis_rig()
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["sensor_model"]["scale_resolved"] == [True, True, False]
    assert report["gyro_scale"][2] == 1.0 and report["gyro_scale_ci95"][2] is None
    assert "1 (held: not resolved; fitted free, it lies in [" in r.summary()
    assert angle_between_deg(r.R, R0) < 0.1


def test_the_model_intervals_use_the_critical_value():
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=6, seconds=15.0)
    m = sm.estimate_sensor_model(camera, gyro)
    assert m.critical == pytest.approx(critical_value(m.n_pairs // 40))  # blocks of two 1 s intervals at 20 Hz
    assert m.critical > 2.3
    sd = np.sqrt(np.diag(m.covariance))
    lo, hi = m.drift_ci95_ppm
    assert (hi - lo) / 2 == pytest.approx(1e6 * m.critical * sd[7], rel=1e-9)
    assert np.allclose(m.bias_ci95_rad_s[:, 1] - m.bias_rad_s, m.critical * sd[3:6])
    assert m.report()["sensor_model"]["interval_critical_value"] == pytest.approx(m.critical)


@pytest.mark.parametrize("factor, held", [(1.15, False), (1.25, True)])
def test_a_scale_beyond_any_gyro_s_error_is_held_at_1_and_said(factor, held):
    _, camera, gyro = _scaled([factor, 1.0, 1.0], seed=7)
    m = sm.estimate_sensor_model(camera, gyro)
    assert (m.scale_note is not None) == held and bool(m.scale_resolved.any()) != held
    if held:
        assert np.all(m.scale == 1.0) and "no gyro's scale error (units?" in m.scale_note
        assert m.report()["gyro_scale_ci95"] == [None, None, None]
    else:
        assert abs(m.scale[0] - factor) < 2e-3 and m.report()["sensor_model"]["scale_note"] is None


def test_a_gyro_in_deg_per_s_is_not_taken_for_a_scale():
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=8)
    r = calibrate(camera, GyroStream(gyro.t, np.degrees(gyro.omega), "gyro"), n_bootstrap=0)
    assert r.verdict.level == "fail" and "deg/s read as rad/s" in r.summary()
    assert not any(x.check == "gyro_scale" for x in r.verdict.reasons)


def test_the_resolution_rule_at_its_boundary(monkeypatch):
    """An axis's scale is estimated up to a 95 % half-width of SCALE_RESOLUTION, held at 1 just
    beyond it."""
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=10, seconds=15.0)
    m = sm.estimate_sensor_model(camera, gyro)
    half = np.log(m.scale_ci95[:, 1] / m.scale_ci95[:, 0]) / 2  # the intervals are exp(sigma +- t sd)
    worst = int(np.argmax(half))
    monkeypatch.setattr(sm, "SCALE_RESOLUTION", 1.01 * half[worst])
    assert sm.estimate_sensor_model(camera, gyro).scale_resolved.all()
    monkeypatch.setattr(sm, "SCALE_RESOLUTION", 0.99 * half[worst])
    held = sm.estimate_sensor_model(camera, gyro)
    assert not held.scale_resolved[worst] and held.scale[worst] == 1.0 and np.isnan(held.scale_ci95[worst]).all()


_BEYOND = np.log1p(sm.SCALE_DEPARTURE)


@pytest.mark.parametrize("away, half, kept", [
    (0.02 + _BEYOND + 1e-4, 0.02, True), (0.02 + _BEYOND - 1e-4, 0.02, False),  # interval just beyond 1 +- 1 %
    (-0.02 - _BEYOND - 1e-4, 0.02, True), (-0.02 - _BEYOND + 1e-4, 0.02, False),
    (0.015, 0.01, False),  # excluding 1 but not 1 +- 1 %: a clean gyro's chance
    (np.log1p(sm.MAX_SCALE_ERROR) - 0.0301, 0.03, True),  # its interval's far end just inside the gyro's range
    (np.log1p(sm.MAX_SCALE_ERROR) - 0.0299, 0.03, False)])  # just beyond it
def test_a_scale_departure_is_measured_at_its_boundaries(away, half, kept):
    assert bool(sm._departs(np.array([away]), np.array([half]))[0]) == kept


def test_an_axis_the_motion_turns_about_little_but_off_by_10_percent_is_estimated_not_held():
    """15 s about one axis (the red team's seed 9300): z's interval is 3 % wide (beyond the
    resolution) and excludes 1. Held at 1, x took up its error (1.04, named, interval excluding its
    truth 1) and R0 was 2.8 deg off."""
    camera, gyro = one_axis_rig((1.0, 1.0, 1.10), 9300)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    m = r.diagnostics["sensor_model"]
    half = np.log(m.scale_ci95[2, 1] / m.scale_ci95[2, 0]) / 2
    assert m.scale_resolved.all() and half > sm.SCALE_RESOLUTION and m.scale_ci95[2, 0] < 1.10 < m.scale_ci95[2, 1]
    assert np.all((m.scale_ci95[:2, 0] < 1.0) & (1.0 < m.scale_ci95[:2, 1]))
    assert angle_between_deg(r.R, RIG_R0) < 0.3
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_scale"]
    assert "axis z 1.10" in reason.message and "axis x" not in reason.message


def test_a_held_axis_s_interval_holds_its_truth_and_bounds_r0_s_error():
    """The red team's seed 9130 (15 s about one axis, z 10 % high, its interval 6 % wide and
    including 1): z is held, the other axes' intervals (widened by what z leaves unknown) hold
    their truth 1, z's interval fitted free holds 1.10, R0's error (2.9 deg) is within what the held
    scale may do to it, and the verdict says so instead of naming x."""
    camera, gyro = one_axis_rig((1.0, 1.0, 1.10), 9130)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    m = r.diagnostics["sensor_model"]
    assert list(m.scale_resolved) == [True, True, False] and m.scale[2] == 1.0
    assert np.all((m.scale_ci95[:2, 0] < 1.0) & (1.0 < m.scale_ci95[:2, 1]))
    assert m.scale_held_ci95[2, 0] <= 1.0 and m.scale_held_ci95[2, 0] < 1.10 < m.scale_held_ci95[2, 1]
    assert np.isnan(m.scale_held_ci95[:2]).all()
    err = angle_between_deg(r.R, RIG_R0)
    assert 1.0 < err < m.scale_held_R0_deg
    assert r.verdict.level == "warning" and not any(x.check == "gyro_scale" for x in r.verdict.reasons)
    (held,) = [x for x in r.verdict.reasons if x.check == "gyro_scale_held"]
    assert "not separable" in held.message and "axis z [" in held.message
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["sensor_model"]["scale_held_ci95"][:2] == [None, None]
    assert report["sensor_model"]["scale_held_R0_deg"] == pytest.approx(m.scale_held_R0_deg)
    assert "1 (held: not resolved; fitted free, it lies in [" in r.summary()


def test_a_clean_gyro_on_motion_about_one_axis_is_not_ok():
    """No scale error, 15 s about one axis (seed 5203): z is held at 1 and right, but nothing on
    this motion says so: a scale in its interval would move R0 by up to 0.9 deg."""
    camera, gyro = one_axis_rig((1.0, 1.0, 1.0), 5203)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    m = r.diagnostics["sensor_model"]
    assert not m.scale_resolved[2] and m.scale_held_R0_deg > SENSOR_THRESHOLDS["gyro_scale_held_R0_deg"][0]
    assert angle_between_deg(r.R, RIG_R0) < 0.1 and r.verdict.level == "warning"
    # the scale named by its own reason; the misalignment terms the motion leaves held by theirs
    assert [x.check for x in r.verdict.reasons if x.check != "gyro_held"] == ["gyro_scale_held"]


def test_a_clean_gyro_on_motion_about_one_axis_with_every_scale_resolved_is_not_ok():
    """No scale error, 15 s about one axis (seed 5604): every scale resolved, but their uncertainty
    carries R0's (0.33 deg radius), beyond its bootstrap radius (0.17): R0 0.42 deg off was ok."""
    camera, gyro = one_axis_rig((1.0, 1.0, 1.0), 5604)
    r = calibrate(camera, gyro, n_bootstrap=20, diagnose=False)
    m = r.diagnostics["sensor_model"]
    assert m.scale_resolved.all() and m.scale_held_R0_deg == 0.0
    assert angle_between_deg(r.R, RIG_R0) > 0.343 > r.bootstrap_ci95_deg
    assert m.scale_spread_R0_deg > SENSOR_THRESHOLDS["gyro_scale_held_R0_deg"][0]
    checks = [x.check for x in r.verdict.reasons if x.check != "gyro_held"]  # the held misalignment: its own
    assert r.verdict.level == "warning" and checks == ["gyro_scale_spread"]


def test_the_two_axis_rig_s_held_axis_moves_r0_by_nothing():
    """z never turns: its scale is held, fitted free anywhere in the gyro's range, and moves R0 by
    nothing the verdict needs to say."""
    _, camera, gyro = _two_axis_rig()
    m = sm.estimate_sensor_model(camera, gyro)
    assert not m.scale_resolved[2] and m.scale_held_R0_deg < 0.05
    assert np.all(np.abs(np.log(m.scale_held_ci95[2])) <= np.log1p(sm.MAX_SCALE_ERROR) + 1e-12)
    assert not any(x.check == "gyro_scale_held" for x in sensor_reasons(m, interval=1.0, motion_median_deg=30.0))


def test_the_scale_jacobian_matches_finite_differences():
    _, camera, gyro = _scaled([1.03, 0.98, 1.0], seed=4)
    m = sm.estimate_sensor_model(camera, gyro)
    i, k = sm._pairs(camera, gyro.t, 1.0, m.offset_mid_s, 0.2)
    i, k = i[::40], k[::40]
    A = np.swapaxes(camera.R[k], -1, -2) @ camera.R[i]
    args = (A, camera.t[i], camera.t[k], 15.0, gyro.t, gyro.omega)
    sigma = np.log(m.scale)
    r0, jac = sm._linearise(m.R, m.bias_rad_s, m.offset_mid_s, 1e-5, *args, sigma)
    assert jac.shape[-1] == 14
    for col in (3, 4, 8, 9, 10):
        step = np.zeros(11)
        step[col] = 1e-6
        numeric = (sm._linearise(m.R, m.bias_rad_s + step[3:6], m.offset_mid_s, 1e-5, *args, sigma + step[8:])[0]
                   - r0) / 1e-6
        assert np.abs(numeric - jac[:, :, col]).max() < 0.02 * np.abs(jac[:, :, col]).max() + 1e-9, col


@pytest.mark.parametrize("error, fires", [(0.008, False), (0.012, True), (-0.008, False), (-0.012, True)])
def test_the_scale_reason_at_its_boundary_of_1_percent(error, fires):
    _, camera, gyro = _scaled([1.0, 1.0 + error, 1.0], seed=1)
    m = sm.estimate_sensor_model(camera, gyro)
    assert abs(m.scale[1] - (1.0 + error)) < 1e-3 and m.scale_resolved.all()
    assert bool(_scale_reasons(m)) == fires


def test_the_reason_needs_the_interval_to_exclude_1_and_the_bound_exceeded():
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=2)
    m = sm.estimate_sensor_model(camera, gyro)
    assert not _scale_reasons(m)
    bound = SENSOR_THRESHOLDS["gyro_scale_error"][0]
    for s, ci, fires in ((1 + 0.99 * bound, (1.009, 1.011), False), (1 + 1.01 * bound, (1.009, 1.011), True),
                         (1 + 1.01 * bound, (0.999, 1.021), False)):  # inside its interval: not named
        moved = dataclasses.replace(m, scale=np.array([1.0, 1.0, s]),
                                    scale_ci95=np.array([[0.999, 1.001], [0.999, 1.001], ci]))
        assert bool(_scale_reasons(moved)) == fires
    held = dataclasses.replace(m, scale=np.array([1.0, 1.0, 1.5]), scale_ci95=np.array([[0.999, 1.001]] * 3),
                               scale_resolved=np.array([True, True, False]))
    assert not _scale_reasons(held)  # an axis held at 1 names no scale


def _misaligned(size, seed):
    """The benchmark's misaligned rig (40 s): the gyro reads ``(I + N(mu)) omega + b``, terms of
    ``size``."""
    return misaligned_rig(seed, size, bias=MISALIGNMENT_BIAS)


@pytest.fixture(scope="module")
def two_percent_misaligned():
    R0, camera, gyro, mu = _misaligned(0.02, 72008)  # before the terms were modelled: ok, R0 1.28 deg off
    return R0, camera, gyro, mu, calibrate(camera, gyro, n_bootstrap=0, diagnose=False)


def test_a_2_percent_misalignment_is_estimated_removed_and_named(two_percent_misaligned):
    R0, _, _, mu, r = two_percent_misaligned
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    est, ci = np.array(report["gyro_misalignment"]), np.array(report["gyro_misalignment_ci95"], float)
    assert np.all(np.abs(est - mu) < 1e-3) and np.all((ci[:, 0] < mu) & (mu < ci[:, 1]))
    assert report["sensor_model"]["misalignment_resolved"] == [True, True, True]
    assert angle_between_deg(r.R, R0) < 0.05
    assert report["sensor_model"]["misalignment_R0_deg"] > 0.343  # left at 0, beyond EuRoC's reference floor
    (reason,) = [x for x in r.verdict.reasons if x.check == "gyro_misalignment"]
    assert r.verdict.level == "warning" and reason.level == "warning"
    assert "gyro axes misaligned" in reason.message and "moves R0 by about" in reason.message
    assert "T_g" in reason.message
    assert reason.threshold == SENSOR_THRESHOLDS["gyro_misalignment_error"][0] and abs(reason.measured - 0.02) < 1e-3
    line = next(x for x in r.summary().splitlines() if x.startswith("gyro misalignment (xy, xz, yz"))
    assert float(line.split("intervals: ")[1].split(" ")[0]) == pytest.approx(mu[0], abs=1e-3)
    assert line.endswith("(removed)")


def test_the_model_s_corrected_rates_undo_the_axes(two_percent_misaligned):
    _, _, gyro, mu, r = two_percent_misaligned
    m = r.diagnostics["sensor_model"]
    T = axes_matrix(np.log(m.scale), m.misalignment)
    true = np.array([[0.3, -0.2, 0.5], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    back = m.corrected(GyroStream(gyro.t[:3], true @ T.T + m.bias_rad_s, "g"))  # it reads T omega + b
    assert np.allclose(back.omega, true) and abs(T[0, 1] - mu[0]) < 1e-3


def test_a_clean_gyro_gives_no_misalignment_reason_and_intervals_about_0():
    R0, camera, gyro, _ = _misaligned(0.0, 72022)  # the clean set's largest R0 error
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    assert r.verdict.level == "ok" and angle_between_deg(r.R, R0) < 0.05
    assert not any(x.check == "gyro_misalignment" for x in r.verdict.reasons)
    est, ci = np.array(r.sensor_model["gyro_misalignment"]), np.array(r.sensor_model["gyro_misalignment_ci95"], float)
    assert np.all(np.abs(est) < 0.0015) and np.all(ci[:, 1] - ci[:, 0] < 0.004)


def _misalignment_reasons(model):
    return [x for x in sensor_reasons(model, interval=1.0, motion_median_deg=30.0) if x.check == "gyro_misalignment"]


@pytest.mark.parametrize("size, fires", [(0.003, False), (0.005, True)])
def test_the_misalignment_reason_at_its_bound_of_0_4_percent(size, fires):
    _, camera, gyro, mu = _misaligned(size, 72001)
    m = sm.estimate_sensor_model(camera, gyro)
    assert np.all(np.abs(m.misalignment - mu) < 5e-4) and m.misalignment_resolved.all()
    assert bool(_misalignment_reasons(m)) == fires


def test_the_misalignment_reason_needs_the_interval_to_exclude_0_and_the_bound_exceeded():
    _, camera, gyro, _ = _misaligned(0.0, 72002)
    m = sm.estimate_sensor_model(camera, gyro)
    assert not _misalignment_reasons(m)
    bound = SENSOR_THRESHOLDS["gyro_misalignment_error"][0]
    for v, ci, fires in ((0.99 * bound, (0.0035, 0.0045), False), (-1.01 * bound, (-0.0045, -0.0035), True),
                         (1.01 * bound, (-0.001, 0.009), False)):  # inside its interval: not named
        moved = dataclasses.replace(m, misalignment=np.array([0.0, 0.0, v]),
                                    misalignment_ci95=np.array([[-0.001, 0.001], [-0.001, 0.001], ci]))
        assert bool(_misalignment_reasons(moved)) == fires
    held = dataclasses.replace(m, misalignment=np.array([0.0, 0.0, 0.05]),
                               misalignment_ci95=np.array([[-0.001, 0.001]] * 2 + [[0.04, 0.06]]),
                               misalignment_resolved=np.array([True, True, False]))
    assert not _misalignment_reasons(held)  # a term held at 0 names nothing


def test_the_misalignment_resolution_rule_at_its_boundary(monkeypatch):
    """A term is estimated up to a 95 % half-width of MISALIGNMENT_RESOLUTION, held at 0 just beyond
    it."""
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=10, seconds=15.0)
    m = sm.estimate_sensor_model(camera, gyro)
    half = (m.misalignment_ci95[:, 1] - m.misalignment_ci95[:, 0]) / 2
    worst = int(np.argmax(half))
    monkeypatch.setattr(sm, "MISALIGNMENT_RESOLUTION", 1.01 * half[worst])
    assert sm.estimate_sensor_model(camera, gyro).misalignment_resolved.all()
    monkeypatch.setattr(sm, "MISALIGNMENT_RESOLUTION", 0.99 * half[worst])
    held = sm.estimate_sensor_model(camera, gyro)
    assert not held.misalignment_resolved[worst] and held.misalignment[worst] == 0.0
    assert np.isnan(held.misalignment_ci95[worst]).all() and held.report()["gyro_misalignment_ci95"][worst] is None
    assert held.scale_resolved.all()  # the scale's own rule is unchanged


def test_a_misalignment_beyond_any_gyro_s_holds_every_term_and_says_so():
    _, camera, gyro, _ = _misaligned(0.0, 72003)
    T = axes_matrix(np.zeros(3), [0.3, 0.0, 0.0])
    m = sm.estimate_sensor_model(camera, GyroStream(gyro.t, (gyro.omega - MISALIGNMENT_BIAS) @ T.T, "g"))
    assert m.scale_note is not None and "no gyro's scale error" in m.scale_note
    assert np.all(m.misalignment == 0.0) and not m.misalignment_resolved.any()


def test_the_terms_of_an_axis_whose_scale_is_held_are_held_at_0_and_said():
    """z never turns: its scale is held at 1, and so are its terms xz, yz (left free they took up a
    changing bias)."""
    _, camera, gyro = _two_axis_rig()
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["sensor_model"]["misalignment_resolved"] == [True, False, False]
    assert report["gyro_misalignment"][1:] == [0.0, 0.0] and report["gyro_misalignment_ci95"][1:] == [None, None]
    line = next(x for x in r.summary().splitlines() if x.startswith("gyro misalignment"))
    assert line.count("0 (held: not resolved)") == 2


def test_a_bias_that_changes_half_way_is_not_taken_for_a_misalignment():
    _, camera, gyro = _rig(seed=4, bias=BIAS)
    w = gyro.omega + np.where(gyro.t[:, None] > 15.0, np.array([0.0, 0.0, 0.02]), 0.0)
    m = sm.estimate_sensor_model(camera, GyroStream(gyro.t, w, "warming"))
    assert m.bias_changes and not _misalignment_reasons(m)
