"""The online estimator's words earn their meaning: ``ready`` only when the motion determines R0 (excitation, distinct
pairs, a radius with a noise floor, a verdict that does not fail), repeated pairs not counted, alarms confirmed and
told apart (re-mount, noise change, outliers, new information), every parameter validated; each rule is tested at
its boundary."""
import math

import numpy as np
import pytest

from replication.core import so3
from replication.core.stats import radius_deg
from replication.rig.online import MIN_EXCITATION_DEG, NOISE_FLOOR_DEG, OnlineCalibrator
from replication.rig.online_events import DUPLICATE_DEG, SMALL_MOTION_DEG, RepeatFilter
from replication.study.live_study import pair_stream


@pytest.fixture
def R0(rng):
    return so3.random_rotations(rng, ())


def _feed(A, B, **kw):
    oc = OnlineCalibrator(**kw)
    return oc, oc.update_many(A, B)


# ------------------------------------------------------------------------------------------------ ready = determined

def test_single_axis_noise_free_motion_is_never_ready_and_the_axis_is_named(rng, R0):
    axis = np.array([0.3, 0.4, 0.5]) / np.linalg.norm([0.3, 0.4, 0.5])
    A, B = pair_stream(rng, 200, R0, noise_deg=0.0, axis=axis)
    oc, states = _feed(A, B)
    assert not any(s.ready for s in states) and not oc.determined
    assert oc.excitation_deg < 1e-3
    named = np.array(oc.status()["least_excited_axis_sensor"])
    assert abs(named @ (R0.T @ axis)) > 0.999  # the sensor-frame axis of the motions
    assert any("does not determine R0" in m for m in oc.status()["not_ready"])
    assert oc.radius > 1e3  # the noise floor over an unexcited axis: no radius of 0


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_named_axis_has_one_sign_whatever_the_motions_direction(rng, R0, sign):
    # eigh's eigenvector sign is arbitrary (it flipped between numpy's AVX-512 and AVX2 paths in notebook 08): the
    # axis is named with its largest component positive
    axis = sign * np.array([0.3, 0.4, 0.5]) / np.linalg.norm([0.3, 0.4, 0.5])
    A, B = pair_stream(rng, 200, R0, noise_deg=0.0, axis=axis)
    oc, _ = _feed(A, B)
    named = np.array(oc.status()["least_excited_axis_sensor"])
    assert named[np.argmax(abs(named))] > 0 and abs(named @ (R0.T @ axis)) > 0.999


def test_one_pair_repeated_is_one_pair(rng, R0):
    A, B = pair_stream(rng, 1, R0)
    oc, states = _feed(np.repeat(A, 200, 0), np.repeat(B, 200, 0))
    assert oc.duplicates == 199 and oc.n_pairs == 1 and not any(s.ready for s in states)
    assert "199 repeated pairs refused" in oc.status()["not_ready"][0]


def test_two_noisy_pairs_repeated_are_never_ready(rng, R0):
    A, B = pair_stream(rng, 2, R0)
    oc, states = _feed(np.tile(A, (100, 1, 1)), np.tile(B, (100, 1, 1)))
    assert oc.duplicates == 198 and not any(s.ready for s in states)


def test_a_stalled_stream_leaves_the_estimate_and_radius_as_they_were(rng, R0):
    A, B = pair_stream(rng, 30, R0)
    oc, _ = _feed(A, B)
    R, radius = oc.estimate().copy(), oc.radius
    states = oc.update_many(np.repeat(A[-1:], 170, 0), np.repeat(B[-1:], 170, 0))
    assert oc.duplicates == 170 and oc.n_pairs == 30
    assert np.array_equal(oc.estimate(), R) and oc.radius == radius and all(s.radius_deg == radius for s in states)


@pytest.mark.parametrize("share, repeat", [(0.9, True), (1.1, False)])
def test_near_duplicates_at_the_tolerance(rng, R0, share, repeat):
    """A pair within duplicate_deg (elementwise) of an earlier one is a repeat; just outside, a new pair."""
    A, B = pair_stream(rng, 1, R0, motion_deg=(30.0, 40.0))
    tol = math.radians(DUPLICATE_DEG)
    # a unit rotation vector: scale it to the elementwise change
    small = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, 1.0]))
    step = share * tol / np.abs(B[0] @ so3.matrix_from_rotation_vector(1e-6 * np.array([0.0, 0.0,
                                                                                        1.0])) - B[0]).max() * 1e-6
    B2 = B[0] @ so3.matrix_from_rotation_vector(step * so3.rotation_vector_from_matrix(small))
    assert np.isclose(np.abs(B2 - B[0]).max(), share * tol, rtol=1e-3)
    f = RepeatFilter()
    assert not f.seen(A[0].ravel().tolist(), B[0].ravel().tolist())
    assert f.seen(A[0].ravel().tolist(), B2.ravel().tolist()) is repeat


