"""Rotation-matrix helpers: validation, projection onto SO(3), noise, sampling, error metrics.

Conventions used throughout the package
---------------------------------------
* Rotations are 3x3 matrices acting on column vectors, batched over leading
  dimensions: an array of shape ``(..., 3, 3)``.
* ``camera_from_sensor`` is the paper's ``R0``: it maps vectors given in the
  inertial/magnetic sensor frame into the camera frame (eq. (1): ``C_t = R0 I_t``).
* Angles are in degrees in every public name that ends in ``_deg``; otherwise radians.
* Randomness only through an explicit :class:`numpy.random.Generator`.

Reference: Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment
Calibration"; equation numbers below are the paper's.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = [
    "check_matrices",
    "check_rotation_matrices",
    "check_init",
    "skew",
    "nearest_rotation",
    "det3",
    "noise_rotations",
    "sample_ball",
    "random_rotations",
    "frobenius_error",
    "angle_between_deg",
    "chordal_to_angle_deg",
    "nearest_rotation_up_to_sign",
    "rotation_angle_deg",
    "orthonormality_residual",
    "log_map",
    "exp_map",
    "as_quaternion",
    "quaternion_to_matrix",
    "cumulative_product",
]

#: Default tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` for accepting a rotation.
ROTATION_ATOL = 1e-6


def _first_index(mask: np.ndarray) -> tuple:
    """Index (over the leading dimensions) of the first True entry of ``mask`` (``()`` for a scalar)."""
    mask = np.asarray(mask)
    return tuple(int(i) for i in np.argwhere(mask)[0]) if mask.ndim else ()


def det3(M) -> np.ndarray:
    """Determinants of 3x3 matrices, batched: (..., 3, 3) -> (...), as the triple product of the rows.

    Elementwise (no LAPACK call per matrix), so much faster than ``numpy.linalg.det`` on large
    batches of 3x3 matrices; same value to rounding.
    """
    M = np.asarray(M, dtype=float)
    a, b, c = M[..., 0, :], M[..., 1, :], M[..., 2, :]
    return (a[..., 0] * (b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1])
            - a[..., 1] * (b[..., 0] * c[..., 2] - b[..., 2] * c[..., 0])
            + a[..., 2] * (b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]))


def check_matrices(M, name: str = "M") -> np.ndarray:
    """Validate a batch of 3x3 matrices and return it as a float array.

    Parameters
    ----------
    M : array_like, shape (..., 3, 3)
        Matrices to check.
    name : str
        Name used in error messages.

    Returns
    -------
    numpy.ndarray of float64, shape (..., 3, 3)

    Raises
    ------
    ValueError
        If ``M`` is not real-valued numeric, does not end in ``(3, 3)``, or holds NaN/inf.
    """
    if np.iscomplexobj(M):
        raise ValueError(f"{name} must be real-valued; got a complex array")
    try:
        M = np.asarray(M, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array of 3x3 matrices: {exc}") from None
    if M.ndim < 2 or M.shape[-2:] != (3, 3):
        raise ValueError(f"{name} must have shape (..., 3, 3), got {M.shape}")
    finite = np.isfinite(M).all(axis=(-2, -1))
    if not finite.all():
        raise ValueError(f"{name} contains NaN or inf (first at index {_first_index(~finite)})")
    return M


def check_rotation_matrices(R, name: str = "R", atol: float = ROTATION_ATOL) -> np.ndarray:
    """Validate that every 3x3 block of ``R`` is a proper rotation (in SO(3)).

    A block ``R`` is accepted when ``||R^T R - I||_F <= atol`` and
    ``|det(R) - 1| <= atol`` (eqs. (9)-(10) of the paper as a test).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    name : str
        Name used in error messages.
    atol : float
        Tolerance of the orthonormality and determinant tests.

    Returns
    -------
    numpy.ndarray of float64, shape (..., 3, 3)

    Raises
    ------
    ValueError
        Naming the first offending index: wrong shape, NaN/inf, not orthonormal,
        or a reflection (det = -1).
    """
    R = check_matrices(R, name)
    E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
    ortho = np.sqrt(np.einsum("...ab,...ab->...", E, E))  # ||R^T R - I||_F
    bad = ortho > atol
    if bad.any():
        idx = _first_index(bad)
        raise ValueError(
            f"{name} is not a rotation matrix at index {idx}: "
            f"||R^T R - I||_F = {ortho[idx]:.3g} > {atol:g} ({int(bad.sum())} bad of {bad.size})"
        )
    det = det3(R)
    bad = np.abs(det - 1.0) > atol
    if bad.any():
        idx = _first_index(bad)
        raise ValueError(
            f"{name} is not a rotation matrix at index {idx}: det = {det[idx]:.6g} "
            f"(a reflection; a rotation has det = +1)"
        )
    return R


def check_init(init, batch_shape: tuple, name: str = "init") -> np.ndarray:
    """A start rotation for a batch of problems: ``None`` means the identity; broadcast to ``batch_shape``.

    Raises
    ------
    ValueError
        ``init`` is not a rotation, or does not broadcast to ``batch_shape + (3, 3)``.
    """
    if init is None:
        return np.broadcast_to(np.eye(3), tuple(batch_shape) + (3, 3))
    init = check_rotation_matrices(init, name)
    try:
        return np.broadcast_to(init, tuple(batch_shape) + (3, 3))
    except ValueError:
        raise ValueError(
            f"{name} must have shape (3, 3) or broadcast to the batch shape {tuple(batch_shape) + (3, 3)}, "
            f"got {init.shape}"
        ) from None


def skew(v) -> np.ndarray:
    """Skew-symmetric matrix ``[v x]`` with ``[v x] w = v x w``.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        ``[[0, -v3, v2], [v3, 0, -v1], [-v2, v1, 0]]``.
    """
    v = np.asarray(v, dtype=float)
    if v.shape[-1:] != (3,):
        raise ValueError(f"v must have shape (..., 3), got {v.shape}")
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def nearest_rotation(M, *, enforce_det: bool = True) -> np.ndarray:
    """Project 3x3 matrices onto the rotation group by SVD (eqs. (16)-(17)).

    With ``M = U Sigma A^T`` (eq. (16)) the paper takes ``U A^T`` (eq. (17)), the
    nearest *orthogonal* matrix in Frobenius norm. ``U A^T`` has ``det = -1``
    whenever ``det M < 0``; the nearest *rotation* is then
    ``U diag(1, 1, -1) A^T`` (flip the direction of the smallest singular value),
    which is what ``enforce_det=True`` returns.

    Parameters
    ----------
    M : array_like, shape (..., 3, 3)
        Matrices to project; must be finite.
    enforce_det : bool, default True
        ``True``: nearest matrix in SO(3). ``False``: paper-literal eq. (17),
        nearest matrix in O(3), which may be a reflection.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    M = check_matrices(M, "M")
    U, _, At = np.linalg.svd(M)  # eq. (16): M = U Sigma A^T
    if enforce_det:
        d = np.where(det3(U @ At) < 0, -1.0, 1.0)
        U = U.copy()
        U[..., :, 2] *= d[..., None]
    return U @ At  # eq. (17)


