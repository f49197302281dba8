"""Rotation-matrix helpers: validation, projection onto SO(3), noise, sampling, error metrics,
conversions.

Every conversion of the package (rotation vectors, quaternions, Euler angles, slerp) lives here,
named ``<to>_from_<from>`` (``quaternion_from_matrix``, ``matrix_from_quaternion``): the naming rule
of ``docs/conventions.md``. Conventions (frames in names, batching, degrees vs radians, the paper's
symbols): ``docs/conventions.md``.

Reference: Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment
Calibration"; equation numbers below are the paper's.
"""
from __future__ import annotations

import math

import numpy as np

from .._jitter import jitter
from .checks import check_matrices
from .kernels import polar_factor

__all__ = [
    "skew",
    "canonical_axis",
    "nearest_rotation",
    "noise_rotations",
    "sample_ball",
    "random_rotations",
    "frobenius_error",
    "angle_between_deg",
    "angle_deg_from_chordal",
    "nearest_rotation_up_to_sign",
    "rotation_angle_deg",
    "orthonormality_residual",
    # conversions, <to>_from_<from>
    "rotation_vector_from_matrix",
    "matrix_from_rotation_vector",
    "quaternion_from_matrix",
    "matrix_from_quaternion",
    "quaternion_from_rotation_vector",
    "yaw_pitch_roll_deg_from_matrix",
    "matrix_from_euler",
    "slerp",
    "slerp_interpolator",
    "cumulative_product",
]

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


def canonical_axis(v) -> np.ndarray:
    """An axis with the sign that makes its largest component positive: an eigenvector's sign is
    arbitrary (numpy's AVX-512 and AVX2 paths returned opposite ones), an axis named in a message or
    a report must not be.

    >>> canonical_axis([0.2, -0.9, 0.1]).tolist()
    [-0.2, 0.9, -0.1]
    """
    v = np.asarray(v, dtype=float)
    return v * math.copysign(1.0, v[int(np.argmax(np.abs(v)))])


def nearest_rotation(M, *, enforce_det: bool = True) -> np.ndarray:
    """Project 3x3 matrices onto the rotation group (eqs. (16)-(17)).

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
        Computed batched by :func:`replication.core.kernels.polar_factor` (Newton's iteration for
        the polar factor; the SVD for nearly singular matrices, reflections with ``enforce_det`` and
        small batches): the SVD path's answer to about 1e-13.
    """
    M = check_matrices(M, "M")
    # eqs. (16)-(17) as U A^T of the SVD M = U Sigma A^T, batched by replication.core.kernels (no
    # SVD per matrix)
    return polar_factor(M, "rotation" if enforce_det else "orthogonal")


def nearest_rotation_up_to_sign(M) -> np.ndarray:
    """The rotation nearest to ``M`` or to ``-M``: ``nearest_rotation(sign(det M) M)``, batched.

    For a matrix known only up to sign (an eigen- or singular vector reshaped to
    3x3), ``-M`` is the right candidate when ``det M < 0``: projecting ``M``
    itself with the det fix would flip only its weakest direction instead.

    With ``M = U Sigma A^T`` and ``det M != 0``, ``sign(det M) = det(U A^T)`` and the
    result is ``det(U A^T) U A^T``, the orthogonal polar factor times ``sign(det M)``
    (:func:`replication.core.kernels.polar_factor`). A singular ``M`` (``det M = 0``) is
    projected as ``nearest_rotation(M)``.
    """
    M = check_matrices(M, "M")
    return polar_factor(M, "up_to_sign")  # eqs. (16)-(17), batched (replication.core.kernels)


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
        mats = _scipy_rotation().random(n, rng=rng).as_matrix() if n else np.empty((0, 3, 3))
        return jitter(mats.reshape(shape + (3, 3)))
    lo, hi = (float(a) for a in angle_range_deg)
    if not (0.0 <= lo <= hi <= 180.0):
        raise ValueError(f"angle_range_deg must satisfy 0 <= lo <= hi <= 180, got {angle_range_deg}")
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.radians(rng.uniform(lo, hi, size=n))
    mats = _scipy_rotation().from_rotvec(axis * angle[:, None]).as_matrix() if n else np.empty((0, 3, 3))
    return jitter(mats.reshape(shape + (3, 3)))


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
    ang = _scipy_rotation().from_matrix(flat).magnitude() if len(flat) else np.empty(0)
    return np.degrees(ang).reshape(R.shape[:-2])


def angle_deg_from_chordal(distance) -> np.ndarray:
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


def _scipy_rotation():
    """SciPy's ``Rotation``, imported on first use: ``import replication.core.so3`` loads NumPy
    only."""
    from scipy.spatial.transform import Rotation

    return Rotation


def _batched(func, X, tail_in, tail_out):
    """Apply a SciPy ``Rotation`` conversion to an array batched over leading dimensions."""
    lead = X.shape[: X.ndim - len(tail_in)]
    flat = X.reshape((-1,) + tail_in)
    out = func(flat) if len(flat) else np.empty((0,) + tail_out)
    return out.reshape(lead + tail_out)


