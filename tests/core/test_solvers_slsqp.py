import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from replication.core import handeye, so3
from replication.core.solvers import Solution, available, solve, sqp, two_step
from replication.study.simulation import simulate
from replication.testing import assert_rotations_close


def near(R0, deg=30.0):
    """A start ``deg`` from R0: SQP's contract is local (from far starts it can stop at a wrong
    stationary point of (8) — notebook 03 measures how often)."""
    return R0 @ Rotation.from_rotvec(np.radians(deg) * np.array([0.6, 0.0, 0.8])).as_matrix()


def test_noise_free_recovery_and_history(problem):
    R0, A, B = problem
    res = sqp(A, B, max_iterations=60, init=near(R0))
    assert res.history.iterates.shape == (60, 3, 3) and res.history.cost.shape == (60,)
    assert res.history.success and 1 <= res.iterations <= 60
    assert so3.frobenius_error(res.R, R0) < 1e-8  # SLSQP's ftol: measured 7e-10
    # after it stops, the history repeats the last iterate
    assert np.array_equal(res.history.iterates[-1], res.history.iterates[res.iterations - 1])


def test_reaches_the_minimiser_of_eq8_which_beats_the_two_step_fixed_point():
    sim = simulate(11, 20)
    s = sqp(sim.A, sim.B, max_iterations=100)
    r = two_step(sim.A, sim.B, iterations=50)
    cost_sqp = handeye.handeye_cost(s.R, sim.A, sim.B)
    assert s.history.success.all()
    assert np.all(cost_sqp <= handeye.handeye_cost(r.R, sim.A, sim.B) + 1e-12)


def test_registered_and_batched(problem):
    R0, A, B = problem
    assert "sqp" in available()
    R = solve("sqp", np.stack([A, A]), np.stack([B, B]), init=near(R0))
    assert R.shape == (2, 3, 3)
    assert_rotations_close(R, R0, 5e-5)


@pytest.mark.parametrize(
    "kwargs, message",
    [({"constraints": "none"}, "constraints must be"), ({"max_iterations": 0}, "max_iterations"),
     ({"init": np.eye(3) * 2}, "init is not a rotation")],
)
def test_bad_arguments(problem, kwargs, message):
    _, A, B = problem
    with pytest.raises(ValueError, match=message):
        sqp(A, B, **kwargs)


def test_the_answer_is_the_solution_solve_gives_with_the_history(problem):
    """The projected last iterate with solve's cost (8) and certificate, bit for bit; the history
    holds every iterate and the cost (8) at each."""
    R0, A, B = problem
    res = sqp(A, B, max_iterations=60, init=near(R0))
    full = solve("sqp", A, B, full_output=True, max_iterations=60, init=near(R0))
    assert isinstance(res, Solution) and res.method == "sqp"
    for name in ("R", "cost", "lower_bound", "duality_gap", "global_optimum", "certificate"):
        assert np.array_equal(getattr(res, name), getattr(full, name)), name
    assert np.array_equal(res.R, res.history.projected[-1]) and res.global_optimum
    assert res.cost.shape == () and res.history.cost.shape == (60,)