def nearest_rotation_up_to_sign(M) -> np.ndarray:
    """The rotation nearest to ``M`` or to ``-M``: ``nearest_rotation(sign(det M) M)``, batched.

    For a matrix known only up to sign (an eigen- or singular vector reshaped to
    3x3), ``-M`` is the right candidate when ``det M < 0``: projecting ``M``
    itself with the det fix would flip only its weakest direction instead.

    With ``M = U Sigma A^T`` and ``det M != 0``, ``sign(det M) = det(U A^T)`` and the
    result is ``det(U A^T) U A^T``: one SVD, no determinant of ``M`` itself. A singular
    ``M`` (``det M = 0``) is projected as ``nearest_rotation(M)``.
    """
    M = check_matrices(M, "M")
    U, s, At = np.linalg.svd(M)  # eq. (16)
    P = U @ At  # eq. (17)
    d = np.where(det3(P) < 0, -1.0, 1.0)
    singular = s[..., 2] == 0
    if singular.any():  # sign(det M) = +1: flip the weakest direction instead (as nearest_rotation)
        U = U.copy()
        U[..., :, 2] *= np.where(singular, d, 1.0)[..., None]
        P = U @ At
        d = np.where(singular, 1.0, d)
    return P * d[..., None, None]


def noise_rotations(v) -> np.ndarray:
    """The paper's small-rotation error model (Sec. III-A).

    ``deltaR = nearest_rotation([v x] + U)`` with ``U`` the identity. The result is
    the rotation about ``v / ||v||`` by ``arctan(||v||)`` (not ``||v||``): the
    paper's bound ``||v|| < 0.02`` therefore gives angles below 1.146 deg, not
    below 1 deg as the paper states.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
    """
    return nearest_rotation(skew(v) + np.eye(3))


