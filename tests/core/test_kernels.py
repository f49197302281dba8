"""The batched small-matrix kernels (replication/core/kernels.py) against the LAPACK path they
replace.

Every kernel is compared with ``method="lapack"`` (today's ``numpy.linalg`` path) to 1e-12 on
random, near-rotation, rank-deficient, repeated-singular-value and reflection inputs at batch shapes
(), (n,) and (a, b); each fallback threshold is tested just below and just above.
"""
import numpy as np
import pytest

from replication.core import kernels
from replication.core.checks import check_rotation_matrices
from replication.core.kernels import (
    EIG3_SAFE,
    MIN_BATCH,
    MIN_BATCH_LARGE,
    POLAR_SAFE,
    SOLVE3_SAFE,
    TOP3_SAFE,
    bottom_eigenvector4,
    eigvalsh3,
    lapack_reference,
    polar_factor,
    rotation_violation,
    solve3,
    top_eigenvector3,
)
from replication.core.so3 import nearest_rotation, nearest_rotation_up_to_sign, random_rotations

SHAPES = [(), (64,), (8, 9)]
MODES = ["rotation", "orthogonal", "up_to_sign"]


def _svd_compose(rng, shape, sigma):
    """Matrices ``U diag(sigma) V^T`` with Haar-random ``U``, ``V`` (det +1 each) and the given
    singular values."""
    U, V = random_rotations(rng, shape), random_rotations(rng, shape)
    return U @ (np.asarray(sigma, dtype=float)[..., None] * np.swapaxes(V, -1, -2))


def _matrices(kind, rng, shape):
    n = shape if shape else ()
    if kind == "random":
        return rng.normal(size=n + (3, 3))
    if kind == "near_rotation":
        return random_rotations(rng, n) + 1e-6 * rng.normal(size=n + (3, 3))
    if kind == "scaled_unit_vector":  # the two-step iterate: a unit 9-vector reshaped, about R0 / sqrt(3)
        return random_rotations(rng, n) / np.sqrt(3.0) + 0.02 * rng.normal(size=n + (3, 3))
    if kind == "rank_two":
        return _svd_compose(rng, n, np.broadcast_to([2.0, 0.5, 0.0], n + (3,)))
    if kind == "rank_one":
        return _svd_compose(rng, n, np.broadcast_to([1.0, 0.0, 0.0], n + (3,)))
    if kind == "repeated_singular_values":
        return _svd_compose(rng, n, np.broadcast_to([2.0, 0.7, 0.7], n + (3,)))
    if kind == "scaled_rotation":
        return 3.0 * random_rotations(rng, n)
    if kind == "reflection":
        return -random_rotations(rng, n) + 1e-3 * rng.normal(size=n + (3, 3))
    if kind == "reflection_repeated":  # det < 0 with sigma_2 = sigma_3: no unique nearest rotation
        return -_svd_compose(rng, n, np.broadcast_to([2.0, 1.0, 1.0], n + (3,)))
    raise AssertionError(kind)


KINDS = ["random", "near_rotation", "scaled_unit_vector", "rank_two", "rank_one", "repeated_singular_values",
         "scaled_rotation", "reflection", "reflection_repeated"]


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("mode", MODES)
def test_polar_factor_matches_the_svd_path(kind, mode, shape, rng):
    M = _matrices(kind, rng, shape)
    got = polar_factor(M, mode, method="kernel")
    want = polar_factor(M, mode, method="lapack")
    assert got.shape == M.shape
    assert np.max(np.abs(got - want)) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
def test_so3_doors_use_the_kernel_and_agree_with_the_svd(shape, rng):
    M = _matrices("random", rng, (max(MIN_BATCH, 64),) + shape)
    with lapack_reference():
        before = (nearest_rotation(M), nearest_rotation(M, enforce_det=False), nearest_rotation_up_to_sign(M))
    after = (nearest_rotation(M), nearest_rotation(M, enforce_det=False), nearest_rotation_up_to_sign(M))
    for b, a in zip(before, after):
        assert np.max(np.abs(a - b)) <= 1e-12
        assert not np.array_equal(a, b) or M.size == 0  # the kernel, not LAPACK, answered (rounding differs)


