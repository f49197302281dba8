"""Validated motion pairs (:class:`Motions`) and their observability, built once at the public door.

Every solver's public door (:func:`replication.core.solvers.solve` and each exported solver
function) turns ``(A, B)`` into a :class:`Motions` by :func:`prepare_motions`; private solver cores
receive it and never validate again. The operator ``K`` of
:func:`replication.core.handeye.kronecker_operator`, its decompositions (one ``eigh`` of ``K^T K``
for the singular values and the top singular vectors, one of ``sym(K)`` where a solver needs its
eigenvectors) and :class:`MotionObservability` are computed on first use and cached. Notation and
frames: ``docs/conventions.md``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .checks import _first_index
from .handeye import check_motion_pairs, kronecker_operator
from .kernels import eigvalsh3, top_eigenvector3
from .so3 import rotation_vector_from_matrix

__all__ = ["MotionObservability", "motion_observability", "check_observable", "Motions", "prepare_motions"]


@dataclass(frozen=True)
class MotionObservability:
    """How well a set of motion pairs determines ``R0``.

    Attributes
    ----------
    kron_singular_values : ndarray, shape (..., 9)
        Singular values of :func:`kronecker_operator`, descending (:attr:`Motions.singular_values`).
        Noise-free, ``sigma_1 = 1``; the fixed point ``K vec(R0) = vec(R0)`` is unique iff the
        motions are not all about one axis.
    spectral_ratio : ndarray, shape (...)
        ``sigma_2 / sigma_1`` of ``K``. One two-step iteration is a power-method
        step on ``K^T K``, so the raw iterate's other components shrink by
        ``spectral_ratio**2`` per iteration. A ratio of 1 (a repeated top singular
        value) leaves the two-step limit undetermined: it always happens with
        ``J = 2`` pairs, where ``sigma_1`` is triple (see
        :mod:`replication.core.solvers.iteration`).
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
        """Iterations for the projected two-step error to shrink by ``reduction`` (noise-free
        analysis).

        From ``two_step_rate``; ``inf`` where it is 1 (all motions about one axis). A diagnostic:
        :func:`replication.core.solvers.two_step` decides its iterations itself.
        """
        rate = np.clip(self.two_step_rate, 1e-300, None)
        with np.errstate(divide="ignore"):
            return np.where(rate < 1.0, np.log(reduction) / np.log(rate), np.inf)


def _axis_spread_deg(w: np.ndarray):
    """``(s_2, sqrt(s_1^2 + s_2^2 + s_3^2)) / sqrt(J)`` of the (..., J, 3) rotation vectors ``w``,
    degrees.

    The first is the axis spread of :class:`MotionObservability`, the second the RMS motion angle.
    """
    gram = np.swapaxes(w, -1, -2) @ w  # (..., 3, 3): s_k^2 are its eigenvalues
    ev = np.clip(eigvalsh3(gram), 0.0, None)
    J = w.shape[-2]
    return np.degrees(np.sqrt(ev[..., 1] / J)), np.degrees(np.sqrt(ev.sum(axis=-1) / J))


def _largest_singular_value(M: np.ndarray) -> np.ndarray:
    """``sigma_max`` of 3x3 matrices, ``sqrt(lambda_max(M^T M))`` (the spectral norm, without an SVD
    per matrix)."""
    return np.sqrt(np.clip(eigvalsh3(np.swapaxes(M, -1, -2) @ M)[..., -1], 0.0, None))


#: Below this, the gap between the two largest eigenvalues of ``sym(K)`` and the data's
#: inconsistency both vanish to rounding: a second rotation solves eq. (7) exactly (see
#: :meth:`Motions.require`).
NONUNIQUE_TOL = 1e-10


def _first_batch_index(mask):
    """``(index, " at batch index (...)")`` of the first True of a batch mask (``((), "")`` for a
    scalar)."""
    idx = _first_index(mask)
    return idx, (f" at batch index {idx}" if idx else "")


