import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from conftest import noisy_problem
from replication.core import checks, handeye, so3
from replication.core.so3 import random_rotations
from replication.core.solvers import ConvergenceWarning, Solution, solve, two_step, two_step_fixed_point
from replication.testing import assert_rotations_close


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_noise_free_recovery_from_any_valid_start(seed):
    """Any rotation start (the corrected variant accepts all) recovers R0 to 1e-9 Frobenius."""
    rng = np.random.default_rng(seed)
    R0, init = so3.random_rotations(rng, 2)
    A = so3.random_rotations(rng, 20)
    res = two_step(A, R0.T @ A @ R0, iterations=100, init=init)
    assert so3.frobenius_error(res.R, R0) < 1e-9
    assert so3.frobenius_error(res.history.R_left, R0) < 1e-9


def test_result_shapes_and_costs(problem):
    R0, A, B = problem
    AA, BB = np.stack([A] * 6).reshape(2, 3, 20, 3, 3), np.stack([B] * 6).reshape(2, 3, 20, 3, 3)
    res = two_step(AA, BB, iterations=7)
    for name in ("right", "left", "right_raw", "left_raw"):
        assert getattr(res.history, name).shape == (2, 3, 7, 3, 3)
    assert res.history.cost_right.shape == (2, 3, 7) and res.history.R_left.shape == (2, 3, 3, 3)
    steps = res.history
    per_iterate = handeye.handeye_cost(steps.left, AA[..., None, :, :, :], BB[..., None, :, :, :])
    assert np.allclose(steps.cost_left, per_iterate)
    assert np.all(np.diff(res.history.cost_left[0, 0]) <= 1e-12)  # noise-free: the cost falls every iteration


def test_batched_equals_looped(rng):
    R0 = so3.random_rotations(rng, 5)
    A = so3.random_rotations(rng, (5, 20))
    B = np.swapaxes(R0, -1, -2)[:, None] @ A @ R0[:, None]
    B = so3.noise_rotations(so3.sample_ball(rng, (5, 20), 0.02)) @ B
    batched = two_step(A, B, iterations=30)
    for n in range(5):
        one = two_step(A[n], B[n], iterations=30)
        assert np.allclose(batched.history.right[n], one.history.right, atol=1e-13)
        assert np.allclose(batched.history.cost_left[n], one.history.cost_left, atol=1e-12)


def test_the_default_start_is_the_identity(problem):
    """``init=None`` is documented as the identity: the same iterates, bit for bit; another start
    gives others."""
    _, A, B = problem
    default, identity = two_step(A, B, iterations=20), two_step(A, B, iterations=20, init=np.eye(3))
    assert np.array_equal(default.history.left, identity.history.left)
    assert np.array_equal(default.history.cost_right, identity.history.cost_right)
    other = two_step(A, B, iterations=20, init=so3.matrix_from_rotation_vector(np.array([0.0, 0.0, 1.0])))
    # the start matters to the first iterate
    assert so3.frobenius_error(other.history.left[0], default.history.left[0]) > 1e-3


def test_raw_iterates_follow_eqs_14_15_literally(problem):
    _, A, B = problem
    H1, H2 = handeye.stack_H1(A), handeye.stack_H2(B)
    init = so3.random_rotations(np.random.default_rng(3), ())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        res = two_step(A, B, iterations=4, init=init)
    Rl = init
    for n in range(4):
        Rr = handeye.v2h(H1 @ Rl) @ np.linalg.pinv(H2)
        Rl = np.linalg.pinv(H1) @ handeye.h2v(Rr @ H2)
        assert np.allclose(res.history.right_raw[n], Rr, atol=1e-13)
        assert np.allclose(res.history.left_raw[n], Rl, atol=1e-13)


def test_negative_start_fails_as_printed_and_is_corrected(problem):
    R0, A, B = problem
    init = R0 @ Rotation.from_rotvec([0, 0, np.radians(170)]).as_matrix()
    paper = two_step(A, B, iterations=60, init=init, variant="paper")
    fixed = two_step(A, B, iterations=60, init=init)
    assert np.isclose(np.linalg.det(paper.R), -1) and so3.frobenius_error(paper.R, R0) > 3
    assert so3.frobenius_error(fixed.R, R0) < 1e-9
    # no gap to the minimum over SO(3) from a reflection; the corrected answer is the certified
    # minimiser
    assert np.isnan(paper.duality_gap) and not paper.global_optimum and paper.certificate == "lagrangian"
    assert fixed.global_optimum and fixed.duality_gap <= 1e-8 * 20


def test_noisy_iterates_converge_to_the_fixed_point(problem, rng):
    R0, A, B = problem
    An = so3.noise_rotations(so3.sample_ball(rng, 20, 0.02)) @ A
    Bn = so3.noise_rotations(so3.sample_ball(rng, 20, 0.02)) @ B
    res = two_step(An, Bn, iterations=80)
    right, left = two_step_fixed_point(An, Bn)
    assert_rotations_close(res.R, right, 1e-8, name="R_right")
    assert_rotations_close(res.history.R_left, left, 1e-8, name="R_left")
    assert 0.05 < so3.angle_between_deg(res.R, R0) < 0.5  # the noise moves it (measured 0.23 deg)


