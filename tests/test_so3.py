import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from replication import so3

finite = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


def test_check_rotation_accepts_rotations(rng):
    R = so3.random_rotations(rng, (4, 5))
    assert so3.check_rotation_matrices(R).shape == (4, 5, 3, 3)


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.zeros((3, 4)), r"shape \(\.\.\., 3, 3\)"),
        (np.full((2, 3, 3), np.nan), "NaN or inf"),
        (np.diag([1.0, 1.0, 1.1]), "not a rotation matrix"),
        (np.diag([1.0, 1.0, -1.0]), "reflection"),
        ("abc", "numeric"),
    ],
)
def test_check_rotation_rejects(bad, message):
    with pytest.raises(ValueError, match=message):
        so3.check_rotation_matrices(bad)


def test_check_rotation_names_the_index(rng):
    R = so3.random_rotations(rng, 6)
    R[4] *= 1.01
    with pytest.raises(ValueError, match=r"index \(4,\)"):
        so3.check_rotation_matrices(R, "R")


@settings(max_examples=60, deadline=None)
@given(arrays(float, (3, 3), elements=finite))
def test_nearest_rotation_is_a_rotation_and_nearest(M):
    if abs(np.linalg.det(M)) < 1e-6 or np.linalg.cond(M) > 1e8:
        return  # the projection is not unique for (nearly) singular M
    P = so3.nearest_rotation(M)
    so3.check_rotation_matrices(P)
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
    so3.check_rotation_matrices(R)
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
    R[1, 2] = so3.exp_map(np.radians([0.0, 0.0, 0.5]))
    R[0, 1] = so3.exp_map(np.radians([0.0, 0.2, 0.0]))
    assert_rotations_close(R, np.eye(3), 0.6)
    with pytest.raises(AssertionError, match=r"by 0\.5 deg at index \(1, 2\) \(> 0\.1 deg; 2 of 6 off\)"):
        assert_rotations_close(R, np.eye(3), 0.1)


def test_yaw_pitch_roll_order_is_in_the_name():
    R = so3.from_euler("ZYX", [30.0, -20.0, 10.0], degrees=True)
    np.testing.assert_allclose(so3.yaw_pitch_roll_deg(R), [30.0, -20.0, 10.0])
    np.testing.assert_allclose(R, so3.from_euler("z", [30.0], degrees=True) @ so3.from_euler("y", [-20.0], degrees=True)
                               @ so3.from_euler("x", [10.0], degrees=True))
    assert so3.yaw_pitch_roll_deg(np.broadcast_to(R, (4, 5, 3, 3))).shape == (4, 5, 3)
