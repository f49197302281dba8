"""VINS-Mono's online camera-IMU extrinsic *rotation* initialiser, ported to ``A X = X B``. Theory
and measured numbers: ``docs/studies.md``, section ``replication.study.vins_rule``."""
from __future__ import annotations

import numpy as np

from ..core.checks import check_rotation_matrices
from ..core.so3 import angle_between_deg, matrix_from_quaternion, quaternion_from_matrix, skew

__all__ = ["VinsExRotation"]


def _eigen_quaternion_xyzw(M: np.ndarray) -> np.ndarray:
    """``Quaterniond(M).coeffs()``: Eigen's ``(x, y, z, w)`` with Eigen's choice of sign.

    Eigen (``quaternionbase_assign_impl``): if ``trace > 0`` then ``w = sqrt(trace + 1) / 2 > 0``;
    otherwise ``i`` = index of the largest diagonal entry (ties to the lower index) and coefficient
    ``i`` is positive. Magnitudes come from :func:`replication.core.so3.quaternion_from_matrix` (``w
    >= 0``); only the sign is Eigen's.
    """
    q = quaternion_from_matrix(M)  # (w, x, y, z), w >= 0
    if np.trace(M) <= 0.0:
        i = 0
        if M[1, 1] > M[0, 0]:
            i = 1
        if M[2, 2] > M[i, i]:
            i = 2
        if q[1 + i] < 0.0:
            q = -q
    return np.array([q[1], q[2], q[3], q[0]])


def _l_minus_r(q_Rc: np.ndarray, q_Rimu: np.ndarray) -> np.ndarray:
    """``L - R`` of lines 32-47, from Eigen-order ``(x, y, z, w)`` quaternions of ``Rc[i]`` and
    ``Rimu[i]``.

    ``L(q_Rc) x = q_Rc (x) x`` and ``R(q_Rimu) x = x (x) q_Rimu`` (Hamilton products, ``x`` in
    Eigen's order).
    """
    w, q = q_Rc[3], q_Rc[:3]  # L34-L35: w = Quaterniond(Rc[i]).w(); q = Quaterniond(Rc[i]).vec();
    L = np.empty((4, 4))  # L32: Matrix4d L, R;
    L[:3, :3] = w * np.eye(3) + skew(q)  # L36: L.block<3,3>(0,0) = w*I + skewSymmetric(q);
    L[:3, 3] = q  # L37: L.block<3,1>(0,3) = q;
    L[3, :3] = -q  # L38: L.block<1,3>(3,0) = -q.transpose();
    L[3, 3] = w  # L39: L(3,3) = w;

    w, q = q_Rimu[3], q_Rimu[:3]  # L41-L43: Quaterniond R_ij(Rimu[i]); w = R_ij.w(); q = R_ij.vec();
    R = np.empty((4, 4))
    R[:3, :3] = w * np.eye(3) - skew(q)  # L44: R.block<3,3>(0,0) = w*I - skewSymmetric(q);
    R[:3, 3] = q  # L45: R.block<3,1>(0,3) = q;
    R[3, :3] = -q  # L46: R.block<1,3>(3,0) = -q.transpose();
    R[3, 3] = w  # L47: R(3,3) = w;
    return L - R  # (L - R) of L49


#: Singular values within this share of the largest from the smallest count as repeated (see
#: :meth:`VinsExRotation.update`).
NULL_TOL = 1e-9


