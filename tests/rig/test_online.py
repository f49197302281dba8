"""The online estimator: O(1) updates equal to the batch solver on the same pairs, a calibrated
radius, re-mount detection on synthetic steps, and bad input refused like the rest of the
package."""
import math

import numpy as np
import pytest

from conftest import drift_pairs
from replication.core import so3
from replication.core.handeye import kronecker_operator
from replication.core.solvers import chordal_optimal
from replication.core.stats import radius_deg
from replication.rig.online import MIN_EXCITATION_DEG, MIN_PAIRS, NOISE_FLOOR_DEG, OnlineCalibrator
from replication.rig.online_events import DUPLICATE_DEG, RepeatFilter
from replication.study.live_study import pair_stream
from replication.study.simulation import simulate
from replication.testing import assert_rotations_close


def _noisy_pairs(rng, J, R0, *, noise_deg=0.2, max_motion_deg=60.0):
    """Camera motions up to ``max_motion_deg``, sensor motions ``R0^T A R0``, Gaussian noise on both
    sides."""
    w = rng.normal(size=(J, 3))
    w *= (np.radians(max_motion_deg) * rng.uniform(0.3, 1.0, J) / np.linalg.norm(w, axis=1))[:, None]
    A = so3.matrix_from_rotation_vector(w)
    B = R0.T @ A @ R0
    noise = lambda: so3.matrix_from_rotation_vector(rng.normal(size=(J, 3)) * np.radians(noise_deg) / np.sqrt(2 * 3))  # noqa: E731
    return noise() @ A, noise() @ B


def test_running_K_and_estimate_equal_the_batch_solver():
    sim = simulate(3, 1, n_motions=250)
    A, B = sim.A[0], sim.B[0]
    oc = OnlineCalibrator(cusum_h=1e9)
    oc.update_many(A, B)
    np.testing.assert_allclose(oc.K, kronecker_operator(A, B), rtol=0, atol=1e-14)
    assert_rotations_close(oc.estimate(), chordal_optimal(A, B).R, 1e-9)
    assert oc.n_pairs == 250 and oc.alarms == []


def test_forgetting_weighs_pairs_by_their_age():
    sim = simulate(4, 1, n_motions=40)
    A, B = sim.A[0], sim.B[0]
    oc = OnlineCalibrator(forgetting=0.9, cusum_h=1e9)
    oc.update_many(A, B)
    weights = 0.9 ** np.arange(39, -1, -1.0)
    np.testing.assert_allclose(oc.K, kronecker_operator(A, B, weights=weights), rtol=0, atol=1e-14)


def test_pairwise_updates_equal_the_replay():
    sim = simulate(5, 1, n_motions=60)
    one, many = OnlineCalibrator(), OnlineCalibrator()
    states = [one.update(a, b) for a, b in zip(sim.A[0], sim.B[0])]
    assert [s.radius_deg for s in states] == [s.radius_deg for s in many.update_many(sim.A[0], sim.B[0])]
    assert np.array_equal(one.R, many.R)


def test_radius_covers_the_error_about_95_percent(rng):
    """Coverage at several checkpoints over 150 problems: inside 88-99 % (the 95 % level, 150
    draws)."""
    R0s = so3.random_rotations(rng, 150)
    covered, checks = [], (20, 40, 100)
    for R0 in R0s:
        A, B = _noisy_pairs(rng, 100, R0)
        oc = OnlineCalibrator(cusum_h=1e9)
        for j, state in enumerate(oc.update_many(A, B), 1):
            if j in checks:
                covered.append(oc.error_deg(R0) <= state.radius_deg)
    share = np.mean(covered)
    assert 0.88 <= share <= 0.99, share


def test_ready_when_the_radius_is_below_the_target(rng):
    R0 = so3.random_rotations(rng, ())
    A, B = _noisy_pairs(rng, 200, R0)
    oc = OnlineCalibrator(target_deg=0.1, cusum_h=1e9)
    states = oc.update_many(A, B)
    first = next(i for i, s in enumerate(states) if s.ready)
    assert all(not s.ready for s in states[:first]) and states[first].radius_deg < 0.1
    assert states[first - 1].radius_deg >= 0.1 or states[first - 1].n_pairs < oc.min_pairs


@pytest.mark.parametrize("step_deg, max_delay", [(2.0, 22), (5.0, 16)])
def test_a_remount_is_detected_within_a_few_pairs(rng, step_deg, max_delay):
    R0 = so3.random_rotations(rng, ())
    A1, B1 = _noisy_pairs(rng, 150, R0)
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(step_deg) * np.array([0.6, 0.0, 0.8]))  # the sensor re-mounted
    A2, B2 = _noisy_pairs(rng, 150, R1)
    oc = OnlineCalibrator()
    oc.update_many(np.concatenate([A1, A2]), np.concatenate([B1, B2]))
    assert len(oc.alarms) == 1 and 150 <= oc.alarms[0] < 150 + max_delay, oc.alarms
    assert oc.error_deg(R1) < 0.2  # it started over and re-converged to the new mounting


def test_no_false_alarm_without_a_change(rng):
    R0 = so3.random_rotations(rng, ())
    A, B = _noisy_pairs(rng, 5000, R0)
    oc = OnlineCalibrator()
    oc.update_many(A, B)
    assert oc.alarms == []


@pytest.mark.parametrize("A, message", [
    (2 * np.eye(3), "not a rotation matrix"),
    (np.diag([1.0, 1.0, -1.0]), "reflection"),
    (np.full((3, 3), np.nan), "not a rotation matrix"),
    (np.eye(4), "a pair is two 3x3 rotations"),
])
def test_bad_pairs_are_refused_and_leave_the_state_alone(A, message):
    oc = OnlineCalibrator()
    with pytest.raises(ValueError, match=message):
        oc.update(A, np.eye(3))
    assert oc.n_pairs == 0


@pytest.mark.parametrize("kwargs, message", [
    ({"target_deg": 0}, "target_deg must be"), ({"level": 1.0}, "level must be in"),
    ({"forgetting": 0.0}, "forgetting must be in"), ({"step_every": 0}, "step_every must be"),
    ({"min_pairs": 3}, "min_pairs must be >= 4"), ({"init": 2 * np.eye(3)}, "not a rotation"),
])
def test_bad_settings_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        OnlineCalibrator(**kwargs)


# ------------------------------------------------------------------------------------------------
# the live front end

def _streams(seconds=60.0, phase=0.0):
    """The synthetic rig, its first motion component shifted by ``phase``, the orientation sensor at
    200 Hz."""
    from replication.testing import rig_streams

    return rig_streams(seconds, phase=(phase, 0.0, 0.0), sensor_step=1)


