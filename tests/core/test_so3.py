import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from replication.core import checks, so3

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


def test_check_rotation_accepts_rotations(rng):
    R = so3.random_rotations(rng, (4, 5))
    assert np.array_equal(checks.check_rotation_matrices(R), R)


@pytest.mark.parametrize("atol", [None, 1e-4, 1e-2])  # None: the default, ROTATION_ATOL = 1e-6
def test_check_rotation_tolerance_boundary(rng, atol):
    """``||R^T R - I||_F <= atol``: a rotation scaled by ``s`` has ``|s^2 - 1| sqrt 3`` there."""
    R = so3.random_rotations(rng, 3)
    bound, options = (1e-6, {}) if atol is None else (atol, {"atol": atol})
    for share, accepted in ((1 - 1e-3, True), (1 + 1e-3, False)):
        M = R.copy()
        M[1] *= np.sqrt(1 + share * bound / np.sqrt(3))
        residual = so3.orthonormality_residual(M[1])
        assert residual == pytest.approx(share * bound, rel=1e-6)
        if accepted:
            assert np.array_equal(checks.check_rotation_matrices(M, **options), M)
        else:
            with pytest.raises(ValueError, match=r"not a rotation matrix at index 1\b"):
                checks.check_rotation_matrices(M, **options)
    with pytest.raises(ValueError, match=r"atol must be <= 0.01"):
        checks.check_rotation_matrices(R, atol=1e-2 * (1 + 1e-9))  # MAX_ROTATION_ATOL, just above


def test_check_rotation_names_the_index(rng):
    R = so3.random_rotations(rng, 6)
    R[4] *= 1.01
    with pytest.raises(ValueError, match=r"index 4\b"):
        checks.check_rotation_matrices(R, "R")


@settings(max_examples=60, deadline=None)
@given(arrays(float, (3, 3), elements=finite))
def test_nearest_rotation_is_a_rotation_and_nearest(M):
    assume(abs(np.linalg.det(M)) >= 1e-6 and np.linalg.cond(M) <= 1e8)  # else the projection is not unique
    P = so3.nearest_rotation(M)
    checks.check_rotation_matrices(P)
    others = so3.random_rotations(np.random.default_rng(0), 500)
    assert np.all(np.linalg.norm(M - P) <= np.linalg.norm(M - others, axis=(-2, -1)) + 1e-12)


def test_nearest_rotation_paper_literal_keeps_reflection():
    M = np.diag([2.0, 1.0, -0.5])
    assert np.isclose(np.linalg.det(so3.nearest_rotation(M, enforce_det=False)), -1)
    assert np.allclose(so3.nearest_rotation(M), np.eye(3))


def test_nearest_rotation_fixes_rotations(rng):
    R = so3.random_rotations(rng, 50)
    assert np.abs(so3.nearest_rotation(R) - R).max() < 1e-14


@settings(max_examples=50, deadline=None)
@given(arrays(float, (3,), elements=st.floats(-0.5, 0.5)))
def test_noise_rotation_angle_is_arctan_of_norm(v):
    angle = so3.rotation_angle_deg(so3.noise_rotations(v))
    assert np.isclose(angle, np.degrees(np.arctan(np.linalg.norm(v))), atol=1e-9)


def test_skew_is_cross_product(rng):
    v, w = rng.normal(size=(2, 3))
    assert np.allclose(so3.skew(v) @ w, np.cross(v, w))


@pytest.mark.parametrize("dist", ["uniform", "uniform_norm", "sphere", "cube"])
def test_sample_ball_bounds(rng, dist):
    v = so3.sample_ball(rng, (100, 4), 0.02, distribution=dist)
    assert v.shape == (100, 4, 3)
    norms = np.linalg.norm(v, axis=-1)
    assert norms.max() <= 0.02 + 1e-15
    if dist == "sphere":
        assert np.allclose(norms, 0.02)
    if dist == "uniform":  # volume-uniform: P(norm < r/2) = 1/8
        assert abs(np.mean(norms < 0.01) - 0.125) < 0.05


def test_sample_ball_rejects():
    with pytest.raises(ValueError, match="unknown distribution"):
        so3.sample_ball(np.random.default_rng(0), 3, 0.1, distribution="gauss")
    with pytest.raises(ValueError, match="Generator"):
        so3.sample_ball(0, 3, 0.1)
    with pytest.raises(ValueError, match="radius"):
        so3.sample_ball(np.random.default_rng(0), 3, -1)


