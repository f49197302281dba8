"""Batched small-matrix kernels: elementwise NumPy over the batch instead of one LAPACK call per 3x3
matrix. Theory and measured numbers: ``docs/methods.md``, section ``replication.core.kernels``."""
from __future__ import annotations

import contextlib

import numpy as np

__all__ = ["POLAR_SAFE", "EIG3_SAFE", "SOLVE3_SAFE", "EIG4_SAFE", "TOP3_SAFE", "MIN_BATCH", "MIN_BATCH_LARGE",
           "polar_factor", "eigvalsh3", "top_eigenvector3", "solve3", "bottom_eigenvector4", "rotation_violation",
           "lapack_reference", "cofactors", "bottom_eigenvector4_block"]

#: Lower bound on ``sigma_min / sigma_max`` (``>= 2 |det M| / ||M||_F^3``) below which
#: :func:`polar_factor` hands a matrix to LAPACK: the polar factor's condition number is ``sigma_max
#: / (sigma_2 + sigma_3)``, so at the bound the Newton iterate and LAPACK's SVD still agree to about
#: 1e-13, and rank-deficient matrices (whose nearest orthogonal matrix is not unique) never enter
#: the iteration.
POLAR_SAFE = 1e-3
#: ``1 - |r|`` (``r`` the normalised determinant of the trigonometric solution) below which
#: :func:`eigvalsh3` hands a matrix to LAPACK: two eigenvalues are then within a few thousandths of
#: the spread, where ``arccos`` loses digits.
EIG3_SAFE = 1e-4
#: ``|det A| / ||A||_F^3`` below which :func:`solve3` hands a system to LAPACK (condition number
#: above about 1e3).
SOLVE3_SAFE = 1e-3
#: Bound on ``sin`` of the angle between :func:`bottom_eigenvector4`'s answer and the eigenvector
#: (its residual over the gap to the other eigenvalues) above which the matrix goes to LAPACK: about
#: a gap below 0.4 % of ``||S||``.
EIG4_SAFE = 1e-13
#: Batches of fewer matrices go to LAPACK whole in :func:`polar_factor` and :func:`eigvalsh3`: below
#: it the kernels' fixed Python cost exceeds LAPACK's per-matrix cost (crossover measured at 32-64
#: matrices on the loaded 2-core EPYC).
MIN_BATCH = 64
#: The same for :func:`solve3` and :func:`bottom_eigenvector4`, whose LAPACK calls cost less per
#: matrix (crossover measured at 256-512 systems for ``solve``; 4x4 ``eigh`` wins at every size
#: unless ``lambda_1 << lambda_2``).
MIN_BATCH_LARGE = 256
#: Newton iterations of :func:`polar_factor` at most; converged entries stop changing, the rest go
#: to LAPACK.
_POLAR_MAX_ITERATIONS = 16
#: A Newton step below this (Frobenius) ends the iteration: the next one would change the factor by
#: about its square.
_POLAR_LAST_STEP = 1e-9

#: Matrices per block of the iterative kernel: small enough that its temporaries stay in cache.
_CHUNK = 8192

_FORCE_LAPACK = [False]


@contextlib.contextmanager
def lapack_reference():
    """Inside this block every kernel takes the LAPACK path (the behaviour before the kernels; for
    benchmarks)."""
    previous = _FORCE_LAPACK[0]
    _FORCE_LAPACK[0] = True
    try:
        yield
    finally:
        _FORCE_LAPACK[0] = previous


def _use_kernel(n: int, method: str, minimum: int = MIN_BATCH) -> bool:
    if method not in ("auto", "kernel", "lapack"):
        raise ValueError(f"method must be 'auto', 'kernel' or 'lapack', got {method!r}")
    if method == "auto":
        return not _FORCE_LAPACK[0] and n >= minimum
    return method == "kernel"


def _entries(M: np.ndarray) -> np.ndarray:
    """(..., 3, 3) -> (9, n): row-major entries as nine contiguous arrays over the flattened
    batch."""
    return np.ascontiguousarray(M.reshape(-1, 9).T)


#: Row-major cofactor ``k`` of a 3x3 matrix is ``x[_P1[k]] x[_P2[k]] - x[_P3[k]] x[_P4[k]]`` (its
#: entries ``x``).
_P1, _P2 = np.array([4, 5, 3, 2, 0, 1, 1, 2, 0]), np.array([8, 6, 7, 7, 8, 6, 5, 3, 4])
_P3, _P4 = np.array([5, 3, 4, 1, 2, 0, 2, 0, 1]), np.array([7, 8, 6, 8, 6, 7, 4, 5, 3])


