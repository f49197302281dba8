"""The online calibrator's rules (:class:`replication.rig.online.OnlineCalibrator`) at their boundaries: every option's
range and default, the running sums and their forgetting, the radius (``inf`` until the motion determines ``R0``),
``determined`` and ``ready``, the evidence and the not-ready sentences. Mutation testing (scripts/mutation) found
these unguarded by the fast tests."""
import math

import numpy as np
import pytest

from replication.core import so3
from replication.core.handeye import kronecker_operator
from replication.core.stats import radius_deg
from replication.rig.online import MIN_EXCITATION_DEG, MIN_PAIRS, NOISE_FLOOR_DEG, OnlineCalibrator
from replication.rig.online_events import DUPLICATE_DEG

R0 = so3.matrix_from_rotation_vector(np.array([0.4, -0.2, 0.9]))


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
    with pytest.raises(ValueError, match=rf"^{name} must be > 0, got 0$"):
        OnlineCalibrator(**{name: 0})


def test_duplicate_tolerance_may_be_zero():
    assert OnlineCalibrator(duplicate_deg=0.0).duplicate_deg == 0.0
    with pytest.raises(ValueError, match=r"^duplicate_deg must be >= 0, got -0\.001$"):
        OnlineCalibrator(duplicate_deg=-0.001)


def test_the_cusum_cap_must_exceed_k():
    OnlineCalibrator(cusum_k=2.0, cusum_cap=2.0000001)
    with pytest.raises(ValueError, match=r"^cusum_cap must be above cusum_k \(else the detector's sum never rises\), "
                                         r"got cusum_cap=2\.0, cusum_k=2\.0$"):
        OnlineCalibrator(cusum_k=2.0, cusum_cap=2.0)
    with pytest.raises(ValueError, match=r"^cusum_cap must be a finite number"):
        OnlineCalibrator(cusum_cap=math.inf)


def test_level_and_reference_rate_ranges():
    assert OnlineCalibrator(level=0.5).level == 0.5
    for bad in (0.0, 1.0):
        with pytest.raises(ValueError, match=rf"^level must be in \(0, 1\), got {bad}$"):
            OnlineCalibrator(level=bad)
    assert OnlineCalibrator(reference_rate=1.0).reference_rate == 1.0
    with pytest.raises(ValueError, match=r"^reference_rate must be in \(0, 1\], got 0\.0$"):
        OnlineCalibrator(reference_rate=0.0)


@pytest.mark.parametrize("name, least", [("step_every", 1), ("refine_every", 1), ("min_pairs", 4),
                                         ("confirm_pairs", 5), ("drift_pairs", 10)])
def test_integer_options_and_their_least_values(name, least):
    kw = {name: least}
    if name == "confirm_pairs":
        kw["max_confirm_pairs"] = least
    c = OnlineCalibrator(**kw)
    assert getattr(c, name) == least and type(getattr(c, name)) is int
    with pytest.raises(ValueError, match=rf"^{name} must be >= {least}, got {least - 1}$"):
        OnlineCalibrator(**{name: least - 1})
    with pytest.raises(ValueError, match=rf"^{name} must be a finite integer, got {least}\.0$"):
        OnlineCalibrator(**{name: float(least)})


def test_the_confirmation_window_bounds():
    assert OnlineCalibrator(confirm_pairs=7, max_confirm_pairs=7).max_confirm_pairs == 7
    with pytest.raises(ValueError, match=r"^max_confirm_pairs must be at least confirm_pairs = 7, got 6$"):
        OnlineCalibrator(confirm_pairs=7, max_confirm_pairs=6)
    with pytest.raises(ValueError, match=r"^max_confirm_pairs must be >= 5, got 4$"):
        OnlineCalibrator(max_confirm_pairs=4)


def test_forgetting_is_bounded_by_the_pairs_it_needs():
    lowest = (10 - 1) / (10 + 1)
    assert OnlineCalibrator(forgetting=lowest).forgetting == lowest
    assert OnlineCalibrator(forgetting=1.0).forgetting == 1.0
    with pytest.raises(ValueError, match=r"^forgetting must be in \[0\.818182, 1\], got 0\.8$"):
        OnlineCalibrator(forgetting=0.8)
    with pytest.raises(ValueError, match=r"^forgetting must be in \[0\.818182, 1\], got 1\.01$"):
        OnlineCalibrator(forgetting=1.01)
    assert OnlineCalibrator(min_pairs=4, forgetting=0.6).forgetting == 0.6  # (4 - 1) / (4 + 1)


def test_the_start_rotation():
    c = OnlineCalibrator(init=R0)
    assert np.array_equal(c.R, R0)
    with pytest.raises(ValueError, match=r"^init must be one 3x3 rotation, got shape \(2, 3, 3\)$"):
        OnlineCalibrator(init=np.stack([R0, R0]))
    with pytest.raises(ValueError, match="init is not a rotation matrix"):
        OnlineCalibrator(init=2 * R0)