def test_random_rotations_angle_range_and_determinism():
    R = so3.random_rotations(np.random.default_rng(1), (10, 20), angle_range_deg=(5, 15))
    checks.check_rotation_matrices(R)
    ang = so3.rotation_angle_deg(R)
    assert ang.min() >= 5 - 1e-9 and ang.max() <= 15 + 1e-9
    again = so3.random_rotations(np.random.default_rng(1), (10, 20), angle_range_deg=(5, 15))
    assert np.array_equal(R, again)
    with pytest.raises(ValueError, match="angle_range_deg"):
        so3.random_rotations(np.random.default_rng(1), 3, angle_range_deg=(10, 200))


def test_angle_is_accurate_for_tiny_rotations():
    from scipy.spatial.transform import Rotation

    R = Rotation.from_rotvec([1e-10, 0, 0]).as_matrix()
    angle = float(so3.rotation_angle_deg(R))
    assert abs(angle - np.degrees(1e-10)) < 1e-6 * np.degrees(1e-10)  # arccos of the trace gives 0


def test_frobenius_error_matches_angle(rng):
    R1, R2 = so3.random_rotations(rng, (2, 100))
    theta = np.radians(so3.angle_between_deg(R1, R2))
    assert np.allclose(so3.frobenius_error(R1, R2), 2 * np.sqrt(2) * np.sin(theta / 2))


def test_assert_rotations_close_names_the_worst_index():
    from replication.testing import assert_rotations_close

    R = np.broadcast_to(np.eye(3), (2, 3, 3, 3)).copy()
    R[1, 2] = so3.matrix_from_rotation_vector(np.radians([0.0, 0.0, 0.5]))
    R[0, 1] = so3.matrix_from_rotation_vector(np.radians([0.0, 0.2, 0.0]))
    assert_rotations_close(R, np.eye(3), 0.6)
    with pytest.raises(AssertionError, match=r"by 0\.5 deg at index \(1, 2\) \(> 0\.1 deg; 2 of 6 off\)"):
        assert_rotations_close(R, np.eye(3), 0.1)


def test_yaw_pitch_roll_order_is_in_the_name():
    R = so3.matrix_from_euler("ZYX", [30.0, -20.0, 10.0], degrees=True)
    np.testing.assert_allclose(so3.yaw_pitch_roll_deg_from_matrix(R), [30.0, -20.0, 10.0])
    np.testing.assert_allclose(R, so3.matrix_from_euler("z", [30.0], degrees=True) @ so3.matrix_from_euler("y", [-20.0],
                                                                                                           degrees=True)
                               @ so3.matrix_from_euler("x", [10.0], degrees=True))
    assert so3.yaw_pitch_roll_deg_from_matrix(np.broadcast_to(R, (4, 5, 3, 3))).shape == (4, 5, 3)


# -----------------------------------------------------------------------------------------
# conversions, round trips
#
# Measured (NumPy/SciPy of requirements.lock, 2 000 rotations per band): every round trip below is
# within 1.1e-15 (absolute, for vectors of norm <= pi and for matrix entries) and, near angle 0,
# within 4e-16 of the angle (relative). The tolerances are 1e-14 absolute and 1e-14 relative: 10 to
# 25 times what is measured.
ABS, REL = 1e-14, 1e-14

#: Angle bands (rad): near 0 (1e-12 .. 1e-6), generic (log-uniform 1e-6 .. 1, and uniform 1e-3 .. pi
#: - 1e-3), and near a half-turn (pi - 1e-9 .. pi, where the axis no longer follows from the
#: antisymmetric part of R).
BANDS = {
    "near 0": lambda rng, n: 10 ** rng.uniform(-12, -6, n),
    "small": lambda rng, n: 10 ** rng.uniform(-6, 0, n),
    "generic": lambda rng, n: rng.uniform(1e-3, np.pi - 1e-3, n),
    "near pi": lambda rng, n: np.pi - rng.uniform(0, 1e-9, n),
}


def _rotvecs(rng, band, shape=(400,)):
    n = int(np.prod(shape))
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return (axis * BANDS[band](rng, n)[:, None]).reshape(shape + (3,))