def cofactors(x, rows: int = 9):
    """Cofactor matrix (9, n) and determinant (n) of the matrices whose row-major entries are ``x``
    (9, n).

    Parameters
    ----------
    x : (9, n) ndarray
        Row-major entries of n 3x3 matrices.
    rows : int
        9 for every cofactor, 3 for the first three only (enough for the determinant).

    Returns
    -------
    C : (rows, n) ndarray
        Row-major cofactors.
    det : (n,) ndarray
        Determinants.

    Notes
    -----
    Nine cofactors in seven NumPy passes over (9, n) (four gathers, two products, a difference)
    rather than 27 over (n,) and a stack; each entry is still ``p q - r s`` in that order, and the
    determinant ``(a C_0 + b C_1) + c C_2``, so the result is the same to the last bit.
    """
    C = x[_P1[:rows]] * x[_P2[:rows]]
    C -= x[_P3[:rows]] * x[_P4[:rows]]
    t = x[:3] * C[:3]
    return C, t[0] + t[1] + t[2]


def _lapack_polar(M: np.ndarray, mode: str) -> np.ndarray:
    """Today's SVD path of :func:`replication.core.so3.nearest_rotation` /
    ``nearest_rotation_up_to_sign``."""
    U, s, At = np.linalg.svd(M)  # eq. (16): M = U Sigma A^T
    P = U @ At  # eq. (17)
    if mode == "orthogonal":
        return P
    d = np.where(_det(P) < 0, -1.0, 1.0)
    if mode == "rotation":
        U = U.copy()
        U[..., :, 2] *= d[..., None]
        return U @ At
    singular = s[..., 2] == 0
    if singular.any():  # sign(det M) = +1: flip the weakest direction instead (as nearest_rotation)
        U = U.copy()
        U[..., :, 2] *= np.where(singular, d, 1.0)[..., None]
        P = U @ At
        d = np.where(singular, 1.0, d)
    return P * d[..., None, None]


def _det(M):
    a, b, c = M[..., 0, :], M[..., 1, :], M[..., 2, :]
    return (a[..., 0] * (b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1])
            - a[..., 1] * (b[..., 0] * c[..., 2] - b[..., 2] * c[..., 0])
            + a[..., 2] * (b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]))


def polar_factor(M, mode: str = "rotation", *, method: str = "auto") -> np.ndarray:
    """The nearest orthogonal matrix or rotation to each 3x3 matrix (eqs. (16)-(17)), batched.

    Parameters
    ----------
    M : ndarray, shape (..., 3, 3)
        Finite matrices (callers validate).
    mode : {"rotation", "orthogonal", "up_to_sign"}
        ``"orthogonal"``: ``U A^T`` of the SVD ``M = U Sigma A^T`` (eq. (17), det ``sign(det M)``);
        ``"rotation"``: ``U diag(1, 1, det(U A^T)) A^T``, the nearest rotation;
        ``"up_to_sign"``: ``sign(det M) U A^T``, the rotation nearest to ``M`` or ``-M``
        (see :func:`replication.core.so3.nearest_rotation_up_to_sign`).
    method : {"auto", "kernel", "lapack"}
        ``"auto"``: the Newton kernel for batches of at least :data:`MIN_BATCH` matrices;
        ``"kernel"``: always; ``"lapack"``: one SVD per matrix.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        The same as the SVD path to about 1e-13. Matrices with ``2 |det M| / ||M||_F^3 <=
        POLAR_SAFE`` (near rank deficiency), reflections in mode ``"rotation"`` and any entry the
        iteration did not settle are computed by SVD.
    """
    if mode not in ("rotation", "orthogonal", "up_to_sign"):
        raise ValueError(f"mode must be 'rotation', 'orthogonal' or 'up_to_sign', got {mode!r}")
    M = np.asarray(M, dtype=float)
    n = M.size // 9
    if not _use_kernel(n, method):
        return _lapack_polar(M, mode)
    x = _entries(M)
    _, det = cofactors(x, rows=3)
    norm2 = np.einsum("kn,kn->n", x, x)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        safe = 2.0 * np.abs(det) > POLAR_SAFE * norm2 * np.sqrt(norm2)
    if mode == "rotation":
        safe &= det > 0
    if n <= _CHUNK and safe.all():  # one block, every matrix in it: no gather and scatter (the same arithmetic)
        out, safe = _newton_polar(x, det)
        if mode == "up_to_sign":
            out *= np.where(det < 0, -1.0, 1.0)
        safe_idx = ()
    else:
        out = np.empty_like(x)
        safe_idx = np.flatnonzero(safe)
    for start in range(0, len(safe_idx), _CHUNK):  # blocks that stay in cache (no page faults per temporary)
        idx = safe_idx[start:start + _CHUNK]
        Q, settled = _newton_polar(x[:, idx], det[idx])
        if mode == "up_to_sign":
            Q *= np.where(det[idx] < 0, -1.0, 1.0)
        out[:, idx] = Q
        safe[idx[~settled]] = False
    rest = np.flatnonzero(~safe)
    if rest.size:
        out[:, rest] = _lapack_polar(x[:, rest].T.reshape(-1, 3, 3), mode).reshape(-1, 9).T
    return out.T.reshape(M.shape)