def _pairs(n, rng, noise_deg=0.0, axes=None):
    A = so3.random_rotations(rng, n) if axes is None else so3.matrix_from_rotation_vector(
        np.radians(rng.uniform(20, 60, n))[:, None] * np.asarray(axes, float)[rng.integers(0, len(axes), n)])
    B = R0.T @ A @ R0
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
    assert so3.angle_between_deg(c.estimate(), R0) < 0.5
    # the radius: (s^2 / 3) G^-1 at the calibrator's level, s^2 the mean square residual corrected for 3 unknowns
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
    with pytest.raises(ValueError, match=r"^a pair is two 3x3 rotations, got shapes \(2, 3, 3\) and \(2, 3, 3\)$"):
        c.update(np.stack([R0, R0]), np.stack([R0, R0]))
    with pytest.raises(ValueError, match=r"^a pair is two 3x3 rotations: "):
        c.update(np.stack([R0, R0]), R0)
    with pytest.raises(ValueError, match=r"^A \(camera motion\) is not a rotation matrix"):
        c.update(2 * R0, R0)
    with pytest.raises(ValueError, match=r"^B \(sensor motion\) is a reflection"):
        c.update(R0, -R0)
    with pytest.raises(ValueError, match=r"^need two \(J, 3, 3\) arrays of the same J, "
                                         r"got \(2, 3, 3\) and \(3, 3, 3\)$"):
        c.update_many(np.stack([R0] * 2), np.stack([R0] * 3))
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
    assert c2._next_refine == c2.n_pairs + max(c2.refine_every, c2.n_pairs // 10)


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
    assert so3.angle_between_deg(c.R, R0 @ turn) < 0.3
    assert c.n_pairs < 260 - 150 + 40 and c.n_total == 260
    assert c._next_refine > c.n_pairs


# --------------------------------------------------------------------------------------------- judging and status
def _small_noisy_pairs(n, rng, noise_deg):
    """Motions of 4-8 deg about random axes, sensor motions with ``noise_deg`` per axis."""
    axes = rng.standard_normal((n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    A = so3.matrix_from_rotation_vector(np.radians(rng.uniform(4, 8, n))[:, None] * axes)
    return A, R0.T @ A @ R0 @ so3.matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal((n, 3)))


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
    # a calibrator whose thresholds equal what it measures: the excitation is enough, the radius is not below target
    same = OnlineCalibrator(target_deg=c.radius, min_excitation_deg=c.excitation_deg)
    same.update_many(A, B)
    assert same.excitation_deg == c.excitation_deg and same.radius == c.radius and same.determined
    assert same.status()["not_ready"] == [f"95 % radius {c.radius:.3g} deg >= target {c.radius:g} deg"]


def test_status_names_the_unexcited_axis_to_three_decimals():
    axis = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    B = so3.matrix_from_rotation_vector(np.radians(np.linspace(20.0, 60.0, 12))[:, None] * axis)
    A = R0 @ B @ R0.T
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
    # ten motions of 1-3 deg about axes within a few microradians of z: lambda_min(G) ~ 3e-13, far below
    # 1e-12 but above 1e-12 lambda_max (lambda_max ~ 0.015 < 1)
    rng = np.random.default_rng(5)
    axes = np.tile([0.0, 0.0, 1.0], (10, 1))
    axes[:, :2] += 3e-6 * rng.standard_normal((10, 2))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    B = so3.matrix_from_rotation_vector(np.radians(np.linspace(1.0, 3.0, 10))[:, None] * axes)
    A = R0 @ B @ R0.T
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
    A = np.stack([R0, R0])
    with pytest.raises(ValueError, match=r"^A \(camera motions\) is not a rotation"):
        OnlineCalibrator().update_many(2 * A, A)
    with pytest.raises(ValueError, match=r"^B \(sensor motions\) "):
        OnlineCalibrator().update_many(A, -A)


# --------------------------------------------------------------------------------------------- changes, online
def _outliers_after_the_start():
    """40 pairs; pairs 10-13 (just after the detector starts at pair 10) have a 2 deg error in the sensor motion."""
    rng = np.random.default_rng(11)
    A, B = _pairs(40, rng, 0.2)
    B[10:14] = B[10:14] @ so3.matrix_from_rotation_vector(np.radians(2.0) * np.array([1.0, 0.0, 0.0]))
    return A, B


def test_outliers_right_after_the_detector_starts_date_their_onset_at_its_start():
    A, B = _outliers_after_the_start()
    c = OnlineCalibrator()
    states = c.update_many(A[:16], B[:16])
    # each outlier adds cap - k = 8 to the CUSUM: above h = 30 at the fourth (pair 13); the next go to the window
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
    # Newton from the estimate before a 170 deg re-mount would stop at another critical point of eq. (8)
    rng = np.random.default_rng(0)
    A, B = _pairs(60, rng, 0.2)
    turn = so3.matrix_from_rotation_vector(np.radians(170.0) * np.array([0.0, 0.6, 0.8]))
    B[30:] = turn.T @ B[30:] @ turn
    c = OnlineCalibrator()
    c.update_many(A, B)
    assert [e.kind for e in c.events] == ["remount"] and c.alarms == [43]
    assert so3.angle_between_deg(c.R, R0 @ turn) < 0.2


def test_a_refinement_does_not_restart_the_cusum_building_up():
    # the noise triples from pair 27 on; the estimate is refined at pair 29 (its 30th) while the CUSUM rises
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
    c.update_many(A, R0.T @ A @ R0)
    assert RECENT_PAIRS == 200 and c.n_total == 260
    assert c.evidence()["motion_median_deg"] < 12.0  # the last 200: 110 of about 10 deg, 90 of about 50


def test_a_complex_pair_is_refused_by_update_as_by_update_many():
    A = np.eye(3) + 0j
    with pytest.raises(ValueError, match="real-valued; got a complex array"):
        OnlineCalibrator().update(A, np.eye(3))
    with pytest.raises(ValueError, match="real-valued"):
        OnlineCalibrator().update_many(A[None], np.eye(3)[None])
