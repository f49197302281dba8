"""The rotation and number checks of :mod:`replication.core.checks` at their boundaries: ``atol`` in
``(0, MAX_ROTATION_ATOL]``, orthonormality and determinant at exactly ``atol``, the first offending
index and the counts in the messages, numbers strictly or not above a minimum, and the per-sample
check of one flat rotation. Mutation testing (scripts/mutation) found these unguarded by the fast
tests."""
import math

import numpy as np
import pytest

from conftest import NUMPY_REPR
from replication.core import checks, so3
from replication.core.checks import (
    MAX_ROTATION_ATOL,
    ROTATION_ATOL,
    check_atol,
    check_number,
    check_rotation_flat,
    check_rotation_matrices,
)
from replication.rig.live import LiveRig
from replication.rig.online import OnlineCalibrator
from replication.rig.streams import OrientationStream


def _stretched(eps):
    """A matrix with ||R^T R - I||_F = eps exactly in its (0, 0) entry: diag(sqrt(1 + eps), 1,
    1)."""
    return np.diag([math.sqrt(1.0 + eps), 1.0, 1.0])


def test_atol_is_a_positive_number_up_to_the_maximum():
    assert check_atol(MAX_ROTATION_ATOL) == MAX_ROTATION_ATOL
    assert check_atol(1e-300) == 1e-300
    with pytest.raises(ValueError, match=r"atol must be <= 0\.01 \(MAX_ROTATION_ATOL.*got 0\.010000000000000002"):
        check_atol(float(np.nextafter(MAX_ROTATION_ATOL, 1.0)))
    with pytest.raises(ValueError, match=r"atol must be > 0\b.*got 0"):
        check_atol(0)
    with pytest.raises(ValueError, match=r"\btol must be > 0\b.*got -1\.0"):
        check_atol(-1.0, "tol")
    with pytest.raises(ValueError, match=r"atol must be a finite number.*got nan"):
        check_atol(math.nan)


def test_check_number_strict_and_not_and_integers():
    assert check_number("x", 1.5, minimum=1.0) == 1.5
    with pytest.raises(ValueError, match=r"x must be > 1\b.*got 1\.0"):
        check_number("x", 1.0, minimum=1.0)
    assert check_number("x", 1.0, minimum=1.0, strict=False) == 1.0
    with pytest.raises(ValueError, match=r"x must be >= 1\b.*got 0\.5"):
        check_number("x", 0.5, minimum=1.0, strict=False)
    assert check_number("n", 3, integer=True) == 3 and check_number("n", np.int64(3), integer=True) == 3
    for bad in (3.0, True, "3"):
        with pytest.raises(ValueError, match=r"\bn must be a finite integer"):
            check_number("n", bad, integer=True)
    for bad in (True, math.inf, -math.inf, math.nan, "1", None, 1j):
        with pytest.raises(ValueError, match=r"x must be a finite number"):
            check_number("x", bad)
    assert check_number("x", np.float32(2.5)) == 2.5 and check_number("x", -7) == -7
    assert check_number("x", 0.0, minimum=None) == 0.0


def test_orthonormality_at_exactly_atol_passes_and_beyond_fails():
    atol = 1e-4
    ok = np.stack([np.eye(3), _stretched(atol * (1 - 1e-6))])
    assert check_rotation_matrices(ok, atol=atol) is not None
    bad = np.stack([np.eye(3), np.eye(3), _stretched(atol * 1.01), _stretched(atol * 2)])
    with pytest.raises(ValueError, match=r"Q is not a rotation matrix at index 2\b.* 0\.000101 > 0\.0001"
                                         r".*2 bad of 4"):
        check_rotation_matrices(bad, "Q", atol=atol)
    # the default tolerance
    check_rotation_matrices(_stretched(ROTATION_ATOL * 0.99))
    with pytest.raises(ValueError, match="not a rotation matrix at index \\(\\)"):
        check_rotation_matrices(_stretched(ROTATION_ATOL * 1.01))


