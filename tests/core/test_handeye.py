import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from replication.core import handeye, motions, so3
from replication.core.solvers import pair_residual_deg


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 12), st.integers(0, 2**32 - 1))
def test_v2h_h2v_are_inverse_layouts(J, seed):
    M = np.random.default_rng(seed).normal(size=(3 * J, 3))
    H = handeye.v2h(M)
    assert H.shape == (3, 3 * J)
    assert np.array_equal(handeye.h2v(H), M)
    assert np.array_equal(H[:, 3:6] if J > 1 else H, M[3:6] if J > 1 else M)


def test_operators_equal_the_literal_pseudo_inverse_formulas(problem, rng):
    _, A, B = problem
    H1, H2 = handeye.stack_H1(A), handeye.stack_H2(B)
    X, Y = rng.normal(size=(2, 3, 3))
    assert np.allclose(handeye.v2h(H1 @ X) @ np.linalg.pinv(H2), handeye.operator_T(A, B, X))  # eq. (14)
    assert np.allclose(np.linalg.pinv(H1) @ handeye.h2v(Y @ H2), handeye.operator_T_adjoint(A, B, Y))  # (15)
    K = handeye.kronecker_operator(A, B)
    assert np.allclose(K @ handeye.vec(X), handeye.vec(handeye.operator_T(A, B, X)))
    assert np.allclose(handeye.unvec(handeye.vec(X)), X)


def test_cost_zero_at_truth_and_kron_form_exact_for_any_matrix(problem, rng):
    R0, A, B = problem
    assert handeye.handeye_cost(R0, A, B) < 1e-25
    X = rng.normal(size=(5, 3, 3))
    K = handeye.kronecker_operator(A, B)
    assert np.allclose(handeye.handeye_cost_kron(X, K, len(A)), handeye.handeye_cost(X, A[None], B[None]))


def test_batched_weights_are_normalised_per_problem(rng):
    """A (2, 3) batch of problems, each with its own weights on its own scale (1e-3 .. 1e3): every K
    equals the problem's own ``sum_j w_j kron(B_j, A_j) / sum_j w_j``, as if computed alone (a
    normalisation over the whole batch would scale each K by its share of the batch's total
    weight)."""
    J = 7
    A, B = so3.random_rotations(rng, (2, 2, 3, J))  # unrelated A and B: any scale error in K shows
    w = rng.uniform(0.1, 1.0, (2, 3, J)) * np.logspace(-3, 3, 6).reshape(2, 3, 1)
    w[1, 2, :3] = 0.0  # a problem with some pairs switched off
    K = handeye.kronecker_operator(A, B, weights=w)
    assert K.shape == (2, 3, 9, 9)
    for idx in np.ndindex(2, 3):
        alone = handeye.kronecker_operator(A[idx], B[idx], weights=w[idx])
        by_definition = sum(w[idx][j] * np.kron(B[idx][j], A[idx][j]) for j in range(J)) / w[idx].sum()
        np.testing.assert_allclose(K[idx], alone, rtol=0, atol=1e-15)
        np.testing.assert_allclose(K[idx], by_definition, rtol=0, atol=1e-14)
    # one weight vector for the whole batch broadcasts, normalised within each problem just the same
    shared = handeye.kronecker_operator(A, B, weights=w[0, 0])
    for idx in np.ndindex(2, 3):
        np.testing.assert_allclose(shared[idx], handeye.kronecker_operator(A[idx], B[idx], weights=w[0, 0]),
                                   rtol=0, atol=1e-15)


@pytest.mark.parametrize("convention", ["body_from_world", "world_from_body"])
def test_relative_rotations_satisfy_eq7(rng, convention):
    R0 = so3.random_rotations(rng, ())
    I = so3.random_rotations(rng, 8)
    C = R0 @ I  # eq. (1), body-from-world
    if convention == "world_from_body":
        C, I = np.swapaxes(C, -1, -2), np.swapaxes(I, -1, -2)
    A = handeye.relative_rotations(C, convention=convention)
    B = handeye.relative_rotations(I, convention=convention)
    assert A.shape == (7, 3, 3)
    assert np.abs(A @ R0 - R0 @ B).max() < 1e-12


