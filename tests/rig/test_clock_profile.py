"""The offset profile (replication.rig.clock_profile): a clean rig and a drift are no step, a step
and two steps are; each model's decision at its thresholds; windows left out; a stamp skip told the
clock's. Rigs: ``replication.testing``'s noisy rig (60 s, a gyro bias) and its clock edits."""

import numpy as np
import pytest

from conftest import clock_rig as _rig
from conftest import drifting
from conftest import quiet_calibrate as _cal
from replication.core.so3 import matrix_from_rotation_vector
from replication.rig import clock_profile
from replication.rig.streams import GyroStream, integrate_gyro
from replication.testing import RIG_R0 as R0
from replication.testing import clock_drifting
from replication.testing import clock_stepped as lost
from replication.testing import noisy_rig as rig


def _profile(camera, gyro):
    return clock_profile.offset_profile(camera, integrate_gyro(gyro), R0, 0.0)


@pytest.mark.parametrize("ppm, choice", [(0.0, "one offset"), (200.0, "drift")])
def test_clean_and_drifting_clocks_are_no_step(ppm, choice):
    camera, gyro = _rig(8003)
    p = _profile(camera, drifting(gyro, ppm) if ppm else gyro)
    assert p.step is None and p.choice == choice
    if ppm:
        assert p.drift_ppm == pytest.approx(ppm, rel=0.2)


def _gains(p):
    """The least scaled chi-square gain of the one step and of the step with a drift over the
    models without a step (the bend's divided by BEND_SHARE), and the second's gain over the first
    as a share of STEP_LR."""
    c, n = p.chi2, len(p.t_s)
    s1, s2 = max(1.0, c["step"] / (n - 4)), max(1.0, c["step and drift"] / (n - 5))

    def over(x, scale):
        return min(c["drift"] - x, (c["drift that bends"] - x) / clock_profile.BEND_SHARE, c["one offset"] - x) / scale
    share = (c["step"] - c["step and drift"]) / s2 / clock_profile.STEP_LR
    return over(c["step"], s1), over(c["step and drift"], s2), share


def test_the_step_threshold_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8005)
    gyro = lost(gyro, 30.0, 2)  # a 10 ms step: the one step gains more than the step with a drift
    one, with_drift, _ = _gains(_profile(camera, gyro))
    assert one > with_drift
    monkeypatch.setattr(clock_profile, "STEP_LR", 1.01 * one)
    assert _profile(camera, gyro).step is None
    monkeypatch.setattr(clock_profile, "STEP_LR", 0.99 * one)
    assert _profile(camera, gyro).step.size_s == pytest.approx(-0.010, abs=0.002)


def test_a_step_with_a_drift_is_named_with_its_size_and_the_drift(monkeypatch):
    camera, gyro = _rig(8002)
    gyro = clock_drifting(lost(gyro, 30.0, 2), -100.0, 30.0)  # 10 ms lost and a drift the same way
    p = _profile(camera, gyro)
    one, with_drift, _ = _gains(p)
    assert one < clock_profile.STEP_LR < with_drift  # the one step alone was not named (a steep ramp fit as well)
    assert p.choice == "step" and p.step.size_s == pytest.approx(-0.010, abs=0.0015)
    assert p.drift_ppm == pytest.approx(-100.0, abs=30.0) and p.ratio_one > p.ratio_drift > clock_profile.STEP_LR
    monkeypatch.setattr(clock_profile, "STEP_LR", 1.01 * with_drift)
    assert _profile(camera, gyro).step is None
    monkeypatch.setattr(clock_profile, "STEP_LR", 0.99 * with_drift)
    assert _profile(camera, gyro).step.size_s == pytest.approx(-0.010, abs=0.0015)


def test_the_step_drift_share_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8001)
    gyro = clock_drifting(lost(gyro, 30.0, 2), -100.0, 30.0)
    one, with_drift, share = _gains(_profile(camera, gyro))
    assert min(one, with_drift) > clock_profile.STEP_LR  # both named: the drift kept where it gains the share
    monkeypatch.setattr(clock_profile, "STEP_DRIFT_SHARE", 0.99 * share)
    kept = _profile(camera, gyro)
    assert kept.step.size_s == pytest.approx(-0.010, abs=0.001) and kept.drift_ppm == pytest.approx(-100.0, abs=20.0)
    monkeypatch.setattr(clock_profile, "STEP_DRIFT_SHARE", 1.01 * share)
    alone = _profile(camera, gyro)  # the one step: the drift read into its size, the ramp's slope reported
    assert alone.step.size_s < -0.0125 and alone.drift_ppm < -250.0