def rotation_vector_from_matrix(R) -> np.ndarray:
    """Rotation vectors ``w`` (radians, ``|w| <= pi``) with ``R = exp([w]x)`` (the log map of
    SO(3)), batched.

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
        # column k of S = (R + R^T) / 2 - c I, k the best-conditioned column of n n^T (its largest
        # diagonal entry); only that column is formed, each entry by the same operations as in S
        idx = np.flatnonzero(far)
        Rf, cf = R.reshape(-1, 3, 3)[idx], c.reshape(-1)[idx]
        d = np.einsum("nii->ni", Rf)
        k = np.argmax(0.5 * (d + d) - cf[:, None], axis=-1)
        rows = np.arange(k.size)
        n = 0.5 * (Rf[rows, :, k] + Rf[rows, k, :]) + 0.0  # + 0.0: S's x - c * 0 (c < 0) turns -0.0 into 0.0 too
        n[rows, k] -= cf
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        sign = np.where(np.einsum("ni,ni->n", n, v.reshape(-1, 3)[idx]) < 0, -1.0, 1.0)
        w.reshape(-1, 3)[idx] = n * (sign * theta.reshape(-1)[idx])[:, None]  # w is a new contiguous array
    return w


def matrix_from_rotation_vector(w) -> np.ndarray:
    """Rotation matrices ``exp([w]x)`` (the exp map of SO(3)) from rotation vectors (radians),
    batched: (..., 3) -> (..., 3, 3).

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


def quaternion_from_matrix(R) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)``, scalar first, with ``w >= 0``, batched: (..., 3, 3) ->
    (..., 4).

    ``R`` rotates by ``theta`` about the unit axis ``n`` and
    ``q = (cos(theta/2), sin(theta/2) n)``, from :func:`rotation_vector_from_matrix` (elementwise).
    ``w >= 0`` because ``theta <= 180`` deg; the sign is ambiguous only at ``theta = 180`` deg.
    """
    return quaternion_from_rotation_vector(rotation_vector_from_matrix(R))


def quaternion_from_rotation_vector(w) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)``, scalar first, from rotation vectors ``|w| <= pi``
    (radians), batched: (..., 3) -> (..., 4); ``quaternion_from_matrix(R)`` is
    ``quaternion_from_rotation_vector(rotation_vector_from_matrix(R))``."""
    w = np.asarray(w, dtype=float)
    theta = np.sqrt(np.einsum("...i,...i->...", w, w))
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(theta > 1e-6, np.sin(0.5 * theta) / theta, 0.5 - theta * theta / 48.0)  # sin(t/2)/t
    return np.concatenate([np.cos(0.5 * theta)[..., None], k[..., None] * w], axis=-1)


def matrix_from_quaternion(q) -> np.ndarray:
    """Rotation matrices from quaternions ``(w, x, y, z)``, scalar first (normalised first),
    batched."""
    q = np.asarray(q, dtype=float)
    return _batched(lambda v: _scipy_rotation().from_quat(v, scalar_first=True).as_matrix(), q, (4,), (3, 3))


def yaw_pitch_roll_deg_from_matrix(R) -> np.ndarray:
    """Yaw, pitch, roll (degrees, in that order) with ``R = Rz(yaw) Ry(pitch) Rx(roll)``, batched:
    (..., 3, 3) -> (..., 3).

    The intrinsic z-y'-x'' (Tait-Bryan) angles of the aerospace convention; pitch in
    ``[-90, 90]``, yaw and roll in ``(-180, 180]``. Roll-first order is ``[..., ::-1]``.
    See ``docs/conventions.md``.
    """
    R = np.asarray(R, dtype=float)
    return _batched(lambda m: _scipy_rotation().from_matrix(m).as_euler("ZYX", degrees=True), R, (3, 3), (3,))


def matrix_from_euler(seq: str, angles, *, degrees: bool = False) -> np.ndarray:
    """Rotation matrices from Euler angles in SciPy's ``seq`` (upper case: intrinsic), batched:
    (..., len(seq)) -> (..., 3, 3)."""
    angles = np.asarray(angles, dtype=float)
    return _batched(lambda a: _scipy_rotation().from_euler(seq, a, degrees=degrees).as_matrix(), angles,
                    (len(seq),), (3, 3))


def slerp_interpolator(t, R):
    """A function ``times -> rotations`` (..., 3, 3) interpolating ``R`` (sampled at increasing
    ``t``) along the geodesic.

    SciPy's ``Slerp``, built once: call the result as often as needed.
    """
    from scipy.spatial.transform import Slerp

    interpolator = Slerp(np.asarray(t, dtype=float), _scipy_rotation().from_matrix(np.asarray(R, dtype=float)))
    return lambda times: interpolator(times).as_matrix()


def slerp(t, R, times) -> np.ndarray:
    """Rotations ``R`` (sampled at increasing ``t``) interpolated at ``times`` (see
    :func:`slerp_interpolator`)."""
    return slerp_interpolator(t, R)(times)


def cumulative_product(R) -> np.ndarray:
    """Running products ``P_k = R_0 R_1 ... R_k`` along axis -3, batched: (..., N, 3, 3) -> (..., N,
    3, 3).

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