def test_exact_repeats_only_with_zero_tolerance(rng, R0):
    A, B = pair_stream(rng, 1, R0, motion_deg=(30.0, 40.0))
    f = RepeatFilter(0.0)
    fa, fb = A[0].ravel().tolist(), B[0].ravel().tolist()
    assert not f.seen(fa, fb) and f.seen(fa, fb)
    assert not f.seen(fa, (B[0] @ so3.matrix_from_rotation_vector(np.array([0.0, 0.0, 1e-9]))).ravel().tolist())


@pytest.mark.parametrize("angle, small", [(0.9 * SMALL_MOTION_DEG, True), (1.1 * SMALL_MOTION_DEG, False)])
def test_a_rig_at_rest_is_not_a_repeat(angle, small):
    A = so3.matrix_from_rotation_vector(np.radians(angle) * np.array([1.0, 0.0, 0.0]))
    f = RepeatFilter()
    flat = A.ravel().tolist()
    assert not f.seen(flat, flat)
    assert f.seen(flat, flat) is (not small)  # below SMALL_MOTION_DEG never a repeat


def test_noise_free_data_get_the_noise_floor_not_zero(rng, R0):
    A, B = pair_stream(rng, 50, R0, noise_deg=0.0)
    radii = []
    for floor in (NOISE_FLOOR_DEG, 2 * NOISE_FLOOR_DEG):
        oc, _ = _feed(A, B, noise_floor_deg=floor)
        oc.estimate()
        G = 2 * 50 * np.eye(3) - B.sum(0) - B.sum(0).T
        assert oc.radius == pytest.approx(radius_deg(np.radians(floor) ** 2 / 3 * np.linalg.inv(G)), rel=1e-9)
        radii.append(oc.radius)
    assert radii[1] == pytest.approx(2 * radii[0], rel=1e-9)


@pytest.mark.parametrize("excitation, determined", [(0.98 * MIN_EXCITATION_DEG, False),
                                                    (1.02 * MIN_EXCITATION_DEG, True)])
def test_determined_at_the_excitation_threshold(excitation, determined):
    """Motions about z (20-40 deg) and about x by small angles phi_k: about z, lambda_min(G) = sum_k 4 sin^2(phi_k /
    2), so the excitation is sqrt of that over the n pairs."""
    n_z, n_x = 20, 20
    u = np.linspace(0.5, 1.5, n_x)
    target = math.radians(excitation) ** 2 * (n_z + n_x)
    lo, hi = 0.0, 1.0
    for _ in range(100):  # the scale c of phi_k = c u_k that gives the target
        c = 0.5 * (lo + hi)
        lo, hi = (c, hi) if np.sum(4 * np.sin(c * u / 2) ** 2) < target else (lo, c)
    A = np.concatenate([so3.matrix_from_rotation_vector(np.outer(np.radians(np.linspace(20, 40, n_z)), [0, 0, 1])),
                        so3.matrix_from_rotation_vector(np.outer(c * u, [1, 0, 0]))])
    oc, _ = _feed(A, A.copy())  # R0 = I, noise-free
    oc.estimate()
    assert oc.excitation_deg == pytest.approx(excitation, rel=1e-6)
    assert oc.determined is determined


def test_ready_needs_the_verdict_not_to_fail(rng, R0):
    A, B = pair_stream(rng, 60, R0)
    oc, states = _feed(A, B, target_deg=0.5)
    assert states[-1].ready
    oc.set_context(offset_s=0.2, offset_correlation=0.99, max_offset_s=0.2, offset_resolution_s=5e-4)
    assert not oc.ready and oc.current_verdict.level == "fail"
    assert any("search bound" in m for m in oc.status()["not_ready"])


