"""The gyro bias change (replication.rig.bias_change): a step is found at its time with its size, a
ramp is told from a step, the shortest side a step may leave is held at its boundary, a badly
tracked camera pose is clipped, and the change removed leaves the rates unbiased."""
from types import SimpleNamespace

import numpy as np
import pytest

from replication.rig.bias_change import MIN_SIDE_S, BiasChange, bias_change_of, fit_bias_change, rate_residuals
from replication.rig.streams import GyroStream, OrientationStream, integrate_gyro
from replication.testing import RIG_R0, rig_streams

DIRECTION = np.array([1.0, -1.0, 1.0]) / np.sqrt(3.0)


@pytest.fixture(scope="module")
def rig():
    rng = np.random.default_rng(5)
    _, camera, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    return camera, gyro


def _with(gyro, extra):
    return GyroStream(gyro.t, gyro.omega + extra(gyro.t)[:, None] * DIRECTION, gyro.source)


@pytest.mark.parametrize("at", [12.0, 27.5])
def test_a_step_is_found_at_its_time_with_its_size(rig, at):
    camera, gyro = rig
    change = fit_bias_change(camera, integrate_gyro(_with(gyro, lambda t: 0.02 * (t >= at))), RIG_R0, 0.0)
    assert change.kind == "step"
    assert abs(change.time_s - at) <= 0.1
    assert change.size_rad_s == pytest.approx(0.02, rel=0.05)
    assert change.after - change.before == pytest.approx(0.02 * DIRECTION, abs=2e-3)


def test_a_ramp_is_told_from_a_step(rig):
    camera, gyro = rig
    change = fit_bias_change(camera, integrate_gyro(_with(gyro, lambda t: 0.001 * t)), RIG_R0, 0.0)
    assert change.kind == "ramp"
    assert change.size_rad_s == pytest.approx(0.001 * 40.0, rel=0.1)
    assert np.isnan(change.time_s) and "steady drift" in change.words(0.0)


def test_a_step_leaves_at_least_min_side_s_on_each_side(rig):
    camera, gyro = rig
    inside = fit_bias_change(camera, integrate_gyro(_with(gyro, lambda t: 0.02 * (t >= MIN_SIDE_S + 0.5))),
                             RIG_R0, 0.0)
    assert abs(inside.time_s - (MIN_SIDE_S + 0.5)) <= 0.1
    near_start = fit_bias_change(camera, integrate_gyro(_with(gyro, lambda t: 0.02 * (t >= MIN_SIDE_S - 0.5))),
                                 RIG_R0, 0.0)
    assert near_start.time_s >= camera.t[0] + MIN_SIDE_S - 0.05
    short = OrientationStream(camera.t[:int(2 * MIN_SIDE_S / 0.05) - 2], camera.R[:int(2 * MIN_SIDE_S / 0.05) - 2])
    assert fit_bias_change(short, integrate_gyro(gyro), RIG_R0, 0.0) is None


def test_a_badly_tracked_pose_does_not_move_the_sides(rig):
    camera, gyro = rig
    R = np.array(camera.R)
    R[300] = R[300] @ np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # one pose 90 deg off
    oriented = integrate_gyro(_with(gyro, lambda t: 0.02 * (t >= 20.0)))
    clean = fit_bias_change(camera, oriented, RIG_R0, 0.0)
    bad = fit_bias_change(OrientationStream(camera.t, R, "camera"), oriented, RIG_R0, 0.0)
    assert np.linalg.norm(bad.before - clean.before) < 2e-3 and abs(bad.time_s - 20.0) <= 0.1


def test_the_change_removed_leaves_no_bias(rig):
    camera, gyro = rig
    stepped = _with(gyro, lambda t: 0.03 * (t >= 15.0))
    change = fit_bias_change(camera, integrate_gyro(stepped), RIG_R0, 0.0)
    _, _, e = rate_residuals(camera, integrate_gyro(change.corrected(stepped)), RIG_R0, 0.0)
    t = 0.5 * (camera.t[1:] + camera.t[:-1])
    for part in (t < 14.0, t > 16.0):
        assert np.linalg.norm(np.median(e[part], axis=0) - np.median(e, axis=0)) < 2e-3
    assert change.to_dict(5.0)["time_s"] == pytest.approx(change.time_s - 5.0)


def test_bias_at_holds_a_ramp_at_its_ends():
    change = BiasChange("ramp", float("nan"), np.zeros(3), np.ones(3), 10.0, 20.0, 0.0)
    assert change.bias_at(np.array([0.0, 15.0, 30.0])) == pytest.approx(np.array([[0.0] * 3, [0.5] * 3, [1.0] * 3]))


@pytest.mark.parametrize("changes", [False, True])
def test_the_change_is_fitted_only_where_the_halves_biases_differ(rig, changes):
    camera, gyro = rig
    model = SimpleNamespace(bias_changes=changes, R=RIG_R0, offset_mid_s=0.0)
    found = bias_change_of(model, camera, integrate_gyro(_with(gyro, lambda t: 0.02 * (t >= 20.0))))
    assert (found is not None) is changes