def _newton_polar(x: np.ndarray, det: np.ndarray):
    """Scaled Newton iteration for the orthogonal polar factor of nonsingular matrices ``x`` (9, n).

    Returns the factor (9, n) and the mask of entries that settled. Determinant scaling ``zeta =
    |det X|^{-1/3}`` while the step is large, then the plain iteration, whose error after a step of
    size ``delta`` is about ``delta^2 / 2``: a step below :data:`_POLAR_LAST_STEP` leaves rounding
    only.
    """
    X = x * (np.abs(det) ** (-1.0 / 3.0))  # |det| = 1: the first scaling
    step = np.full(X.shape[1], np.inf)
    scaled = True
    for _ in range(_POLAR_MAX_ITERATIONS):
        C, d = cofactors(X)
        if scaled:  # X <- (zeta X + C / (zeta d)) / 2, C / d = X^{-T}
            zeta = np.abs(d) ** (-1.0 / 3.0)
            alpha, beta = 0.5 * zeta, 0.5 / (zeta * d)
        else:
            alpha, beta = 0.5, 0.5 / d
        X_new = alpha * X
        X_new += beta * C
        diff = np.subtract(X_new, X, out=X)  # X is not needed again: its buffer takes the step
        step = np.sqrt(np.einsum("kn,kn->n", diff, diff))
        X = X_new
        worst = float(np.max(step))
        if worst < _POLAR_LAST_STEP:
            break
        scaled = scaled and worst > 1e-2
    return X, step < _POLAR_LAST_STEP


def eigvalsh3(S, *, method: str = "auto") -> np.ndarray:
    """Eigenvalues of symmetric 3x3 matrices in ascending order, batched: (..., 3, 3) -> (..., 3).

    The closed form of the characteristic cubic (``q = tr S / 3``, ``p = ||S - q I||_F / sqrt 6``,
    ``r = det((S - q I) / p) / 2``, eigenvalues ``q + 2 p cos(arccos(r) / 3 + 2 pi k / 3)``); only
    the lower triangle is read, as LAPACK's ``eigvalsh`` does. Matrices with two eigenvalues close
    together relative to their spread (``1 - |r| < EIG3_SAFE``) go to LAPACK, so the result agrees
    with ``numpy.linalg.eigvalsh`` to about 1e-13 times ``||S||``.

    Parameters
    ----------
    S : ndarray, shape (..., 3, 3)
    method : {"auto", "kernel", "lapack"}
        As in :func:`polar_factor`.
    """
    S = np.asarray(S, dtype=float)
    n = S.size // 9
    if not _use_kernel(n, method):
        return np.linalg.eigvalsh(S)
    x = _entries(S)
    s00, s10, s11, s20, s21, s22 = x[0], x[3], x[4], x[6], x[7], x[8]
    q = (s00 + s11 + s22) / 3.0
    b00, b11, b22 = s00 - q, s11 - q, s22 - q
    off = s10 * s10 + s20 * s20 + s21 * s21
    p = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        # det(S - q I) / (2 p^3), symmetric, from the lower triangle
        det = (b00 * (b11 * b22 - s21 * s21) - s10 * (s10 * b22 - s21 * s20) + s20 * (s10 * s21 - b11 * s20))
        r = det / (2.0 * p * p * p)
    safe = np.abs(r) < 1.0 - EIG3_SAFE  # False for NaN (p = 0: a multiple of I) as well
    phi = np.arccos(np.where(safe, r, 0.0)) / 3.0
    top = q + 2.0 * p * np.cos(phi)
    low = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    out = np.stack([low, 3.0 * q - top - low, top], axis=-1)
    rest = np.flatnonzero(~safe)
    if rest.size:
        out[rest] = np.linalg.eigvalsh(S.reshape(-1, 3, 3)[rest])
    return out.reshape(S.shape[:-1])


