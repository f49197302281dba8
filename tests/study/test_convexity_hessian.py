"""The cost (8) as a quadratic (``replication.study.convexity.hessian``): its Hessian in vec(R),
positive semi-definite and singular exactly noise-free, and the derivatives on SO(3) computed from
it, against finite differences and the solver's end points."""
import numpy as np
import pytest

from replication.core import handeye, so3
from replication.core.solvers import chordal_optimal
from replication.study import convexity as bl

# --- the Hessian of (8) in vec(R)
# ----------------------------------------------------------------------------------

def test_cost_hessian_vec_is_the_quadratic_form_of_eq8_for_any_matrix(noisy):
    H = bl.cost_hessian_vec(noisy.A, noisy.B)
    X = np.random.default_rng(0).normal(size=(40, 3, 3))  # not rotations: f is a quadratic on all 3x3 matrices
    x = handeye.vec(X)
    f = handeye.handeye_cost(X, noisy.A, noisy.B)
    np.testing.assert_allclose(0.5 * np.einsum("na,nab,nb->n", x, H, x), f, rtol=1e-12)
    np.testing.assert_allclose(H, np.swapaxes(H, -1, -2), atol=1e-12)


def test_cost_hessian_vec_is_psd_and_singular_exactly_noise_free(noisy, clean):
    ev = np.linalg.eigvalsh(bl.cost_hessian_vec(noisy.A, noisy.B))
    assert ev[:, 0].min() > 1e-4 * 20  # measured 0.0004 J and more with the paper's noise
    H0 = bl.cost_hessian_vec(clean.A, clean.B)
    assert np.abs(np.einsum("nab,nb->na", H0, handeye.vec(clean.R0))).max() < 1e-12  # vec(R0) is a null vector
    conv = bl.cost_convexity(clean.A, clean.B)
    assert conv["PSD"] == conv["problems"] == 40 and abs(conv["smallest / J (min)"]) < 1e-12


def test_cost_convexity_counts_against_its_tolerance(noisy):
    """``PSD`` counts problems whose smallest eigenvalue / J is at least ``-tol``: just below and
    just above."""
    smallest = bl.cost_convexity(noisy.A, noisy.B)["smallest / J (min)"]
    assert bl.cost_convexity(noisy.A, noisy.B, tol=-(smallest - 1e-9))["PSD"] == 40
    assert bl.cost_convexity(noisy.A, noisy.B, tol=-(smallest + 1e-9))["PSD"] == 39
    with pytest.raises(ValueError, match="same shape"):
        bl.cost_hessian_vec(noisy.A, noisy.B[:, :4])


# --- derivatives on SO(3), independent of the solver's
# ---------------------------------------------------------------

def test_derivatives_on_so3_match_finite_differences(noisy):
    R = so3.random_rotations(np.random.default_rng(3), 40)
    cost, grad, hess = bl.cost_derivatives_on_so3(noisy.A, noisy.B, R)
    np.testing.assert_allclose(cost, handeye.handeye_cost(R, noisy.A, noisy.B), rtol=1e-12)
    f = lambda w: handeye.handeye_cost(R @ so3.matrix_from_rotation_vector(w), noisy.A, noisy.B)  # noqa: E731
    eps, E = 1e-4, np.eye(3)
    g_fd = np.stack([(f(eps * E[k]) - f(-eps * E[k])) / (2 * eps) for k in range(3)], -1)
    np.testing.assert_allclose(grad, g_fd, atol=1e-5)  # measured 4e-7
    def second(k, m):
        return (f(eps * (E[k] + E[m])) - f(eps * (E[k] - E[m])) - f(eps * (E[m] - E[k]))
                + f(-eps * (E[k] + E[m]))) / (4 * eps ** 2)

    h_fd = np.stack([np.stack([second(k, m) for m in range(3)], -1) for k in range(3)], -2)
    np.testing.assert_allclose(hess, h_fd, atol=1e-4)  # measured 4e-6 on entries up to 140


def test_derivatives_on_so3_agree_with_the_solver_at_its_end_points(noisy):
    starts = so3.random_rotations(np.random.default_rng(4), 40)
    res = chordal_optimal(noisy.A, noisy.B, init=starts, certify=False, max_iterations=100)
    _, grad, hess = bl.cost_derivatives_on_so3(noisy.A, noisy.B, res.R)
    np.testing.assert_allclose(np.linalg.eigvalsh(hess)[:, 0] / 20, res.hessian_min_eigenvalue, atol=1e-10)
    np.testing.assert_allclose(np.linalg.norm(grad, axis=-1) / 20, res.gradient_norm, atol=1e-10)