def test_a_reflection_is_named_with_its_index_and_determinant():
    R = np.stack([[np.eye(3), np.eye(3)], [np.eye(3), np.diag([1.0, 1.0, -1.0])]])
    with pytest.raises(ValueError, match=r"R is not a rotation matrix at index \(1, 1\).*det = -1\b.*reflection"):
        check_rotation_matrices(R)


def test_the_determinant_test_uses_atol():
    # orthonormal to rounding but det off: a matrix scaled along one axis fails the first test; here
    # a tiny non-orthogonal shear passes it with the loosest atol while det stays 1 + O(shear^2)
    s = 1e-3
    M = np.array([[1.0, s, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    ortho = np.linalg.norm(M.T @ M - np.eye(3))
    assert check_rotation_matrices(M, atol=ortho * 1.01) is not None  # det = 1 exactly
    D = np.diag([1.0, 1.0, 1.0 + 4e-3])  # ||R^T R - I||_F = 8.016e-3, |det - 1| = 4e-3
    assert check_rotation_matrices(D, atol=MAX_ROTATION_ATOL) is not None
    D = np.diag([-1.0, 1.0, 1.0 + 4e-3])
    with pytest.raises(ValueError, match="a reflection"):
        check_rotation_matrices(D, atol=MAX_ROTATION_ATOL)


def _flat(M):
    return [float(v) for v in np.asarray(M).reshape(9)]


def test_flat_rotation_check_at_its_tolerance():
    check_rotation_flat("R", _flat(np.eye(3)))
    eps = 1e-6
    # largest entry of R^T R - I: the (0, 0) entry (1 + e)^2 - 1
    for _k, col in ((0, 0), (4, 1), (8, 2)):
        M = np.eye(3)
        M[col, col] = math.sqrt(1.0 + eps)
        check_rotation_flat("R", _flat(M), atol=eps * (1 + 1e-9))
        with pytest.raises(ValueError, match=r"R is not a rotation matrix.*\|R\^T R - I\| = 1e-06"):
            check_rotation_flat("R", _flat(M), atol=eps * (1 - 1e-6))
    # off-diagonal entries of R^T R: columns not orthogonal
    for a, b in ((0, 1), (0, 2), (1, 2)):
        M = np.eye(3)
        M[a, b] = 1e-5  # column b gains a component along axis a: <col a, col b> = 1e-5
        with pytest.raises(ValueError, match="max \\|R\\^T R - I\\| = 1e-05"):
            check_rotation_flat("R", _flat(M), atol=1e-6)
        check_rotation_flat("R", _flat(M), atol=2e-5)
    with pytest.raises(ValueError, match=r"R is a reflection \(det -1\)"):
        check_rotation_flat("R", _flat(np.diag([1.0, -1.0, 1.0])))
    for k in range(9):
        bad = _flat(np.eye(3))
        bad[k] = math.nan
        with pytest.raises(ValueError, match=r"R is not a rotation matrix.*NaN or inf"):
            check_rotation_flat("R", bad)
    bad = _flat(np.eye(3))
    bad[3] = math.inf
    with pytest.raises(ValueError, match="NaN or inf"):
        check_rotation_flat("R", bad)
    # a rotation with every entry non-zero: the determinant uses all nine
    c, s = math.cos(0.7), math.sin(0.7)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    Rx = np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])
    R = Rz @ Rx @ Rz
    check_rotation_flat("R", _flat(R))
    with pytest.raises(ValueError, match="reflection"):
        check_rotation_flat("R", _flat(-R))
    for k in range(3):
        F = R.copy()
        F[:, k] = -F[:, k]
        with pytest.raises(ValueError, match="reflection"):
            check_rotation_flat("R", _flat(F))
        F = R.copy()
        F[k, :] = -F[k, :]
        with pytest.raises(ValueError, match="reflection"):
            check_rotation_flat("R", _flat(F))


def test_flat_check_edge_cases():
    # a rotation with a zero (0, 0) entry: the determinant is a sum of products, never a quotient
    check_rotation_flat("R", _flat(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])))
    # the tolerance is inclusive: a column whose squared norm rounds to exactly 1 + 2**-29
    M = np.eye(3)
    M[0, 0] = 1.0 + 2.0 ** -30
    check_rotation_flat("R", _flat(M), atol=2.0 ** -29)
    with pytest.raises(ValueError, match="max"):
        check_rotation_flat("R", _flat(M), atol=2.0 ** -29 * (1 - 1e-9))