#: Relative gap ``(lambda_3 - lambda_2) / lambda_3`` below which :func:`top_eigenvector3` hands a
#: matrix to LAPACK: the cross-product eigenvector's error is about the eigenvalue's rounding over
#: the gap (below 1e-12 above it).
TOP3_SAFE = 1e-2


def top_eigenvector3(S, *, method: str = "auto") -> np.ndarray:
    """Unit eigenvectors of the largest eigenvalue of symmetric positive semidefinite 3x3 matrices,
    batched: (..., 3, 3) -> (..., 3), as ``numpy.linalg.eigh(S)[1][..., :, -1]`` up to sign.

    With ``lambda`` the largest eigenvalue (:func:`eigvalsh3`), the eigenvector is orthogonal to the
    rows of ``S - lambda I``: the longest of the three cross products of two rows, normalised.
    Matrices whose two largest eigenvalues are within :data:`TOP3_SAFE` of the largest (the
    direction then ill-determined), or with ``lambda <= 0``, go to LAPACK.

    Parameters
    ----------
    S : ndarray, shape (..., 3, 3)
    method : {"auto", "kernel", "lapack"}
        As in :func:`polar_factor`.
    """
    S = np.asarray(S, dtype=float)
    n = S.size // 9
    if not _use_kernel(n, method):
        return np.linalg.eigh(S)[1][..., :, -1]
    flat = S.reshape(-1, 3, 3)
    ev = eigvalsh3(flat, method=method)
    lam = ev[:, 2]
    x = _entries(flat)
    r = x.reshape(3, 3, -1).copy()  # rows of S - lambda I: r[i] (3, n)
    r[0, 0] -= lam
    r[1, 1] -= lam
    r[2, 2] -= lam
    c = np.stack([np.cross(r[0], r[1], axis=0), np.cross(r[0], r[2], axis=0), np.cross(r[1], r[2], axis=0)])
    norm2 = np.einsum("pkn,pkn->pn", c, c)
    best = np.argmax(norm2, axis=0)
    cols = np.arange(c.shape[-1])
    v = c[best, :, cols]  # (n, 3)
    size = np.sqrt(norm2[best, cols])
    with np.errstate(invalid="ignore", divide="ignore"):
        safe = (lam > 0) & (lam - ev[:, 1] > TOP3_SAFE * lam) & (size > 0)
        v = v / np.where(size > 0, size, 1.0)[:, None]
    rest = np.flatnonzero(~safe)
    if rest.size:
        v[rest] = np.linalg.eigh(flat[rest])[1][..., :, -1]
    return v.reshape(S.shape[:-1])


def solve3(A, b, *, method: str = "auto") -> np.ndarray:
    """Solutions ``x`` of ``A x = b`` for 3x3 systems, batched: (..., 3, 3), (..., 3) -> (..., 3).

    Cramer's rule through the cofactors; systems with ``|det A| / ||A||_F^3 <= SOLVE3_SAFE``
    (condition number above about 1e3) go to ``numpy.linalg.solve``, so the result agrees with it to
    about 1e-13 relative.
    """
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float)
    batch = np.broadcast_shapes(A.shape[:-2], b.shape[:-1])
    A = np.broadcast_to(A, batch + (3, 3))
    b = np.broadcast_to(b, batch + (3,))
    n = A.size // 9
    if not _use_kernel(n, method, MIN_BATCH_LARGE):
        return np.linalg.solve(A, b[..., None])[..., 0]
    x = _entries(A)
    rhs = np.ascontiguousarray(b.reshape(-1, 3).T)
    C, det = cofactors(x)
    norm2 = np.einsum("kn,kn->n", x, x)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        safe = np.abs(det) > SOLVE3_SAFE * norm2 * np.sqrt(norm2)
        # x = adj(A) b / det, adj(A) = C^T
        sol = np.stack([C[0] * rhs[0] + C[3] * rhs[1] + C[6] * rhs[2],
                        C[1] * rhs[0] + C[4] * rhs[1] + C[7] * rhs[2],
                        C[2] * rhs[0] + C[5] * rhs[1] + C[8] * rhs[2]], axis=-1) / det[:, None]
    rest = np.flatnonzero(~safe)
    if rest.size:
        sol[rest] = np.linalg.solve(A.reshape(-1, 3, 3)[rest], rhs[:, rest].T[..., None])[..., 0]
    return sol.reshape(batch + (3,))


