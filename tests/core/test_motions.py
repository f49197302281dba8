"""The validated motion pairs (``replication/core/motions.py``): ``Motions``' tolerance on
rotations (``atol``) at its bounds, its decompositions of ``K`` made once and shared (singular
values, top vectors, the eigenvalues of ``sym(K)``), and the leave-one-out spread that tells a
single pair carrying an axis from two."""
import numpy as np
import pytest

from conftest import _noisy_batch, _one_axis_plus_one_turn
from replication.core.handeye import relative_rotations
from replication.core.motions import Motions


def test_singular_values_and_top_vectors_from_one_eigh_match_the_svd(rng):
    """One eigh of K^T K stands for the SVD of K: the top pair to rounding, the small values within
    eps sigma_1^2 / sigma_k (what their docstring states), the limit's vectors paired as K v1 =
    sigma_1 u1."""
    m = Motions(*_noisy_batch(rng, J=3))  # J = 3: small singular values down to about 1e-5
    U, s, Vt = np.linalg.svd(m.K)
    sv = m.singular_values
    assert np.max(np.abs(sv[..., :2] - s[..., :2]) / s[..., :2]) <= 1e-14
    assert np.all(np.abs(sv - s) <= 8 * np.finfo(float).eps * s[..., :1] ** 2 / np.maximum(s, 1e-300) + 1e-15)
    assert m.observability.kron_singular_values is sv
    u1, s1, v1 = m.top_singular_vectors
    sign = np.sign(np.einsum("...i,...i->...", v1, Vt[..., 0, :]))[..., None]
    assert np.max(np.abs(v1 - sign * Vt[..., 0, :])) <= 1e-12
    assert np.max(np.abs(u1 - sign * U[..., :, 0])) <= 1e-12
    assert np.max(np.abs(np.einsum("...ab,...b->...a", m.K, v1) - s1[..., None] * u1)) <= 1e-14
    assert np.max(np.abs(s1 - s[..., 0])) <= 1e-14



def test_sym_eigvals_come_from_the_decomposition_made_first(rng):
    A, B = _noisy_batch(rng)
    fresh = Motions(A, B)
    want = np.linalg.eigvalsh(fresh.sym)[..., ::-1]
    assert np.array_equal(fresh.sym_eigvals, want)  # eigvalsh when nothing asked for the vectors
    primed = Motions(A, B)
    _ = primed.sym_eigh
    assert primed.sym_eigvals is primed.sym_eigh[0]
    assert np.max(np.abs(primed.sym_eigvals - want)) <= 1e-14


@pytest.mark.parametrize("atol, match", [
    (float("nan"), r"atol must be a finite number, got nan"),
    (float("inf"), r"atol must be a finite number, got inf"),
    (-1.0, r"atol must be > 0, got -1.0"),
    (0.0, r"atol must be > 0, got 0.0"),
    (0.5, r"atol must be <= 0.01 \(MAX_ROTATION_ATOL.*got 0.5"),
    ("1e-6", r"atol must be a finite number, got '1e-6'"),
    (True, r"atol must be a finite number, got True"),
], ids=["nan", "inf", "negative", "zero", "too-loose", "str", "bool"])
def test_motions_refuse_a_bad_atol(problem, atol, match):
    _, A, B = problem
    with pytest.raises(ValueError, match=match):
        Motions(2 * A, B, atol=atol)  # a NaN tolerance used to accept these non-rotations
    with pytest.raises(ValueError, match=match):
        Motions(A, B, atol=atol)
    with pytest.raises(ValueError, match=match):
        relative_rotations(A, atol=atol)



@pytest.mark.parametrize("atol", [1e-12, 1e-4, np.float64(1e-2)])
def test_motions_accept_an_atol_in_range(problem, atol):
    _, A, B = problem
    assert Motions(A, B, atol=atol).J == 20
    with pytest.raises(ValueError, match="not a rotation matrix"):
        Motions(2 * A, B, atol=atol)



def test_two_turns_or_two_pairs_are_not_one_pair(rng):
    from replication.core.motions import Motions

    _, A, B = _one_axis_plus_one_turn(rng, noise_deg=0.0, second_turn_deg=30.0)
    assert Motions(A, B).leave_one_out_spread_deg[0] > 5.0
    _, A, B = _one_axis_plus_one_turn(rng, J=2, noise_deg=0.0)
    assert np.isnan(Motions(A, B).leave_one_out_spread_deg[0])  # J = 2 has no redundancy to speak of