def test_small_motions_warn(rng):
    R0 = so3.random_rotations(rng, ())
    A = so3.random_rotations(rng, 20, angle_range_deg=(0, 2))
    with pytest.warns(ConvergenceWarning, match="need about"):
        two_step(A, R0.T @ A @ R0, iterations=50)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"iterations": 0}, "positive integer"),
        ({"iterations": 2.5}, "positive integer"),
        ({"iterations": 5, "init": np.eye(4)}, r"init must have shape"),
        ({"iterations": 5, "init": 2 * np.eye(3)}, "init is not a rotation"),
        ({"iterations": 5, "init": np.ones((7, 3, 3)) / 3}, "init is not a rotation"),
        ({"iterations": 5, "variant": "fast"}, "variant must be one of"),
    ],
)
def test_bad_arguments(problem, kwargs, message):
    _, A, B = problem
    with pytest.raises(ValueError, match=message):
        two_step(A, B, **kwargs)


def test_init_batch_mismatch(problem):
    _, A, B = problem
    init = np.broadcast_to(np.eye(3), (4, 3, 3))
    with pytest.raises(ValueError, match="broadcast to the batch shape"):
        two_step(np.stack([A, A]), np.stack([B, B]), iterations=3, init=init)


def test_too_few_motions_and_nan(problem):
    _, A, B = problem
    with pytest.raises(ValueError, match="at least 2 motion pairs"):
        two_step(A[:1], B[:1], iterations=3)
    A = A.copy()
    A[2, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        two_step(A, B, iterations=3)


def test_no_underflow_when_sigma1_is_well_below_one(rng):
    """Inconsistent pairs make sigma_1(K) < 1: the printed iterates shrink like sigma_1^(2n).

    Without rescaling they reach 0 after a few hundred iterations and the projection returns
    garbage.
    """
    A = random_rotations(rng, (2, 20))
    B = random_rotations(rng, (2, 20))  # unrelated: sigma_1(K) around 0.5
    res = two_step(A, B, iterations=2000, convergence_tol_deg=180)
    assert np.all(res.history.left_raw[..., -1, :, :] == 0)  # the printed iteration has underflowed
    checks.check_rotation_matrices(res.history.R_left)
    fixed = two_step_fixed_point(A, B)[1]
    assert_rotations_close(res.history.R_left, fixed, 1e-6, name="R_left")


def test_the_answer_is_the_solution_solve_gives_for_two_step_right():
    """R^r with the cost (8) and certificate of solve(full_output=True), bit for bit; R^l
    (two_step_left's) in the history."""
    _, A, B = noisy_problem()
    res = two_step(A, B, iterations=50)
    full = solve("two_step_right", A, B, full_output=True, iterations=50)
    assert isinstance(res, Solution) and res.method == "two_step_right"
    for name in ("R", "cost", "lower_bound", "duality_gap", "global_optimum", "certificate"):
        assert np.array_equal(getattr(res, name), getattr(full, name)), name
    assert np.array_equal(res.history.R_left, solve("two_step_left", A, B, iterations=50))
    assert np.array_equal(res.R, res.history.right[-1]) and int(res.iterations) == 50
    assert full.history is None and full.iterations is None  # solve returns the answer, not how it ran
    assert res.observability.spectral_ratio.shape == ()
    # with noise the fixed point is not the minimiser of (8), and the certificate says so
    assert not res.global_optimum and res.duality_gap > 1e-8 * 30


def test_auto_counts_its_iterations_and_keeps_the_last(problem):
    _, A, B = problem
    res = two_step(A, B)
    assert res.history.right.shape == (1, 3, 3) and 1 <= int(res.iterations) < 50
    assert not res.history.closed_form and res.global_optimum


def test_certify_false_gives_the_estimate_without_a_certificate():
    _, A, B = noisy_problem()
    lean, certified = two_step(A, B, iterations=50, certify=False), two_step(A, B, iterations=50)
    assert np.array_equal(lean.R, certified.R) and np.array_equal(lean.cost, certified.cost)
    assert np.isnan(lean.lower_bound) and np.isnan(lean.duality_gap)
    assert not lean.global_optimum and lean.certificate == "none"


def test_paper_variant_on_degenerate_motion_is_not_certified(rng):
    """One rotation axis: R0 is not unique, the printed iteration still runs; no certificate is
    claimed."""
    R0 = so3.random_rotations(rng, ())
    A = so3.matrix_from_rotation_vector(np.outer(rng.uniform(0.2, 1.0, 10), [0.0, 0.0, 1.0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = two_step(A, R0.T @ A @ R0, iterations=20, variant="paper")
    assert res.certificate == "none" and np.isnan(res.lower_bound) and not res.global_optimum
    assert np.isfinite(res.cost)