@pytest.mark.parametrize("band", list(BANDS))
def test_matrix_from_rotation_vector_is_rodrigues(rng, band):
    from scipy.spatial.transform import Rotation

    w = _rotvecs(rng, band)
    np.testing.assert_allclose(so3.matrix_from_rotation_vector(w), Rotation.from_rotvec(w).as_matrix(), rtol=0,
                               atol=ABS)


@pytest.mark.parametrize("band", list(BANDS))
def test_rotation_vector_from_matrix_inverts_matrix_from_rotation_vector(rng, band):
    w = _rotvecs(rng, band)
    theta = np.linalg.norm(w, axis=-1)
    back = so3.rotation_vector_from_matrix(so3.matrix_from_rotation_vector(w))
    err = np.linalg.norm(back - w, axis=-1)
    assert np.all(err <= np.maximum(ABS * (theta >= 1e-6), REL * theta)), err.max()  # near 0: relative to the angle
    assert np.all(np.linalg.norm(back, axis=-1) <= np.pi)
    np.testing.assert_allclose(np.radians(so3.rotation_angle_deg(so3.matrix_from_rotation_vector(w))), theta, rtol=REL,
                               atol=0)


def test_rotation_vector_from_matrix_at_a_half_turn_is_either_sign(rng):
    """At exactly pi, ``w`` and ``-w`` are one rotation: ``log`` may return either, but exp(log R)
    is R."""
    w = _rotvecs(rng, "generic", (50,))
    w *= np.pi / np.linalg.norm(w, axis=-1, keepdims=True)
    w = np.concatenate([w, np.pi * np.eye(3), -np.pi * np.eye(3)])
    R = so3.matrix_from_rotation_vector(w)
    back = so3.rotation_vector_from_matrix(R)
    err = np.minimum(np.linalg.norm(back - w, axis=-1), np.linalg.norm(back + w, axis=-1))
    assert err.max() <= ABS
    np.testing.assert_allclose(so3.matrix_from_rotation_vector(back), R, rtol=0, atol=ABS)


@pytest.mark.parametrize("band", list(BANDS))
def test_matrix_from_rotation_vector_inverts_rotation_vector_from_matrix(rng, band):
    R = so3.matrix_from_rotation_vector(_rotvecs(rng, band))
    np.testing.assert_allclose(so3.matrix_from_rotation_vector(so3.rotation_vector_from_matrix(R)), R, rtol=0, atol=ABS)


@pytest.mark.parametrize("band", list(BANDS))
def test_quaternion_round_trips_and_sign(rng, band):
    from scipy.spatial.transform import Rotation

    w = _rotvecs(rng, band)
    R = so3.matrix_from_rotation_vector(w)
    q = so3.quaternion_from_matrix(R)
    assert q.shape == (400, 4) and np.all(q[:, 0] >= 0)  # scalar first, w >= 0
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, rtol=0, atol=ABS)
    reference = Rotation.from_rotvec(w).as_quat(scalar_first=True)  # SciPy's, with w >= 0 too
    reference *= np.where(reference[:, :1] < 0, -1.0, 1.0)
    np.testing.assert_allclose(q, reference, rtol=0, atol=ABS)
    np.testing.assert_allclose(so3.matrix_from_quaternion(q), R, rtol=0, atol=ABS)
    np.testing.assert_allclose(so3.matrix_from_quaternion(-q), R, rtol=0, atol=ABS)  # q and -q: one rotation
    np.testing.assert_allclose(so3.matrix_from_quaternion(3.0 * q), R, rtol=0, atol=ABS)  # normalised first


def test_quaternion_order_is_scalar_first():
    """A quarter-turn about z is (cos 45, 0, 0, sin 45); read scalar-last it would be another
    rotation."""
    R = so3.matrix_from_rotation_vector(np.array([0.0, 0.0, np.pi / 2]))
    np.testing.assert_allclose(so3.quaternion_from_matrix(R), [np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)], atol=ABS)
    np.testing.assert_allclose(so3.matrix_from_quaternion([0.0, 1.0, 0.0, 0.0]), np.diag([1.0, -1.0, -1.0]), atol=ABS)
    # (x, y, z, w) read as (w, x, y, z)
    scalar_last = so3.matrix_from_quaternion([0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)])
    assert so3.angle_between_deg(scalar_last, R) > 90


