"""The live rig's gyro bias (``rig/online_bias.py``): estimated with R0 on the first window,
removed, published with its interval, and ``ready`` withheld when it cannot be removed."""
import re
from collections import deque

import numpy as np
import pytest

from conftest import needs_real
from replication.core import so3
from replication.rig.online import OnlineCalibrator

BIAS = np.array([0.06, -0.08, 0.04])


def _biased_rig(seconds=40.0, seed=5):
    from replication.rig.streams import GyroStream
    from replication.testing import rig_streams

    R0, camera, gyro, _ = rig_streams(seconds, rng=np.random.default_rng(seed), camera_noise_deg=0.05,
                                      gyro_noise_deg_s=0.2)
    return R0, camera, GyroStream(gyro.t, gyro.omega + BIAS, "gyro")


def _live(camera, gyro, **options):
    from replication.rig.live import LiveRig

    rig = LiveRig(OnlineCalibrator(), diagnose=False, **options)
    for t, kind, k in sorted([(t, 1, k) for k, t in enumerate(camera.t)] + [(t, 0, k) for k, t in enumerate(gyro.t)]):
        rig.add_camera(t, camera.world_from_body[k]) if kind else rig.add_gyro(t, gyro.omega[k])
    rig.finish()
    return rig


def test_the_live_rig_removes_the_gyro_bias_and_publishes_it_with_its_interval():
    R0, camera, gyro = _biased_rig()
    rig = _live(camera, gyro)
    lo, hi = rig.bias.bias_ci95_rad_s[:, 0], rig.bias.bias_ci95_rad_s[:, 1]
    assert np.all(lo <= BIAS) and np.all(BIAS <= hi) and np.all(hi - lo < 0.01)
    assert rig.bias_effect_deg < rig.calibrator.target_deg
    assert rig.calibrator.error_deg(R0) < 0.1 and rig.calibrator.ready
    summary = rig.summary()
    assert summary["gyro_bias_rad_s"] == rig.bias.bias_rad_s.tolist() and summary["ready"]
    assert summary["gyro_bias_ci95_rad_s"] == rig.bias.bias_ci95_rad_s.tolist()
    assert summary["gyro_bias_R0_deg"] == rig.bias_effect_deg
    kept = _live(camera, gyro, gyro_bias=False)  # the bias left in: R0 about a degree off, and not ready
    assert kept.bias is None and kept.calibrator.error_deg(R0) > 0.5 and not kept.calibrator.ready
    assert kept.summary()["gyro_bias_rad_s"] is None


def test_a_bias_that_could_not_be_estimated_withholds_ready_naming_it():
    _, camera, gyro = _biased_rig(seconds=1.5)
    rig = _live(camera, gyro)
    assert rig.bias is None
    reasons = [r for r in rig.verdict().reasons if r.check == "gyro_bias"]
    assert len(reasons) == 1 and reasons[0].level == "fail" and "could not be estimated" in reasons[0].message
    assert any("gyro bias" in why for why in rig.calibrator.status()["not_ready"]) and not rig.calibrator.ready


@pytest.mark.parametrize("factor, reason", [(1.01, False), (0.99, True)])
def test_a_bias_interval_that_leaves_r0_beyond_the_target_withholds_ready(factor, reason):
    from replication.rig.online_bias import start_bias

    _, camera, gyro = _biased_rig(seconds=20.0)
    _, effect, _ = start_bias(camera, gyro, interval=1.0, max_offset=0.2, target_deg=1.0)
    model, again, found = start_bias(camera, gyro, interval=1.0, max_offset=0.2, target_deg=effect * factor)
    assert model is not None and again == effect and (found is not None) is reason
    if reason:
        assert found.check in ("gyro_bias", "gyro_scale") and found.level == "fail" and "leaves R0" in found.message


def test_gyro_bias_must_be_a_bool():
    from replication.rig.live import LiveRig

    with pytest.raises(ValueError, match="gyro_bias must be True or False"):
        LiveRig(OnlineCalibrator(), gyro_bias="yes")