def test_the_profile_refits_r0_with_the_windows_offsets():
    camera, gyro = _two_steps(8011)
    off = R0 @ matrix_from_rotation_vector(np.radians(0.3) * np.array([0.6, 0.0, 0.8]))  # R0 0.3 deg off
    sensor = integrate_gyro(gyro)
    errors = {refit: [abs(s.size_s - t) for s, t in
                      zip(clock_profile.offset_profile(camera, sensor, off, 0.0, refit=refit).steps, (-0.02, -0.03))]
              for refit in (False, True)}
    assert max(errors[False]) > 0.002 and max(errors[True]) < 0.0015


def test_the_step_size_floor_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8005)
    p = _profile(camera, lost(gyro, 30.0, 2))
    size = abs(p.step.size_s)
    monkeypatch.setattr(clock_profile, "JUMP_MIN_S", 1.01 * size)
    assert _profile(camera, lost(gyro, 30.0, 2)).step is None
    monkeypatch.setattr(clock_profile, "JUMP_MIN_S", 0.99 * size)
    assert _profile(camera, lost(gyro, 30.0, 2)).step is not None


def test_too_short_a_recording_has_no_profile():
    camera, gyro = rig(8006, 29.0, 0.05, 0.005)
    assert clock_profile.offset_profile(camera, integrate_gyro(gyro), R0, 0.0) is None
    r = _cal(camera, gyro)
    assert r.segments["clock_profile"] is None and r.segments["clock_jumps"] == []


def test_a_window_without_pairs_is_left_out_not_the_profile():
    camera, gyro = _rig(8007)
    keep = (gyro.t < 27.0) | (gyro.t > 33.5)  # 6.5 s of gyro lost (a gap in its stamps, the clock unchanged)
    p = _profile(camera, GyroStream(gyro.t[keep], gyro.omega[keep], "gyro"))
    assert p is not None and p.step is None and len(p.t_s) < 12 and not np.any((p.t_s > 28.0) & (p.t_s < 32.0))
    assert p.windows_left_out >= 1 and len(p.t_s) + p.windows_left_out == 11  # 11 windows of 5.45 s


def test_a_step_beyond_the_first_search_is_found_and_one_beyond_the_reach_is_not_a_crash():
    camera, gyro = _rig(8008)
    p = _profile(camera, lost(gyro, 30.0, 30))  # 150 ms lost, stamps even
    assert p.step is not None and p.step.size_s == pytest.approx(-0.150, abs=0.003)
    far = _profile(camera, lost(gyro, 30.0, 80))  # 400 ms: beyond PROFILE_REACH_S, its windows left out
    assert far is not None and far.windows_left_out >= 4


def _two_steps(seed, bias=0.0):
    camera, gyro = _rig(seed, bias=bias)
    return camera, lost(lost(gyro, 40.0, 6), 20.0, 4)  # -20 ms at 20 s, then -30 ms more at 40 s: no stamp skip


def _two_gains(p):
    """Two steps' scaled gain over every other model but the step with a drift, and over that; the
    step with a drift's own gain (it is named, and a rival, above STEP_LR)."""
    c, n = p.chi2, len(p.t_s)
    s2 = max(1.0, c["two steps"] / (n - 6))
    rivals = min(c["one offset"], c["drift"], c["drift that bends"], c["step"])
    return (rivals - c["two steps"]) / s2, (c["step and drift"] - c["two steps"]) / s2, _gains(p)[1]


def test_the_two_steps_threshold_at_its_boundary(monkeypatch):
    camera, gyro = _two_steps(8011)
    gain, _, with_drift = _two_gains(_profile(camera, gyro))
    assert with_drift < gain  # no rival near the boundary: the step with a drift is not named there
    monkeypatch.setattr(clock_profile, "STEP_LR", 1.01 * gain)
    assert len(_profile(camera, gyro).steps) <= 1
    monkeypatch.setattr(clock_profile, "STEP_LR", 0.99 * gain)
    assert [round(s.size_s, 2) for s in _profile(camera, gyro).steps] == [-0.02, -0.03]


def test_a_step_with_a_drift_is_a_rival_of_two_steps_only_where_it_is_named(monkeypatch):
    camera, gyro = _two_steps(8011)
    gain, over_drift, with_drift = _two_gains(_profile(camera, gyro))
    assert with_drift < clock_profile.STEP_LR < gain  # two steps named: the step with a drift is no rival
    monkeypatch.setattr(clock_profile, "TWO_STEPS_VS_DRIFT", 2.0 * over_drift / with_drift)  # it would be, if named
    monkeypatch.setattr(clock_profile, "STEP_LR", 1.01 * with_drift)
    assert len(_profile(camera, gyro).steps) == 2
    monkeypatch.setattr(clock_profile, "STEP_LR", 0.99 * with_drift)  # now named: two steps beat it by too little
    assert len(_profile(camera, gyro).steps) <= 1


