"""The online calibrator's rules (:class:`replication.online.OnlineCalibrator`) at their boundaries: every option's
range and default, the running sums and their forgetting, the radius (``inf`` until the motion determines ``R0``),
``determined`` and ``ready``, the evidence and the not-ready sentences. Mutation testing (scripts/mutation) found
these unguarded by the fast tests."""
import math

import numpy as np
import pytest

from replication import so3
from replication.handeye import kronecker_operator
from replication.online import MIN_EXCITATION_DEG, MIN_PAIRS, NOISE_FLOOR_DEG, OnlineCalibrator
from replication.online_events import DUPLICATE_DEG
from replication.stats import radius_deg

R0 = so3.exp_map(np.array([0.4, -0.2, 0.9]))


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
    A = so3.random_rotations(rng, n) if axes is None else so3.exp_map(
        np.radians(rng.uniform(20, 60, n))[:, None] * np.asarray(axes, float)[rng.integers(0, len(axes), n)])
    B = R0.T @ A @ R0
    if noise_deg:
        B = B @ so3.exp_map(np.radians(noise_deg) * rng.standard_normal((n, 3)))
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
    assert any(w.startswith("the motion does not determine R0: RMS rotation about axes perpendicular to [") for w in why)


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
    with pytest.raises(ValueError, match=r"^need two \(J, 3, 3\) arrays of the same J, got \(2, 3, 3\) and \(3, 3, 3\)$"):
        c.update_many(np.stack([R0] * 2), np.stack([R0] * 3))
    assert c.n_total == 0


def test_outliers_decided_online_count_as_dropped_once_and_the_refinement_schedule_resumes():
    rng = np.random.default_rng(7)
    A, B = _pairs(180, rng, 0.2)
    B[125:130] = B[125:130] @ so3.exp_map(np.radians(20.0) * np.array([1.0, 0.0, 0.0]))
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
    turn = so3.exp_map(np.radians(6.0) * np.array([0.0, 1.0, 0.0]))
    B[150:] = turn.T @ B[150:] @ turn  # R0 becomes R0 turn from pair 150 on
    c = OnlineCalibrator()
    states = c.update_many(A, B)
    assert len(c.alarms) == 1 and c.events[0].kind == "remount" and c.alarms[0] == c.events[0].pair
    at = c.alarms[0]
    assert states[at].alarm and states[at].event == "remount"
    assert so3.angle_between_deg(c.R, R0 @ turn) < 0.3
    assert c.n_pairs < 260 - 150 + 40 and c.n_total == 260
    assert c._next_refine > c.n_pairs