def test_a_rest_at_the_start_makes_the_bias_wait_for_motion():
    """12 s at rest, then 40 s of motion (offset given): the bias cannot be estimated on the first
    20 s (most pairs at rest fit no rig), so the pairs wait; half a window later it is, and R0 is
    right."""
    from replication.rig.live import replay
    from replication.rig.streams import GyroStream, OrientationStream
    from replication.testing import rig_streams

    rng = np.random.default_rng(7)
    R0, cam, gyro, _ = rig_streams(40.0, rng=rng, camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    rest, moving = np.arange(0.0, 12.0, 0.05), gyro.t > 0
    camera = OrientationStream(np.r_[rest, cam.t + 12.0], np.concatenate(
        [np.repeat(cam.world_from_body[:1], len(rest), 0), cam.world_from_body]))
    t_rest = np.arange(-1.0, 12.0, 0.005)
    omega = np.concatenate([rng.normal(0, np.radians(0.2), (len(t_rest), 3)), gyro.omega[moving]]) + BIAS
    rows = replay(camera, GyroStream(np.r_[t_rest, gyro.t[moving] + 12.0], omega), OnlineCalibrator(), offset=0.0,
                  reference=R0, diagnose=False)
    summary = rows.attrs["summary"]
    assert summary["gyro_bias_rad_s"] == pytest.approx(BIAS.tolist(), abs=0.003)
    assert rows["t_seen"].iloc[0] >= 30.0 and summary["ready"] and rows["error_deg"].iloc[-1] < 0.1


@pytest.mark.parametrize("seconds", [24.995, 25.005])
def test_raw_samples_are_held_for_at_most_five_windows(seconds):
    """Samples every 10 ms: the held span stays within five windows, and no sample is dropped that
    is within it."""
    from replication.rig.online_bias import BIAS_WAIT_WINDOWS, hold_raw

    assert BIAS_WAIT_WINDOWS == 4
    raw = deque()
    for t in np.arange(0.0, 100.0, 0.01):
        hold_raw(raw, float(t), (0.0, 0.0, 0.0), seconds / 5)
    span = raw[-1][0] - raw[0][0]
    assert span <= seconds < span + 0.01


def test_pairs_held_while_the_bias_waits_are_all_formed_when_it_gives_up():
    """A rig at rest for 100 s (offset given): no bias on any window; after four windows it gives
    up, names why, and every held camera pose is still covered by the gyro (no pair dropped as if
    across a gap)."""
    from replication.rig.live import replay
    from replication.rig.streams import GyroStream, OrientationStream

    rng = np.random.default_rng(3)
    t_cam, t_gyro = np.arange(0.0, 100.0, 0.05), np.arange(-1.0, 101.0, 0.005)
    camera = OrientationStream(t_cam, np.repeat(so3.random_rotations(rng, ())[None], len(t_cam), 0))
    gyro = GyroStream(t_gyro, rng.normal(0.0, np.radians(0.2), (len(t_gyro), 3)) + BIAS)
    rows = replay(camera, gyro, OnlineCalibrator(), offset=0.0, diagnose=False)
    summary = rows.attrs["summary"]
    assert summary["pairs_dropped_at_gaps"] == 0 and summary["pairs"] + summary["repeated_pairs"] >= 45
    assert summary["gyro_bias_rad_s"] is None and not summary["ready"]
    assert any(r["check"] == "gyro_bias" and "could not be estimated" in r["message"]
               for r in summary["verdict"]["reasons"])
    assert rows["t_seen"].iloc[0] >= 80.0


SCALE = np.array([1.03, 1.0, 1.0])  # one gyro axis reads 3 % high: left at 1, R0 about 0.5 deg off (red team 5)


def _scaled_rig(seconds=40.0, seed=5):
    from replication.rig.streams import GyroStream

    R0, camera, gyro = _biased_rig(seconds, seed)
    return R0, camera, GyroStream(gyro.t, (gyro.omega - BIAS) * SCALE + BIAS, "gyro")


def test_the_live_rig_removes_a_gyro_scale_error_and_publishes_it_with_its_interval():
    R0, camera, gyro = _scaled_rig()
    rig = _live(camera, gyro)
    model = rig.bias
    lo, hi = model.scale_ci95[:, 0], model.scale_ci95[:, 1]
    assert model.scale_resolved.all() and lo[0] <= SCALE[0] <= hi[0] and np.all(hi - lo < 0.01)
    assert np.all(np.abs(model.scale - SCALE) < 3e-3)  # the intervals' coverage is measured over seeds (environment.md)
    assert np.allclose(rig._Ti, np.diag(1 / model.scale), atol=0.02)  # the scale divides every rate after the window
    assert np.allclose(np.linalg.inv(rig._Ti), np.diag(model.scale) + _symmetric(model.misalignment), atol=1e-12)
    assert rig.calibrator.error_deg(R0) < 0.1 and rig.calibrator.ready  # left at 1: about 0.5 deg off
    summary = rig.summary()
    assert summary["gyro_scale"] == model.scale.tolist() and summary["gyro_scale_ci95"] == model.scale_ci95.tolist()
    assert 0 < summary["gyro_scale_R0_deg"] <= summary["gyro_bias_R0_deg"] < rig.calibrator.target_deg


def test_the_held_samples_are_integrated_again_with_the_bias_and_the_scale():
    from replication.rig.online_bias import reintegrate

    samples = [(0.1 * k, (1.03 * 0.5 + 0.02, 0.01, -0.04)) for k in range(11)]
    out = reintegrate(samples, (0.02, 0.01, -0.04), ((1 / 1.03, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))
    assert out[0][1] == pytest.approx(np.eye(3)) and out[-1][0] == pytest.approx(1.0)
    assert so3.rotation_vector_from_matrix(out[-1][1]) == pytest.approx([0.5, 0.0, 0.0], abs=1e-12)


@pytest.mark.parametrize("factor, named", [(1.01, False), (0.99, True)])
def test_a_scale_interval_that_leaves_r0_beyond_the_target_withholds_ready_naming_the_scale(factor, named):
    from replication.rig.online_bias import _start

    _, camera, gyro = _scaled_rig(seconds=20.0)
    model, (joint, bias, scale, mis), _ = _start(camera, gyro, 1.0, 0.2, 1.0)
    assert scale > max(bias, mis)  # on this rig the scale's interval leaves more in R0 than the others'
    again, effects, found = _start(camera, gyro, 1.0, 0.2, joint * factor)
    assert effects == (joint, bias, scale, mis) and (found is not None) is named
    if named:
        assert found.check == "gyro_scale" and found.level == "fail"
        assert "gyro scale" in found.message and "leaves R0" in found.message
        assert re.search(r"x 1\.0[23]\d* \[", found.message)


def test_an_axis_whose_scale_is_held_at_1_is_taken_as_within_the_prior():
    from dataclasses import replace

    from replication.rig.online_bias import SCALE_PRIOR, bias_effect_deg, start_bias

    _, camera, gyro = _scaled_rig(seconds=20.0)
    model, _, _ = start_bias(camera, gyro, interval=1.0, max_offset=0.2, target_deg=1.0)
    _, _, resolved, _ = bias_effect_deg(camera, gyro, model, 1.0, parts=True)
    held = replace(model, scale_resolved=np.array([True, True, False]))
    joint, bias, scale, _ = bias_effect_deg(camera, gyro, held, 1.0, parts=True)
    assert SCALE_PRIOR == 0.03 and scale > 5 * resolved and joint >= scale  # z's scale unknown: R0 much less certain


def test_a_scale_not_resolved_on_a_short_first_window_makes_the_rig_wait_for_more_data():
    from replication.rig.streams import GyroStream

    R0, camera, gyro = _scaled_rig(seconds=60.0)
    late = GyroStream(gyro.t + 3.0, gyro.omega, "gyro")  # 3 s clock offset: the first window's pairs span 6 s only
    rig = _live(camera, late, max_offset=4.0)
    assert rig.bias is not None and rig.bias.scale_resolved.all() and rig.bias.span_s > 10.0  # 6 s: none resolved
    assert rig.bias.misalignment_resolved.all()
    assert not any(r.check in ("gyro_scale", "gyro_misalignment") for r in rig.verdict().reasons)
    assert rig.scale_effect_deg < 0.1 and rig.calibrator.error_deg(R0) < 0.1


@needs_real
def test_tumvi_a_gyro_scale_and_a_misalignment_are_removed_online_with_r0_unchanged():
    import warnings

    import replication.rig.realdata as rd
    from replication.rig.live import replay
    from replication.rig.streams import GyroStream, OrientationStream

    tum = rd.data_root() / "tumvi_room1_orbslam3mono"
    cam = rd.load_tum_trajectory(tum / "orbslam3_mono_cam0_traj.txt")
    imu, ref = rd.load_euroc_imu(tum / "imu0_data.csv"), rd.load_reference(tum / "camchain.yaml")
    keep, near = cam.t < cam.t[0] + 50.0, (imu.t > cam.t[0] - 1.0) & (imu.t < cam.t[0] + 51.0)  # 50 s: ready at 22
    cam = OrientationStream(cam.t[keep], cam.world_from_body[keep], "camera")
    runs = {}
    skew = np.eye(3) + _symmetric([0.015] * 3)  # 1.5 % on every term: left at 0, ready 1.1 deg off (red team 6)
    for name, T in (("recorded", np.eye(3)), ("x 3 % high", np.diag(SCALE)), ("misaligned", skew)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rows = replay(cam, GyroStream(imu.t[near], imu.omega[near] @ T.T, "gyro"), OnlineCalibrator(),
                          reference=ref)
        runs[name] = (rows["error_deg"].iloc[-1], rows.attrs["summary"])
    (err, plain), (err_x, scaled), (err_m, skewed) = runs["recorded"], runs["x 3 % high"], runs["misaligned"]
    assert plain["ready"] and scaled["ready"] and err < 0.1 and abs(err_x - err) < 0.01
    assert all(lo <= 1.0 <= hi for lo, hi in plain["gyro_scale_ci95"])  # TUM-VI's gyro: scale 1 on every axis
    lo, hi = scaled["gyro_scale_ci95"][0]
    assert lo <= 1.03 <= hi and scaled["gyro_scale"][0] == pytest.approx(1.03 * plain["gyro_scale"][0], abs=1e-3)
    assert not any(r["check"] == "gyro_scale" for r in scaled["verdict"]["reasons"])
    assert skewed["ready"] and err_m < 0.1  # 0.047 deg (recorded 0.027); left at 0 (all 145 s): 1.1
    assert all(lo <= 0.0 <= hi for lo, hi in plain["gyro_misalignment_ci95"])  # TUM-VI's gyro: orthogonal axes
    terms = zip(skewed["gyro_misalignment_ci95"], skewed["gyro_misalignment"], plain["gyro_misalignment"])
    for (lo, hi), m, m0 in terms:
        assert lo <= 0.015 + m0 <= hi and m == pytest.approx(0.015 + m0, abs=1e-3)


def test_the_live_rig_names_the_gyro_axes_in_not_ready_after_waiting_for_more_data():
    from replication.rig.live import LiveRig

    _, camera, gyro = _scaled_rig(seconds=30.0)
    found = {}
    for target in (0.01, 0.05):  # the joint radius: 0.028 deg on the first 20 s, 0.018 deg on all 30 s
        rig = LiveRig(OnlineCalibrator(target_deg=target), diagnose=False)
        samples = [(t, 1, k) for k, t in enumerate(camera.t)] + [(t, 0, k) for k, t in enumerate(gyro.t)]
        for t, kind, k in sorted(samples):
            rig.add_camera(t, camera.world_from_body[k]) if kind else rig.add_gyro(t, gyro.omega[k])
        rig.finish()
        found[target] = (rig.bias.span_s, [why for why in rig.calibrator.status()["not_ready"] if "gyro" in why],
                         [r for r in rig.verdict().reasons if r.check.startswith("gyro_")], rig.pairs_formed)
    (span, named, reasons, pairs), (span_ok, named_ok, reasons_ok, pairs_ok) = found[0.01], found[0.05]
    assert span > 25.0 and span_ok < 21.0 and pairs == pairs_ok  # waited to the end, every held pair formed
    assert len(named) == 1 and "leaves R0 uncertain" in named[0] and len(reasons) == 1 and reasons[0].level == "fail"
    # whichever leaves most: the misalignment (0.014 deg on 30 s), then the scale (0.010)
    assert reasons[0].check == "gyro_misalignment" and "misalignment" in named[0]
    assert not named_ok and not reasons_ok


MISALIGNED = np.array([0.015, 0.0, 0.015])  # T_g's xy, xz, yz: left at 0, ready with R0 0.3-0.5 deg off (red team 6)


def _symmetric(mu):
    """``N(mu)``: the symmetric off-diagonal matrix of the terms ``(xy, xz, yz)``."""
    (xy, xz, yz) = mu
    return np.array([[0.0, xy, xz], [xy, 0.0, yz], [xz, yz, 0.0]])


def _misaligned_rig(seconds=40.0, seed=5, mu=MISALIGNED):
    from replication.rig.streams import GyroStream

    R0, camera, gyro = _biased_rig(seconds, seed)
    T = np.eye(3) + _symmetric(mu)
    return R0, camera, GyroStream(gyro.t, (gyro.omega - BIAS) @ T.T + BIAS, "gyro")


def test_the_live_rig_removes_a_gyro_misalignment_and_publishes_it_with_its_interval():
    R0, camera, gyro = _misaligned_rig()
    rig = _live(camera, gyro)
    model = rig.bias
    lo, hi = model.misalignment_ci95[:, 0], model.misalignment_ci95[:, 1]
    assert model.misalignment_resolved.all() and np.all(lo <= MISALIGNED) and np.all(MISALIGNED <= hi)
    assert np.all(hi - lo < 0.008)
    T = np.diag(model.scale) + _symmetric(model.misalignment)
    assert np.allclose(np.linalg.inv(rig._Ti), T, atol=1e-12)  # T^-1 (omega - b) of every rate after the window
    assert rig.calibrator.error_deg(R0) < 0.1 and rig.calibrator.ready
    summary = rig.summary()
    assert summary["gyro_misalignment"] == model.misalignment.tolist()
    assert summary["gyro_misalignment_ci95"] == model.misalignment_ci95.tolist()
    assert 0 < summary["gyro_misalignment_R0_deg"] <= summary["gyro_bias_R0_deg"] < rig.calibrator.target_deg
    assert not any(r.check == "gyro_misalignment" for r in rig.verdict().reasons)


def test_the_held_samples_are_integrated_again_through_the_misalignment():
    from types import SimpleNamespace

    from replication.rig.online_bias import rate_correction, reintegrate

    T = np.diag([1.02, 1.0, 0.99]) + _symmetric([0.01, -0.02, 0.005])
    model = SimpleNamespace(bias_rad_s=np.array([0.02, 0.01, -0.04]), scale=np.array([1.02, 1.0, 0.99]),
                            misalignment=np.array([0.01, -0.02, 0.005]))
    b, Ti = rate_correction(model)
    truth = np.array([0.3, -0.2, 0.1])
    samples = [(0.1 * k, tuple(T @ truth + b)) for k in range(11)]
    out = reintegrate(samples, b, Ti)
    assert so3.rotation_vector_from_matrix(out[-1][1]) == pytest.approx(truth, abs=1e-12)
    assert rate_correction(None) == ((0.0, 0.0, 0.0), ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)))


def _terms_held(monkeypatch):
    """The first window's model with every misalignment term held at 0 (as on a window whose motion
    does not resolve them)."""
    from dataclasses import replace

    import replication.rig.sensor_verdict as sv

    estimate = sv.model_or_note

    def held(*args):
        model, note = estimate(*args)
        return (None if model is None else replace(model, misalignment=np.zeros(3),
                                                   misalignment_resolved=np.zeros(3, bool))), note

    monkeypatch.setattr(sv, "model_or_note", held)


def test_a_misalignment_term_held_at_0_is_taken_as_within_the_prior():
    from dataclasses import replace

    from replication.rig.online_bias import MISALIGNMENT_PRIOR, bias_effect_deg, start_bias

    _, camera, gyro = _biased_rig(seconds=20.0)
    model, _, _ = start_bias(camera, gyro, interval=1.0, max_offset=0.2, target_deg=1.0)
    assert model.misalignment_resolved.all()
    _, _, _, resolved = bias_effect_deg(camera, gyro, model, 1.0, parts=True)
    held = replace(model, misalignment_resolved=np.array([True, False, True]))
    joint, _, _, mis = bias_effect_deg(camera, gyro, held, 1.0, parts=True)
    assert MISALIGNMENT_PRIOR == 0.02 and mis > 5 * resolved and joint >= mis  # xz unknown: R0 much less certain


@pytest.mark.parametrize("factor, named", [(1.01, False), (0.99, True)])
def test_unresolved_misalignment_that_leaves_r0_beyond_the_target_withholds_ready_naming_it(
        monkeypatch, factor, named):
    from replication.rig.online_bias import _start

    _terms_held(monkeypatch)
    _, camera, gyro = _misaligned_rig(seconds=20.0)
    model, (joint, bias, scale, mis), _ = _start(camera, gyro, 1.0, 0.2, 5.0)
    assert mis > max(bias, scale)  # the terms held at 0 leave more in R0 than the bias and the scale
    again, effects, found = _start(camera, gyro, 1.0, 0.2, joint * factor)
    assert effects == (joint, bias, scale, mis) and (found is not None) is named
    if named:
        assert found.check == "gyro_misalignment" and found.level == "fail" and "leaves R0 uncertain" in found.message
        assert "misalignment" in found.message and "xy not resolved (held at 0, taken as within +-2 %)" in found.message


def test_the_live_rig_waits_for_the_misalignment_then_names_it_in_not_ready(monkeypatch):
    from replication.rig.live import LiveRig

    _terms_held(monkeypatch)
    _, camera, gyro = _misaligned_rig(seconds=30.0)
    rig = LiveRig(OnlineCalibrator(), diagnose=False)
    samples = [(t, 1, k) for k, t in enumerate(camera.t)] + [(t, 0, k) for k, t in enumerate(gyro.t)]
    for t, kind, k in sorted(samples):
        rig.add_camera(t, camera.world_from_body[k]) if kind else rig.add_gyro(t, gyro.omega[k])
    rig.finish()
    assert rig.bias.span_s > 25.0  # waited for more data to the end of the streams
    named = [why for why in rig.calibrator.status()["not_ready"] if "misalignment" in why]
    reasons = [r for r in rig.verdict().reasons if r.check == "gyro_misalignment"]
    assert len(named) == 1 and "leaves R0 uncertain" in named[0] and len(reasons) == 1 and reasons[0].level == "fail"
    assert not rig.calibrator.ready and rig.summary()["gyro_misalignment_ci95"] == [None, None, None]


@pytest.mark.parametrize("kind, size", [("step", 0.05), ("ramp", 0.05)])
def test_a_bias_that_changes_after_the_first_window_never_leaves_ready_wrong(kind, size):
    """The first window's bias is kept for the whole recording (not followed): a step of 0.05 rad/s
    at 60 s of 120 s, or a ramp to 0.05 rad/s from 20 s to the end, spoils the later pairs. Measured
    on 40 runs (seeds 14000-14007 of the red team's generator): never ready with R0 beyond the
    target or the radius; here: a change is seen, and the rig is not ready with R0 wrong."""
    import math
    import warnings

    from replication.rig.live import replay
    from replication.rig.streams import GyroStream
    from replication.testing import RIG_R0, noisy_rig

    camera, gyro = noisy_rig(14000, 120.0, 0.05, math.radians(0.2), bias_rad_s=0.04)
    share = np.clip((gyro.t - 20.0) / 100.0, 0.0, 1.0) if kind == "ramp" else (gyro.t >= 60.0).astype(float)
    direction = np.array([0.6, -0.3, 0.74]) / np.linalg.norm([0.6, -0.3, 0.74])
    gyro = GyroStream(gyro.t, gyro.omega + size * share[:, None] * direction, "gyro")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = replay(camera, gyro, OnlineCalibrator(), reference=RIG_R0, diagnose=False)
    s = rows.attrs["summary"]
    err = float(rows["error_deg"].iloc[-1])
    assert s["events"] and not any(e["kind"] == "clock_jump" for e in s["events"])  # seen; not a clock step
    assert not (s["ready"] and (err > s["target_deg"] or err > s["radius_deg"]))