def test_live_replay_of_gyro_and_of_orientations_converges_with_one_pair_per_interval():
    from replication.rig.live import replay

    R0, camera, gyro, sensor = _streams()
    for s in (gyro, sensor):
        rows = replay(camera, s, OnlineCalibrator(target_deg=0.2), reference=R0, interval=1.0)
        assert 55 <= len(rows) <= 60 and rows["error_deg"].iloc[-1] < 0.01 and rows["ready"].iloc[-1]
        assert abs(rows.attrs["offset_s"]) < 1e-3 and rows.attrs["alarms"] == []


def test_live_replay_detects_a_synthetic_remount():
    from replication.rig.live import replay

    R0, camera, gyro, _ = _streams(120.0)
    R = so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([0.6, 0.0, 0.8]))
    rows = replay(camera, gyro, OnlineCalibrator(), reference=R0, remount=(60.0, R))
    alarms = rows.loc[rows["alarm"], "t"]
    assert len(alarms) == 1 and 60.0 <= alarms.iloc[0] < 80.0
    assert rows["error_deg"].iloc[-1] < 0.05  # re-converged to the new mounting


def test_live_rig_refuses_time_going_back_and_drops_pairs_across_a_gap():
    from replication.rig.live import LiveRig

    R0, camera, gyro, _ = _streams()
    rig = LiveRig(OnlineCalibrator(), offset=0.0)
    for t, w in zip(gyro.t[:100], gyro.omega[:100]):
        rig.add_gyro(t, w)
    with pytest.raises(ValueError, match="gyro time going backwards"):
        rig.add_gyro(gyro.t[50], gyro.omega[50])
    rig.add_camera(0.0, camera.R[0])
    with pytest.raises(ValueError, match="camera time going backwards"):
        rig.add_camera(0.0, camera.R[0])
    with pytest.raises(ValueError, match="not a rotation matrix"):
        rig.add_camera(1.0, 2 * np.eye(3))
    gap = LiveRig(OnlineCalibrator(), offset=0.0)
    keep = (gyro.t < 20.0) | (gyro.t > 23.0)
    events = sorted([(t, 0, k) for k, t in enumerate(gyro.t) if keep[k]] + [(t, 1, k) for k, t in enumerate(camera.t)])
    for t, kind, k in events:
        gap.add_gyro(t, gyro.omega[k]) if kind == 0 else gap.add_camera(t, camera.R[k])
    assert 3 <= gap.pairs_dropped <= 5 and gap.calibrator.error_deg(R0) < 0.05


def test_cli_online_writes_the_track(tmp_path, capsys):
    import pandas as pd

    from replication.cli import main

    R0, camera, gyro, _ = _streams()
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(camera.R)
    np.savetxt(cam_file, np.column_stack([camera.t + 1e3, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]]),
               fmt="%.9f")
    np.savetxt(imu_file, np.column_stack([np.round((gyro.t + 1e3) * 1e9), gyro.omega, np.zeros((len(gyro.t), 3))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    track = tmp_path / "out" / "track.csv"
    assert main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro",
                 "--online", "--track", str(track), "--bootstrap", "0", "--quiet"]) == 0
    rows = pd.read_csv(track)
    assert {"t", "n_pairs", "radius_deg", "ready", "alarm", "qw"} <= set(rows.columns) and rows["ready"].iloc[-1]
    assert "online:" in capsys.readouterr().out
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_:
        main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--target", "0"])
    assert exit_.value.code == 2  # a usage error
    assert "--target" in capsys.readouterr().err
    assert main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--track", str(track)]) == 2


def test_between_refinements_the_estimate_is_the_last_minimiser(rng):
    """The two-step steps only prepare the next refinement: the published estimate is the one the
    radius describes."""
    R0 = so3.random_rotations(rng, ())
    A, B = _noisy_pairs(rng, 19, R0)
    states = OnlineCalibrator(cusum_h=1e9).update_many(A, B)
    assert all(np.array_equal(s.R, states[9].R) for s in states[9:19])  # refinements at 10 and 20 pairs
    assert all(s.radius_deg == states[9].radius_deg for s in states[9:19])
    assert_rotations_close(states[9].R, chordal_optimal(A[:10], B[:10]).R, 1e-9)


def test_live_pairs_share_no_pose():
    from replication.rig.live import replay

    R0, camera, gyro, _ = _streams()
    spans = []
    replay(camera, gyro, OnlineCalibrator(), interval=1.0, on_pair=lambda t, A, B: spans.append(t))
    ends = np.array(spans)
    assert np.all(np.diff(ends) > 1.0)  # each pair starts at the pose after the previous pair's end


def test_a_mounting_far_from_the_identity_is_found_like_the_batch_solver():
    """R0 150-180 deg from the identity (a camera upside down relative to the sensor),
    Haar-distributed motions: Newton from the identity alone ended about 180 deg off in 21 of these
    30 (a critical point of eq. (8)); the refinement also starts from the relaxed minimiser and
    lands where the batch solver does."""
    from replication.core.solvers import solve

    rng = np.random.default_rng(3)
    for _ in range(30):
        axis = rng.standard_normal(3)
        R0 = so3.matrix_from_rotation_vector(np.radians(rng.uniform(150, 180)) * axis / np.linalg.norm(axis))
        A = so3.random_rotations(rng, 40)
        B = R0.T @ A @ R0 @ so3.matrix_from_rotation_vector(np.radians(0.2) * rng.standard_normal((40, 3)))
        oc = OnlineCalibrator()
        oc.update_many(A, B)
        assert so3.angle_between_deg(oc.estimate(), solve("chordal_optimal", A, B)) < 1e-6

# --------------------------------------------------------------------------------------------------
# The online estimator's words earn their meaning: ``ready`` only when the motion determines R0
# (excitation, distinct pairs, a radius with a noise floor, a verdict that does not fail), repeated
# pairs not counted, alarms confirmed and told apart (re-mount, noise change, outliers, new
# information), every parameter validated; each rule is tested at its boundary.


@pytest.fixture
def R0(rng):
    return so3.random_rotations(rng, ())


def _feed(A, B, **kw):
    oc = OnlineCalibrator(**kw)
    return oc, oc.update_many(A, B)


# ------------------------------------------------------------------------------------------------
# ready = determined

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
    # eigh's eigenvector sign is arbitrary (it flipped between numpy's AVX-512 and AVX2 paths in
    # notebook 08): the axis is named with its largest component positive
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
    """A pair within duplicate_deg (elementwise) of an earlier one is a repeat; just outside, a new
    pair."""
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
    """Motions about z (20-40 deg) and about x by small angles phi_k: about z, lambda_min(G) = sum_k
    4 sin^2(phi_k / 2), so the excitation is sqrt of that over the n pairs."""
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
    """(1 + l) / (1 - l) = min_pairs at the lowest accepted factor: determined only in the limit;
    below it, refused."""
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


# ------------------------------------------------------------------------------------------------
# events told apart

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


# ------------------------------------------------------------------------------------------------
# an undecided end

def test_ready_is_withdrawn_at_the_second_gross_misfit_and_said(rng, R0):
    """A re-mount shows first as pairs that do not fit: one gross misfit leaves ``ready`` (outliers
    happen), the second withdraws it, naming the misfits, before the CUSUM decides."""
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
    """A 5 deg re-mount 3 s before the end of a 60 s replay (three pairs, too few for the CUSUM to
    alarm): the summary is not ready and its verdict warns; without the re-mount, ready and no such
    warning."""
    from replication.rig.live import replay
    from replication.testing import rig_streams

    R0, camera, gyro, _ = rig_streams(60, rng=np.random.default_rng(900), camera_noise_deg=0.1, gyro_noise_deg_s=0.2)
    R = so3.matrix_from_rotation_vector(np.radians(5.0) * np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5,
                                                                                                        0.81]))
    late = replay(camera, gyro, OnlineCalibrator(target_deg=0.5), reference=R0, remount=(57.0, R)).attrs["summary"]
    assert not late["ready"] and late["verdict"]["level"] == "warning" and not late["events"]
    assert [r["check"] for r in late["verdict"]["reasons"]] == ["end_undecided"]
    clean = replay(camera, gyro, OnlineCalibrator(target_deg=0.5), reference=R0).attrs["summary"]
    assert clean["ready"] and clean["verdict"]["level"] == "ok"