def test_ready_at_the_radius_target(rng, R0):
    A, B = pair_stream(rng, 100, R0)
    oc, states = _feed(A, B)
    k = next(i for i, s in enumerate(states) if s.ready)
    r = states[k].radius_deg
    for target, ready in ((r * 1.0001, True), (r, False)):  # ready needs the radius strictly below the target
        oc2, states2 = _feed(A[:k + 1], B[:k + 1], target_deg=target)
        assert states2[-1].ready is ready


def test_with_forgetting_the_effective_pairs_bound_ready(rng, R0):
    """(1 + l) / (1 - l) = min_pairs at the lowest accepted factor: determined only in the limit; below it, refused."""
    lowest = (10 - 1) / (10 + 1)
    with pytest.raises(ValueError, match="forgetting must be in"):
        OnlineCalibrator(forgetting=lowest - 1e-9)
    A, B = pair_stream(rng, 200, R0)
    oc, states = _feed(A[:20], B[:20], forgetting=lowest)
    assert oc.effective_pairs < 9.99 and not oc.determined and not any(s.ready for s in states)
    oc.update_many(A[20:], B[20:])
    assert oc.effective_pairs == pytest.approx(10.0, rel=1e-9) and oc.determined


@pytest.mark.parametrize("kwargs, message", [
    ({"target_deg": 0}, "target_deg must be > 0"), ({"target_deg": "1"}, "target_deg must be a finite number"),
    ({"level": 1.0}, "level must be in"), ({"level": True}, "level must be a finite number"),
    ({"forgetting": 0.5}, "forgetting must be in"), ({"forgetting": float("nan")}, "forgetting must be a finite"),
    ({"step_every": 0}, "step_every must be >= 1"), ({"refine_every": 2.5}, "refine_every must be a finite integer"),
    ({"min_pairs": 3}, "min_pairs must be >= 4"), ({"confirm_pairs": 4}, "confirm_pairs must be >= 5"),
    ({"max_confirm_pairs": 9}, "max_confirm_pairs must be at least confirm_pairs"),
    ({"drift_pairs": 9}, "drift_pairs must be >= 10"),
    ({"cusum_cap": 2.0}, "cusum_cap must be above cusum_k"), ({"cusum_h": -1}, "cusum_h must be > 0"),
    ({"reference_rate": 0.0}, "reference_rate must be in"), ({"noise_floor_deg": 0}, "noise_floor_deg must be > 0"),
    ({"min_excitation_deg": float("inf")}, "min_excitation_deg must be a finite"),
    ({"duplicate_deg": -0.1}, "duplicate_deg must be >= 0"), ({"init": 2 * np.eye(3)}, "not a rotation"),
    ({"init": np.stack([np.eye(3)] * 2)}, "init must be one 3x3 rotation"),
])
def test_every_parameter_is_validated_by_name(kwargs, message):
    with pytest.raises(ValueError, match=message):
        OnlineCalibrator(**kwargs)


# ------------------------------------------------------------------------------------------------ events told apart

def _two_mountings(rng, R0, step_deg, n1=200, n2=200, noise_deg=0.2):
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(step_deg) * np.array([0.6, 0.0, 0.8]))
    A1, B1 = pair_stream(rng, n1, R0, noise_deg=noise_deg)
    A2, B2 = pair_stream(rng, n2, R1, noise_deg=noise_deg)
    return R1, np.concatenate([A1, A2]), np.concatenate([B1, B2])


@pytest.mark.parametrize("step_deg, source", [(5.0, "cusum"), (0.5, "drift")])
def test_a_remount_is_confirmed_by_the_pairs_after_it(rng, R0, step_deg, source):
    R1, A, B = _two_mountings(rng, R0, step_deg)
    oc, states = _feed(A, B)
    assert [e.kind for e in oc.events] == ["remount"] and oc.alarms == [oc.events[0].pair]
    event = oc.events[0]
    assert event.source == source and event.alarm_pair >= 200 and event.angle_deg > event.threshold_deg
    assert so3.angle_between_deg(event.R_after, R1) < 0.2 and oc.error_deg(R1) < 0.1
    assert all(not s.ready for s in states[event.alarm_pair + 1:event.pair])  # not ready while confirming
    assert states[event.pair].alarm and states[event.pair].event == "remount"


def test_an_outlier_burst_is_outliers_not_a_remount(rng, R0):
    A, B = pair_stream(rng, 300, R0)
    A[150:158] = so3.random_rotations(rng, 8)
    oc, _ = _feed(A, B)
    assert [e.kind for e in oc.events] == ["outliers"] and oc.alarms == []
    assert oc.pairs_dropped >= 8 and oc.error_deg(R0) < 0.1


