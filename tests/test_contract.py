"""The contract every registered solver must meet, parametrised over ``available()``.

A new baseline added with ``@register`` is picked up here from the registry; its measured worst error on
:func:`noisy` goes in :data:`MEASURED_WORST_DEG` (a test fails until it does).
"""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from replication.core import checks, so3
from replication.core.solvers import available, solve, solver_info
from replication.study.simulation import simulate
from replication.testing import assert_rotations_close

ALL = available()


def _start_options(method, R0):
    """A local solver gets a start 45 deg from ``R0``; global ones get nothing."""
    if not solver_info(method).local:
        return {}
    tilt = Rotation.from_rotvec(np.radians(45) * np.array([1.0, 2.0, 2.0]) / 3).as_matrix()
    return {"init": R0 @ tilt}


@pytest.fixture(scope="module")
def noisy():
    """Three noisy problems from the paper's simulation (J = 20, ||v|| < 0.02)."""
    sim = simulate(7, 3)
    return sim.R0, sim.A, sim.B


def test_registry_holds_the_required_solvers():
    required = {
        "two_step_right", "two_step_left", "sqp", "park_martin", "horaud_dornaika", "andreff",
        "tsai_lenz", "chordal_optimal", "opencv_tsai", "opencv_park", "opencv_horaud", "robust",
    }
    assert required <= set(ALL)
    for name in ALL:
        assert solver_info(name).reference, name


#: Worst angle (deg) from R0 over the three problems of :func:`noisy`, measured per solver with the NumPy, SciPy
#: and OpenCV of requirements.lock. The optimum of eq. (8) (chordal_optimal, sqp, andreff,
#: horaud_dornaika) is 0.262 deg; OpenCV's Tsai, which is not frame-invariant, is the worst at 0.749 deg.
MEASURED_WORST_DEG = {
    "andreff": 0.2624, "chordal_optimal": 0.2624, "horaud_dornaika": 0.2624, "sqp": 0.2624, "robust": 0.2558,
    "park_martin": 0.2632, "tsai_lenz": 0.2724, "two_step_right": 0.3737, "two_step_left": 0.3930,
    "opencv_horaud": 0.5253, "opencv_park": 0.5293, "opencv_tsai": 0.7486,
}
#: The problems are fixed (seed 7), so only rounding moves these numbers (by far less than 1e-6 deg); a solver that
#: becomes 20 % worse on them fails.
MARGIN = 1.2


def test_every_solver_has_a_measured_accuracy():
    assert set(MEASURED_WORST_DEG) == set(ALL), "measure a new solver's worst error on noisy() and add it"


@pytest.mark.parametrize("method", ALL)
def test_output_is_a_rotation(method, noisy):
    R0, A, B = noisy
    R = solve(method, A, B, **_start_options(method, R0))
    assert R.shape == (3, 3, 3)
    checks.check_rotation_matrices(R, atol=1e-10)
    assert np.all(np.linalg.det(R) > 0)
    # as accurate as measured: the paper's noise (<= 1.15 deg per rotation) moves the optimum 0.26 deg from R0
    assert_rotations_close(R, R0, MARGIN * MEASURED_WORST_DEG[method])


@pytest.mark.parametrize("method", ALL)
def test_noise_free_recovery_of_a_random_R0(method, rng):
    R0 = so3.random_rotations(rng, ())
    A = so3.random_rotations(rng, 12)
    B = R0.T @ A @ R0  # eq. (7) exactly
    R = solve(method, A, B, **_start_options(method, R0))
    assert so3.frobenius_error(R, R0) < 1e-10  # measured: 1.4e-12 (sqp), 6.5e-13 (two-step), others < 1e-14


@pytest.mark.parametrize("method", ALL)
@pytest.mark.parametrize("side", ["camera", "sensor"])
def test_equivariance_under_a_change_of_frame(method, side, noisy):
    """Re-expressing the camera (or sensor) frame by ``G`` must move the estimate by ``G``."""
    R0, A, B = noisy
    G = Rotation.from_rotvec([0.3, -1.1, 0.7]).as_matrix()
    options = _start_options(method, R0)
    R = solve(method, A, B, **options)
    if side == "camera":  # A' = G A G^T, R0' = G R0
        options2 = {k: G @ v for k, v in options.items()}
        R2 = solve(method, G @ A @ G.T, B, **options2)
        expected = G @ R
    else:  # B' = G B G^T, R0' = R0 G^T
        options2 = {k: v @ G.T for k, v in options.items()}
        R2 = solve(method, A, G @ B @ G.T, **options2)
        expected = R @ G.T
    gap = so3.frobenius_error(R2, expected).max()
    if solver_info(method).equivariant:
        # measured: 1.3e-8 for the local solver (sqp stops at its tolerance from the moved start), below 1e-12 for
        # the others
        assert gap < (1e-7 if solver_info(method).local else 1e-10)
    else:  # the registry's flag must be true: a non-equivariant solver visibly moves (measured 9e-4 and more)
        assert gap > 1e-4


@pytest.mark.parametrize("method", ALL)
def test_batched_equals_looped(method, noisy):
    R0, A, B = noisy
    options = _start_options(method, R0)
    batched = solve(method, A.reshape(3, 1, 20, 3, 3), B.reshape(3, 1, 20, 3, 3),
                    **{k: v.reshape(3, 1, 3, 3) for k, v in options.items()})
    assert batched.shape == (3, 1, 3, 3)
    looped = np.stack([solve(method, A[n], B[n], **{k: v[n] for k, v in options.items()})
                       for n in range(3)])
    np.testing.assert_allclose(batched[:, 0], looped, atol=1e-12)


@pytest.mark.parametrize("method", ALL)
def test_too_few_motions_is_refused(method, problem):
    R0, A, B = problem
    need = solver_info(method).min_motions
    assert need >= 2  # one motion never determines R0
    with pytest.raises(ValueError, match=f"at least {need} motion pairs"):
        solve(method, A[: need - 1], B[: need - 1], **_start_options(method, R0))


@pytest.mark.parametrize("method", ALL)
def test_degenerate_motion_is_refused(method, rng):
    R0 = so3.random_rotations(rng, ())
    A = Rotation.from_rotvec(np.outer(np.linspace(0.2, 1.5, 10), [0.0, 0.6, 0.8])).as_matrix()
    with pytest.raises(ValueError, match="degenerate motion"):
        solve(method, A, R0.T @ A @ R0, **_start_options(method, R0))