def test_relative_rotations_rejects():
    with pytest.raises(ValueError, match="convention"):
        handeye.relative_rotations(np.eye(3)[None].repeat(2, 0), convention="nope")
    with pytest.raises(ValueError, match="N >= 2"):
        handeye.relative_rotations(np.eye(3)[None])


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda A, B: (A, B[:-1]), "same shape"),
        (lambda A, B: (A[:1], B[:1]), r"at least 2 motion pairs"),
        (lambda A, B: (A[0], B[0]), r"\(\.\.\., J, 3, 3\)"),
        (lambda A, B: (np.where(np.arange(20)[:, None, None] == 3, np.nan, A), B), "NaN"),
        (lambda A, B: (A * 1.1, B), r"A \(camera relative rotations\) is not a rotation"),
        (lambda A, B: (A, -B), r"B \(sensor relative rotations\).*reflection"),
    ],
)
def test_check_motion_pairs_rejects(problem, make, message):
    _, A, B = problem
    with pytest.raises(ValueError, match=message):
        handeye.check_motion_pairs(*make(A, B))


def test_single_axis_and_no_motion_are_degenerate(rng):
    R0 = so3.random_rotations(rng, ())
    A = Rotation.from_rotvec(np.outer(rng.uniform(0.1, 1.5, 10), [0, 1, 0])).as_matrix()
    with pytest.raises(ValueError, match="degenerate motion: the camera rotations all share one"):
        motions.check_observable(A, R0.T @ A @ R0)
    obs = motions.motion_observability(A, R0.T @ A @ R0)
    assert np.isclose(obs.two_step_rate, 1.0) and np.isclose(obs.kron_singular_values[2], 1.0)
    eye = np.broadcast_to(np.eye(3), (5, 3, 3))
    with pytest.raises(ValueError, match="degenerate motion"):
        motions.check_observable(eye, eye)


def test_degenerate_batch_member_is_named(rng, problem):
    R0, A, B = problem
    A_bad = Rotation.from_rotvec(np.outer(np.linspace(0.1, 1, 20), [0, 0, 1])).as_matrix()
    AA = np.stack([A, A_bad, A])
    BB = np.swapaxes(R0, -1, -2) @ AA @ R0
    with pytest.raises(ValueError, match=r"batch index \(1,\)"):
        motions.check_observable(AA, BB)


def test_observability_of_generic_motion(problem):
    R0, A, B = problem
    obs = motions.check_observable(A, B)
    assert np.isclose(obs.kron_singular_values[0], 1.0) and obs.spectral_ratio < 0.9
    assert obs.camera_axis_spread_deg > 10 and obs.two_step_rate < 0.9
    assert 0 < obs.iterations_for(1e-6) < 100


def test_relative_rotations_of_chosen_pairs_follow_eq_3_in_both_conventions(rng):
    C = so3.random_rotations(rng, (2, 6))  # body_from_world attitudes, batched
    t_index, k_index = np.array([0, 2, 1]), np.array([3, 5, 4])
    A = handeye.relative_rotations(C, pairs=(t_index, k_index))
    assert A.shape == (2, 3, 3, 3)
    np.testing.assert_allclose(A[1, 2], C[1, 4] @ C[1, 1].T, atol=1e-15)  # eq. (3): C_k C_t^T
    Q = np.swapaxes(C, -1, -2)  # the same motions from world_from_body orientations
    assert np.array_equal(handeye.relative_rotations(Q, pairs=(t_index, k_index), convention="world_from_body"), A)
    with pytest.raises(ValueError, match="either reference or pairs"):
        handeye.relative_rotations(C, reference=0, pairs=(t_index, k_index))
    with pytest.raises(ValueError, match="same length, got 1 and 3"):
        handeye.relative_rotations(C, pairs=([0], [1, 2, 3]))
    with pytest.raises(ValueError, match="k_index out of range for N = 6"):
        handeye.relative_rotations(C, pairs=([0, 1], [-1, 2]))
    with pytest.raises(ValueError, match="t_index must be a 1-D array of integers"):
        handeye.relative_rotations(C, pairs=([0.5], [1]))


def test_pair_residual_is_zero_for_exact_pairs_and_the_motion_angle_otherwise(problem):
    R0, A, B = problem
    assert pair_residual_deg(R0, A, B).max() < 1e-12  # measured 3e-14
    tilt = Rotation.from_rotvec([0, 0, np.radians(10)]).as_matrix()
    r = pair_residual_deg(R0, A, B @ tilt)
    np.testing.assert_allclose(r, 10.0, rtol=0, atol=1e-12)  # measured 5e-15



def test_weighted_kronecker_operator(problem):
    _, A, B = problem
    K = handeye.kronecker_operator(A, B)
    np.testing.assert_allclose(handeye.kronecker_operator(A, B, weights=np.full(20, 3.0)), K)
    w = np.ones(20)
    w[:5] = 0
    np.testing.assert_allclose(handeye.kronecker_operator(A, B, weights=w),
                               handeye.kronecker_operator(A[5:], B[5:]), atol=1e-15)