def _ratio(M):
    """The safety measure of :func:`polar_factor`: ``2 |det M| / ||M||_F^3``."""
    return 2.0 * abs(np.linalg.det(M)) / np.linalg.norm(M) ** 3


def _diag_with_ratio(target):
    """``diag(1, 1, t)`` whose ratio ``2 t / (2 + t^2)^1.5`` equals ``target`` (bisection in
    ``t``)."""
    lo, hi = 0.0, 1.0
    for _ in range(200):
        t = 0.5 * (lo + hi)
        lo, hi = (t, hi) if _ratio(np.diag([1.0, 1.0, t])) < target else (lo, t)
    return np.diag([1.0, 1.0, 0.5 * (lo + hi)])


def _lapack_rows(monkeypatch, name):
    """Record how many matrices each call of the LAPACK fallback ``name`` of the kernels module
    received."""
    seen = []
    original = getattr(kernels, name)

    def spy(M, *args, **kwargs):
        seen.append(np.asarray(M).size // 9)
        return original(M, *args, **kwargs)

    monkeypatch.setattr(kernels, name, spy)
    return seen


@pytest.mark.parametrize("factor, to_lapack", [(1.01, 0), (0.99, 1)])
def test_polar_factor_falls_back_below_the_safety_bound_only(factor, to_lapack, rng, monkeypatch):
    seen = _lapack_rows(monkeypatch, "_lapack_polar")
    U, V = random_rotations(rng, 2)
    M = U @ _diag_with_ratio(factor * POLAR_SAFE) @ V.T
    batch = np.concatenate([random_rotations(rng, MIN_BATCH), M[None]])
    out = polar_factor(batch, "rotation")
    assert sum(seen) == to_lapack
    assert np.max(np.abs(out - polar_factor(batch, "rotation", method="lapack"))) <= 1e-12


def test_polar_factor_sends_reflections_to_lapack_only_for_the_nearest_rotation(rng, monkeypatch):
    seen = _lapack_rows(monkeypatch, "_lapack_polar")
    M = np.concatenate([random_rotations(rng, MIN_BATCH), -random_rotations(rng, 3)])
    polar_factor(M, "orthogonal")
    polar_factor(M, "up_to_sign")
    assert seen == []
    polar_factor(M, "rotation")
    assert seen == [3]


def test_polar_factor_unsettled_entries_go_to_lapack(rng, monkeypatch):
    monkeypatch.setattr(kernels, "_POLAR_MAX_ITERATIONS", 1)
    seen = _lapack_rows(monkeypatch, "_lapack_polar")
    M = rng.normal(size=(MIN_BATCH, 3, 3))
    out = polar_factor(M, "up_to_sign")
    assert sum(seen) == MIN_BATCH  # one Newton step settles nothing
    assert np.max(np.abs(out - polar_factor(M, "up_to_sign", method="lapack"))) <= 1e-12


@pytest.mark.parametrize("n, to_lapack", [(MIN_BATCH - 1, True), (MIN_BATCH, False)])
def test_small_batches_go_to_lapack_whole(n, to_lapack, rng, monkeypatch):
    seen = _lapack_rows(monkeypatch, "_lapack_polar")
    polar_factor(rng.normal(size=(n, 3, 3)), "orthogonal")
    assert (seen == [n]) is to_lapack


@pytest.mark.parametrize("n, to_lapack", [(MIN_BATCH_LARGE - 1, True), (MIN_BATCH_LARGE, False)])
def test_small_batches_of_systems_and_4x4_matrices_go_to_lapack_whole(n, to_lapack, rng, monkeypatch):
    seen = []
    solve, eigh = np.linalg.solve, np.linalg.eigh
    monkeypatch.setattr(np.linalg, "solve", lambda A, b: seen.append(("solve", len(A))) or solve(A, b))
    monkeypatch.setattr(np.linalg, "eigh", lambda A: seen.append(("eigh", len(A))) or eigh(A))
    solve3(np.broadcast_to(2.0 * np.eye(3), (n, 3, 3)), np.ones((n, 3)))
    bottom_eigenvector4(np.broadcast_to(np.diag([0.0, 1.0, 2.0, 3.0]), (n, 4, 4)))
    assert (seen == [("solve", n), ("eigh", n)]) is to_lapack
    assert seen == [] or to_lapack


def test_lapack_reference_switches_every_kernel_and_is_restored(rng):
    M = rng.normal(size=(100, 3, 3))
    S = M + np.swapaxes(M, -1, -2)
    b = rng.normal(size=(100, 3))
    with lapack_reference():
        assert np.array_equal(polar_factor(M), polar_factor(M, method="lapack"))
        assert np.array_equal(eigvalsh3(S), np.linalg.eigvalsh(S))
        assert np.array_equal(solve3(S, b), np.linalg.solve(S, b[..., None])[..., 0])
    with pytest.raises(RuntimeError):
        with lapack_reference():
            raise RuntimeError("inside")
    assert not kernels._FORCE_LAPACK[0]
    assert not np.array_equal(polar_factor(M), polar_factor(M, method="lapack"))


def test_bad_mode_or_method_is_named():
    with pytest.raises(ValueError, match="mode must be"):
        polar_factor(np.eye(3), "nearest")
    with pytest.raises(ValueError, match="method must be"):
        eigvalsh3(np.eye(3), method="fast")


def _symmetric(kind, rng, shape):
    n = shape if shape else ()
    if kind == "random":
        M = rng.normal(size=n + (3, 3))
        return M + np.swapaxes(M, -1, -2)
    if kind == "gram_rank_one":  # rotation vectors all about one axis: two zero eigenvalues
        w = rng.normal(size=n + (1, 3)) * rng.normal(size=n + (20, 1))
        return np.swapaxes(w, -1, -2) @ w
    if kind == "gram_near_single_axis":
        w = rng.normal(size=n + (1, 3)) * rng.normal(size=n + (20, 1)) + 1e-4 * rng.normal(size=n + (20, 3))
        return np.swapaxes(w, -1, -2) @ w
    if kind == "multiple_of_identity":
        return rng.normal(size=n)[..., None, None] * np.eye(3)
    if kind == "two_equal":
        Q = random_rotations(rng, n)
        return Q @ (np.array([1.0, 1.0, -2.0])[:, None] * np.swapaxes(Q, -1, -2))
    if kind == "hessian_like":  # negative definite, eigenvalues of order J
        M = rng.normal(size=n + (3, 3))
        return -(M @ np.swapaxes(M, -1, -2) + 20.0 * np.eye(3))
    raise AssertionError(kind)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["random", "gram_rank_one", "gram_near_single_axis", "multiple_of_identity",
                                  "two_equal", "hessian_like"])