def _adjugate4(e):
    """Adjugates of 4x4 matrices from their row-major entries ``e`` (16, n), as (16, n): by the 2x2
    minors of the top and the bottom row pairs (Laplace expansion)."""
    m00, m01, m02, m03, m10, m11, m12, m13, m20, m21, m22, m23, m30, m31, m32, m33 = e
    s0, s1, s2 = m00 * m11 - m10 * m01, m00 * m12 - m10 * m02, m00 * m13 - m10 * m03
    s3, s4, s5 = m01 * m12 - m11 * m02, m01 * m13 - m11 * m03, m02 * m13 - m12 * m03
    c5, c4, c3 = m22 * m33 - m32 * m23, m21 * m33 - m31 * m23, m21 * m32 - m31 * m22
    c2, c1, c0 = m20 * m33 - m30 * m23, m20 * m32 - m30 * m22, m20 * m31 - m30 * m21
    return np.stack([
        m11 * c5 - m12 * c4 + m13 * c3, m02 * c4 - m01 * c5 - m03 * c3,
        m31 * s5 - m32 * s4 + m33 * s3, m22 * s4 - m21 * s5 - m23 * s3,
        m12 * c2 - m10 * c5 - m13 * c1, m00 * c5 - m02 * c2 + m03 * c1,
        m32 * s2 - m30 * s5 - m33 * s1, m20 * s5 - m22 * s2 + m23 * s1,
        m10 * c4 - m11 * c2 + m13 * c0, m01 * c2 - m00 * c4 - m03 * c0,
        m30 * s4 - m31 * s2 + m33 * s0, m21 * s2 - m20 * s4 - m23 * s0,
        m11 * c1 - m10 * c3 - m12 * c0, m00 * c3 - m01 * c1 + m02 * c0,
        m31 * s1 - m30 * s3 - m32 * s0, m20 * s3 - m21 * s1 + m22 * s0])


def _matvec4(e, x):
    """``M x`` for matrices with row-major entries ``e`` (16, n) and vectors ``x`` (4, n)."""
    return np.stack([e[4 * i] * x[0] + e[4 * i + 1] * x[1] + e[4 * i + 2] * x[2] + e[4 * i + 3] * x[3]
                     for i in range(4)])


def bottom_eigenvector4_block(e):
    """:func:`bottom_eigenvector4`'s kernel on one block, with the bound on its error that decides
    the fallback to LAPACK (:data:`EIG4_SAFE`).

    Parameters
    ----------
    e : (16, n) ndarray
        Row-major entries of ``S / ||S||_F``, n symmetric 4x4 matrices.

    Returns
    -------
    x : (4, n) ndarray
        Unit vectors near each bottom eigenvector (three power steps on the adjugate).
    bound : (n,) ndarray
        ``||r|| / (mu - rho)``, a bound on ``sin`` of ``x``'s angle to the eigenvector, with ``rho =
        x^T S x``, ``r = S x - rho x`` and ``mu`` the least eigenvalue of ``S`` on the complement of
        ``x`` (inf where ``mu <= rho``).
    """
    adj = _adjugate4(e)
    k = np.argmax(adj[[0, 5, 10, 15]], axis=0)  # the largest diagonal entry's column
    x = adj.reshape(4, 4, -1)[:, k, np.arange(e.shape[1])]
    for _ in range(3):
        x = _matvec4(adj, x / np.sqrt(np.einsum("in,in->n", x, x)))
    x /= np.sqrt(np.einsum("in,in->n", x, x))
    Sx = _matvec4(e, x)
    rho = np.einsum("in,in->n", x, Sx)
    r = Sx - rho * x
    residual = np.sqrt(np.einsum("in,in->n", r, r))
    w, a, b, c = x  # the last three columns of the quaternion matrix L(x): a basis of the complement of x
    basis = np.stack([np.stack([-a, -b, -c]), np.stack([w, -c, b]), np.stack([c, w, -a]), np.stack([-b, a, w])])
    SB = np.stack([_matvec4(e, basis[:, col]) for col in range(3)], axis=1)  # (4, 3, n): S times each column
    compressed = np.einsum("ikn,iln->nkl", basis, SB)  # B^T S B, (n, 3, 3)
    mu = eigvalsh3(compressed)[..., 0]
    gap = mu - rho
    return x, np.where(gap > 0, residual / np.where(gap > 0, gap, 1.0), np.inf)


