"""MSAC + IRLS (``robust``, :mod:`replication.core.solvers.msac`): its hypotheses drawn in O(J)
memory above a cap, bit-identical to the full enumeration below it.

Figures behind the limits: ``benchmarks/bench_bounded.py``.
"""
import tracemalloc
import warnings
from itertools import combinations

import numpy as np
import pytest

from replication.core import so3
from replication.core.handeye import pair_residual_deg
from replication.core.motions import prepare_motions
from replication.core.solvers import chordal_optimal, msac, robust
from replication.study.baselines import corrupt_pairs
from replication.study.simulation import simulate


def _outlier_problem(J, *, share=0.3, noise_deg=0.5, seed=0):
    rng = np.random.default_rng(seed)
    R0 = so3.random_rotations(rng, ())
    A = so3.random_rotations(rng, J)
    B = so3.matrix_from_rotation_vector(rng.normal(size=(J, 3)) * np.radians(noise_deg)) @ (R0.T @ A @ R0)
    return R0, A, corrupt_pairs(B, share, rng)[0]  # the same draws as notebook 06's outlier sweep


def _robust_before(motions, threshold_deg=5.0, max_hypotheses=200, seed=0, irls_iterations=10):
    """``robust`` as it was before the cost was bounded (all pairs listed, one (..., H, J) residual
    array)."""
    from replication.core.handeye import kronecker_operator
    from replication.core.solvers.certificate import chordal_newton

    A, B, J = motions.A, motions.B, motions.J
    idx = np.array(list(combinations(range(J), 2)))
    if len(idx) > max_hypotheses:
        idx = idx[np.sort(np.random.default_rng(seed).choice(len(idx), size=max_hypotheses, replace=False))]
    alpha, beta = so3.rotation_vector_from_matrix(A), so3.rotation_vector_from_matrix(B)
    R_h = so3.nearest_rotation(np.einsum("...hka,...hkb->...hab", alpha[..., idx, :], beta[..., idx, :]))
    r = pair_residual_deg(R_h, A[..., None, :, :, :], B[..., None, :, :, :])
    best = np.argmin(np.sum(np.minimum(r, threshold_deg) ** 2, axis=-1), axis=-1)
    R = np.take_along_axis(R_h, best[..., None, None, None], axis=-3)[..., 0, :, :]
    for _ in range(irls_iterations):
        w = 1.0 / (1.0 + (pair_residual_deg(R, A, B) / (0.5 * threshold_deg)) ** 2)
        R = chordal_newton(kronecker_operator(A, B, weights=w), R)[0]
    return R


# --- robust
# --------------------------------------------------------------------------------------------------

def test_sample_positions_decode_to_the_itertools_order():
    for J in (3, 4, 17, 200, 1001):
        k = np.arange(J * (J - 1) // 2)
        np.testing.assert_array_equal(msac.pair_at(k, J), np.array(list(combinations(range(J), 2))))
    J = 1_000_000  # the last pairs of the largest J of the benchmark
    n = J * (J - 1) // 2
    np.testing.assert_array_equal(msac.pair_at([0, J - 2, J - 1, n - 2, n - 1], J),
                                  [[0, 1], [0, J - 1], [1, 2], [J - 3, J - 1], [J - 2, J - 1]])


@pytest.mark.parametrize("options", [{}, {"max_hypotheses": 5000}, {"max_hypotheses": 7, "seed": 3}])
def test_robust_below_the_cap_is_bit_identical_to_before(options, monkeypatch):
    sim = simulate(3, 12, n_motions=50)
    m = prepare_motions(sim.A, sim.B)
    before = _robust_before(m, **options)
    np.testing.assert_array_equal(msac.robust.core(m, **options), before)
    monkeypatch.setattr(msac, "_EXACT_BLOCK", 500)  # many blocks of problems x hypotheses: same bits
    np.testing.assert_array_equal(msac.robust.core(m, **options), before)


def test_robust_above_the_cap_draws_the_same_samples_and_agrees(monkeypatch):
    _, A, B = _outlier_problem(60, seed=1)
    m = prepare_motions(np.stack([A, A[::-1]]), np.stack([B, B[::-1]]))
    exact_idx, exact_R = msac.hypotheses(60, 200, 0), msac.robust.core(m)
    monkeypatch.setattr(msac, "MAX_ENUMERATED_PAIRS", 10)  # 1770 pairs: drawn, not listed
    np.testing.assert_array_equal(msac.hypotheses(60, 200, 0), exact_idx)
    np.testing.assert_array_equal(msac.hypotheses(60, 5000, 0), np.array(list(combinations(range(60), 2))))
    # the blocked 81-vector scores equal pair_residual_deg's to rounding
    R_h = so3.random_rotations(np.random.default_rng(2), (2, 30))
    flat = m.A.reshape(-1, 60, 3, 3), m.B.reshape(-1, 60, 3, 3)
    np.testing.assert_allclose(msac.scores_blocked(R_h, *flat, 5.0), msac.scores_exact(R_h, *flat, 5.0),
                               rtol=1e-10)
    monkeypatch.setattr(msac, "SCORE_BLOCK", 70)  # several blocks of pairs and of hypotheses
    np.testing.assert_allclose(msac.scores_blocked(R_h, *flat, 5.0), msac.scores_exact(R_h, *flat, 5.0),
                               rtol=1e-10)
    np.testing.assert_allclose(msac.robust.core(m), exact_R, rtol=0, atol=1e-12)


def test_robust_above_the_cap_recovers_r0_with_30_percent_outliers():
    R0, A, B = _outlier_problem(3000, seed=4)  # 4.5 million two-pair samples, above MAX_ENUMERATED_PAIRS
    assert 3000 * 2999 // 2 > msac.MAX_ENUMERATED_PAIRS
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the outliers make eq. (8) flat: ObservabilityWarning
        err_robust = float(so3.angle_between_deg(robust(A, B), R0))
        err_ls = float(so3.angle_between_deg(chordal_optimal(A, B).R, R0))
    assert err_robust < 0.1
    assert err_ls > 10 * err_robust


def test_robust_memory_is_linear_in_j():
    J = 20_000  # J (J - 1) / 2 = 2e8 samples: an index array of them alone takes 3.2 GB
    R0, A, B = _outlier_problem(J, seed=5)
    m = prepare_motions(A, B)
    tracemalloc.start()
    try:
        R = msac.robust.core(m)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert so3.angle_between_deg(R, R0) < 0.1
    assert peak < 80e6, f"robust at J = {J} peaked at {peak / 1e6:.0f} MB"