def test_eigvalsh3_matches_lapack(kind, shape, rng):
    S = _symmetric(kind, rng, shape)
    got = eigvalsh3(S, method="kernel")
    want = np.linalg.eigvalsh(S)
    assert got.shape == S.shape[:-1]
    scale = np.maximum(1.0, np.max(np.abs(want)))
    assert np.max(np.abs(got - want)) <= 1e-12 * scale


def test_eigvalsh3_reads_the_lower_triangle_as_lapack(rng):
    M = rng.normal(size=(50, 3, 3))  # not symmetric: LAPACK uses the lower triangle
    assert np.max(np.abs(eigvalsh3(M, method="kernel") - np.linalg.eigvalsh(M))) <= 1e-12


def _close_pair(delta):
    """``diag(0, 1, 1 + delta)``: two eigenvalues ``delta`` apart."""
    return np.diag([0.0, 1.0, 1.0 + delta])


def _one_minus_abs_r(S):
    q = np.trace(S) / 3.0
    B = S - q * np.eye(3)
    p = np.sqrt(np.sum(B * B) / 6.0)
    return 1.0 - abs(np.linalg.det(B / p) / 2.0)


@pytest.mark.parametrize("factor, to_lapack", [(1.01, False), (0.99, True)])
def test_eigvalsh3_falls_back_for_close_eigenvalues_only(factor, to_lapack, rng, monkeypatch):
    lo, hi = 0.0, 1.0  # bisection for the delta at which 1 - |r| = factor * EIG3_SAFE
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _one_minus_abs_r(_close_pair(mid)) < factor * EIG3_SAFE else (lo, mid)
    S = np.concatenate([_symmetric("random", rng, (MIN_BATCH,)), _close_pair(hi)[None]])
    seen = []
    original = np.linalg.eigvalsh
    monkeypatch.setattr(np.linalg, "eigvalsh", lambda A: seen.append(len(A)) or original(A))
    got = eigvalsh3(S)
    assert (seen == [1]) is to_lapack
    assert np.max(np.abs(got - original(S))) <= 1e-12


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["random", "spd", "ill_conditioned"])
def test_solve3_matches_lapack(kind, shape, rng):
    n = shape if shape else ()
    A = rng.normal(size=n + (3, 3))
    if kind == "spd":
        A = A @ np.swapaxes(A, -1, -2) + np.eye(3)
    elif kind == "ill_conditioned":
        A = _svd_compose(rng, n, np.broadcast_to([1.0, 1.0, 1e-9], n + (3,)))
    b = rng.normal(size=n + (3,))
    got = solve3(A, b, method="kernel")
    want = np.linalg.solve(A, b[..., None])[..., 0]
    assert got.shape == b.shape
    assert np.max(np.abs(got - want) / np.maximum(1.0, np.linalg.norm(want, axis=-1, keepdims=True))) <= 1e-12


