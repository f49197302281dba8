"""The validated motion pairs (``replication/core/motions.py``): ``Motions``' tolerance on
rotations (``atol``) at its bounds, its decompositions of ``K`` made once and shared (singular
values, top vectors, the eigenvalues of ``sym(K)``), and the leave-one-out spread that tells a
single pair carrying an axis from two."""
import numpy as np

from conftest import _noisy_batch
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
