"""The rotation-only hand-eye problem ``A X = X B`` of Section II, as linear algebra.

Notation (the paper's, Sec. II):

* ``A[..., j]`` = ``Delta R_{c,j}``: relative rotation of the camera, in the camera frame;
* ``B[..., j]`` = ``Delta R_{i,j}``: the same motion seen by the inertial/magnetic sensor;
* ``X`` = ``R0`` = ``camera_from_sensor``; eq. (7): ``Delta R_c R0 = R0 Delta R_i``.

Arrays are batched over leading dimensions: ``A`` and ``B`` have shape
``(..., J, 3, 3)``; an estimate has shape ``(..., 3, 3)``.

The two-step iteration of eqs. (14)-(15) is built from the linear operator
``T(X) = (1/J) sum_j A_j X B_j^T`` and its adjoint ``T*(Y) = (1/J) sum_j A_j^T Y B_j``
(see :func:`operator_T`); in column-major ``vec`` form ``T`` is the 9x9 matrix
``K = (1/J) sum_j B_j kron A_j`` (:func:`kronecker_operator`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .so3 import _first_index, check_matrices, check_rotation_matrices, chordal_to_angle_deg, log_map

__all__ = [
    "check_motion_pairs",
    "relative_rotations",
    "stack_H1",
    "stack_H2",
    "v2h",
    "h2v",
    "operator_T",
    "operator_T_adjoint",
    "kronecker_operator",
    "vec",
    "unvec",
    "handeye_cost",
    "handeye_cost_kron",
    "pair_residual_deg",
    "MotionObservability",
    "motion_observability",
    "check_observable",
    "Motions",
    "prepare_motions",
]


def check_motion_pairs(A, B, *, min_motions: int = 2, atol: float = 1e-6):
    """Validate camera/sensor relative-rotation pairs for ``A X = X B``.

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c``.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``, same shape as ``A``.
    min_motions : int
        Fewest motions ``J`` the caller needs.
    atol : float
        Tolerance of the rotation test (see :func:`check_rotation_matrices`).

    Returns
    -------
    (A, B) : tuple of numpy.ndarray

    Raises
    ------
    ValueError
        Wrong shapes, mismatched shapes, ``J < min_motions``, NaN/inf, or a
        matrix that is not a rotation (the message names the array and index).
    """
    A = check_matrices(A, "A (camera relative rotations)")
    B = check_matrices(B, "B (sensor relative rotations)")
    if A.ndim < 3 or B.ndim < 3:
        raise ValueError(
            f"A and B must have shape (..., J, 3, 3) with J motions; got A {A.shape}, B {B.shape}"
        )
    if A.shape != B.shape:
        raise ValueError(f"A and B must have the same shape; got A {A.shape}, B {B.shape}")
    J = A.shape[-3]
    if J < min_motions:
        raise ValueError(f"need at least {min_motions} motion pairs (J >= {min_motions}), got J = {J}")
    A = check_rotation_matrices(A, "A (camera relative rotations)", atol)
    B = check_rotation_matrices(B, "B (sensor relative rotations)", atol)
    return A, B


def relative_rotations(orientations, *, reference: int | None = None,
                       convention: str = "body_from_world") -> np.ndarray:
    """Relative rotations from absolute orientations (eqs. (3)-(4)).

    The paper's ``C_t`` and ``I_t`` are body-from-world (attitude) matrices: with
    ``v_cam = R0 v_sensor`` for every vector, eq. (1) ``C_t = R0 I_t`` holds. Eq. (3),
    ``C_k = Delta R_c C_t``, gives ``Delta R_c = C_k C_t^T`` (likewise eq. (4) for the
    sensor): the motion from time ``t`` to ``k`` expressed in the body frame.

    Parameters
    ----------
    orientations : array_like, shape (..., N, 3, 3)
        Orientation at each time ``k``.
    reference : int or None
        ``None``: consecutive pairs ``(t, k) = (n, n + 1)``, ``N - 1`` motions.
        An index ``r``: every other time relative to time ``r``, ``N - 1`` motions.
    convention : {"body_from_world", "world_from_body"}
        What ``orientations`` hold. ``"world_from_body"`` (e.g. a SLAM or mocap
        trajectory's quaternions, ``Q_t = C_t^T``) gives ``Delta R = Q_k^T Q_t``.

    Returns
    -------
    numpy.ndarray, shape (..., N - 1, 3, 3)
    """
    if convention not in ("body_from_world", "world_from_body"):
        raise ValueError(
            f"convention must be 'body_from_world' or 'world_from_body', got {convention!r}"
        )
    C = check_rotation_matrices(orientations, "orientations")
    if C.ndim < 3 or C.shape[-3] < 2:
        raise ValueError(f"orientations must have shape (..., N, 3, 3) with N >= 2, got {C.shape}")
    if convention == "world_from_body":
        C = np.swapaxes(C, -1, -2)
    Ct = np.swapaxes(C, -1, -2)
    if reference is None:
        return C[..., 1:, :, :] @ Ct[..., :-1, :, :]  # eq. (3): Delta R = C_k C_t^T
    n = C.shape[-3]
    if not -n <= reference < n:
        raise ValueError(f"reference index {reference} out of range for N = {n}")
    others = [k for k in range(n) if k != reference % n]
    return C[..., others, :, :] @ Ct[..., [reference], :, :]


def stack_H1(A) -> np.ndarray:
    """``H1`` of eq. (11): the camera rotations stacked vertically, shape (..., 3J, 3)."""
    A = check_matrices(A, "A")
    return A.reshape(A.shape[:-3] + (-1, 3))


def stack_H2(B) -> np.ndarray:
    """``H2`` of eq. (12): the sensor rotations side by side, shape (..., 3, 3J)."""
    return v2h(stack_H1(B))


def v2h(M) -> np.ndarray:
    """``V2H``: a (..., 3J, 3) stack of 3x3 blocks to (..., 3, 3J), block by block."""
    M = np.asarray(M, dtype=float)
    if M.shape[-1] != 3 or M.shape[-2] % 3:
        raise ValueError(f"V2H needs shape (..., 3J, 3), got {M.shape}")
    J = M.shape[-2] // 3
    blocks = M.reshape(M.shape[:-2] + (J, 3, 3))
    return np.moveaxis(blocks, -3, -2).reshape(M.shape[:-2] + (3, 3 * J))


def h2v(M) -> np.ndarray:
    """``H2V``: the inverse of :func:`v2h`, (..., 3, 3J) to (..., 3J, 3)."""
    M = np.asarray(M, dtype=float)
    if M.shape[-2] != 3 or M.shape[-1] % 3:
        raise ValueError(f"H2V needs shape (..., 3, 3J), got {M.shape}")
    J = M.shape[-1] // 3
    blocks = M.reshape(M.shape[:-2] + (3, J, 3))
    return np.moveaxis(blocks, -2, -3).reshape(M.shape[:-2] + (3 * J, 3))


def operator_T(A, B, X) -> np.ndarray:
    """``T(X) = (1/J) sum_j A_j X B_j^T`` — the right-hand side of eq. (14).

    Because every block of ``H2`` is a rotation, ``H2 H2^T = J U`` and the
    pseudo-inverse is ``H2^+ = H2^T / J``; then
    ``V2H(H1 X) H2^+ = (1/J) sum_j A_j X B_j^T``.
    """
    return np.mean(A @ X[..., None, :, :] @ np.swapaxes(B, -1, -2), axis=-3)


def operator_T_adjoint(A, B, Y) -> np.ndarray:
    """``T*(Y) = (1/J) sum_j A_j^T Y B_j`` — the right-hand side of eq. (15).

    ``H1^T H1 = J U`` so ``H1^+ = H1^T / J`` and
    ``H1^+ H2V(Y H2) = (1/J) sum_j A_j^T Y B_j``. It is the adjoint of
    :func:`operator_T` in the Frobenius inner product.
    """
    return np.mean(np.swapaxes(A, -1, -2) @ Y[..., None, :, :] @ B, axis=-3)


def vec(X) -> np.ndarray:
    """Column-major vectorisation, (..., 3, 3) -> (..., 9): ``vec(A X B) = (B^T kron A) vec(X)``."""
    X = np.asarray(X, dtype=float)
    return np.swapaxes(X, -1, -2).reshape(X.shape[:-2] + (9,))


def unvec(x) -> np.ndarray:
    """Inverse of :func:`vec`, (..., 9) -> (..., 3, 3)."""
    x = np.asarray(x, dtype=float)
    return np.swapaxes(x.reshape(x.shape[:-1] + (3, 3)), -1, -2)


def kronecker_operator(A, B, weights=None) -> np.ndarray:
    """The 9x9 matrix ``K = (1/J) sum_j B_j kron A_j`` with ``vec(T(X)) = K vec(X)``.

    Each ``B_j kron A_j`` is orthogonal, so ``||K||_2 <= 1``; noise-free,
    ``K vec(R0) = vec(R0)`` (eq. (7)) and ``sigma_1(K) = 1``.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
    weights : None or array_like, shape (..., J)
        Non-negative pair weights: ``K_w = sum_j w_j B_j kron A_j / sum_j w_j``
        (used by robust re-weighting). ``None``: equal weights.

    Returns
    -------
    numpy.ndarray, shape (..., 9, 9)
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    lead, J = A.shape[:-3], A.shape[-3]
    if weights is None:
        w = np.full(lead + (J,), 1.0 / J)
    else:
        w = np.asarray(weights, dtype=float)
        w = w / w.sum(axis=-1, keepdims=True)
    # sum_j w_j B_j[a, b] A_j[c, d] as one (9 x J) @ (J x 9) product per problem, no (J, 9, 9) intermediate
    S = np.swapaxes((B * w[..., None, None]).reshape(lead + (J, 9)), -1, -2) @ A.reshape(lead + (J, 9))
    # (B kron A)[(a, c), (b, d)] = B[a, b] A[c, d]
    return np.swapaxes(S.reshape(lead + (3, 3, 3, 3)), -3, -2).reshape(lead + (9, 9))


def handeye_cost(R, A, B) -> np.ndarray:
    """The cost of eq. (8): ``sum_j ||A_j R - R B_j||_F^2``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Estimate(s) of ``R0``; may carry extra leading dimensions beyond those of
        ``A`` (e.g. an iteration axis), which are broadcast against ``A``/``B``'s
        batch dimensions placed on the left.
    A, B : array_like, shape (..., J, 3, 3)

    Returns
    -------
    numpy.ndarray, shape (...)

    Notes
    -----
    Fig. 4's caption and text print the cost without the square; eq. (8) squares
    it. This function implements eq. (8).
    """
    diff = _pair_differences(R, A, B)
    return np.einsum("...jab,...jab->...", diff, diff)


def _pair_differences(R, A, B) -> np.ndarray:
    """``A_j R - R B_j`` for every pair, shape (..., J, 3, 3); ``R`` broadcast as in :func:`handeye_cost`."""
    Rj = np.asarray(R, dtype=float)[..., None, :, :]
    return np.asarray(A, dtype=float) @ Rj - Rj @ np.asarray(B, dtype=float)


def pair_residual_deg(R, A, B) -> np.ndarray:
    """Per-pair residual angle in degrees: the angle of ``R^T A_j R B_j^T``.

    It is 0 when pair ``j`` satisfies eq. (7) exactly, and relates to the pair's
    term of eq. (8) by ``||A_j R - R B_j||_F = 2 sqrt(2) sin(angle / 2)``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    A, B : array_like, shape (..., J, 3, 3)

    Returns
    -------
    numpy.ndarray, shape (..., J)
    """
    diff = _pair_differences(R, A, B)
    return chordal_to_angle_deg(np.sqrt(np.einsum("...ab,...ab->...", diff, diff)))


def handeye_cost_kron(R, K, n_motions: int) -> np.ndarray:
    """Eq. (8) through the operator ``K``: ``2 J (||R||_F^2 - vec(R)^T K vec(R))``.

    Exact for any 3x3 ``R`` (not only rotations) when every ``A_j``, ``B_j`` is a
    rotation, because then ``||A_j R||_F = ||R B_j||_F = ||R||_F`` and
    ``sum_j <A_j R, R B_j> = J vec(R)^T K vec(R)``. Costs one 9x9 quadratic form
    per estimate instead of ``J`` matrix products; absolute rounding error about
    ``1e-14 J`` (cancellation), so use :func:`handeye_cost` for tiny costs.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Estimates; leading dimensions broadcast against ``K``'s.
    K : array_like, shape (..., 9, 9)
        :func:`kronecker_operator` of the motions.
    n_motions : int
        ``J``.
    """
    x = vec(R)
    quad = np.einsum("...a,...ab,...b->...", x, K, x)
    return 2.0 * n_motions * (np.einsum("...a,...a->...", x, x) - quad)


@dataclass(frozen=True)
class MotionObservability:
    """How well a set of motion pairs determines ``R0``.

    Attributes
    ----------
    kron_singular_values : ndarray, shape (..., 9)
        Singular values of :func:`kronecker_operator`, descending. Noise-free,
        ``sigma_1 = 1``; the fixed point ``K vec(R0) = vec(R0)`` is unique iff the
        motions are not all about one axis.
    spectral_ratio : ndarray, shape (...)
        ``sigma_2 / sigma_1`` of ``K``. One two-step iteration is a power-method
        step on ``K^T K``, so the raw iterate's other components shrink by
        ``spectral_ratio**2`` per iteration. A ratio of 1 (a repeated top singular
        value) leaves the two-step limit undetermined: it always happens with
        ``J = 2`` pairs, where ``sigma_1`` is triple (see
        :mod:`replication.solvers.two_step`).
    two_step_rate : ndarray, shape (...)
        Per-iteration contraction of the *projected* two-step estimate's error,
        noise-free: ``max(sigma_max(mean_j A_j), sigma_max(mean_j B_j))**2``.
        ``T`` maps the tangent directions ``R0 [w]x`` to ``R0 [(mean_j B_j) w]x``
        and the symmetric directions ``R0 S`` to themselves; the SVD projection
        discards the symmetric part, so only the tangent block sets the rate.
        It equals 1 exactly when all motions share a rotation axis.
    camera_axis_spread_deg, sensor_axis_spread_deg : ndarray, shape (...)
        ``s_2 / sqrt(J)`` in degrees, where ``s_2`` is the second singular value of
        the J x 3 stack of rotation vectors: an RMS amount of rotation about axes
        orthogonal to the dominant one. Zero when all motions share one axis.
    camera_rms_motion_deg : ndarray, shape (...)
        RMS rotation angle of the camera motions, degrees (small motions leave ``R0`` poorly
        determined whatever their axes).
    symmetric_gap : ndarray, shape (...)
        ``lambda_1 - lambda_2`` of ``sym(K) = (K + K^T)/2``. Eq. (8) on SO(3) is
        ``2J (3 - vec(R)^T sym(K) vec(R))``: a second rotation fits the data as well as ``R0``
        only if this gap vanishes (noise-free: exactly when the matrices commuting with every
        ``B_j`` are more than the multiples of ``I``, e.g. motions all about one axis, or
        motions about an axis ``n`` together with half-turns about axes perpendicular to ``n``).
    inconsistency : ndarray, shape (...)
        ``1 - lambda_1`` of ``sym(K)``: zero for noise-free data, grows with noise and outliers.
        ``symmetric_gap`` well above ``inconsistency`` means the minimiser of (8) is well
        determined for the data's noise.
    """

    kron_singular_values: np.ndarray
    spectral_ratio: np.ndarray
    two_step_rate: np.ndarray
    camera_axis_spread_deg: np.ndarray
    sensor_axis_spread_deg: np.ndarray
    camera_rms_motion_deg: np.ndarray
    symmetric_gap: np.ndarray
    inconsistency: np.ndarray

    def iterations_for(self, reduction: float = 1e-6) -> np.ndarray:
        """Iterations for the projected two-step error to shrink by ``reduction`` (noise-free analysis).

        From ``two_step_rate``; ``inf`` where it is 1 (all motions about one axis). A diagnostic:
        :func:`replication.solvers.two_step` decides its iterations itself.
        """
        rate = np.clip(self.two_step_rate, 1e-300, None)
        with np.errstate(divide="ignore"):
            return np.where(rate < 1.0, np.log(reduction) / np.log(rate), np.inf)


def _axis_spread_deg(R: np.ndarray):
    """``(s_2, sqrt(s_1^2 + s_2^2 + s_3^2)) / sqrt(J)`` of the (..., J, 3) rotation vectors, degrees.

    The first is the axis spread of :class:`MotionObservability`, the second the RMS motion angle.
    """
    w = log_map(R)
    gram = np.swapaxes(w, -1, -2) @ w  # (..., 3, 3): s_k^2 are its eigenvalues
    ev = np.clip(np.linalg.eigvalsh(gram), 0.0, None)
    J = R.shape[-3]
    return np.degrees(np.sqrt(ev[..., 1] / J)), np.degrees(np.sqrt(ev.sum(axis=-1) / J))


#: Below this, the gap between the two largest eigenvalues of ``sym(K)`` and the data's inconsistency both
#: vanish to rounding: a second rotation solves eq. (7) exactly (see :meth:`Motions.require`).
NONUNIQUE_TOL = 1e-10


def _first_batch_index(mask):
    """``(index, " at batch index (...)")`` of the first True of a batch mask (``((), "")`` for a scalar)."""
    idx = _first_index(mask)
    return idx, (f" at batch index {idx}" if idx else "")


class Motions:
    """Validated motion pairs of ``A X = X B`` and what every solver needs, built once.

    The public door of every solver (:func:`replication.solvers.solve` and each exported
    solver function) turns ``(A, B)`` into a ``Motions`` by :func:`prepare_motions` and hands
    it to private solver cores, which never validate again. The operator ``K``, its SVD and
    the observability diagnostic are computed on first use and cached.

    Attributes
    ----------
    A : ndarray, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c`` (validated float array; do not modify).
    B : ndarray, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    """

    __slots__ = ("A", "B", "_cache")

    def __init__(self, A, B, *, atol: float = 1e-6):
        A, B = check_motion_pairs(A, B, min_motions=1, atol=atol)
        if A.size == 0:
            raise ValueError(f"A and B hold no problems (batch shape {A.shape[:-3]})")
        # private, read-only copies: the caller's arrays may change later, the cached K must not go stale
        A, B = np.array(A, dtype=float), np.array(B, dtype=float)
        A.setflags(write=False)
        B.setflags(write=False)
        self._set(A, B)

    def _set(self, A, B):
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "_cache", {})

    def __setattr__(self, name, value):
        raise AttributeError("Motions is read-only")

    @classmethod
    def _trusted(cls, A: np.ndarray, B: np.ndarray) -> "Motions":
        """Wrap arrays that come from validated motions (a resample, a sub-batch) without re-validating."""
        m = object.__new__(cls)
        m._set(A, B)
        return m

    def __repr__(self):
        return f"Motions(batch_shape={self.batch_shape}, J={self.J})"

    @property
    def J(self) -> int:
        """Number of motion pairs per problem."""
        return self.A.shape[-3]

    @property
    def batch_shape(self) -> tuple:
        """Leading (batch) dimensions."""
        return self.A.shape[:-3]

    def _cached(self, key, compute):
        if key not in self._cache:
            self._cache[key] = compute()
        return self._cache[key]

    @property
    def K(self) -> np.ndarray:
        """:func:`kronecker_operator` of the pairs, shape (..., 9, 9)."""
        return self._cached("K", lambda: kronecker_operator(self.A, self.B))

    @property
    def svd(self):
        """``(U, s, Vt)`` of ``K`` (descending singular values), batched."""
        return self._cached("svd", lambda: np.linalg.svd(self.K))

    @property
    def axis_spread_deg(self):
        """``(camera, sensor)`` axis spreads in degrees (see :class:`MotionObservability`)."""
        return self._cached("spread", lambda: (_axis_spread_deg(self.A)[0], _axis_spread_deg(self.B)[0]))

    @property
    def rms_motion_deg(self):
        """RMS rotation angle of the camera motions, degrees."""
        return self._cached("rms_motion", lambda: _axis_spread_deg(self.A)[1])

    @property
    def sym_eigvals(self) -> np.ndarray:
        """Eigenvalues of ``sym(K) = (K + K^T) / 2``, descending, shape (..., 9)."""
        def compute():
            K = self.K
            return np.linalg.eigvalsh(0.5 * (K + np.swapaxes(K, -1, -2)))[..., ::-1]
        return self._cached("sym_eigvals", compute)

    @property
    def observability(self) -> MotionObservability:
        """The :class:`MotionObservability` diagnostic."""
        def compute():
            sv = self.svd[1]
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(sv[..., 0] > 0, sv[..., 1] / sv[..., 0], 1.0)
            rate = np.maximum(
                np.linalg.norm(self.A.mean(axis=-3), ord=2, axis=(-2, -1)),
                np.linalg.norm(self.B.mean(axis=-3), ord=2, axis=(-2, -1)),
            ) ** 2
            ev = self.sym_eigvals
            return MotionObservability(sv, ratio, rate, *self.axis_spread_deg, self.rms_motion_deg,
                                       ev[..., 0] - ev[..., 1], 1.0 - ev[..., 0])
        return self._cached("observability", compute)

    def require(self, *, min_motions: int = 2, observable: bool = True,
                min_axis_spread_deg: float = 1e-6) -> "Motions":
        """Raise ``ValueError`` unless ``J >= min_motions`` and (if ``observable``) ``R0`` is determined.

        Degenerate: on the camera or the sensor side every rotation axis is parallel (axis spread
        below ``min_axis_spread_deg``; see :func:`check_observable`), or, more generally, a second
        rotation solves eq. (7) exactly (``symmetric_gap`` and ``inconsistency`` of
        :class:`MotionObservability` both below ``1e-10``). Returns ``self``.
        """
        if self.J < min_motions:
            raise ValueError(f"need at least {min_motions} motion pairs (J >= {min_motions}), got J = {self.J}")
        if observable:
            for side, spread in zip(("camera", "sensor"), self.axis_spread_deg):
                bad = np.asarray(spread) < min_axis_spread_deg
                if bad.any():
                    idx, where = _first_batch_index(bad)
                    raise ValueError(
                        f"degenerate motion: the {side} rotations{where} all share one "
                        f"rotation axis or do not rotate (axis spread {float(spread[idx]):.3g} deg < "
                        f"{min_axis_spread_deg:g} deg); R0 is then not unique: at least two motions "
                        f"with non-parallel rotation axes are needed"
                    )
            ev = self.sym_eigvals
            twin = (ev[..., 0] - ev[..., 1] < NONUNIQUE_TOL) & (1.0 - ev[..., 0] < NONUNIQUE_TOL)
            if np.any(twin):
                _, where = _first_batch_index(twin)
                raise ValueError(
                    f"degenerate motion{where}: R0 is not unique: a second rotation solves eq. (7) exactly "
                    f"(the two largest eigenvalues of sym(K) are both 1 to within {NONUNIQUE_TOL:g}), as for "
                    f"motions about one axis n together with half-turns about axes perpendicular to n; add "
                    f"motions about other axes"
                )
        return self

    def subset(self, index) -> "Motions":
        """The pairs ``A[..., index, :, :]`` (a resample or a selection), without re-validating."""
        return Motions._trusted(self.A[..., index, :, :], self.B[..., index, :, :])

    def batch(self, index) -> "Motions":
        """Problems ``A[index]`` of the batch, without re-validating."""
        return Motions._trusted(self.A[index], self.B[index])


