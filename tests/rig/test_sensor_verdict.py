"""The verdict on a gyro's sensor model: the reasons on the scales the motion does not separate."""
import dataclasses

import numpy as np
import pytest

from replication.rig import sensor_model as sm
from replication.rig.sensor_verdict import SENSOR_THRESHOLDS, sensor_reasons
from replication.testing import rig_streams

BOUND = SENSOR_THRESHOLDS["gyro_scale_held_R0_deg"][0]


@pytest.fixture(scope="module")
def model():
    R0, camera, gyro = rig_streams(seconds=20.0, camera_noise_deg=0.05, gyro_noise_deg_s=0.2,
                                   rng=np.random.default_rng(3))[:3]
    return sm.estimate_sensor_model(camera, gyro)


def _found(model, held_deg, spread_deg, resolved=(True, True, False)):
    moved = dataclasses.replace(model, scale_resolved=np.array(resolved),
                                scale_held_ci95=np.array([[np.nan, np.nan], [np.nan, np.nan], [0.97, 1.04]]),
                                scale_held_R0_deg=held_deg, scale_spread_R0_deg=spread_deg)
    return [x for x in sensor_reasons(moved, interval=1.0, motion_median_deg=30.0) if x.check.startswith("gyro_scale")]


@pytest.mark.parametrize("factor, fires", [(0.99, False), (1.01, True)])
def test_the_held_scales_reason_at_its_bound(model, factor, fires):
    found = _found(model, 0.7 * factor * BOUND, 0.3 * factor * BOUND)  # the held part and the spread added
    assert bool(found) == fires
    if fires:
        (reason,) = found
        assert reason.check == "gyro_scale_held" and reason.level == "warning" and reason.threshold == BOUND
        assert reason.measured == pytest.approx(factor * BOUND)
        assert "not separable on this motion" in reason.message and "axis z [0.9700, 1.0400]" in reason.message
        assert "R0 may be off by" in reason.message and "axis x" not in reason.message


@pytest.mark.parametrize("factor, fires", [(0.99, False), (1.01, True)])
def test_the_spread_reason_at_its_bound_where_no_scale_is_held(model, factor, fires):
    found = _found(model, 0.0, factor * BOUND, resolved=(True, True, True))
    assert bool(found) == fires
    if fires:
        (reason,) = found
        assert reason.check == "gyro_scale_spread" and reason.measured == pytest.approx(factor * BOUND)
        assert "poorly separated" in reason.message and "not in R0's bootstrap radius" in reason.message


def test_a_rich_motion_s_scales_give_no_reason(model):
    assert model.scale_resolved.all() and model.scale_held_R0_deg == 0.0
    assert 0.0 < model.scale_spread_R0_deg < 0.2 * BOUND
    assert not [x for x in sensor_reasons(model, interval=1.0, motion_median_deg=30.0) if x.check.startswith("gyro")]
