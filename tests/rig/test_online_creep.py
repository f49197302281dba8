"""The online estimator's creep test (:mod:`replication.rig.online_creep`): the slope of R0 over the
pairs since the last start, its lag in the radius, and ``not_ready`` naming the creep with its
rate."""
import numpy as np
import pytest

from replication.core import so3
from replication.rig.online import OnlineCalibrator
from replication.rig.online_creep import CREEP_LEVEL, CREEP_MIN_PAIRS, CreepTest, _gradient
from replication.rig.online_guard import _share
from replication.study.live_study import pair_stream

AXIS = np.array([0.3, -0.5, 0.81]) / np.linalg.norm([0.3, -0.5, 0.81])


def _creeping(seed, n, rate_deg_per_pair, noise_deg=0.05):
    """``n`` pairs whose camera_from_sensor turns ``rate_deg_per_pair`` per pair about AXIS."""
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    Rt = lambda j: R0 @ so3.matrix_from_rotation_vector(np.radians(rate_deg_per_pair * j) * AXIS)  # noqa: E731
    A, B = zip(*[[x[0] for x in pair_stream(rng, 1, Rt(j), noise_deg=noise_deg)] for j in range(n)])
    return Rt, np.array(A), np.array(B)


def _quiet(**kw):
    """A calibrator whose change detector never raises an alarm: the creep test alone."""
    return OnlineCalibrator(cusum_h=1e9, drift_pairs=10 ** 6, **kw)


def test_the_constants():
    assert (CREEP_LEVEL, CREEP_MIN_PAIRS) == (0.999, 40)
    assert CreepTest().threshold == pytest.approx(16.55, abs=0.01)  # chi^2_3 at 0.999 (Wilson-Hilferty; 16.27)