def prepare_motions(A, B=None, *, min_motions: int = 2, require_observable: bool = True,
                    min_axis_spread_deg: float = 1e-6) -> Motions:
    """The public door: validate motion pairs once and return a :class:`Motions`.

    Parameters
    ----------
    A : array_like, shape (..., J, 3, 3), or Motions
        Camera relative rotations ``Delta R_c``; a :class:`Motions` (with ``B=None``) is not
        validated again, only checked against ``min_motions`` and degeneracy.
    B : array_like, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.
    min_motions : int
        Fewest motion pairs accepted.
    require_observable : bool
        Raise ``ValueError`` for degenerate motion (see :func:`check_observable`).
    min_axis_spread_deg : float
        Degeneracy threshold (see :func:`check_observable`).

    Returns
    -------
    Motions

    Raises
    ------
    ValueError
        See :func:`check_motion_pairs` and :meth:`Motions.require`.
    """
    if isinstance(A, Motions):
        if B is not None:
            raise ValueError("pass either a Motions object or the arrays A and B, not both")
        m = A
    else:
        if B is None:
            raise ValueError("B (sensor relative rotations) is missing")
        m = Motions(A, B)
    return m.require(min_motions=min_motions, observable=require_observable,
                     min_axis_spread_deg=min_axis_spread_deg)


def motion_observability(A, B) -> MotionObservability:
    """Observability diagnostics of motion pairs (see :class:`MotionObservability`)."""
    return prepare_motions(A, B, min_motions=1, require_observable=False).observability


def check_observable(A, B, *, min_axis_spread_deg: float = 1e-6) -> MotionObservability:
    """Raise ``ValueError`` when the motions cannot determine ``R0``.

    ``A X = X B`` determines ``X`` only if at least two motions have
    non-parallel rotation axes. With every axis parallel to ``a`` (camera) and
    ``b`` (sensor), ``R0 Rot(b, phi)`` solves it for every ``phi``; with no
    motion at all, every rotation does.

    Parameters
    ----------
    A, B : array_like, shape (..., J, 3, 3)
    min_axis_spread_deg : float
        Below this axis spread (see :class:`MotionObservability`) on either side
        the motions are called degenerate. The default only catches exact
        degeneracy up to rounding; noisy near-degenerate data passes and should
        be judged from the returned diagnostics.

    Returns
    -------
    MotionObservability
    """
    return prepare_motions(A, B, min_motions=1, min_axis_spread_deg=min_axis_spread_deg).observability