class VinsExRotation:
    """Online rotation calibration of VINS-Mono's ``InitialEXRotation``, in our ``A X = X B``
    convention.

    Parameters
    ----------
    window_size : int
        ``WINDOW_SIZE`` of ``parameters.h`` (10): fewest pairs before success can be declared.
    huber_deg : float
        Huber threshold in degrees (5.0 in the C++).
    ready_singular_value : float
        Threshold on the second-smallest singular value (0.25 in the C++).

    Attributes
    ----------
    R : numpy.ndarray, shape (3, 3)
        Current ``camera_from_sensor`` estimate (``ric^T``); identity before the first pair.
    ready : bool
        Whether success has been declared (latched).
    ready_at : int or None
        0-based index ``j`` of the pair whose update first declared success (``ready_at + 1`` pairs
        had then been seen, VINS-Mono's ``frame_count``).
    R_ready : numpy.ndarray or None
        The estimate at that moment (VINS-Mono's ``calib_ric_result``, as ``camera_from_sensor``).
    singular_values : numpy.ndarray, shape (4,)
        Singular values of the last stacked system, in decreasing order (Eigen's and NumPy's order).
    weights : numpy.ndarray, shape (N,)
        Huber weight of every pair in the last solve.
    """

    def __init__(self, window_size: int = 10, huber_deg: float = 5.0, ready_singular_value: float = 0.25):
        if int(window_size) != window_size or window_size < 1:
            raise ValueError(f"window_size must be a positive integer, got {window_size}")
        if not huber_deg > 0:
            raise ValueError(f"huber_deg must be positive, got {huber_deg}")
        if not np.isfinite(ready_singular_value):
            raise ValueError(f"ready_singular_value must be finite, got {ready_singular_value!r}")
        self.window_size = int(window_size)
        self.huber_deg = float(huber_deg)
        self.ready_singular_value = float(ready_singular_value)
        # L3-L9 (constructor): frame_count = 0; ric = Identity. The C++ pushes a dummy identity at
        # index 0 of Rc, Rc_g, Rimu and loops from i = 1; here the lists start empty and are indexed
        # from 0.
        self.frame_count = 0
        self._Rc: list[np.ndarray] = []
        self._Rimu: list[np.ndarray] = []
        self._Rc_g: list[np.ndarray] = []
        self._ric = np.eye(3)
        self._angular_distance: list[float] = []  # per-pair caches (see update)
        self._q_Rc: list[np.ndarray] = []
        self._q_Rimu: list[np.ndarray] = []
        self._L_minus_R: list[np.ndarray] = []
        self.ready = False
        self.ready_at: int | None = None
        self.R_ready: np.ndarray | None = None
        self.singular_values = np.full(4, np.nan)
        self.weights = np.empty(0)

    @property
    def R(self) -> np.ndarray:
        """Current ``camera_from_sensor`` estimate, ``ric^T``."""
        return self._ric.T.copy()

    def update(self, A_j, B_j) -> bool:
        """Add one pair (camera motion ``A_j``, sensor motion ``B_j``), re-solve, return the C++
        return value.

        The return value is ``CalibrationExRotation``'s for this call; since old rows never change
        it stays ``True`` once it has been ``True`` (see the module docstring), so it equals
        :attr:`ready`.

        Raises
        ------
        ValueError
            ``A_j`` or ``B_j`` is not a single 3x3 rotation matrix.
        """
        A_j = check_rotation_matrices(A_j, "A_j (camera relative rotation)")
        B_j = check_rotation_matrices(B_j, "B_j (sensor relative rotation)")
        if A_j.shape != (3, 3) or B_j.shape != (3, 3):
            raise ValueError(f"A_j and B_j must each be one 3x3 rotation; got A_j {A_j.shape}, B_j {B_j.shape}")
        Rc_new = A_j.T  # solveRelativeR's transpose: camera_{k-1}_from_camera_k (module docstring)
        Rimu_new = B_j.T  # delta_q: imu_{k-1}_from_imu_k

        self.frame_count += 1  # L13: frame_count++;
        self._Rc.append(Rc_new)  # L14: Rc.push_back(solveRelativeR(corres));
        self._Rimu.append(Rimu_new)  # L15: Rimu.push_back(delta_q_imu.toRotationMatrix());
        self._Rc_g.append(self._ric.T @ Rimu_new @ self._ric)  # L16: Rc_g.push_back(ric.inverse() * delta_q_imu * ric);
        # Rc[i], Rimu[i] and Rc_g[i] never change once pushed, so the per-pair conversions of the
        # loop body (L23-L26, L32-L47) are computed once here and cached; the loop then uses them.
        # L23-L26: angular_distance = 180 / M_PI *
        # Quaterniond(Rc[i]).angularDistance(Quaterniond(Rc_g[i]));
        self._angular_distance.append(float(angle_between_deg(self._Rc[-1], self._Rc_g[-1])))
        self._q_Rc.append(_eigen_quaternion_xyzw(self._Rc[-1]))  # L34-L35: Quaterniond(Rc[i])
        self._q_Rimu.append(_eigen_quaternion_xyzw(self._Rimu[-1]))  # L41: Quaterniond R_ij(Rimu[i]);
        self._L_minus_R.append(_l_minus_r(self._q_Rc[-1], self._q_Rimu[-1]))  # L32-L47

        A = np.zeros((self.frame_count * 4, 4))  # L18-L19: MatrixXd A(frame_count * 4, 4); A.setZero();
        weights = np.empty(self.frame_count)
        for i in range(self.frame_count):  # L21: for (int i = 1; i <= frame_count; i++)
            angular_distance = self._angular_distance[i]  # L23-L26 (cached at insertion)
            # L30: huber = angular_distance > 5.0 ? 5.0 / angular_distance : 1.0;
            huber = self.huber_deg / angular_distance if angular_distance > self.huber_deg else 1.0
            weights[i] = huber

            L_minus_R = self._L_minus_R[i]  # L32-L47 (cached at insertion, see _l_minus_r)
            A[4 * i:4 * i + 4, :] = huber * L_minus_R  # L49: A.block<4,4>((i-1)*4, 0) = huber * (L - R);

        _, s, Vt = np.linalg.svd(A)  # L52: JacobiSVD<MatrixXd> svd(A, ComputeFullU | ComputeFullV);
        x = Vt[3]  # L53: x = svd.matrixV().col(3);  (Eigen coefficient order x, y, z, w)
        # Deviation from the C++ (deterministic replays): where the smallest singular value is
        # repeated, the last singular vector is any vector of a subspace of dimension >= 2, which
        # the SVD picks by rounding. This is always so for the first pair (L(q) - R(p) has its
        # singular values in equal pairs) and again whenever the system is that degenerate. Its
        # estimate then sets the Huber weights of the pairs that follow (line 16), so every later
        # estimate would depend on rounding. There the port takes the quaternion of that subspace
        # nearest the identity (the estimate's start, line 7).
        null = Vt[s - s[-1] <= NULL_TOL * max(s[0], 1e-300)]
        if len(null) >= 2:
            x = null.T @ (null @ np.array([0.0, 0.0, 0.0, 1.0]))
            x = x / np.linalg.norm(x) if np.linalg.norm(x) > 1e-12 else Vt[3]
        X = matrix_from_quaternion(np.array([x[3], x[0], x[1], x[2]]))  # L54: Quaterniond estimated_R(x);
        self._ric = X.T  # L55: ric = estimated_R.toRotationMatrix().inverse();
        self.singular_values = s
        self.weights = weights
        ric_cov = s[1:]  # L59: ric_cov = svd.singularValues().tail<3>();  (decreasing order)
        # L60: if (frame_count >= WINDOW_SIZE && ric_cov(1) > 0.25)
        success = self.frame_count >= self.window_size and ric_cov[1] > self.ready_singular_value
        if success and not self.ready:
            self.ready = True  # L62-L63: calib_ric_result = ric; return true;
            self.ready_at = self.frame_count - 1
            self.R_ready = self.R
        return bool(success)  # L60-L66: return true / return false;
