import numpy as np
import pytest

from replication.core import checks, so3
from replication.study.paper import r0_camera_from_sensor
from replication.study.simulation import SimulationSettings, noise_bound_for_angle_deg, simulate


def test_shapes_truth_and_noise_bound():
    sim = simulate(7, 50)
    assert sim.A.shape == sim.B.shape == (50, 20, 3, 3) and sim.R0.shape == (50, 3, 3)
    assert np.allclose(sim.R0, r0_camera_from_sensor())
    checks.check_rotation_matrices(sim.A)
    checks.check_rotation_matrices(sim.B)
    # residual of eq. (7) comes only from the two noise rotations, each below arctan(0.02)
    resid = so3.angle_between_deg(sim.A @ sim.R0[:, None], sim.R0[:, None] @ sim.B)
    assert 0 < resid.max() <= 2 * np.degrees(np.arctan(0.02)) + 1e-9


def test_noise_free_is_exact_and_runs_are_independent_streams():
    sim = simulate(3, 10, noise_camera=0.0, noise_sensor=0.0, random_R0=True)
    assert np.abs(sim.A @ sim.R0[:, None] - sim.R0[:, None] @ sim.B).max() < 1e-12
    more = simulate(3, 25, noise_camera=0.0, noise_sensor=0.0, random_R0=True)
    assert np.array_equal(sim.A, more.A[:10]) and np.array_equal(sim.R0, more.R0[:10])
    assert not np.array_equal(simulate(4, 10).A, simulate(3, 10).A)


def test_motion_angle_range_is_respected():
    sim = simulate(1, 20, motion_angle_range_deg=(10, 20), noise_camera=0.0)
    ang = so3.rotation_angle_deg(sim.A)
    assert ang.min() >= 10 - 1e-9 and ang.max() <= 20 + 1e-9


def test_noise_bound_for_angle():
    assert noise_bound_for_angle_deg(45) == pytest.approx(1.0)
    v = so3.sample_ball(np.random.default_rng(0), 100, noise_bound_for_angle_deg(5), "sphere")
    assert np.allclose(so3.rotation_angle_deg(so3.noise_rotations(v)), 5)
    with pytest.raises(ValueError, match="angle_deg"):
        noise_bound_for_angle_deg(95)


@pytest.mark.parametrize(
    "kwargs, message",
    [({"n_motions": 1}, "n_motions"), ({"noise_sensor": -1.0}, "noise_sensor"),
     ({"noise_camera": np.nan}, "noise_camera")],
)
def test_bad_settings(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SimulationSettings(**kwargs)
    with pytest.raises(ValueError, match="n_runs"):
        simulate(0, 0)