# ------------------------------------------------------------------------------------------------
# near copies
def test_near_copies_of_pairs_are_counted_once_and_the_radius_covers_the_error():
    """15 noisy pairs (0.3 deg) each given 8 times with a 1e-4 rad jitter (a case once found:
    counted as new information, the radius covered the error in 8 of 30 runs, seeds [5, 0..29]):
    copies far below the noise are repeats, the radius covers the error in at least 26 of 30 (29
    measured)."""
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


def test_the_calibrator_starts_at_the_widest_tolerance_and_then_takes_the_noise(rng, R0):
    oc = OnlineCalibrator()
    assert oc._repeats.tolerance_deg == pytest.approx(5 * DUPLICATE_DEG)  # the noise unknown: the widest
    oc.update_many(*pair_stream(rng, 100, R0, noise_deg=0.3))
    rms = oc.status()["rms_residual_deg"]
    assert 0.2 < rms < 0.4 and oc._repeats.tolerance_deg == pytest.approx(0.1 * rms)

# --------------------------------------------------------------------------------------------------
# The online calibrator's rules (:class:`replication.rig.online.OnlineCalibrator`) at their
# boundaries: every option's range and default, the running sums and their forgetting, the radius
# (``inf`` until the motion determines ``R0``), ``determined`` and ``ready``, the evidence and the
# not-ready sentences. Mutation testing (scripts/mutation) found these unguarded by the fast tests.


R0_MO = so3.matrix_from_rotation_vector(np.array([0.4, -0.2, 0.9]))


def test_defaults():
    c = OnlineCalibrator()
    assert (c.target_deg, c.level, c.forgetting, c.step_every, c.refine_every, c.min_pairs) == (0.5, 0.95, 1.0, 5, 10,
                                                                                                 MIN_PAIRS)
    assert (c.cusum_k, c.cusum_h, c.cusum_cap, c.reference_rate) == (2.0, 30.0, 10.0, 1 / 30)
    assert (c.confirm_pairs, c.max_confirm_pairs, c.drift_pairs) == (10, 60, 50)
    assert (c.noise_floor_deg, c.min_excitation_deg, c.duplicate_deg) == (NOISE_FLOOR_DEG, MIN_EXCITATION_DEG,
                                                                          DUPLICATE_DEG)
    assert np.array_equal(c.R, np.eye(3)) and c.radius == math.inf and not c.ready and not c.determined
    assert (c.n_total, c.duplicates, c.pairs_dropped, c.alarms, c.events) == (0, 0, 0, [], [])
    assert c.current_verdict is None and np.array_equal(c.K, np.zeros((9, 9)))
    assert (MIN_PAIRS, MIN_EXCITATION_DEG, NOISE_FLOOR_DEG) == (10, 1.0, 0.01)


@pytest.mark.parametrize("name", ["target_deg", "cusum_h", "cusum_k", "noise_floor_deg", "min_excitation_deg"])
def test_positive_options(name):
    OnlineCalibrator(**{name: 1e-9})
    with pytest.raises(ValueError, match=rf"\b{name} must be > 0\b.*got 0"):
        OnlineCalibrator(**{name: 0})


def test_duplicate_tolerance_may_be_zero():
    assert OnlineCalibrator(duplicate_deg=0.0).duplicate_deg == 0.0
    with pytest.raises(ValueError, match=r"duplicate_deg must be >= 0\b.*got -0\.001"):
        OnlineCalibrator(duplicate_deg=-0.001)


def test_the_cusum_cap_must_exceed_k():
    OnlineCalibrator(cusum_k=2.0, cusum_cap=2.0000001)
    with pytest.raises(ValueError, match=r"cusum_cap must be above cusum_k.*got cusum_cap=2\.0, cusum_k=2\.0"):
        OnlineCalibrator(cusum_k=2.0, cusum_cap=2.0)
    with pytest.raises(ValueError, match=r"cusum_cap must be a finite number"):
        OnlineCalibrator(cusum_cap=math.inf)


def test_level_and_reference_rate_ranges():
    assert OnlineCalibrator(level=0.5).level == 0.5
    for bad in (0.0, 1.0):
        with pytest.raises(ValueError, match=rf"\blevel must be in \(0, 1\).*got {bad}"):
            OnlineCalibrator(level=bad)
    assert OnlineCalibrator(reference_rate=1.0).reference_rate == 1.0
    with pytest.raises(ValueError, match=r"reference_rate must be in \(0, 1\].*got 0\.0"):
        OnlineCalibrator(reference_rate=0.0)


@pytest.mark.parametrize("name, least", [("step_every", 1), ("refine_every", 1), ("min_pairs", 4),
                                         ("confirm_pairs", 5), ("drift_pairs", 10)])
