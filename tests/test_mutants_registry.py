"""The answer checks of :mod:`replication.core.solvers._registry` at their boundaries: which local answers get a
:class:`LocalMinimumWarning` or a :class:`ConvergenceWarning` (cost gap, angle, gradient), and when a closed form's
answer is grossly off. Mutation testing (scripts/mutation) found these rules unguarded by the fast tests."""
import math
import warnings

import numpy as np
import pytest

from replication.core import so3
from replication.core.motions import prepare_motions
from replication.core.solvers import _registry, certificate
from replication.core.solvers._warnings import AccuracyWarning, ConvergenceWarning, LocalMinimumWarning

J = 10


def _motions(batch=(), noise_deg=0.0, seed=7):
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, batch)
    A = so3.random_rotations(rng, batch + (J,))
    B = np.swapaxes(R0, -1, -2)[..., None, :, :] @ A @ R0[..., None, :, :]
    if noise_deg:
        B = B @ so3.matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal(B.shape[:-2] + (3,)))
    return prepare_motions(A, B)


def _rotated(R, deg, axis=(0.0, 0.0, 1.0)):
    return R @ so3.matrix_from_rotation_vector(np.radians(deg) * np.asarray(axis, float) / np.linalg.norm(axis))


def _warned(fn, *args, **kwargs):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    return out, [(w.category, str(w.message)) for w in caught]


@pytest.fixture
def crafted(monkeypatch):
    """check_local_answer with the gap to f*, f*'s bound and the angle to the minimiser set by the test."""
    state = {}

    def gap_to_global(motions, R, cert=None):
        return np.zeros(state["gap"].shape), state["lower"], state["gap"]

    monkeypatch.setattr(_registry, "_gap_to_global", gap_to_global)
    monkeypatch.setattr(_registry, "angle_between_deg", lambda R, S: state["angle"])
    return state


def _tolerance(lower):
    return _registry.LOCAL_RTOL * abs(lower) + _registry.LOCAL_ATOL * J


def test_local_answer_boundaries_of_gap_and_angles(crafted):
    m = _motions((6,))
    R = certificate.global_certificate(m).R
    lower = -2.0  # |f*| enters the tolerance (the certified bound can be a negative number near 0)
    tol = _tolerance(lower)
    crafted["lower"] = np.full(6, lower)
    wrong, short_tol = _registry.WRONG_POINT_DEG, _registry.LOCAL_ANGLE_TOL_DEG
    #                         gap      angle: off, short, off,  at the point tol, short at angle tol, clean
    crafted["gap"] = np.array([tol * 1.001, tol, tol * 1.001, tol * 1.001, 0.0, 0.0])
    crafted["angle"] = np.array([2 * wrong, 2 * wrong, wrong, wrong * 1.0001, short_tol, short_tol * 1.01])
    flagged, caught = _warned(_registry.check_local_answer, m, R, "fake")
    # 0: above the gap tolerance and beyond 1 deg -> another point; 1: at the tolerance -> only stopped short;
    # 2: at exactly 1 deg -> short; 3: beyond 1 deg -> off; 4: at exactly the angle tolerance -> clean; 5: short
    assert flagged.tolist() == [True, True, True, True, False, True]
    kinds = [c for c, _ in caught]
    assert kinds == [LocalMinimumWarning, ConvergenceWarning]
    local, conv = caught[0][1], caught[1][1]
    assert local.startswith(f"fake did not reach the global minimum of eq. (8) in 2 of 6 problems: its cost exceeds "
                            f"the certified minimum f* by up to {tol * 1.001:.3g} (tolerance 0.001 f* + 1e-06 J) and "
                            f"its answer is {wrong * 1.0001:.3g}-{2 * wrong:.3g} deg from the certified minimiser; ")
    assert local.endswith(". A local method from a start far from R0 does this; use chordal_optimal, "
                          "or a start near R0")
    assert conv == ("fake stopped short of the minimum of eq. (8) in 3 of 6 problems: up to 2 deg from the certified "
                    "minimiser (tolerance 0.0001 deg); tighten its tolerance or use chordal_optimal")