def bottom_eigenvector4(S, *, method: str = "auto") -> np.ndarray:
    """Unit eigenvectors of the smallest eigenvalue of symmetric positive semidefinite 4x4 matrices,
    batched: (..., 4, 4) -> (..., 4), as ``numpy.linalg.eigh(S)[1][..., :, 0]`` up to sign.

    ``adj(S) = sum_i (prod_{j != i} lambda_j) v_i v_i^T`` is dominated by ``v_1`` when ``lambda_1``
    is the smallest: start from its largest column, three power steps with ``adj(S)``, then a check:
    with the Rayleigh quotient ``rho``, the residual ``r = S x - rho x`` and ``mu`` the smallest
    eigenvalue of ``S`` on the complement of ``x`` (the other three eigenvalues, to second order in
    ``r``), ``||r|| / (mu - rho)`` bounds ``sin`` of the angle to the eigenvector. Where it exceeds
    :data:`EIG4_SAFE` (or ``mu <= rho``: ``x`` is not the bottom eigenvector; or ``lambda_1 /
    lambda_2`` is too large for three steps) the matrix goes to LAPACK.

    Parameters
    ----------
    S : ndarray, shape (..., 4, 4)
        Symmetric positive semidefinite matrices (only such; a matrix with a negative eigenvalue may
        go to LAPACK).
    method : {"auto", "kernel", "lapack"}
        As in :func:`polar_factor`.
    """
    S = np.asarray(S, dtype=float)
    n = S.size // 16
    if not _use_kernel(n, method, MIN_BATCH_LARGE):
        return np.linalg.eigh(S)[1][..., :, 0]
    flat = S.reshape(-1, 4, 4)
    e = np.ascontiguousarray(flat.reshape(-1, 16).T)
    scale = np.sqrt(np.einsum("kn,kn->n", e, e))
    empty = ~(scale > 0)  # a zero matrix: every vector is an eigenvector; LAPACK's answer, not the kernel's
    e[:, empty], scale[empty] = np.eye(4).reshape(16, 1), 1.0
    e /= scale
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.empty((4, e.shape[1]))
        bound = np.empty(e.shape[1])
        for start in range(0, e.shape[1], _CHUNK):
            block = slice(start, start + _CHUNK)
            out[:, block], bound[block] = bottom_eigenvector4_block(e[:, block])
        safe = (bound <= EIG4_SAFE) & ~empty
    out = out.T
    rest = np.flatnonzero(~safe)
    if rest.size:
        out[rest] = np.linalg.eigh(flat[rest])[1][..., :, 0]
    return out.reshape(S.shape[:-1])


def rotation_violation(R) -> np.ndarray:
    """``max(||R^T R - I||_F, |det R - 1|)`` of each 3x3 matrix in one pass, batched: (..., 3, 3) ->
    (...).

    NaN (or inf) wherever the matrix holds NaN or inf, so ``violation <= atol`` is the whole
    rotation test of :func:`~replication.core.checks.check_rotation_matrices`.
    """
    R = np.asarray(R, dtype=float)
    x = _entries(R)
    a, b, c, d, e, f, g, h, i = x
    with np.errstate(invalid="ignore", over="ignore"):
        # the six distinct entries of R^T R - I (columns' norms and dot products)
        e00 = a * a + d * d + g * g - 1.0
        e11 = b * b + e * e + h * h - 1.0
        e22 = c * c + f * f + i * i - 1.0
        e01 = a * b + d * e + g * h
        e02 = a * c + d * f + g * i
        e12 = b * c + e * f + h * i
        ortho = np.sqrt(e00 * e00 + e11 * e11 + e22 * e22 + 2.0 * (e01 * e01 + e02 * e02 + e12 * e12))
        det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
        worst = np.maximum(ortho, np.abs(det - 1.0))  # NaN propagates
    return worst.reshape(R.shape[:-2])