class Motions:
    """Validated motion pairs of ``A X = X B`` and what every solver needs, built once.

    The public door of every solver (:func:`replication.core.solvers.solve` and each exported
    solver function) turns ``(A, B)`` into a ``Motions`` by :func:`prepare_motions` and hands
    it to private solver cores, which never validate again. The operator ``K``, its SVD and
    the observability diagnostic are computed on first use and cached.

    Attributes
    ----------
    A : ndarray, shape (..., J, 3, 3)
        Camera relative rotations ``Delta R_c`` (validated float array; do not modify).
    B : ndarray, shape (..., J, 3, 3)
        Sensor relative rotations ``Delta R_i``.

    ``Motions(A, B, atol=1e-6)``: ``atol`` is the tolerance of the rotation test of ``A`` and ``B``,
    a finite number in ``(0, 1e-2]`` (:func:`replication.core.checks.check_rotation_matrices`;
    ``ValueError`` naming ``atol`` otherwise).
    """

    __slots__ = ("A", "B", "_cache")

    def __init__(self, A, B, *, atol: float = 1e-6):
        A, B = check_motion_pairs(A, B, min_motions=1, atol=atol)
        if A.size == 0:
            raise ValueError(f"A and B hold no problems (batch shape {A.shape[:-3]})")
        # private, read-only copies: the caller's arrays may change later, the cached K must not go
        # stale
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
    def _trusted(cls, A: np.ndarray, B: np.ndarray) -> Motions:
        """Wrap arrays that come from validated motions (a resample, a sub-batch) without
        re-validating."""
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
        """``(U, s, Vt)`` of ``K`` (descending singular values), batched (the full SVD; the solvers
        use :attr:`singular_values` and :attr:`top_singular_vectors`, from one ``eigh`` of ``K^T
        K``)."""
        return self._cached("svd", lambda: np.linalg.svd(self.K))

    def _gram_eigh(self):
        """``eigh`` of ``K^T K``, eigenvalues descending (columns of the vectors in the same order):
        the one 9x9 decomposition behind :attr:`singular_values` and :attr:`top_singular_vectors`
        (half an SVD's cost)."""
        def compute():
            K = self.K
            w, V = np.linalg.eigh(np.swapaxes(K, -1, -2) @ K)
            return w[..., ::-1], V[..., :, ::-1]
        return self._cached("gram_eigh", compute)

    @property
    def singular_values(self) -> np.ndarray:
        """Singular values of ``K``, descending, shape (..., 9): ``sqrt`` of the eigenvalues of
        ``K^T K`` (within about ``eps sigma_1^2 / sigma_k`` of the SVD's: relative rounding for the
        top ones, which decide ``spectral_ratio``; an exact zero reads as up to about ``sqrt(eps)
        sigma_1``)."""
        return self._cached("singular_values", lambda: np.sqrt(np.clip(self._gram_eigh()[0], 0.0, None)))

    @property
    def top_singular_vectors(self):
        """``(u1, sigma_1, v1)``: the top right singular vector ``v1`` of ``K`` (the top eigenvector
        of ``K^T K``), ``sigma_1 = ||K v1||`` and ``u1 = K v1 / sigma_1``, so ``K v1 = sigma_1 u1``
        (the pairing of the two-step iteration's limits); each to about ``eps / (1 - sigma_2 /
        sigma_1)`` as from the SVD."""
        def compute():
            v1 = self._gram_eigh()[1][..., :, 0]
            Kv = np.einsum("...ab,...b->...a", self.K, v1)
            s1 = np.sqrt(np.einsum("...a,...a->...", Kv, Kv))
            return Kv / np.where(s1 > 0, s1, 1.0)[..., None], s1, v1
        return self._cached("top_singular_vectors", compute)

    @property
    def rotation_vectors(self):
        """``(log A, log B)``: the rotation vectors of the camera and sensor motions (radians),
        (..., J, 3) each."""
        return self._cached("rotation_vectors", lambda: (rotation_vector_from_matrix(self.A),
                                                         rotation_vector_from_matrix(self.B)))

    def _spreads(self):
        return self._cached("spreads", lambda: tuple(_axis_spread_deg(w) for w in self.rotation_vectors))

    @property
    def axis_spread_deg(self):
        """``(camera, sensor)`` axis spreads in degrees (see :class:`MotionObservability`)."""
        camera, sensor = self._spreads()
        return camera[0], sensor[0]

    @property
    def leave_one_out_spread_deg(self):
        """``(spread, pair)``: the smaller of the camera and sensor axis spreads (as
        :attr:`axis_spread_deg`, RMS over the ``J - 1`` other pairs) once the pair that turns most
        about axes other than the dominant one is left out, and that pair's index (per problem; that
        of the side with the smaller spread). Far below the full spread, the rotation about the
        dominant axis rests on that one pair. NaN where ``J < 3``."""
        def compute():
            out = []
            for w in self.rotation_vectors:
                gram = np.swapaxes(w, -1, -2) @ w
                n = top_eigenvector3(gram)  # the dominant axis
                along = np.einsum("...ja,...a->...j", w, n)
                perp = np.sum(w * w, axis=-1) - along ** 2  # squared turn about axes other than n
                k = np.argmax(perp, axis=-1)
                wk = np.take_along_axis(w, k[..., None, None], axis=-2)[..., 0, :]
                rest = gram - wk[..., :, None] * wk[..., None, :]
                ev = np.clip(eigvalsh3(rest), 0.0, None)
                spread = np.degrees(np.sqrt(ev[..., 1] / max(self.J - 1, 1)))
                out.append((np.where(self.J >= 3, spread, np.nan), k))
            (cam, k_cam), (sen, k_sen) = out
            return np.fmin(cam, sen), np.where(sen < cam, k_sen, k_cam)
        return self._cached("leave_one_out", compute)

    @property
    def rms_motion_deg(self):
        """RMS rotation angle of the camera motions, degrees."""
        return self._spreads()[0][1]

    @property
    def sym(self) -> np.ndarray:
        """``sym(K) = (K + K^T) / 2``, shape (..., 9, 9)."""
        def compute():
            K = self.K
            return 0.5 * (K + np.swapaxes(K, -1, -2))
        return self._cached("sym", compute)

    @property
    def sym_eigh(self):
        """``(eigenvalues, eigenvectors)`` of ``sym(K)``, eigenvalues descending (vector columns in
        that order): the relaxed start
        (:func:`replication.core.solvers.certificate.relaxed_rotation`) and, once computed,
        :attr:`sym_eigvals` too, so a solver that needs both makes one decomposition (:func:`solve`
        asks for this first for such solvers)."""
        def compute():
            w, V = np.linalg.eigh(self.sym)
            return w[..., ::-1], V[..., :, ::-1]
        return self._cached("sym_eigh", compute)

    @property
    def sym_eigvals(self) -> np.ndarray:
        """Eigenvalues of ``sym(K) = (K + K^T) / 2``, descending, shape (..., 9): those of
        :attr:`sym_eigh` where it was computed first, else ``eigvalsh`` (the two agree to rounding,
        about ``eps ||sym(K)||``)."""
        def compute():
            if "sym_eigh" in self._cache:
                return self._cache["sym_eigh"][0]
            return np.linalg.eigvalsh(self.sym)[..., ::-1]
        return self._cached("sym_eigvals", compute)

    @property
    def observability(self) -> MotionObservability:
        """The :class:`MotionObservability` diagnostic."""
        def compute():
            sv = self.singular_values
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(sv[..., 0] > 0, sv[..., 1] / sv[..., 0], 1.0)
            rate = np.maximum(_largest_singular_value(self.A.mean(axis=-3)),
                              _largest_singular_value(self.B.mean(axis=-3))) ** 2
            ev = self.sym_eigvals
            return MotionObservability(sv, ratio, rate, *self.axis_spread_deg, self.rms_motion_deg,
                                       ev[..., 0] - ev[..., 1], 1.0 - ev[..., 0])
        return self._cached("observability", compute)

    def require(self, *, min_motions: int = 2, observable: bool = True,
                min_axis_spread_deg: float = 1e-6) -> Motions:
        """Raise ``ValueError`` unless ``J >= min_motions`` and (if ``observable``) ``R0`` is
        determined.

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

    def subset(self, index) -> Motions:
        """The pairs ``A[..., index, :, :]`` (a resample or a selection), without re-validating."""
        return Motions._trusted(self.A[..., index, :, :], self.B[..., index, :, :])

    def batch(self, index) -> Motions:
        """Problems ``A[index]`` of the batch, without re-validating."""
        return Motions._trusted(self.A[index], self.B[index])


def prepare_motions(A, B=None, *, min_motions: int = 2, require_observable: bool = True,
                    min_axis_spread_deg: float = 1e-6, _sym_vectors: bool = False) -> Motions:
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
    _sym_vectors : bool
        For solvers that start from the relaxed solution: decompose ``sym(K)`` with its eigenvectors
        (:attr:`Motions.sym_eigh`) before the checks, which then take its eigenvalues (one
        decomposition, not two).

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
    if _sym_vectors:
        m.require(min_motions=min_motions, observable=False)
        _ = m.sym_eigh
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