@pytest.mark.parametrize("k", range(1, 9))
def test_a_finite_matrix_whose_entries_cancel_is_judged_by_its_orthogonality_not_as_nan(k):
    # entries +-1e308: finite, their sum 0; the squares overflow, so |R^T R - I| is inf
    flat = [0.0] * 9
    flat[0], flat[k] = 1e308, -1e308
    with pytest.raises(ValueError, match=r"R is not a rotation matrix.*\|R\^T R - I\| = inf"):
        check_rotation_flat("R", flat)


def test_finite_entries_whose_sum_overflows_are_said_as_magnitudes_not_nan():
    flat = [1e308, 1e308] + [0.0] * 7
    with pytest.raises(ValueError, match=r"R is not a rotation matrix.*entries of magnitude 1e\+308"):
        check_rotation_flat("R", flat)
    with pytest.raises(ValueError, match=r"R is not a rotation matrix.*NaN or inf"):
        check_rotation_flat("R", [math.inf] + [0.0] * 8)


@pytest.mark.parametrize("atol", [0.0, -1e-6, MAX_ROTATION_ATOL * 1.01, math.nan])
def test_the_flat_check_validates_its_tolerance_like_the_array_check(atol):
    with pytest.raises(ValueError, match="atol"):
        check_rotation_flat("R", [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], atol=atol)
    check_rotation_flat("R", [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], atol=MAX_ROTATION_ATOL)


def _rig_streams():
    t = np.arange(0.0, 20.0, 0.05)
    R = so3.matrix_from_rotation_vector(np.stack([np.sin(t), np.cos(0.7 * t), 0.3 * t], axis=-1))
    return OrientationStream(t, R, "c"), OrientationStream(t, R @ so3.matrix_from_rotation_vector(np.array([0.1, 0.2,
                                                                                                            0.3])), "s")


def test_parameter_refusals_show_numpy_scalars_as_plain_numbers():
    """Parameters given as NumPy scalars (read from an array, a config parsed by NumPy): the refusal
    shows the number (``-1.0``), never ``np.float64(-1.0)``."""
    from replication.core.checks import check_number, check_range
    from replication.rig.calibration import calibrate
    from replication.rig.poses import calibrate_poses
    from replication.study.vins_rule import VinsExRotation

    cam, sen = _rig_streams()
    cases = [
        (lambda: check_number("x", np.float64(-1), minimum=0), "x must be > 0, got -1.0"),
        (lambda: check_number("x", np.float64(1.5), integer=True), "got 1.5"),
        (lambda: check_range("x", np.float64(2.0), low=0.0, high=1.0), "got 2.0"),
        (lambda: calibrate(cam, sen, interval=np.float64(-1)), "interval must be > 0, got -1.0"),
        (lambda: calibrate(cam, sen, n_bootstrap=np.int64(-1)), "n_bootstrap must be >= 0, got -1"),
        (lambda: calibrate_poses(cam.R[:8], sen.R[:8], pairs=np.str_("x")), "got 'x'"),
        (lambda: LiveRig(OnlineCalibrator(), max_offset=0.3, offset_window=np.float64(1.5)), "got 1.5"),
        (lambda: VinsExRotation(huber_deg=np.float64(0.0)), "got 0.0"),
    ]
    for build, phrase in cases:
        with pytest.raises(ValueError) as err:
            build()
        assert phrase in str(err.value) and not NUMPY_REPR.search(str(err.value)), str(err.value)


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
        checks.check_rotation_matrices(bad)
