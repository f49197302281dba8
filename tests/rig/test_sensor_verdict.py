"""The verdict on a gyro's sensor model: the held scales' reason."""
import dataclasses

import numpy as np
import pytest

from replication.rig import sensor_model as sm
from replication.rig.sensor_verdict import SENSOR_THRESHOLDS, sensor_reasons
from replication.testing import rig_streams


@pytest.fixture(scope="module")
def model():
    R0, camera, gyro = rig_streams(seconds=20.0, camera_noise_deg=0.05, gyro_noise_deg_s=0.2,
                                   rng=np.random.default_rng(3))[:3]
    return sm.estimate_sensor_model(camera, gyro)


def _held(model, effect, resolved=(True, True, False)):
    held = dataclasses.replace(model, scale_resolved=np.array(resolved),
                               scale_held_ci95=np.array([[np.nan, np.nan], [np.nan, np.nan], [0.97, 1.04]]),
                               scale_held_R0_deg=effect)
    return [x for x in sensor_reasons(held, interval=1.0, motion_median_deg=30.0) if x.check == "gyro_scale_held"]


@pytest.mark.parametrize("factor, fires", [(0.99, False), (1.01, True)])
def test_the_held_scales_reason_at_its_bound(model, factor, fires):
    bound = SENSOR_THRESHOLDS["gyro_scale_held_R0_deg"][0]
    found = _held(model, factor * bound)
    assert bool(found) == fires
    if fires:
        (reason,) = found
        assert reason.level == "warning" and reason.threshold == bound and reason.measured == factor * bound
        assert "not separable on this motion" in reason.message and "axis z [0.9700, 1.0400]" in reason.message
        assert "R0 may be off by" in reason.message and "axis x" not in reason.message


def test_no_held_scale_no_reason_whatever_its_effect(model):
    assert model.scale_resolved.all() and model.scale_held_R0_deg == 0.0
    assert not _held(model, 10.0, resolved=(True, True, True))
    assert not [x for x in sensor_reasons(model, interval=1.0, motion_median_deg=30.0) if x.check.startswith("gyro")]
