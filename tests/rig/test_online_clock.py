"""The live rig's clock watch (:mod:`replication.rig.online_clock`): after an event the offset is
measured again; a clock step is named (the event and a ``clock_jump`` reason) and paired with."""
import math
import warnings

import numpy as np
import pytest

from replication.rig.live import LiveRig, replay
from replication.rig.online import OnlineCalibrator
from replication.rig.online_clock import CLOCK_CHECK_S, CLOCK_STEP_MIN_S, ClockWatch
from replication.testing import RIG_R0, camera_clock_jumped, clock_stepped, noisy_rig


def _replay(camera, gyro):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return replay(camera, gyro, OnlineCalibrator(), reference=RIG_R0, diagnose=False)


def test_the_constants():
    assert CLOCK_CHECK_S == 15.0 and CLOCK_STEP_MIN_S == 0.010


@pytest.mark.parametrize("which", ["sensor", "camera"])
def test_a_30_ms_clock_step_is_named_and_paired_with(which):
    """30 ms at 30 s of 60 s (the sensor's clock without a skip in its stamps, or the camera's with
    one): was a ``noise_change`` in 5 of 6 runs; now a ``clock_jump`` event and reason with both
    offsets, the new offset used, R0 right."""
    camera, gyro = noisy_rig(8001, 60.0, 0.05, math.radians(0.2), bias_rad_s=0.04)
    if which == "sensor":
        gyro = clock_stepped(gyro, 30.0, 6)            # 6 samples of 5 ms lost, the stamps even
    else:
        camera = camera_clock_jumped(camera, 30.0, 0.030)
    rows = _replay(camera, gyro)
    s = rows.attrs["summary"]
    assert [e["kind"] for e in s["events"]] == ["clock_jump"]
    reason = [r for r in s["verdict"]["reasons"] if r["check"] == "clock_jump"]
    assert len(reason) == 1 and reason[0]["level"] == "warning"
    assert reason[0]["measured"] == pytest.approx(0.030, abs=0.012)  # two 15 s offsets: a few ms each
    assert "the clock offset moved from" in reason[0]["message"] and "a clock step" in reason[0]["message"]
    assert s["clock_offset_s"] == pytest.approx(-0.030, abs=0.008)  # paired with the new offset
    assert rows["error_deg"].iloc[-1] < 0.2


def test_a_clean_rig_names_no_clock_step():
    camera, gyro = noisy_rig(8001, 60.0, 0.05, math.radians(0.2), bias_rad_s=0.04)
    s = _replay(camera, gyro).attrs["summary"]
    assert not any(e["kind"] == "clock_jump" for e in s["events"])
    assert not any(r["check"] == "clock_jump" for r in s["verdict"]["reasons"])


@pytest.mark.parametrize("moved, named", [(0.9 * CLOCK_STEP_MIN_S, False), (1.1 * CLOCK_STEP_MIN_S, True)])
def test_an_offset_that_moved_is_a_step_from_clock_step_min_s_on(moved, named):
    rig = LiveRig(OnlineCalibrator(), offset=0.01, gyro_bias=False)
    watch = ClockWatch(0.2)
    watch.measure = lambda t_from, resolution: 0.01 + moved
    watch.residual_deg = lambda rig, t_from, offset: 1.0 if offset == 0.01 else 0.3  # the new offset fits
    watch.camera.append((100.0, np.eye(3)))
    watch.sensor.append((101.0, np.eye(3)))
    watch.baseline = 0.01
    watch.watch(100.0 - CLOCK_CHECK_S - 1.0, -1)
    watch.poll(rig, 1e-3)
    assert bool(watch.found) == named and not watch.pending
    assert rig.offset == pytest.approx(0.01 + moved if named else 0.01)


@pytest.mark.parametrize("fit, named", [(0.45, True), (0.55, False)])
def test_an_offset_that_moved_is_a_step_only_where_the_pairs_fit_with_it(fit, named):
    """A bias change also moves the offset the speeds give: a step needs the pairs since the alarm
    to fit with the new offset, their median residual at most CLOCK_FIT_SHARE (0.5) of the old."""
    rig = LiveRig(OnlineCalibrator(), offset=0.01, gyro_bias=False)
    watch = ClockWatch(0.2)
    watch.baseline = 0.01
    watch.measure = lambda t_from, resolution: 0.05
    watch.residual_deg = lambda rig, t_from, offset: 1.0 if offset == 0.01 else fit
    watch.camera.append((100.0, np.eye(3)))
    watch.sensor.append((101.0, np.eye(3)))
    watch.watch(100.0 - CLOCK_CHECK_S - 1.0, -1)
    watch.poll(rig, 1e-3)
    assert bool(watch.found) == named
    if named:
        assert "median residual 0.45 deg, 1 with the old" in watch.found[0].message