@pytest.mark.parametrize("factor, to_lapack", [(1.01, False), (0.99, True)])
def test_solve3_falls_back_for_ill_conditioned_systems_only(factor, to_lapack, rng, monkeypatch):
    lo, hi = 0.0, 1.0
    for _ in range(200):
        t = 0.5 * (lo + hi)
        lo, hi = (t, hi) if t / (2.0 + t * t) ** 1.5 < factor * SOLVE3_SAFE else (lo, t)
    A = np.concatenate([np.broadcast_to(4.0 * np.eye(3), (MIN_BATCH_LARGE, 3, 3)), np.diag([1.0, 1.0, hi])[None]])
    b = rng.normal(size=(MIN_BATCH_LARGE + 1, 3))
    seen = []
    original = np.linalg.solve
    monkeypatch.setattr(np.linalg, "solve", lambda A, b: seen.append(len(A)) or original(A, b))
    got = solve3(A, b)
    assert (seen == [1]) is to_lapack
    assert np.max(np.abs(got - original(A, b[..., None])[..., 0])) <= 1e-12


def test_solve3_singular_system_raises_as_lapack():
    A = np.broadcast_to(np.eye(3), (MIN_BATCH, 3, 3)).copy()
    A[5] = 0.0
    with pytest.raises(np.linalg.LinAlgError):
        solve3(A, np.ones((MIN_BATCH, 3)), method="kernel")


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["random", "near_rotation", "reflection", "scaled_rotation"])
def test_rotation_violation_is_the_two_tests_in_one(kind, shape, rng):
    R = _matrices(kind, rng, shape)
    E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
    want = np.maximum(np.linalg.norm(E, axis=(-2, -1)), np.abs(np.linalg.det(R) - 1.0))
    got = rotation_violation(R)
    assert got.shape == R.shape[:-2]
    assert np.max(np.abs(got - want)) <= 1e-12 * np.maximum(1.0, np.max(want))


def test_rotation_violation_propagates_nan_and_inf(rng):
    R = random_rotations(rng, 4)
    R[1, 0, 2] = np.nan
    R[2, 1, 1] = np.inf
    v = rotation_violation(R)
    assert not v[1] <= 1.0 and not v[2] <= 1.0 and v[0] < 1e-12 and v[3] < 1e-12


@pytest.mark.parametrize("factor, ok", [(0.99, True), (1.01, False)])
def test_check_rotation_matrices_fast_pass_keeps_the_threshold(factor, ok, rng):
    R = random_rotations(rng, 50)
    eps = np.sqrt(1.0 + factor * 1e-6) - 1.0  # ||R^T R - I||_F = (1 + eps)^2 - 1 = factor * atol; det - 1 = eps
    R[7] = R[7] @ np.diag([1.0, 1.0, 1.0 + eps])
    if ok:
        assert check_rotation_matrices(R, "R") is not None
    else:
        with pytest.raises(ValueError, match=r"R is not a rotation matrix at index 7\b"):
            check_rotation_matrices(R, "R")