def test_integer_options_and_their_least_values(name, least):
    kw = {name: least}
    if name == "confirm_pairs":
        kw["max_confirm_pairs"] = least
    c = OnlineCalibrator(**kw)
    assert getattr(c, name) == least and type(getattr(c, name)) is int
    with pytest.raises(ValueError, match=rf"\b{name} must be >= {least}\b.*got {least - 1}"):
        OnlineCalibrator(**{name: least - 1})
    with pytest.raises(ValueError, match=rf"\b{name} must be a finite integer.*got {least}\.0"):
        OnlineCalibrator(**{name: float(least)})


def test_the_confirmation_window_bounds():
    assert OnlineCalibrator(confirm_pairs=7, max_confirm_pairs=7).max_confirm_pairs == 7
    with pytest.raises(ValueError, match=r"max_confirm_pairs must be at least confirm_pairs = 7.*got 6"):
        OnlineCalibrator(confirm_pairs=7, max_confirm_pairs=6)
    with pytest.raises(ValueError, match=r"max_confirm_pairs must be >= 5\b.*got 4"):
        OnlineCalibrator(max_confirm_pairs=4)


def test_forgetting_is_bounded_by_the_pairs_it_needs():
    lowest = (10 - 1) / (10 + 1)
    assert OnlineCalibrator(forgetting=lowest).forgetting == lowest
    assert OnlineCalibrator(forgetting=1.0).forgetting == 1.0
    with pytest.raises(ValueError, match=r"forgetting must be in \[0\.818182, 1\].*got 0\.8"):
        OnlineCalibrator(forgetting=0.8)
    with pytest.raises(ValueError, match=r"forgetting must be in \[0\.818182, 1\].*got 1\.01"):
        OnlineCalibrator(forgetting=1.01)
    assert OnlineCalibrator(min_pairs=4, forgetting=0.6).forgetting == 0.6  # (4 - 1) / (4 + 1)


def test_the_start_rotation():
    c = OnlineCalibrator(init=R0_MO)
    assert np.array_equal(c.R, R0_MO)
    with pytest.raises(ValueError, match=r"init must be one 3x3 rotation.*shape \(2, 3, 3\)"):
        OnlineCalibrator(init=np.stack([R0_MO, R0_MO]))
    with pytest.raises(ValueError, match="init is not a rotation matrix"):
        OnlineCalibrator(init=2 * R0_MO)


def _pairs(n, rng, noise_deg=0.0, axes=None):
    A = so3.random_rotations(rng, n) if axes is None else so3.matrix_from_rotation_vector(
        np.radians(rng.uniform(20, 60, n))[:, None] * np.asarray(axes, float)[rng.integers(0, len(axes), n)])
    B = R0_MO.T @ A @ R0_MO
    if noise_deg:
        B = B @ so3.matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal((n, 3)))
    return A, B


def test_the_running_operator_is_the_weighted_mean_of_b_kron_a():
    rng = np.random.default_rng(1)
    A, B = _pairs(21, rng, 0.5)
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert np.allclose(c.K, kronecker_operator(A, B), atol=1e-12)
    lam = 0.9
    f = OnlineCalibrator(forgetting=lam)
    f.update_many(A, B)
    w = lam ** np.arange(20, -1, -1.0)
    K = np.einsum("i,iab,icd->acbd", w, B, A).reshape(9, 9) / w.sum()
    assert np.allclose(f.K, K, atol=1e-12)
    assert f.effective_pairs == pytest.approx(w.sum() ** 2 / (w ** 2).sum())


def test_radius_and_readiness_once_determined():
    rng = np.random.default_rng(2)
    A, B = _pairs(40, rng, 0.2)
    c = OnlineCalibrator(target_deg=5.0)
    states = c.update_many(A, B)
    assert all(s.radius_deg == math.inf and not s.determined and not s.estimated for s in states[:MIN_PAIRS - 1])
    s = states[MIN_PAIRS - 1]
    assert s.estimated and s.determined and s.ready and 0 < s.radius_deg < 5.0 and s.n_pairs == MIN_PAIRS
    assert so3.angle_between_deg(c.estimate(), R0_MO) < 0.5
    # the radius: (s^2 / 3) G^-1 at the calibrator's level, s^2 the mean square residual corrected
    # for 3 unknowns
    x = c.R.reshape(-1, order="F")
    e = c.evidence()
    assert e["n_pairs"] == 40 and e["effective_pairs"] == 40 and e["determined"] is True and e["checking"] is False
    assert e["motion_median_deg"] == pytest.approx(float(np.median(so3.rotation_angle_deg(A))))
    G = 2 * 40 * np.eye(3) - B.sum(0) - B.sum(0).T
    cost = float(np.sum(np.linalg.norm(A @ c.R - c.R @ B, axis=(1, 2)) ** 2))
    s2 = cost / 40 * 40 / (2 * 37)
    assert e["rms_residual_deg"] == pytest.approx(math.degrees(math.sqrt(s2)), rel=1e-6)
    assert c.radius == pytest.approx(radius_deg((s2 / 3) * np.linalg.inv(G), 0.95), rel=1e-6)
    assert e["excitation_deg"] == pytest.approx(math.degrees(math.sqrt(np.linalg.eigvalsh(G)[0] / 40)), rel=1e-9)
    assert e["radius_deg"] == c.radius and x.shape == (9,)


def test_not_ready_sentences():
    rng = np.random.default_rng(3)
    c = OnlineCalibrator(target_deg=1e-6)
    A, B = _pairs(12, rng, 0.3)
    c.update_many(A[:5], B[:5])
    why = c.status()["not_ready"]
    assert why[0] == "5.0 effective distinct pairs < 10"
    assert why[1].startswith("the motion does not determine R0: RMS rotation about axes perpendicular to any axis "
                             "(sensor frame) is 0 deg < 1 deg; rotate about other axes")
    assert why[2] == "95 % radius inf deg >= target 1e-06 deg"
    c.update(A[0], B[0])  # a repeat
    c.update_many(A[5:], B[5:])
    st = c.status()
    assert st["ready"] is False and st["repeated_pairs"] == 1
    assert st["not_ready"][0].startswith("95 % radius ") and st["not_ready"][0].endswith(" deg >= target 1e-06 deg")
    single = OnlineCalibrator()
    A1, B1 = _pairs(12, rng, 0.3, axes=[(0.0, 0.0, 1.0)])
    single.update_many(A1, B1)
    why = single.status()["not_ready"]
    assert any(w.startswith("the motion does not determine R0: RMS rotation about axes perpendicular to [")
               for w in why)