def test_the_quaternion_of_a_half_turn_has_w_zero(rng):
    axis = np.array([2.0, -1.0, 2.0]) / 3.0
    q = so3.quaternion_from_matrix(so3.matrix_from_rotation_vector(np.pi * axis))
    assert abs(q[0]) <= ABS and np.allclose(np.abs(q[1:]), np.abs(axis), atol=ABS)


def test_yaw_pitch_roll_round_trips(rng):
    n = 400
    ypr = np.column_stack([rng.uniform(-180, 180, n), rng.uniform(-89.9, 89.9, n), rng.uniform(-180, 180, n)])
    R = so3.matrix_from_euler("ZYX", ypr, degrees=True)
    # measured: 4e-13 deg (the angles of a rotation 0.1 deg from gimbal lock are ill-conditioned);
    # bound 1e-10 deg
    np.testing.assert_allclose(so3.yaw_pitch_roll_deg_from_matrix(R), ypr, rtol=0, atol=1e-10)
    # any rotation, gimbal lock included: the angles give the rotation back
    R = np.concatenate([so3.random_rotations(rng, n), so3.matrix_from_euler("ZYX", [[10.0, 90.0, 0.0], [0.0, -90.0,
                                                                                                        5.0]],
                                                                        degrees=True)])
    with pytest.warns(UserWarning, match="Gimbal lock detected"):  # SciPy's, for the last two
        angles = so3.yaw_pitch_roll_deg_from_matrix(R)
    assert np.all(np.abs(angles[:, 1]) <= 90.0) and np.all(np.abs(angles[:, [0, 2]]) <= 180.0)
    np.testing.assert_allclose(so3.matrix_from_euler("ZYX", angles, degrees=True), R, rtol=0, atol=ABS)


@pytest.mark.parametrize("shape", [(), (5,), (2, 3, 4), (0,), (3, 0)])
def test_conversions_keep_batch_shapes(rng, shape):
    w = _rotvecs(rng, "generic", shape) if np.prod(shape) else np.zeros(shape + (3,))
    R = so3.matrix_from_rotation_vector(w)
    assert R.shape == shape + (3, 3) and so3.rotation_vector_from_matrix(R).shape == shape + (3,)
    q = so3.quaternion_from_matrix(R)
    assert q.shape == shape + (4,) and so3.matrix_from_quaternion(q).shape == shape + (3, 3)
    assert so3.yaw_pitch_roll_deg_from_matrix(R).shape == shape + (3,) and so3.rotation_angle_deg(R).shape == shape
    if np.prod(shape):  # batched equals one at a time
        flat_w, flat_R = w.reshape(-1, 3), R.reshape(-1, 3, 3)
        for k in (0, len(flat_w) - 1):
            np.testing.assert_array_equal(so3.matrix_from_rotation_vector(flat_w[k]), flat_R[k])
            np.testing.assert_array_equal(so3.rotation_vector_from_matrix(flat_R[k]),
                                          so3.rotation_vector_from_matrix(R).reshape(-1, 3)[k])
            np.testing.assert_array_equal(so3.quaternion_from_matrix(flat_R[k]), q.reshape(-1, 4)[k])


def test_rotation_vector_from_matrix_half_turns_with_signed_zero_entries_give_no_negative_zero():
    """Beyond 120 deg the axis is a column of (R + R^T)/2 - c I; its off-diagonal entries are x - c
    * 0 (c < 0), which turns an entry of -0.0 into 0.0: the rotation vector of diag(1, -1, -1)
    written with -0.0 is (pi, 0, 0)."""
    R = np.array([[1.0, -0.0, -0.0], [-0.0, -1.0, -0.0], [-0.0, -0.0, -1.0]])
    w = so3.rotation_vector_from_matrix(R)
    assert np.array_equal(w, [np.pi, 0.0, 0.0]) and not np.signbit(w).any()


def test_cumulative_product_matches_a_loop(rng):
    R = so3.random_rotations(rng, 37)
    expected, P = [], np.eye(3)
    for r in R:
        P = P @ r
        expected.append(P)
    np.testing.assert_allclose(so3.cumulative_product(R), expected, atol=1e-13)