@pytest.mark.parametrize("bad, message", [
    (np.nan, "contains NaN or inf"),
    ("reflection", "a reflection"),
])
def test_check_rotation_matrices_messages_unchanged(bad, message, rng):
    R = random_rotations(rng, 10)
    if bad == "reflection":
        R[3] = -R[3]
    else:
        R[3, 0, 0] = bad
    with pytest.raises(ValueError, match=message):
        check_rotation_matrices(R, "R")


def _psd4(kind, rng, shape):
    n = shape if shape else ()
    Q = np.linalg.qr(rng.normal(size=n + (4, 4)))[0]
    ev = {"handeye_noise_free": [0.0, 3.0, 7.0, 12.0], "handeye_noisy": [2e-3, 3.0, 7.0, 12.0],
          "random": None, "repeated_bottom": [1.0, 1.0, 5.0, 9.0], "slow_power_steps": [4.0, 6.0, 7.0, 12.0],
          "zero": [0.0, 0.0, 0.0, 0.0]}[kind]
    if ev is None:
        G = rng.normal(size=n + (4, 4))
        return G @ np.swapaxes(G, -1, -2)
    return Q @ (np.asarray(ev)[:, None] * np.swapaxes(Q, -1, -2))


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["handeye_noise_free", "handeye_noisy", "random", "repeated_bottom",
                                  "slow_power_steps", "zero"])
def test_bottom_eigenvector4_matches_lapack_up_to_sign(kind, shape, rng):
    S = _psd4(kind, rng, shape)
    got = bottom_eigenvector4(S, method="kernel")
    want = np.linalg.eigh(S)[1][..., :, 0]
    assert got.shape == S.shape[:-1]
    diff = np.minimum(np.max(np.abs(got - want), axis=-1), np.max(np.abs(got + want), axis=-1))
    assert np.max(diff) <= 1e-12


def test_horaud_dornaika_unchanged_by_the_kernel(rng):
    from replication.core.solvers import solve

    R0 = random_rotations(rng, ())
    A = random_rotations(rng, (MIN_BATCH_LARGE, 20))
    B = np.swapaxes(R0, -1, -2) @ A @ R0
    B = B @ random_rotations(rng, (MIN_BATCH_LARGE, 20), angle_range_deg=(0.0, 0.5))
    with lapack_reference():
        before = solve("horaud_dornaika", A, B)
    after = solve("horaud_dornaika", A, B)
    assert np.max(np.abs(after - before)) <= 1e-12
    assert not np.array_equal(after, before)  # the kernel answered


@pytest.mark.parametrize("factor, to_lapack", [(1.01, False), (0.99, True)])
def test_bottom_eigenvector4_falls_back_above_the_angle_bound_only(factor, to_lapack, rng, monkeypatch):
    S = _psd4("slow_power_steps", rng, (MIN_BATCH_LARGE,))
    e = np.ascontiguousarray(S.reshape(-1, 16).T)
    e /= np.sqrt(np.einsum("kn,kn->n", e, e))
    bound = kernels.bottom_eigenvector4_block(e)[1]
    assert np.all(bound > 1e-6)  # three power steps at lambda_1 / lambda_2 = 2/3 are far from converged
    monkeypatch.setattr(kernels, "EIG4_SAFE", factor * float(np.max(bound)))
    seen = []
    original = np.linalg.eigh
    monkeypatch.setattr(np.linalg, "eigh", lambda A: seen.append(len(A)) or original(A))
    bottom_eigenvector4(S)
    assert (sum(seen) >= 1) is to_lapack  # at 0.99 x the largest bound that matrix goes to LAPACK; at 1.01 x none


@pytest.mark.parametrize("shape", SHAPES)
def test_quaternion_from_rotation_vector_is_quaternion_from_matrix_without_the_rotation_vector_from_matrix(shape, rng):
    from replication.core.so3 import (
        quaternion_from_matrix,
        quaternion_from_rotation_vector,
        rotation_vector_from_matrix,
    )

    R = random_rotations(rng, shape)
    assert np.array_equal(quaternion_from_rotation_vector(rotation_vector_from_matrix(R)), quaternion_from_matrix(R))
    q = quaternion_from_rotation_vector(np.array([0.0, 0.0, np.pi / 2]))
    assert np.allclose(q, [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)], atol=1e-15)