def test_the_slope_gradient_is_the_sum_of_the_pairs_shares():
    rng = np.random.default_rng(3)
    R0 = so3.random_rotations(rng, ())
    A, B = pair_stream(rng, 20, R0, noise_deg=0.5)
    R = R0 @ so3.matrix_from_rotation_vector(np.array([0.01, -0.02, 0.005]))
    c = rng.uniform(-2, 2, len(A))
    M = np.einsum("i,iab,icd->acbd", c, B, A).reshape(9, 9)
    shares = sum(ci * np.array(_share(R, a, b)[0]) for ci, a, b in zip(c, A, B))
    assert np.allclose(_gradient(M, R), shares, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_creep_just_below_the_target_widens_the_radius_and_just_above_withholds_ready(seed):
    """400 pairs at 0.05 deg of noise (radius about 0.01 deg), target 0.2 deg: the mounting at the
    last test (pair 372) is about 186 x rate from the estimate (the pairs' centroid), so the radius
    with the lag reaches the target at about 0.00102 deg per pair; 0.0008 stays below (ready by the
    radius, the creep measured), 0.0011 above (not ready, the creep named with its rate)."""
    Rt, A, B = _creeping([5, seed], 400, 0.0008)
    oc = _quiet(target_deg=0.2)
    oc.update_many(A, B)
    status = oc.status()
    assert status["creep_deg_per_pair"] == pytest.approx(0.0008, rel=0.15)
    assert 0.15 < status["radius_deg"] < 0.2  # the lag is in the radius, still below the target
    assert status["radius_deg"] >= oc.error_deg(Rt(372))  # the radius holds the mounting at its last test
    assert not any("creeps" in why for why in status["not_ready"])
    Rt, A, B = _creeping([5, seed], 400, 0.0011)
    oc = _quiet(target_deg=0.2)
    states = oc.update_many(A, B)
    status = oc.status()
    assert status["radius_deg"] >= 0.2 and not states[-1].ready
    creep = [why for why in status["not_ready"] if "the mounting creeps" in why]
    assert len(creep) == 1 and "0.0011" in creep[0] and "deg per pair" in creep[0]


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_steady_mounting_finds_no_creep(seed):
    _, A, B = _creeping([5, seed], 400, 0.0)
    oc = _quiet(target_deg=0.2)
    states = oc.update_many(A, B)
    assert oc.status()["creep_deg_per_pair"] is None and states[-1].ready
    assert oc.status()["radius_deg"] < 0.02


def test_forgetting_turns_the_test_off():
    """With forgetting the estimate's memory is short (its lag bounded by it): the slope over the
    pairs is not measured, and no lag is added."""
    _, A, B = _creeping([5, 0], 400, 0.0011)
    oc = _quiet(target_deg=0.2, forgetting=0.99)
    oc.update_many(A, B)
    assert oc.status()["creep_deg_per_pair"] is None


def test_a_restart_forgets_the_slope():
    Rt, A, B = _creeping([5, 0], 400, 0.0011)
    oc = _quiet(target_deg=0.2)
    oc.update_many(A, B)
    assert oc.status()["creep_deg_per_pair"] is not None
    oc.restart()
    oc.update_many(*pair_stream(np.random.default_rng(9), 100, Rt(399), noise_deg=0.05))
    assert oc.status()["creep_deg_per_pair"] is None


@pytest.mark.parametrize("rate", [0.0008, 0.0011])
def test_an_outlier_burst_during_a_creep_is_outliers_not_the_creeps_step(rate):
    """Eight random camera motions at pairs 140-147 of a creep (its slope found before, at 0.05 deg
    of noise): the burst's window lies ahead of the lagging estimate, in the creep's direction, yet
    it is no re-mount (outliers: nothing restarts), so not the creep's next step; the creep's own
    re-mount later is (one drift)."""
    Rt, A, B = _creeping([5, 0], 260, rate)
    A[140:148] = so3.random_rotations(np.random.default_rng(3), 8)
    oc = OnlineCalibrator()
    states = oc.update_many(A, B)
    assert [(e.kind, e.pair, e.onset_pair) for e in oc.events][0] == ("outliers", 153, 140)
    assert [e.kind for e in oc.events] == ["outliers", "drift"] and oc.events[1].pair > 153 and oc.alarms == []
    assert [s.event for s in states if s.event] == ["outliers", "drift"]


def _stepped(seed, n, at, step_deg, noise_deg=0.05):
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    R1 = R0 @ so3.matrix_from_rotation_vector(np.radians(step_deg) * AXIS)
    A0, B0 = pair_stream(rng, at, R0, noise_deg=noise_deg)
    A1, B1 = pair_stream(rng, n - at, R1, noise_deg=noise_deg)
    return np.concatenate([A0, A1]), np.concatenate([B0, B1])


@pytest.mark.parametrize("seed", [0, 1])
def test_a_step_fits_as_a_step_and_a_creep_as_a_creep(seed):
    """Both leave a slope over the pairs; the blocks tell them apart: 0.3 deg at pair 300 of 400,
    and a creep of 0.3 deg over the last 300 (0.001 deg per pair from pair 100)."""
    A, B = _stepped([6, seed], 400, 300, 0.3)
    oc = _quiet(target_deg=0.2)
    oc.update_many(A, B)
    as_step, as_creep, _ = oc._creep.step_or_creep(oc.R)
    assert oc.status()["creep_deg_per_pair"] is not None and as_step > as_creep
    Rt, A, B = _creeping([6, seed], 400, 0.001)
    A, B = A[:100], B[:100]  # flat for 100 pairs, then the creep
    R0 = Rt(0)
    rng = np.random.default_rng([7, seed])
    A2, B2 = zip(*[[x[0] for x in pair_stream(rng, 1, R0 @ so3.matrix_from_rotation_vector(
        np.radians(0.001 * j) * AXIS), noise_deg=0.05)] for j in range(300)])
    oc = _quiet(target_deg=0.2)
    oc.update_many(np.concatenate([A, A2]), np.concatenate([B, B2]))
    as_step, as_creep, (first, _, u) = oc._creep.step_or_creep(oc.R)
    assert as_creep > as_step
    assert 50 <= first <= 160 and np.degrees(np.linalg.norm(u)) == pytest.approx(0.001, rel=0.2)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_step_after_a_long_steady_stretch_is_a_remount(seed):
    """A 1 deg re-mount at pair 500 of 800 (0.3 deg of noise): a re-mount, started over, never a
    drift, even where the pairs after the step leave a slope before it is decided."""
    A, B = _stepped([8, seed], 800, 500, 1.0, noise_deg=0.3)
    oc = OnlineCalibrator()
    oc.update_many(A, B)
    assert [e.kind for e in oc.events if e.kind != "outliers"] == ["remount"] and len(oc.alarms) == 1
    assert 500 <= oc.alarms[0] < 560
