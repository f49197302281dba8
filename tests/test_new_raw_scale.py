"""A gyro axis's scale error estimated and named (issue 34's scale lie); the intervals' block jackknife."""
import dataclasses
import importlib.util
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from replication.core.so3 import angle_between_deg, exp_map
from replication.rig import sensor_model as sm
from replication.rig.calibration import calibrate
from replication.rig.gyro_model import critical_value
from replication.rig.sensor_verdict import SENSOR_THRESHOLDS, sensor_reasons
from replication.rig.streams import GyroStream, OrientationStream

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = json.loads((ROOT / "docs" / "calibration_report.schema.json").read_text())
_spec = importlib.util.spec_from_file_location("bench_sensor_model", ROOT / "benchmarks" / "bench_sensor_model.py")
bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(bench)
BIAS = np.array([0.03, -0.02, 0.04])


def _scaled(scale, seed=0, seconds=30.0):
    """``(R0, camera, gyro)``: the benchmark's noisy rig, its gyro reading ``scale * omega + BIAS``."""
    R0, camera, gyro = bench.biased_rig(seconds, camera_noise_deg=0.05, gyro_noise_deg_s=0.2,
                                        rng=np.random.default_rng(seed))
    return R0, camera, GyroStream(gyro.t, gyro.omega * np.asarray(scale, float) + BIAS, "gyro")


def _scale_reasons(model):
    return [x for x in sensor_reasons(model, interval=1.0, motion_median_deg=30.0) if x.check == "gyro_scale"]


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


def test_clean_gyro_scales_hold_1_and_give_no_reason():
    R0, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=3)
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    assert r.verdict.level == "ok" and angle_between_deg(r.R, R0) < 0.05
    ci = np.array(r.sensor_model["gyro_scale_ci95"], float)
    assert np.all((ci[:, 0] < 1.0) & (1.0 < ci[:, 1])) and np.all(ci[:, 1] - ci[:, 0] < 0.005)


def test_the_scale_jacobian_matches_finite_differences():
    _, camera, gyro = _scaled([1.03, 0.98, 1.0], seed=4)
    m = sm.estimate_sensor_model(camera, gyro)
    i, k = sm._pairs(camera, gyro.t, 1.0, m.offset_mid_s, 0.2)
    i, k = i[::40], k[::40]
    A = np.swapaxes(camera.R[k], -1, -2) @ camera.R[i]
    args = (A, camera.t[i], camera.t[k], 15.0, gyro.t, gyro.omega)
    sigma = np.log(m.scale)
    r0, jac = sm._linearise(m.R, m.bias_rad_s, m.offset_mid_s, 1e-5, *args, sigma)
    assert jac.shape[-1] == 11
    for col in (3, 4, 8, 9, 10):
        step = np.zeros(11)
        step[col] = 1e-6
        numeric = (sm._linearise(m.R, m.bias_rad_s + step[3:6], m.offset_mid_s, 1e-5, *args, sigma + step[8:])[0]
                   - r0) / 1e-6
        assert np.abs(numeric - jac[:, :, col]).max() < 0.02 * np.abs(jac[:, :, col]).max() + 1e-9, col


def _two_axis_rig(seed=5):
    """A sensor whose rates lie in its x-y plane (its z axis never turns): R0 is determined (the axes vary in that
    plane), z's scale is not."""
    from replication.rig.streams import integrate_gyro

    R0, rng = bench.R0_TRUE, np.random.default_rng(seed)
    t = np.arange(-1, 31, 0.005)
    w = np.stack([0.6 * np.sin(0.7 * t), 0.5 * np.sin(0.45 * t + 1.0), 0 * t], -1)
    Q = integrate_gyro(GyroStream(t, w, "truth")).R
    cam = slice(200, len(t) - 200, 10)  # 20 Hz inside the gyro's span
    C = Q[cam] @ R0.T @ exp_map(rng.normal(0, np.radians(0.05) / np.sqrt(3), (len(t[cam]), 3)))
    raw = w + BIAS + rng.normal(0, np.radians(0.2), w.shape)
    return R0, OrientationStream(t[cam], C, "camera"), GyroStream(t, raw, "gyro")


def test_an_axis_the_motion_does_not_turn_about_keeps_scale_1_and_says_so():
    R0, camera, gyro = _two_axis_rig()
    r = calibrate(camera, gyro, n_bootstrap=0, diagnose=False)
    report = r.to_dict()
    jsonschema.validate(report, SCHEMA)
    assert report["sensor_model"]["scale_resolved"] == [True, True, False]
    assert report["gyro_scale"][2] == 1.0 and report["gyro_scale_ci95"][2] is None
    assert "1 (held: not resolved)" in r.summary()
    assert angle_between_deg(r.R, R0) < 0.1


def test_the_critical_value_is_student_s_t_of_the_blocks():
    assert critical_value(7) == pytest.approx(2.447, abs=1e-3)  # 15 s at 20 Hz: 280 pairs, blocks of 40
    assert critical_value(29) == pytest.approx(2.048, abs=1e-3)  # 60 s
    assert critical_value(10 ** 6) == pytest.approx(1.96, abs=1e-3)


def test_the_jackknife_sees_a_block_that_pulls_the_fit():
    """Doubling one block's residuals along a parameter's gradient widens that parameter's jackknife deviation."""
    from replication.rig.gyro_model import _block_jackknife

    rng = np.random.default_rng(9)
    jac = rng.normal(size=(400, 3, 2))
    r = rng.normal(size=(400, 3))
    base = _block_jackknife(r, jac, np.ones(400), 40, np.arange(2))
    assert base[1] == 10 and base[0].shape == (2, 2) and np.all(np.linalg.eigvalsh(base[0]) > 0)
    r2 = r.copy()
    r2[:40] *= 5.0
    assert _block_jackknife(r2, jac, np.ones(400), 40, np.arange(2))[0][0, 0] > 2 * base[0][0, 0]


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
    """An axis's scale is estimated up to a 95 % half-width of SCALE_RESOLUTION, held at 1 just beyond it."""
    _, camera, gyro = _scaled([1.0, 1.0, 1.0], seed=10, seconds=15.0)
    m = sm.estimate_sensor_model(camera, gyro)
    half = np.log(m.scale_ci95[:, 1] / m.scale_ci95[:, 0]) / 2  # the intervals are exp(sigma +- t sd)
    worst = int(np.argmax(half))
    monkeypatch.setattr(sm, "SCALE_RESOLUTION", 1.01 * half[worst])
    assert sm.estimate_sensor_model(camera, gyro).scale_resolved.all()
    monkeypatch.setattr(sm, "SCALE_RESOLUTION", 0.99 * half[worst])
    held = sm.estimate_sensor_model(camera, gyro)
    assert not held.scale_resolved[worst] and held.scale[worst] == 1.0 and np.isnan(held.scale_ci95[worst]).all()