def test_gradient_tells_a_stop_before_converging_from_another_stationary_point(crafted, monkeypatch):
    m = _motions((4,))
    R = certificate.global_certificate(m).R
    crafted["lower"] = np.zeros(4)
    crafted["gap"] = np.ones(4)
    crafted["angle"] = np.full(4, 90.0)
    tol = _registry.STATIONARY_TOL
    # |grad (8)| / J = 2 |grad g|: 0 and exactly the tolerance are stationary; above it, still moving
    norms = np.array([0.0, tol / 2, 3 * tol, tol / 2 * 1.01])
    grad = np.zeros((4, 3))
    grad[:, 1] = -norms
    monkeypatch.setattr(_registry, "_derivatives", lambda M, R: (None, grad, None))
    _, caught = _warned(_registry.check_local_answer, m, R, "fake")
    (kind, msg), = caught
    assert kind is LocalMinimumWarning
    assert (f"; 2 where eq. (8) still has a gradient (up to {6 * tol:.3g} J): the solver stopped before converging "
            f"(e.g. its iteration limit); 2 at another stationary point of (8). A local") in msg
    for moving, stationary in ((norms * 0, True), (norms * 0 + 3 * tol, False)):
        grad[:, 1] = moving
        _, caught = _warned(_registry.check_local_answer, m, R, "fake")
        assert ("at another stationary point" in caught[0][1]) is stationary
        assert ("still has a gradient" in caught[0][1]) is not stationary
        assert "; 4 " in caught[0][1]


def test_real_local_answers_are_classified_by_angle():
    m = _motions((3,))
    R0 = certificate.global_certificate(m).R
    R = np.stack([_rotated(R0[0], 3.0), _rotated(R0[1], 0.3), _rotated(R0[2], 5e-5)])
    flagged, caught = _warned(_registry.check_local_answer, m, R, "fake")
    assert flagged.tolist() == [True, True, False]
    assert [c for c, _ in caught] == [LocalMinimumWarning, ConvergenceWarning]
    assert "in 1 of 3 problems" in caught[0][1] and "1 where eq. (8) still has a gradient" in caught[0][1]
    assert "3-3 deg from the certified minimiser" in caught[0][1]
    assert "in 1 of 3 problems: up to 0.3 deg" in caught[1][1]


def test_the_gradient_in_the_message_is_that_of_eq_8_at_the_answer():
    m = _motions()  # one problem: batch shape ()
    R = _rotated(certificate.global_certificate(m).R, 3.0)
    K = m.K
    grad = certificate._derivatives(0.5 * (K + np.swapaxes(K, -1, -2)), R)[1]
    _, caught = _warned(_registry.check_local_answer, m, R, "fake")
    assert f"1 where eq. (8) still has a gradient (up to {2 * float(np.linalg.norm(grad)):.3g} J)" in caught[0][1]
    # in a batch, the largest over the problems that are off and moving only
    mb = _motions((3,))
    Rb = certificate.global_certificate(mb).R.copy()
    Rb[0] = _rotated(Rb[0], 3.0)
    Rb[2] = _rotated(Rb[2], 0.5)  # short of the minimum (a ConvergenceWarning), with a gradient of its own
    Kb = mb.K
    g = certificate._derivatives(0.5 * (Kb + np.swapaxes(Kb, -1, -2)), Rb)[1]
    _, caught = _warned(_registry.check_local_answer, mb, Rb, "fake")
    assert f"(up to {2 * float(np.linalg.norm(g[0])):.3g} J)" in caught[0][1]