def sample_ball(rng: np.random.Generator, shape, radius: float, distribution: str = "uniform"):
    """Random 3-vectors with ``||v|| <= radius``.

    Parameters
    ----------
    rng : numpy.random.Generator
    shape : tuple of int
        Leading shape; the result has shape ``shape + (3,)``.
    radius : float
        Bound on the norm.
    distribution : {"uniform", "uniform_norm", "sphere", "cube"}
        ``"uniform"``: uniform in the ball's volume (norms concentrate near the
        bound); ``"uniform_norm"``: uniform direction, norm uniform in
        ``[0, radius]``; ``"sphere"``: uniform direction, norm exactly ``radius``;
        ``"cube"``: each component uniform in ``[-radius/sqrt(3), radius/sqrt(3)]``
        (the cube inscribed in the ball).

    Returns
    -------
    numpy.ndarray, shape ``shape + (3,)``
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if not np.isfinite(radius) or radius < 0:
        raise ValueError(f"radius must be finite and >= 0, got {radius}")
    shape = tuple(np.atleast_1d(shape).astype(int)) if np.ndim(shape) else (int(shape),)
    if distribution == "cube":
        return rng.uniform(-1.0, 1.0, shape + (3,)) * radius / np.sqrt(3.0)
    direction = rng.normal(size=shape + (3,))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    if distribution == "uniform":
        norm = radius * rng.uniform(size=shape) ** (1.0 / 3.0)
    elif distribution == "uniform_norm":
        norm = radius * rng.uniform(size=shape)
    elif distribution == "sphere":
        norm = np.full(shape, float(radius))
    else:
        raise ValueError(
            f"unknown distribution {distribution!r}; choose from "
            "'uniform', 'uniform_norm', 'sphere', 'cube'"
        )
    return direction * norm[..., None]


def random_rotations(
    rng: np.random.Generator, shape, *, angle_range_deg=None
) -> np.ndarray:
    """Random rotation matrices.

    Parameters
    ----------
    rng : numpy.random.Generator
    shape : int or tuple of int
        Leading shape; the result has shape ``shape + (3, 3)``.
    angle_range_deg : None or (float, float)
        ``None``: uniform (Haar) on SO(3). ``(lo, hi)``: axis uniform on the
        sphere and rotation angle uniform in ``[lo, hi]`` degrees
        (``0 <= lo <= hi <= 180``).

    Returns
    -------
    numpy.ndarray, shape ``shape + (3, 3)``
    """
    if not isinstance(rng, np.random.Generator):
        raise ValueError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    shape = (int(shape),) if np.ndim(shape) == 0 else tuple(int(s) for s in shape)
    n = int(np.prod(shape))
    if angle_range_deg is None:
        mats = Rotation.random(n, rng=rng).as_matrix() if n else np.empty((0, 3, 3))
        return mats.reshape(shape + (3, 3))
    lo, hi = (float(a) for a in angle_range_deg)
    if not (0.0 <= lo <= hi <= 180.0):
        raise ValueError(f"angle_range_deg must satisfy 0 <= lo <= hi <= 180, got {angle_range_deg}")
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.radians(rng.uniform(lo, hi, size=n))
    mats = Rotation.from_rotvec(axis * angle[:, None]).as_matrix() if n else np.empty((0, 3, 3))
    return mats.reshape(shape + (3, 3))


def frobenius_error(R_est, R_true) -> np.ndarray:
    """The paper's error metric ``||R_est - R_true||_F`` (Fig. 3, Table I), batched.

    For two rotations it equals ``2 sqrt(2) |sin(theta / 2)|`` with ``theta`` the
    angle of ``R_true^T R_est``; its maximum is ``2 sqrt(2) = 2.83``. Values
    above that mean ``R_est`` is not a rotation (e.g. an infeasible SQP iterate).
    """
    R_est = check_matrices(R_est, "R_est")
    R_true = check_matrices(R_true, "R_true")
    return np.linalg.norm(R_est - R_true, axis=(-2, -1))


def orthonormality_residual(M) -> np.ndarray:
    """``||M^T M - I||_F`` of each 3x3 matrix (0 for a rotation or a reflection); shape (...)."""
    M = np.asarray(M, dtype=float)
    return np.linalg.norm(np.swapaxes(M, -1, -2) @ M - np.eye(3), axis=(-2, -1))


def rotation_angle_deg(R) -> np.ndarray:
    """Rotation angle in degrees, in ``[0, 180]``, accurate for tiny angles.

    Computed by SciPy through the quaternion (``2 atan2(|q_v|, |q_w|)``), not
    ``arccos((tr R - 1) / 2)``, which loses half the digits near 0.
    """
    R = check_matrices(R, "R")
    flat = R.reshape(-1, 3, 3)
    ang = Rotation.from_matrix(flat).magnitude() if len(flat) else np.empty(0)
    return np.degrees(ang).reshape(R.shape[:-2])


def chordal_to_angle_deg(distance) -> np.ndarray:
    """Rotation angle in degrees from a chordal distance: ``2 arcsin(min(1, d / (2 sqrt 2)))``.

    Inverts ``||R1 - R2||_F = 2 sqrt(2) sin(theta / 2)`` (see :func:`frobenius_error`);
    distances above ``2 sqrt 2`` (only possible for non-rotations) map to 180 deg.
    """
    d = np.asarray(distance, dtype=float)
    return np.degrees(2.0 * np.arcsin(np.minimum(1.0, d / (2.0 * np.sqrt(2.0)))))


def angle_between_deg(R_est, R_true) -> np.ndarray:
    """Geodesic distance ``angle(R_true^T R_est)`` in degrees, batched and broadcast."""
    R_est = check_matrices(R_est, "R_est")
    R_true = check_matrices(R_true, "R_true")
    return rotation_angle_deg(np.swapaxes(R_true, -1, -2) @ R_est)


def _batched(func, X, tail_in, tail_out):
    """Apply a SciPy ``Rotation`` conversion to an array batched over leading dimensions."""
    lead = X.shape[: X.ndim - len(tail_in)]
    flat = X.reshape((-1,) + tail_in)
    out = func(flat) if len(flat) else np.empty((0,) + tail_out)
    return out.reshape(lead + tail_out)


def log_map(R) -> np.ndarray:
    """Rotation vectors ``w`` (radians, ``|w| <= pi``) with ``R = exp([w]x)``, batched.

    Elementwise NumPy (no per-matrix call): ``theta = atan2(|v|, (tr R - 1) / 2)`` with
    ``v = vee(R - R^T) / 2 = sin(theta) n``; beyond 120 deg the axis comes from the
    symmetric part ``(R + R^T) / 2 - cos(theta) I = (1 - cos(theta)) n n^T`` (its sign from
    ``v``), which stays accurate up to a half-turn. Agrees with SciPy's
    ``Rotation.as_rotvec`` to about 1e-15 (at exactly 180 deg up to the sign of ``w``).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (not validated; callers validate).

    Returns
    -------
    numpy.ndarray, shape (..., 3)
    """
    R = np.asarray(R, dtype=float)
    v = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    c = np.clip(0.5 * (R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1.0), -1.0, 1.0)
    s = np.sqrt(np.einsum("...i,...i->...", v, v))
    theta = np.arctan2(s, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(s > 1e-8, theta / s, 1.0 + s * s / 6.0)  # theta / sin(theta)
    w = v * ratio[..., None]
    far = c < -0.5
    if far.any():
        S = 0.5 * (R[far] + np.swapaxes(R[far], -1, -2)) - c[far][:, None, None] * np.eye(3)
        k = np.argmax(np.einsum("nii->ni", S), axis=-1)  # the best-conditioned column of n n^T
        n = np.take_along_axis(S, k[:, None, None], axis=-1)[..., 0]
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        sign = np.where(np.einsum("ni,ni->n", n, v[far]) < 0, -1.0, 1.0)
        w[far] = n * (sign * theta[far])[:, None]
    return w


def exp_map(w) -> np.ndarray:
    """Rotation matrices ``exp([w]x)`` from rotation vectors (radians), batched: (..., 3) -> (..., 3, 3).

    Rodrigues' formula ``I + sin(t)/t [w]x + (1 - cos(t))/t^2 [w]x^2`` (``t = |w|``), elementwise,
    with Taylor terms for ``t < 1e-4``.
    """
    w = np.asarray(w, dtype=float)
    if w.shape[-1:] != (3,):
        raise ValueError(f"w must have shape (..., 3), got {w.shape}")
    t2 = np.einsum("...i,...i->...", w, w)
    t = np.sqrt(t2)
    small = t < 1e-4
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / t)
        b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(t)) / t2)
    W = skew(w)
    return np.eye(3) + a[..., None, None] * W + b[..., None, None] * (W @ W)


def as_quaternion(R) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)``, scalar first, with ``w >= 0``, batched: (..., 3, 3) -> (..., 4).

    ``R`` rotates by ``theta`` about the unit axis ``n`` and
    ``q = (cos(theta/2), sin(theta/2) n)``, from :func:`log_map` (elementwise). ``w >= 0``
    because ``theta <= 180`` deg; the sign is ambiguous only at ``theta = 180`` deg.
    """
    w = log_map(R)
    theta = np.sqrt(np.einsum("...i,...i->...", w, w))
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(theta > 1e-6, np.sin(0.5 * theta) / theta, 0.5 - theta * theta / 48.0)  # sin(t/2)/t
    return np.concatenate([np.cos(0.5 * theta)[..., None], k[..., None] * w], axis=-1)


def quaternion_to_matrix(q) -> np.ndarray:
    """Rotation matrices from quaternions ``(w, x, y, z)``, scalar first (normalised first), batched."""
    q = np.asarray(q, dtype=float)
    return _batched(lambda v: Rotation.from_quat(v, scalar_first=True).as_matrix(), q, (4,), (3, 3))


def cumulative_product(R) -> np.ndarray:
    """Running products ``P_k = R_0 R_1 ... R_k`` along axis -3, batched: (..., N, 3, 3) -> (..., N, 3, 3).

    A log-depth prefix scan (Hillis & Steele): ``ceil(log2 N)`` batched matrix
    products instead of a Python loop over ``N``. Each ``P_k`` is the product of
    ``O(log N)`` partial products, so rounding grows like ``log N``, not ``N``.
    """
    P = np.array(check_matrices(R, "R"), dtype=float)
    n = P.shape[-3]
    shift = 1
    while shift < n:
        P[..., shift:, :, :] = P[..., :-shift, :, :] @ P[..., shift:, :, :]
        shift *= 2
    return P