def test_the_refit_leaves_out_the_windows_of_large_error_at_its_boundary(monkeypatch):
    camera, gyro = _two_steps(8011)
    off = R0 @ matrix_from_rotation_vector(np.radians(0.3) * np.array([0.6, 0.0, 0.8]))
    sensor = integrate_gyro(gyro)
    se = clock_profile.offset_profile(camera, sensor, off, 0.0, refit=False).se_s  # the windows the refit sees
    ratio = np.max(se) / np.median(se)  # the window across a step
    assert ratio > clock_profile.REFIT_SE
    offsets = {}
    for share in (0.99, 1.01, 2.0):
        monkeypatch.setattr(clock_profile, "REFIT_SE", share * ratio)
        offsets[share] = clock_profile.offset_profile(camera, sensor, off, 0.0).offset_s
    assert np.array_equal(offsets[1.01], offsets[2.0]) and not np.allclose(offsets[0.99], offsets[1.01], atol=1e-6)


def test_two_steps_are_named_inside_calibrate_where_its_r0_is_off():
    # calibrate's R0 (the sensor model's, one offset and a drift) was 0.1 deg off: the offsets crept
    # between the steps, a step with a drift came within 17 of two steps (bench seeds 0-29: seed 1)
    camera, gyro = _two_steps(1, bias=0.05)
    p = _cal(camera, gyro).segments["clock_profile"]
    assert [round(s["size_s"], 2) for s in p["steps"]] == [-0.02, -0.03]


def test_the_two_steps_size_floor_at_its_boundary(monkeypatch):
    camera, gyro = _two_steps(8011)
    least = min(abs(s.size_s) for s in _profile(camera, gyro).steps)
    monkeypatch.setattr(clock_profile, "TWO_STEPS_MIN_S", 1.01 * least)
    assert len(_profile(camera, gyro).steps) <= 1
    monkeypatch.setattr(clock_profile, "TWO_STEPS_MIN_S", 0.99 * least)
    assert len(_profile(camera, gyro).steps) == 2


def test_one_step_and_a_slow_drift_are_not_two_steps():
    camera, gyro = _rig(8000, bias=0.05)  # a 30 ms step; the offsets after it creep by 3 ms (one step and a drift)
    p = _cal(camera, lost(gyro, 30.0, 6)).segments["clock_profile"]
    (step,) = p["steps"]
    assert step["size_s"] == pytest.approx(-0.030, abs=0.002) and p["chi2"]["two steps"] < p["chi2"]["step"]


def test_a_short_skip_is_the_clock_s_at_the_match_boundary(monkeypatch):
    t = np.concatenate([np.arange(0.0, 30.0, 0.05), np.arange(30.02, 60.0, 0.05)])  # one 70 ms interval
    share = abs(0.020 - 0.025) / 0.025  # a 20 ms skip read against a 25 ms step
    monkeypatch.setattr(clock_profile, "SKIP_MATCH", 1.01 * share)
    assert clock_profile.skip(t, 30.0, 3.0, 0.025)[1] == pytest.approx(0.02)
    monkeypatch.setattr(clock_profile, "SKIP_MATCH", 0.99 * share)
    assert clock_profile.skip(t, 30.0, 3.0, 0.025) is None
    assert clock_profile.skip(t, 30.0, 3.0, -0.02) is None  # the skip says the other clock's sign
    assert clock_profile.skip(t, 40.0, 3.0, 0.02) is None  # not near the step


def _drift_stops(gyro, ppm, stop):
    return GyroStream(gyro.t + ppm * 1e-6 * (np.minimum(gyro.t, stop) - stop), gyro.omega, gyro.source)


def test_a_drift_that_stops_is_no_step():
    camera, gyro = _rig(8039, bias=0.05)  # before the drift that bends was a rival: a false 11 ms step at 17.6 s
    r = _cal(camera, _drift_stops(gyro, 500.0, 30.0))
    p = r.segments["clock_profile"]
    assert r.segments["clock_jumps"] == [] and p["choice"] == "drift" and p["steps"] == []
    assert p["chi2"]["drift that bends"] < p["chi2"]["step"] < p["chi2"]["drift"]  # the step only beat the one ramp


def test_the_bend_share_at_its_boundary(monkeypatch):
    camera, gyro = _rig(8006)
    gyro = lost(gyro, 30.0, 2)  # a 10 ms step: it beats the drift that bends by far less than the one ramp
    p = _profile(camera, gyro)
    c, n = p.chi2, len(p.t_s)
    scales = {"step": max(1.0, c["step"] / (n - 4)), "step and drift": max(1.0, c["step and drift"] / (n - 5))}
    share = max((c["drift that bends"] - c[m]) / (s * clock_profile.STEP_LR) for m, s in scales.items())
    assert share < 1.0  # named where either step model beats the bend by the share
    monkeypatch.setattr(clock_profile, "BEND_SHARE", 1.01 * share)
    assert _profile(camera, gyro).step is None
    monkeypatch.setattr(clock_profile, "BEND_SHARE", 0.99 * share)
    assert _profile(camera, gyro).step.size_s == pytest.approx(-0.010, abs=0.002)