def test_scattered_outliers_raise_no_remount(rng, R0):
    A, B = pair_stream(rng, 600, R0)
    bad = rng.random(600) < 0.1
    bad[:30] = False
    A[bad] = so3.random_rotations(rng, int(bad.sum()))
    oc, _ = _feed(A, B)
    assert oc.alarms == [] and oc.error_deg(R0) < 0.1


def test_a_noise_jump_is_a_noise_change(rng, R0):
    A1, B1 = pair_stream(rng, 200, R0, noise_deg=0.2)
    A2, B2 = pair_stream(rng, 200, R0, noise_deg=0.8)
    oc, _ = _feed(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
    assert "noise_change" in [e.kind for e in oc.events] and oc.alarms == []


def test_informative_pairs_after_single_axis_motion_raise_no_remount(rng, R0):
    A1, B1 = pair_stream(rng, 100, R0, axis=[0.0, 0.0, 1.0])
    A2, B2 = pair_stream(rng, 100, R0)
    oc, states = _feed(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
    assert oc.alarms == [] and not any(s.ready for s in states[:100]) and oc.error_deg(R0) < 0.1


def test_the_detector_starts_only_once_the_motion_determines_r0(rng, R0):
    A, B = pair_stream(rng, 100, R0, axis=[0.0, 0.0, 1.0])
    oc, _ = _feed(A, B)
    assert not oc._detector.armed
    oc.update_many(*pair_stream(rng, 20, R0))
    assert oc._detector.armed


def test_the_cusum_adds_at_most_cap_minus_k_per_pair(rng, R0):
    A, B = pair_stream(rng, 50, R0)
    oc, _ = _feed(A, B)
    det = oc._detector
    det.cusum = 0.0
    oc.update(so3.random_rotations(rng, ()), B[0])  # a gross outlier: d^2 / m is in the thousands
    assert det.cusum == pytest.approx(oc.cusum_cap - oc.cusum_k)


def test_the_reference_level_stops_following_once_a_change_builds_up(rng, R0):
    A, B = pair_stream(rng, 50, R0)
    oc, _ = _feed(A, B)
    det = oc._detector
    a, b = pair_stream(rng, 1, R0)
    for start, follows in ((oc.cusum_h / 3 + 5.0, False), (0.0, True)):
        det.cusum, level = start, det.level
        oc.update(a[0] @ so3.matrix_from_rotation_vector(np.radians([0.5, 0.0, 0.0])), b[0])  # an in-between residual
        assert bool(det.level != level) == follows
        a, b = pair_stream(rng, 1, R0)


# ------------------------------------------------------------------------------------------------ an undecided end

def test_ready_is_withdrawn_at_the_second_gross_misfit_and_said(rng, R0):
    """A re-mount shows first as pairs that do not fit: one gross misfit leaves ``ready`` (outliers happen), the
    second withdraws it, naming the misfits, before the CUSUM decides."""
    from replication.rig.online import MISFITS_WITHDRAW_READY

    A, B = pair_stream(rng, 300, R0)
    oc, _ = _feed(A, B)
    assert oc.ready and oc.unresolved_end() is None
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.6, 0.0, 0.8]))
    A2, B2 = pair_stream(rng, MISFITS_WITHDRAW_READY, R1)
    oc.update(A2[0], B2[0])
    assert oc.ready and oc.unresolved_end() is None and not oc.alarms
    oc.update(A2[1], B2[1])
    assert not oc.ready and not oc.checking and not oc.alarms
    assert any("2 recent pairs do not fit the estimate" in w for w in oc.status()["not_ready"])
    reason = oc.unresolved_end()
    assert (reason.check, reason.level, reason.measured, reason.threshold) == ("end_undecided", "warning", 2.0, 2.0)
    assert "a change of R0 at the end is neither confirmed nor ruled out" in reason.message


def test_an_alarm_being_confirmed_at_the_end_is_an_undecided_end(rng, R0):
    A, B = pair_stream(rng, 300, R0)
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.6, 0.0, 0.8]))
    A2, B2 = pair_stream(rng, 8, R1)
    oc, _ = _feed(np.concatenate([A, A2]), np.concatenate([B, B2]))
    assert oc.checking and not oc.ready
    reason = oc.unresolved_end()
    assert reason.check == "end_undecided" and "was being confirmed" in reason.message


