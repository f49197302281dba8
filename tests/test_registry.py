import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from replication import so3
from replication.motions import Motions
from replication.solvers import _registry, available, register, solve, solver_info
from replication.testing import assert_rotations_close


def test_available_lists_the_paper_method():
    assert {"two_step_right", "two_step_left"} <= set(available())
    assert "Zhang" in solver_info("two_step_left").reference


@pytest.mark.parametrize("method", ["two_step_right", "two_step_left"])
def test_solve_recovers_and_returns_rotations(problem, method):
    R0, A, B = problem
    R = solve(method, np.stack([A, A]), np.stack([B, B]))
    assert R.shape == (2, 3, 3)
    so3.check_rotation_matrices(R)
    assert_rotations_close(R, R0, 5e-8)


def test_unknown_method_lists_the_available_ones(problem):
    _, A, B = problem
    with pytest.raises(ValueError, match="unknown solver 'nope'; available: .*two_step_left"):
        solve("nope", A, B)


def test_register_new_solver_and_refuse_duplicates(problem, monkeypatch):
    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    R0, A, B = problem

    seen = []

    @register("truth_oracle", reference="test", min_motions=3)
    def oracle(motions, *, answer):
        seen.append(motions)
        return np.broadcast_to(answer, motions.batch_shape + (3, 3))

    assert "truth_oracle" in available()
    assert np.array_equal(solve("truth_oracle", A, B, answer=R0), R0)
    # the decorator returns the public door: it validates like solve() and hands the core a Motions
    assert np.array_equal(oracle(A, B, answer=R0), R0)
    assert all(isinstance(m, Motions) and m.J == 20 for m in seen)
    with pytest.raises(ValueError, match="not a rotation matrix"):
        oracle(2 * A, B, answer=R0)
    with pytest.raises(ValueError, match="at least 3 motion pairs"):
        solve("truth_oracle", A[:2], B[:2], answer=R0)
    with pytest.raises(ValueError, match="already registered"):
        register("truth_oracle", reference="again")(oracle)


def test_solve_refuses_degenerate_motion(rng):
    R0 = so3.random_rotations(rng, ())
    A = Rotation.from_rotvec(np.outer(np.linspace(0.2, 1.0, 8), [1, 0, 0])).as_matrix()
    with pytest.raises(ValueError, match="degenerate motion"):
        solve("two_step_right", A, R0.T @ A @ R0)