def test_local_check_skips_failures_and_reflections():
    m = _motions((3,))
    R = _rotated(certificate.global_certificate(m).R, 20.0)
    R[0] = np.nan
    R[1] = -R[1]  # a reflection, far off
    flagged, caught = _warned(_registry.check_local_answer, m, R, "fake")
    assert flagged.tolist() == [False, False, True]
    assert "in 1 of 3 problems" in caught[0][1]


def _geodesic(R_from, R_to, t):
    return R_from @ so3.matrix_from_rotation_vector(t * so3.rotation_vector_from_matrix(np.swapaxes(R_from, -1,
                                                                                                    -2) @ R_to))


def _gross_case():
    """A noisy problem, its certificate, a far answer, the gross bound ``GROSS_FACTOR f* + LOCAL_ATOL J`` and cost
    (8)."""
    m = _motions(noise_deg=3.0)
    cert = certificate.global_certificate(m)
    far = _rotated(cert.R, 120.0, (1.0, 2.0, 0.5))
    bound = _registry.GROSS_FACTOR * float(cert.cost) + _registry.LOCAL_ATOL * J
    return m, cert, far, bound, lambda R: float(_registry.handeye_cost(R, m.A, m.B))


def _bisect(cert, far, cost, target):
    """The bracket ``(lo, hi)`` of the fraction along the geodesic from the minimiser to ``far`` where cost = target."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if cost(_geodesic(cert.R, far, mid)) <= target else (lo, mid)
    return lo, hi


def test_gross_screen_at_ten_times_the_certified_minimum():
    m, cert, far, bound, cost = _gross_case()
    assert cost(_geodesic(cert.R, far, 1.0)) > bound
    lo, hi = _bisect(cert, far, cost, bound)
    inside, outside = _geodesic(cert.R, far, lo - 1e-6), _geodesic(cert.R, far, hi + 1e-6)
    flagged, caught = _warned(_registry.check_answer, m, inside, "fake")
    assert not flagged and caught == []
    flagged, caught = _warned(_registry.check_answer, m, outside, "fake")
    assert flagged
    (kind, msg), = caught
    angle = so3.angle_between_deg(outside, cert.R)
    assert kind is AccuracyWarning
    assert msg.startswith(f"fake is far from the certified minimiser of eq. (8) in 1 of 1 problems: up to "
                          f"{float(angle):.3g} deg from it, cost (8) up to 10 x the minimum (tolerance 10 x + 1e-06 J)")


def test_gross_screen_in_a_batch_flags_only_the_gross_ones():
    m = _motions((4,), noise_deg=3.0)
    R = certificate.global_certificate(m).R.copy()
    R[1] = _rotated(R[1], 150.0, (1.0, 0.0, 0.0))
    R[3] = _rotated(R[3], 150.0, (0.0, 1.0, 0.0))
    R[2] = np.nan
    flagged, caught = _warned(_registry.check_answer, m, R, "fake")
    assert flagged.tolist() == [False, True, False, True]
    assert [c for c, _ in caught] == [AccuracyWarning]
    assert "in 2 of 4 problems" in caught[0][1]


def test_reflections_are_flagged_and_said_with_the_two_step_hint():
    m = _motions((3,))
    R = certificate.global_certificate(m).R.copy()
    R[0], R[2] = -_rotated(R[0], 120.0), -R[2]  # a reflection far off is only said as a reflection
    flagged, caught = _warned(_registry.check_answer, m, R, "two_step_x")
    assert flagged.tolist() == [True, False, True]
    assert caught == [(AccuracyWarning, "two_step_x returned a reflection (det -1), not a rotation, in 2 of 3 problems"
                                        ": the paper-literal variant fails so from a start more than 120 deg from R0")]
    _, caught = _warned(_registry.check_answer, m, R, "other")
    assert caught == [(AccuracyWarning, "other returned a reflection (det -1), not a rotation, in 2 of 3 problems")]
    flagged, caught = _warned(_registry.check_answer, m, certificate.global_certificate(m).R, "other")
    assert not flagged.any() and caught == []


def test_a_singular_answer_is_flagged_and_said_not_an_error():
    """det 0 is neither a rotation nor a reflection: flagged and said, never handed to the gross screen (which
    measured its angle and raised SciPy's "Non-positive determinant")."""
    m = _motions((3,))
    R = certificate.global_certificate(m).R.copy()
    R[1] = np.diag([1.0, 1.0, 0.0])
    flagged, caught = _warned(_registry.check_answer, m, R, "fake")
    assert flagged.tolist() == [False, True, False]
    assert caught == [(AccuracyWarning, "fake returned a singular matrix (det 0), not a rotation, in 1 of 3 problems")]


# ------------------------------------------------------------------ what solve() accepts from a core, at the door

@pytest.fixture
def core(monkeypatch):
    """``make(answer, local=False) -> name``: a solver whose core returns ``answer(motions)``, registered for the
    test."""
    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    count = []

    def make(answer, local=False):
        name = f"test_core_{len(count)}"
        count.append(name)
        _registry.register(name, reference="test", local=local)(lambda motions, **_: answer(motions))
        return name

    return make


def _identity_motions(batch=(), seed=3):
    """Motions with ``R0 = I`` (``B = A``): the identity is their exact minimiser."""
    A = so3.random_rotations(np.random.default_rng(seed), batch + (J,))
    return A, A.copy()


def test_an_answer_exactly_at_the_answer_tolerance_is_accepted(core):
    x = 7.071067811865475e-07  # columns 0 and 1 at a cosine x: ||R^T R - I||_F = sqrt(2) x = ANSWER_ATOL exactly
    M = np.array([[1.0, x, 0.0], [0.0, math.sqrt(1.0 - x * x), 0.0], [0.0, 0.0, 1.0]])
    assert np.linalg.norm(M.T @ M - np.eye(3)) == _registry.ANSWER_ATOL
    name = core(lambda motions: M.copy())
    R = _registry.solve(name, *_identity_motions())
    assert np.array_equal(R, M)
    wider = core(lambda motions: np.array([[1.0, 1.01 * x, 0.0], [0.0, math.sqrt(1.0 - x * x), 0.0],
                                           [0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match=r"not a rotation at batch index \(\): \|\|R\^T R - I\|\|_F = 1.01e-06"):
        _registry.solve(wider, *_identity_motions())


@pytest.mark.parametrize("scale, words", [(2.0, r"det R = 8: \| \|det R\| - 1 \| = 7 "),
                                          (-2.0, r"det R = -8: \| \|det R\| - 1 \| = 7 "),
                                          (0.5, r"det R = 0.125: \| \|det R\| - 1 \| = 0.875 ")])
def test_a_refused_answer_states_its_determinant_s_distance_from_plus_or_minus_one(core, scale, words):
    name = core(lambda motions: scale * np.eye(3))
    with pytest.raises(ValueError, match=rf"solver '{name}' returned a matrix that is not a rotation at batch index "
                                         rf"\(\): \|\|R\^T R - I\|\|_F = [0-9.]+, {words}\(tolerance ANSWER_ATOL"):
        _registry.solve(name, *_identity_motions())


@pytest.mark.parametrize("value", [1e200, np.inf, -np.inf])
def test_an_overflowing_or_infinite_answer_is_refused_without_a_numpy_warning(core, value):
    M = np.eye(3)
    M[1, 2] = value
    name = core(lambda motions: M.copy())
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # an overflow or invalid value in the check would raise RuntimeWarning here
        with pytest.raises(ValueError, match=r"not a rotation at batch index \(\): "):
            _registry.solve(name, *_identity_motions())


@pytest.mark.parametrize("local", [False, True])
def test_a_rotation_whose_determinant_rounds_below_one_is_not_a_reflection(core, local):
    m = _motions(noise_deg=3.0)
    # the minimiser shrunk: det = 1 - 5e-7, within ANSWER_ATOL of 1: a rotation to the tolerance, not a reflection
    M = certificate.global_certificate(m).R @ np.diag([1.0 - 2.5e-7, 1.0 - 2.5e-7, 1.0])
    name = core(lambda motions: M.copy(), local=local)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sol = _registry.solve(name, m, full_output=True)
    assert np.isfinite(sol.duality_gap)  # a reflection's gap is NaN: never certified


def test_the_gross_screen_keeps_a_two_dimensional_batch_shape():
    m = _motions((2, 3), noise_deg=3.0)
    R = certificate.global_certificate(m).R.copy()
    R[1, 2] = _rotated(R[1, 2], 150.0, (1.0, 0.0, 0.0))
    flagged, caught = _warned(_registry.check_answer, m, R, "fake")
    assert flagged.shape == (2, 3) and flagged.tolist() == [[False, False, False], [False, False, True]]
    assert "in 1 of 6 problems" in caught[0][1]
    one = _motions(noise_deg=3.0)
    flagged, _ = _warned(_registry.check_answer, one, certificate.global_certificate(one).R, "fake")
    assert flagged.shape == () and not flagged


def test_the_gross_threshold_is_ten_times_the_minimum_plus_the_absolute_tolerance():
    """Answers whose cost (8) lies 0.5 LOCAL_ATOL J below and above ``GROSS_FACTOR f* + LOCAL_ATOL J``."""
    m, cert, far, bound, cost = _gross_case()

    def at(target):  # the answer on the geodesic from the minimiser towards `far` whose cost is `target`
        return _geodesic(cert.R, far, _bisect(cert, far, cost, target)[0])

    half = 0.5 * _registry.LOCAL_ATOL * J
    below, above = at(bound - half), at(bound + half)
    assert cost(below) == pytest.approx(bound - half, abs=1e-9) and cost(above) == pytest.approx(bound + half, abs=1e-9)
    flagged, caught = _warned(_registry.check_answer, m, below, "fake")
    assert not flagged and caught == []
    flagged, caught = _warned(_registry.check_answer, m, above, "fake")
    assert flagged and [c for c, _ in caught] == [AccuracyWarning]


def test_check_answer_reads_an_object_array_of_numbers_as_floats():
    m = _motions((2,), noise_deg=3.0)
    R = certificate.global_certificate(m).R.copy()
    R[1] = -R[1]
    flagged, caught = _warned(_registry.check_answer, m, R.astype(object), "fake")
    assert flagged.tolist() == [False, True]
    assert caught == [(AccuracyWarning, "fake returned a reflection (det -1), not a rotation, in 1 of 2 problems")]


def test_the_gradient_quoted_is_the_largest_over_problems_off_and_moving_only(crafted, monkeypatch):
    m = _motions((3,))
    R = certificate.global_certificate(m).R
    tol = _tolerance(0.0)
    crafted["lower"] = np.zeros(3)
    crafted["gap"] = np.array([2 * tol, 0.0, 2 * tol])
    crafted["angle"] = np.array([5.0, 0.5, 5.0])  # 0 and 2: another point; 1: short of the minimum
    stat = _registry.STATIONARY_TOL
    grad = np.zeros((3, 3))
    grad[:, 0] = [2 * stat, 50 * stat, 0.0]  # 0 moving; 1 (short, not off) has the largest gradient; 2 stationary
    monkeypatch.setattr(_registry, "_derivatives", lambda M, R: (None, grad, None))
    _, caught = _warned(_registry.check_local_answer, m, R, "fake")
    assert [c for c, _ in caught] == [LocalMinimumWarning, ConvergenceWarning]
    assert f"1 where eq. (8) still has a gradient (up to {4 * stat:.3g} J)" in caught[0][1]
    assert "; 1 at another stationary point of (8)" in caught[0][1]