def test_cofactors_are_the_explicit_formula_to_the_last_bit(rng):
    """Seven passes over (9, n) instead of 27 over (n,): the same products and differences in the
    same order."""
    x = rng.normal(size=(9, 1000))
    a, b, c, d, e, f, g, h, i = x
    want = np.stack([e * i - f * h, f * g - d * i, d * h - e * g, c * h - b * i, a * i - c * g, b * g - a * h,
                     b * f - c * e, c * d - a * f, a * e - b * d])
    C, det = kernels.cofactors(x)
    assert np.array_equal(C, want)
    assert np.array_equal(det, a * want[0] + b * want[1] + c * want[2])
    C3, det3 = kernels.cofactors(x, rows=3)
    assert np.array_equal(C3, want[:3]) and np.array_equal(det3, det)


def _gram3(kind, rng, n):
    if kind == "rotation_vectors":  # the axis-spread Gram matrices sum_j w_j w_j^T
        w = rng.normal(size=n + (20, 3)) * np.array([1.0, 0.3, 0.1])
        return np.swapaxes(w, -1, -2) @ w
    if kind == "rank_one":  # motions about one axis
        w = rng.normal(size=n + (3, 1))
        return w @ np.swapaxes(w, -1, -2)
    if kind == "repeated_top":  # no unique dominant axis: LAPACK's answer
        Q = random_rotations(rng, n)
        return Q @ (np.array([0.2, 1.0, 1.0])[:, None] * np.swapaxes(Q, -1, -2))
    if kind == "zero":
        return np.zeros(n + (3, 3))
    raise AssertionError(kind)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("kind", ["rotation_vectors", "rank_one", "repeated_top", "zero"])
def test_top_eigenvector3_matches_lapack_up_to_sign(kind, shape, rng):
    S = _gram3(kind, rng, shape if shape else ())
    got = top_eigenvector3(S, method="kernel")
    want = np.linalg.eigh(S)[1][..., :, -1]
    assert got.shape == S.shape[:-1]
    diff = np.minimum(np.max(np.abs(got - want), axis=-1), np.max(np.abs(got + want), axis=-1))
    assert np.max(diff) <= 1e-12
    assert np.allclose(np.linalg.norm(got, axis=-1), 1.0, atol=1e-14)


@pytest.mark.parametrize("factor, to_lapack", [(1.01, False), (0.99, True)])
def test_top_eigenvector3_falls_back_below_its_gap_bound_only(factor, to_lapack, rng, monkeypatch):
    Q = random_rotations(rng, ())
    gap = factor * TOP3_SAFE  # (lambda_3 - lambda_2) / lambda_3
    close = Q @ (np.array([0.1, 1.0 - gap, 1.0])[:, None] * Q.T)
    S = np.concatenate([_gram3("rotation_vectors", rng, (MIN_BATCH,)), close[None]])
    seen = []
    original = np.linalg.eigh
    monkeypatch.setattr(np.linalg, "eigh", lambda A: seen.append(len(A)) or original(A))
    got = top_eigenvector3(S)
    assert (seen == [1]) is to_lapack
    want = original(S)[1][..., :, -1]
    assert np.max(np.minimum(np.abs(got - want).max(-1), np.abs(got + want).max(-1))) <= 1e-12


@pytest.mark.parametrize("mode", MODES)
def test_polar_factor_one_block_path_is_the_gathered_path_to_the_last_bit(mode, rng):
    """A batch whose matrices are all safe skips the gather and scatter; one unsafe matrix more (to
    LAPACK) sends the same matrices through the gathered path: the Newton iterates are the same to
    the last bit."""
    X = _matrices("scaled_unit_vector", rng, (MIN_BATCH,))
    alone = polar_factor(X, mode)
    with_singular = polar_factor(np.concatenate([X, np.zeros((1, 3, 3))]), mode)
    assert np.array_equal(alone, with_singular[:-1])