def test_pairs_are_refused_unless_two_rotations():
    c = OnlineCalibrator()
    with pytest.raises(ValueError, match=r"a pair is two 3x3 rotations.*shapes \(2, 3, 3\) and \(2, 3, 3\)"):
        c.update(np.stack([R0_MO, R0_MO]), np.stack([R0_MO, R0_MO]))
    with pytest.raises(ValueError, match=r"a pair is two 3x3 rotations: "):
        c.update(np.stack([R0_MO, R0_MO]), R0_MO)
    with pytest.raises(ValueError, match=r"A \(camera motion\) is not a rotation matrix"):
        c.update(2 * R0_MO, R0_MO)
    with pytest.raises(ValueError, match=r"B \(sensor motion\) is a reflection"):
        c.update(R0_MO, -R0_MO)
    with pytest.raises(ValueError, match=r"need two \(J, 3, 3\) arrays of the same J.*got \(2, 3, 3\) and \(3, 3, 3\)"):
        c.update_many(np.stack([R0_MO] * 2), np.stack([R0_MO] * 3))
    assert c.n_total == 0


def test_outliers_decided_online_count_as_dropped_once_and_the_refinement_schedule_resumes():
    rng = np.random.default_rng(7)
    A, B = _pairs(180, rng, 0.2)
    B[125:130] = B[125:130] @ so3.matrix_from_rotation_vector(np.radians(20.0) * np.array([1.0, 0.0, 0.0]))
    c = OnlineCalibrator()
    kinds = [s.event for s in c.update_many(A, B)]
    assert "outliers" in kinds and c.alarms == []
    ev = c.events[0]
    assert ev.kind == "outliers" and c.pairs_dropped == ev.pairs_dropped == 5
    k = kinds.index("outliers")
    assert c.n_pairs == c.n_total == 180
    c2 = OnlineCalibrator()
    c2.update_many(A[:k + 1], B[:k + 1])
    n, R = c2.n_pairs, c2.R
    states = c2.update_many(A[k + 1:], B[k + 1:])
    refined = [s.n_pairs for s, before in zip(states, [R] + [s.R for s in states]) if not np.array_equal(s.R, before)]
    assert refined[0] == n + max(c2.refine_every, n // 10)  # the next refinement: the usual gap after the decision


def test_a_remount_online_starts_over_from_the_new_estimate():
    rng = np.random.default_rng(8)
    A, B = _pairs(260, rng, 0.2)
    turn = so3.matrix_from_rotation_vector(np.radians(6.0) * np.array([0.0, 1.0, 0.0]))
    B[150:] = turn.T @ B[150:] @ turn  # R0 becomes R0 turn from pair 150 on
    c = OnlineCalibrator()
    states = c.update_many(A, B)
    assert len(c.alarms) == 1 and c.events[0].kind == "remount" and c.alarms[0] == c.events[0].pair
    at = c.alarms[0]
    assert states[at].alarm and states[at].event == "remount"
    assert so3.angle_between_deg(c.R, R0_MO @ turn) < 0.3
    assert c.n_pairs < 260 - 150 + 40 and c.n_total == 260
    assert c._next_refine > c.n_pairs


# ---------------------------------------------------------------------------------------------
# judging and status
def _small_noisy_pairs(n, rng, noise_deg):
    """Motions of 4-8 deg about random axes, sensor motions with ``noise_deg`` per axis."""
    axes = rng.standard_normal((n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    A = so3.matrix_from_rotation_vector(np.radians(rng.uniform(4, 8, n))[:, None] * axes)
    return A, R0_MO.T @ A @ R0_MO @ so3.matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal((n, 3)))


def test_the_online_verdict_judges_what_the_estimator_measured_and_the_front_ends_context():
    from replication.rig.quality import Reason

    rng = np.random.default_rng(21)
    A, B = _small_noisy_pairs(20, rng, 1.5)
    c = OnlineCalibrator()
    c.update_many(A, B)
    c.update(A[3], B[3])  # a repeat, refused
    c.set_context(gyro_rate_hz=20.0, extra=[Reason("named", "warning", None, None, "a named input mistake")])
    e = c.evidence()
    v = c.current_verdict
    assert v == c.verdict()  # set_context judges again at once
    by = {r.check: r for r in v.reasons}
    assert [r.check for r in v.reasons] == ["n_pairs", "residual_to_motion", "residual_median_deg", "bootstrap_deg",
                                            "repeated_pairs", "gyro_rate_hz", "named"]
    assert by["n_pairs"].measured == 20.0 == round(e["effective_pairs"])
    assert by["residual_to_motion"].measured == pytest.approx(e["residual_median_deg"] / e["motion_median_deg"])
    assert by["residual_median_deg"].measured == e["residual_median_deg"] > 2.0
    assert by["bootstrap_deg"].measured == c.radius > 5.0 and by["bootstrap_deg"].level == "fail"
    assert by["bootstrap_deg"].message.startswith("95 % radius (curvature of eq. (8)) ")
    assert by["repeated_pairs"].measured == 1.0 and by["gyro_rate_hz"].measured == 20.0
    assert by["named"].message == "a named input mistake"
    assert v.level == "fail" and not c.ready and c.determined


def test_the_online_verdict_names_weak_excitation_and_no_radius_while_the_motion_does_not_determine_r0():
    rng = np.random.default_rng(22)
    A, B = _pairs(15, rng, 0.0, axes=[(0.0, 0.0, 1.0)])
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert c.radius == math.inf and not c.determined
    v = c.verdict()
    by = {r.check: r for r in v.reasons}
    assert "bootstrap_deg" not in by  # no radius: not "inf deg > 5 deg"
    assert by["excitation_deg"].measured == pytest.approx(c.excitation_deg) and c.excitation_deg < 1.0
    assert by["n_pairs"].measured == 15.0


def test_evidence_before_any_pair_and_the_residual_median_from_min_pairs_residuals_on():
    c = OnlineCalibrator()
    e = c.evidence()
    assert e["motion_median_deg"] is None and e["residual_median_deg"] is None and e["pairs_dropped"] == 0
    rng = np.random.default_rng(23)
    A, B = _pairs(20, rng, 0.2)
    c.update_many(A[:19], B[:19])  # armed at pair 10: 9 residuals on arrival since
    assert c.determined and c.evidence()["residual_median_deg"] is None
    c.update(A[19], B[19])
    assert c.evidence()["residual_median_deg"] > 0


def test_status_thresholds_are_strict_where_the_rule_says_below():
    rng = np.random.default_rng(24)
    A, B = _pairs(10, rng, 0.2)
    c = OnlineCalibrator(target_deg=5.0)
    c.update_many(A, B)
    assert c.effective_pairs == MIN_PAIRS and c.status()["not_ready"] == [] and c.ready
    # a calibrator whose thresholds equal what it measures: the excitation is enough, the radius is
    # not below target
    same = OnlineCalibrator(target_deg=c.radius, min_excitation_deg=c.excitation_deg)
    same.update_many(A, B)
    assert same.excitation_deg == c.excitation_deg and same.radius == c.radius and same.determined
    assert same.status()["not_ready"] == [f"95 % radius {c.radius:.3g} deg >= target {c.radius:g} deg"]


def test_status_names_the_unexcited_axis_to_three_decimals():
    axis = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    B = so3.matrix_from_rotation_vector(np.radians(np.linspace(20.0, 60.0, 12))[:, None] * axis)
    A = R0_MO @ B @ R0_MO.T
    c = OnlineCalibrator()
    c.update_many(A, B)
    why = [w for w in c.status()["not_ready"] if w.startswith("the motion does not determine R0")]
    assert len(why) == 1
    assert ("[0.267, 0.535, 0.802] (sensor frame)" in why[0]) or ("[-0.267, -0.535, -0.802] (sensor frame)" in why[0])


def test_a_radius_at_a_higher_level_is_larger():
    rng = np.random.default_rng(25)
    A, B = _pairs(30, rng, 0.3)
    c95, c99 = OnlineCalibrator(), OnlineCalibrator(level=0.99)
    c95.update_many(A, B)
    c99.update_many(A, B)
    assert c99.radius > 1.2 * c95.radius and np.array_equal(c95.R, c99.R)
    assert c99.radius == pytest.approx(radius_deg(c99._cov, 0.99))


def test_with_forgetting_the_radius_is_the_weighted_least_squares_covariance():
    rng = np.random.default_rng(26)
    A, B = _pairs(40, rng, 0.3)  # more than one batch of 16 pairs in the sums
    lam = 0.9
    c = OnlineCalibrator(forgetting=lam)
    c.update_many(A, B)
    w = lam ** np.arange(39, -1, -1.0)
    G = 2 * w.sum() * np.eye(3) - np.einsum("i,iab->ab", w, B + np.swapaxes(B, 1, 2))
    G2 = 2 * (w ** 2).sum() * np.eye(3) - np.einsum("i,iab->ab", w ** 2, B + np.swapaxes(B, 1, 2))
    s2 = math.radians(c.evidence()["rms_residual_deg"]) ** 2
    Gi = np.linalg.inv(G)
    assert c.radius == pytest.approx(radius_deg((s2 / 3) * Gi @ G2 @ Gi, 0.95), rel=1e-9)
    assert c.radius < 0.9 * radius_deg((s2 / 3) * Gi, 0.95)  # not the unweighted form (s^2 / 3) G^-1


def test_the_noise_level_from_four_pairs_divides_by_at_least_one():
    rng = np.random.default_rng(27)
    A, B = _pairs(4, rng, 0.5)
    c = OnlineCalibrator(min_pairs=4)
    c.update_many(A, B)
    cost = float(np.sum(np.linalg.norm(A @ c.R - c.R @ B, axis=(1, 2)) ** 2))
    # s^2 = (cost / J) J / (2 max(J - 3, 1)) with J = 4
    assert c.evidence()["rms_residual_deg"] == pytest.approx(math.degrees(math.sqrt(cost / 2.0)), rel=1e-6)


def test_the_radius_is_infinite_only_about_an_exactly_unexcited_axis_however_small_the_motions():
    # ten motions of 1-3 deg about axes within a few microradians of z: lambda_min(G) ~ 3e-13, far
    # below 1e-12 but above 1e-12 lambda_max (lambda_max ~ 0.015 < 1)
    rng = np.random.default_rng(5)
    axes = np.tile([0.0, 0.0, 1.0], (10, 1))
    axes[:, :2] += 3e-6 * rng.standard_normal((10, 2))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    B = so3.matrix_from_rotation_vector(np.radians(np.linspace(1.0, 3.0, 10))[:, None] * axes)
    A = R0_MO @ B @ R0_MO.T
    c = OnlineCalibrator()
    c.update_many(A, B)
    lam = np.linalg.eigvalsh(2 * 10 * np.eye(3) - B.sum(0) - B.sum(0).T)
    assert 1e-12 * lam[-1] < lam[0] < 1e-12 and lam[-1] < 1.0
    assert c.effective_pairs == 10 and math.isfinite(c.radius) and c.radius > 1000.0 and not c.determined


def test_motion_angles_at_0_and_180_deg_within_rounding_are_recorded():
    c = OnlineCalibrator()
    half_turn = np.diag([1.0, -1.0 - 1e-10, -1.0])  # trace -1 - 1e-10: acos would be out of its domain
    rest = np.diag([1.0 + 1e-10, 1.0, 1.0])         # trace 3 + 1e-10
    c.update(half_turn, half_turn)
    c.update(rest, rest)
    assert c.n_total == 2 and c.evidence()["motion_median_deg"] == pytest.approx(90.0)


def test_the_estimate_is_refined_on_the_documented_schedule():
    # at min_pairs, then every refine_every pairs or a tenth of the pairs so far, whichever is more
    rng = np.random.default_rng(28)
    A, B = _pairs(150, rng, 0.2)
    c = OnlineCalibrator()
    refined, last = [], c.R
    for s in c.update_many(A, B):
        if not np.array_equal(s.R, last):
            refined.append(s.n_pairs)
            last = s.R
    assert c.events == []
    assert refined == [10, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 121, 133, 146]


# ------------------------------------------------------------------------------------------------
# the radius's rules (the unexcited-axis bound, a creep's lag), the two-step schedule between
# refinements and the recent residuals, each at its boundary


class _NumpyWithEigh:
    """numpy, with ``linalg.eigh`` replaced (patched into the online module only)."""

    def __init__(self, eigh):
        self.linalg = type("linalg", (), {"eigh": staticmethod(eigh)})

    def __getattr__(self, name):
        return getattr(np, name)


@pytest.mark.parametrize("above, finite", [(False, False), (True, True)], ids=["at", "just-above"])
def test_the_radius_is_infinite_while_lambda_min_is_at_most_1e_12_lambda_max(monkeypatch, above, finite):
    """``lambda_min(G)`` set to exactly ``1e-12 lambda_max`` (the other eigenvalues unchanged): no
    radius; the next float up: a finite one."""
    from replication.rig import online

    def eigh(G):
        lam, V = np.linalg.eigh(G)
        bound = 1e-12 * float(lam[-1])
        assert 1e-12 * float(lam[1]) < bound  # the rule reads lambda_max, not the middle eigenvalue
        return np.r_[np.nextafter(bound, np.inf) if above else bound, lam[1:]], V

    monkeypatch.setattr(online, "np", _NumpyWithEigh(eigh))
    A, B = _pairs(30, np.random.default_rng(40), 0.3)
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert c.effective_pairs == 30 and math.isfinite(c.radius) is finite


def test_the_creep_test_is_told_the_latest_pair_and_whether_a_drift_is_followed(monkeypatch):
    from replication.rig.online_creep import CreepTest

    test, calls = CreepTest.test, []

    def spy(self, R, S, SB, s2, last, following=False):
        calls.append((last, following, c.n_total - 1, c.forgetting < 1.0))  # forgetting < 1: a drift followed
        return test(self, R, S, SB, s2, last, following)

    monkeypatch.setattr(CreepTest, "test", spy)
    A, B = drift_pairs(0, n_before=100, n_drift=800, rate_deg=0.0025, noise_deg=0.05)
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert [e.kind for e in c.events] == ["drift"] and 20 < sum(told for _, told, _, _ in calls) < len(calls)
    assert [(last, told) for last, told, _, _ in calls] == [(pair, following) for _, _, pair, following in calls]


@pytest.mark.parametrize("noise_floor_deg, finite_cov", [(1e140, True), (1e154, False)])
def test_a_covariance_beyond_the_floats_gives_an_infinite_radius_not_an_error(noise_floor_deg, finite_cov):
    """A noise floor of 1e154 deg about an axis excited by microradians (``lambda_min ~ 3e-13``):
    the covariance overflows; the radius is infinite, as it is while the covariance is finite but
    its eigenvalues' sums overflow."""
    rng = np.random.default_rng(5)
    axes = np.tile([0.0, 0.0, 1.0], (10, 1))
    axes[:, :2] += 3e-6 * rng.standard_normal((10, 2))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    B = so3.matrix_from_rotation_vector(np.radians(np.linspace(1.0, 3.0, 10))[:, None] * axes)
    c = OnlineCalibrator(noise_floor_deg=noise_floor_deg)
    with np.errstate(over="ignore"):
        c.update_many(R0_MO @ B @ R0_MO.T, B)
    assert c.effective_pairs == 10 and c.radius == math.inf and bool(np.all(np.isfinite(c._cov))) is finite_cov


@pytest.mark.parametrize("lag", [0.0, 0.3])
def test_a_creep_found_adds_its_lag_to_the_radius(monkeypatch, lag):
    from replication.rig.online_creep import CreepTest

    def found(self, R, S, SB, s2, last, following=False):
        self.found = (0.01, lag, 99.0, 30, np.array([1.0, 0.0, 0.0])) if lag else None
        return self.found

    A, B = _pairs(30, np.random.default_rng(41), 0.3)
    plain = OnlineCalibrator()
    plain.update_many(A, B)
    monkeypatch.setattr(CreepTest, "test", found)
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert 0.05 < plain.radius < 1.0 and c.radius == pytest.approx(plain.radius + lag, rel=1e-12)


@pytest.mark.parametrize("axes, steps", [
    ([[0.0, 0.0, 1.0]], [5, 15, 25, 35]),  # one axis: the detector never starts, a step between refinements
    (None, [5]),                           # determined at the first refinement (10 pairs): the detector starts
], ids=["undetermined", "determined"])
def test_a_two_step_step_runs_every_step_every_pairs_until_the_detector_starts(monkeypatch, axes, steps):
    from replication.rig import online

    project, seen = online.nearest_rotation_up_to_sign, []

    def spy(M):
        seen.append(c.n_pairs)
        return project(M)

    monkeypatch.setattr(online, "nearest_rotation_up_to_sign", spy)
    A, B = _pairs(40, np.random.default_rng(42), 0.2, axes=axes)
    c = OnlineCalibrator()
    states = c.update_many(A, B)
    assert c.determined is (axes is None) and [s.n_pairs for s in states][-1] == 40
    assert seen == [n for n in steps for _ in range(2)]  # eqs. (14) and (15): two projections a step


def test_estimate_runs_newton_to_convergence_and_a_refinement_30_iterations(monkeypatch):
    from replication.core.solvers import certificate

    newton, asked = certificate.chordal_newton, []

    def spy(K, init, *, max_iterations=30, **kw):
        asked.append(max_iterations)
        return newton(K, init, max_iterations=max_iterations, **kw)

    monkeypatch.setattr(certificate, "chordal_newton", spy)
    A, B = _pairs(12, np.random.default_rng(43), 0.2)
    c = OnlineCalibrator()
    c.update_many(A, B)
    c.estimate()
    assert asked == [30, 100]


def test_the_residual_median_reads_the_last_recent_pairs_only():
    """300 pairs at 0.6 deg of noise, then 200 at 0.05 deg: the median over the last 200 residuals
    is that of the quiet pairs (a noise drop raises no alarm)."""
    from replication.rig.online import RECENT_PAIRS

    rng = np.random.default_rng(44)
    R0 = so3.random_rotations(rng, ())
    loud, quiet = pair_stream(rng, 300, R0, noise_deg=0.6), pair_stream(rng, RECENT_PAIRS, R0, noise_deg=0.05)
    c = OnlineCalibrator()
    c.update_many(np.concatenate([loud[0], quiet[0]]), np.concatenate([loud[1], quiet[1]]))
    assert c.events == [] and c.n_total == 500
    assert c.evidence()["residual_median_deg"] < 0.1


def test_update_takes_the_same_array_likes_as_update_many():
    rng = np.random.default_rng(29)
    A, B = _pairs(12, rng, 0.2)
    text = OnlineCalibrator()
    for a, b in zip(A.astype(str), B.astype(str)):  # numbers as text, as numpy converts them
        text.update(a, b)
    batch = OnlineCalibrator()
    batch.update_many(A.astype(str), B.astype(str))
    assert text.n_total == batch.n_total == 12 and np.allclose(text.R, batch.R, atol=1e-12)


def test_update_many_names_the_camera_or_the_sensor_motions():
    A = np.stack([R0_MO, R0_MO])
    with pytest.raises(ValueError, match=r"A \(camera motions\) is not a rotation"):
        OnlineCalibrator().update_many(2 * A, A)
    with pytest.raises(ValueError, match=r"B \(sensor motions\) "):
        OnlineCalibrator().update_many(A, -A)


# ---------------------------------------------------------------------------------------------
# changes, online
def _outliers_after_the_start():
    """40 pairs; pairs 10-13 (just after the detector starts at pair 10) have a 2 deg error in the
    sensor motion."""
    rng = np.random.default_rng(11)
    A, B = _pairs(40, rng, 0.2)
    B[10:14] = B[10:14] @ so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([1.0, 0.0, 0.0]))
    return A, B


def test_outliers_right_after_the_detector_starts_date_their_onset_at_its_start():
    A, B = _outliers_after_the_start()
    c = OnlineCalibrator()
    states = c.update_many(A[:16], B[:16])
    # each outlier adds cap - k = 8 to the CUSUM: above h = 30 at the fourth (pair 13); the next go
    # to the window
    assert [s.checking for s in states[9:16]] == [False, False, False, False, True, True, True]
    assert "a change is being confirmed (2 of 10 pairs)" in c.status()["not_ready"]
    c.update_many(A[16:], B[16:])
    (ev,) = c.events
    assert (ev.kind, ev.source, ev.alarm_pair, ev.onset_pair, ev.pair, ev.window_pairs) == (
        "outliers", "cusum", 13, 10, 23, 10)
    assert ev.pairs_dropped == c.pairs_dropped == 4 and c.alarms == []


def test_the_first_refinement_gives_a_verdict_that_ready_reads():
    rng = np.random.default_rng(30)
    A, B = _pairs(10, rng, 0.2)
    c = OnlineCalibrator(target_deg=5.0)
    c.update_many(A[:9], B[:9])
    assert c.current_verdict is None
    c.update(A[9], B[9])
    assert c.current_verdict is not None and c.current_verdict.level == "warning" and c.ready
    c.set_context(gyro_rate_hz=100.0, interval_s=0.02)  # 2 gyro samples per pair: fail
    assert c.current_verdict.level == "fail" and not c.ready


def test_after_a_large_remount_the_estimate_restarts_from_the_windows_own_estimate():
    # Newton from the estimate before a 170 deg re-mount would stop at another critical point of eq.
    # (8)
    rng = np.random.default_rng(0)
    A, B = _pairs(60, rng, 0.2)
    turn = so3.matrix_from_rotation_vector(np.radians(170.0) * np.array([0.0, 0.6, 0.8]))
    B[30:] = turn.T @ B[30:] @ turn
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert [e.kind for e in c.events] == ["remount"] and c.alarms == [43]
    assert so3.angle_between_deg(c.R, R0_MO @ turn) < 0.2


def test_a_refinement_does_not_restart_the_cusum_building_up():
    # the noise triples from pair 27 on; the estimate is refined at pair 29 (its 30th) while the
    # CUSUM rises
    rng = np.random.default_rng(12)
    A, B = _pairs(60, rng, 0.2)
    B[27:] = B[27:] @ so3.matrix_from_rotation_vector(np.radians(0.6) * rng.standard_normal((33, 3)))
    c = OnlineCalibrator()
    c.update_many(A, B)
    ev = c.events[0]
    assert ev.kind == "noise_change" and ev.source == "cusum" and 27 <= ev.onset_pair <= 29 and ev.alarm_pair == 35


def test_before_any_pair_the_evidence_is_the_floor_and_nothing_estimated():
    c = OnlineCalibrator()
    e = c.evidence()
    assert e["rms_residual_deg"] == pytest.approx(NOISE_FLOOR_DEG) and e["effective_pairs"] == 0.0
    assert c.status()["not_ready"][0] == "0.0 effective distinct pairs < 10"
    rng = np.random.default_rng(31)
    A, B = _pairs(1, rng, 0.2)
    assert c.update(A[0], B[0]).estimated is False


def test_restart_forgets_the_pairs_and_starts_from_the_last_estimate():
    rng = np.random.default_rng(32)
    A, B = _pairs(12, rng, 0.2)
    c = OnlineCalibrator()
    c.update_many(A, B)
    last = c.R.copy()
    c.restart()
    assert np.array_equal(c.R, last) and c.n_pairs == 0 and c.radius == math.inf and not c.determined
    c.restart(init=[[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert np.array_equal(c.R, np.eye(3)) and c.R.dtype == float


def test_the_motion_median_reads_the_last_recent_pairs_only():
    from replication.rig.online import RECENT_PAIRS

    rng = np.random.default_rng(33)
    n_big, n_small = 150, 110
    axes = rng.standard_normal((n_big + n_small, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    angles = np.r_[np.full(n_big, 50.0), np.full(n_small, 10.0)] + rng.uniform(-1, 1, n_big + n_small)
    A = so3.matrix_from_rotation_vector(np.radians(angles)[:, None] * axes)
    c = OnlineCalibrator()
    c.update_many(A, R0_MO.T @ A @ R0_MO)
    assert RECENT_PAIRS == 200 and c.n_total == 260
    assert c.evidence()["motion_median_deg"] < 12.0  # the last 200: 110 of about 10 deg, 90 of about 50


@pytest.mark.parametrize("complex_side", ["A", "B"])
def test_a_complex_pair_is_refused_by_update_as_by_update_many(complex_side):
    A, B = (np.eye(3) + 0j, np.eye(3)) if complex_side == "A" else (np.eye(3), np.eye(3) + 0j)
    with pytest.raises(ValueError, match=r"^a pair is two 3x3 rotations, real-valued; got a complex array$"):
        OnlineCalibrator().update(A, B)
    with pytest.raises(ValueError, match="real-valued"):
        OnlineCalibrator().update_many(A[None], B[None])


@pytest.mark.parametrize("R0", [np.eye(3) * (1 + 1e-3j), (np.eye(3) + 0j).tolist()], ids=["array", "list"])
def test_error_deg_refuses_a_complex_reference_like_update(R0):
    with pytest.raises(ValueError, match="R0 must be real-valued; got a complex array"):
        OnlineCalibrator().error_deg(R0)


# --------------------------------------------------------------------------------------------------
# the drift's end on the estimates' centroids (point 2) and the live gyro bias


def test_the_centroid_is_the_weighted_mean_pair_index():
    A, B = drift_pairs(1, n_before=40, n_drift=0)
    cal = OnlineCalibrator()
    cal.update_many(A[:33], B[:33])
    cal.K  # noqa: B018  (flushes the buffer)
    assert cal.centroid == pytest.approx(16.0)
    lam = OnlineCalibrator(forgetting=0.9)
    lam.update_many(A[:40], B[:40])
    lam.K  # noqa: B018
    w = 0.9 ** np.arange(39, -1, -1.0)
    assert lam.centroid == pytest.approx(float(w @ np.arange(40) / w.sum()))