def test_a_remount_just_before_the_end_of_a_live_replay_is_not_ready_and_warned():
    """A 5 deg re-mount 3 s before the end of a 60 s replay (three pairs, too few for the CUSUM to alarm): the
    summary is not ready and its verdict warns; without the re-mount, ready and no such warning."""
    from replication.rig.live import replay
    from replication.study.simulation import rig_streams

    R0, camera, gyro, _ = rig_streams(60, rng=np.random.default_rng(900), camera_noise_deg=0.1, gyro_noise_deg_s=0.2)
    R = so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5,
                                                                                                        0.81]))
    late = replay(camera, gyro, OnlineCalibrator(target_deg=0.5), reference=R0, remount=(57.0, R)).attrs["summary"]
    assert not late["ready"] and late["verdict"]["level"] == "warning" and not late["events"]
    assert [r["check"] for r in late["verdict"]["reasons"]] == ["end_undecided"]
    clean = replay(camera, gyro, OnlineCalibrator(target_deg=0.5), reference=R0).attrs["summary"]
    assert clean["ready"] and clean["verdict"]["level"] == "ok"


# ------------------------------------------------------------------------------------------------ near copies
def test_near_copies_of_pairs_are_counted_once_and_the_radius_covers_the_error():
    """15 noisy pairs (0.3 deg) each given 8 times with a 1e-4 rad jitter (a red-team case: counted as new
    information, the radius covered the error in 8 of 30 runs, seeds [5, 0..29]): copies far below the noise are
    repeats, the radius covers the error in at least 26 of 30 (29 measured)."""
    covered = 0
    for seed in range(30):
        rng = np.random.default_rng([5, seed])
        R0 = so3.random_rotations(rng, ())
        A, B = pair_stream(rng, 15, R0, noise_deg=0.3)
        jitter = lambda M: so3.matrix_from_rotation_vector(rng.normal(0, 1e-4, (len(M), 3))) @ M  # noqa: E731
        oc, _ = _feed(jitter(np.repeat(A, 8, axis=0)), jitter(np.repeat(B, 8, axis=0)))
        oc.estimate()
        assert oc.n_pairs <= 16 and oc.duplicates >= 104
        covered += oc.error_deg(R0) <= oc.radius
    assert covered >= 26


@pytest.mark.parametrize("rms, tol", [(0.05, DUPLICATE_DEG), (0.2, 0.02), (0.4, 0.04), (0.6, 0.05), (math.inf, 0.05)])
def test_the_repeat_tolerance_is_a_tenth_of_the_noise_between_its_bounds(rms, tol):
    from replication.rig.online_events import REPEAT_MAX_FACTOR, REPEAT_NOISE_SHARE

    assert (REPEAT_NOISE_SHARE, REPEAT_MAX_FACTOR) == (0.1, 5.0)
    f = RepeatFilter()
    f.set_noise(rms)
    assert f.tolerance_deg == pytest.approx(tol, rel=1e-12)
    g = RepeatFilter(0.0)
    g.set_noise(rms)
    assert g.tolerance_deg == 0.0  # exact repeats stay exact


@pytest.mark.parametrize("share, repeat", [(0.99, True), (1.01, False)])
def test_near_copies_at_the_widened_tolerance_wherever_they_fall_in_the_grid(share, repeat):
    rng = np.random.default_rng(61)
    for _ in range(100):
        A, B = so3.random_rotations(rng, 2)
        f = RepeatFilter()
        f.set_noise(0.3)
        tol = math.radians(f.tolerance_deg)
        assert f.tolerance_deg == pytest.approx(0.03)
        f.seen(A.ravel().tolist(), B.ravel().tolist())
        near = (B.ravel() + share * tol * rng.choice([-1.0, 1.0], 9)).tolist()  # every entry moved
        assert f.seen(A.ravel().tolist(), near) is repeat


def test_the_calibrator_starts_at_the_widest_tolerance_and_then_takes_the_noise(rng, R0):
    oc = OnlineCalibrator()
    assert oc._repeats.tolerance_deg == pytest.approx(5 * DUPLICATE_DEG)  # the noise unknown: the widest
    oc.update_many(*pair_stream(rng, 100, R0, noise_deg=0.3))
    rms = oc.status()["rms_residual_deg"]
    assert 0.2 < rms < 0.4 and oc._repeats.tolerance_deg == pytest.approx(0.1 * rms)
