"""Faster equivalents of steps of the lab's processing chain (:mod:`replication.study.lab.chain`),
for the seed studies of ``notebooks/05_table2_experiment.ipynb``, each checked against the original
in ``tests/study/test_lab_claims.py``:

* :func:`refine_camera_orientations`: PnP's least squares (the reprojection error
  ``cv2.solvePnPRefineLM`` minimises) solved for many images at once, by Gauss-Newton with the
  analytic Jacobian of OpenCV's camera model (:func:`_project`); it gives every frame of a static
  orientation its own attitude (the all-sample calibration) and refines the dynamic trial's SQPnP
  poses (``camera_orientations(..., refine="batched")``);
* :func:`ecompass_attitudes`: ``ahrs``' ``ecompass`` on arrays of samples;
* :func:`madgwick_marg`: ``ahrs``' Madgwick MARG update transcribed to plain Python floats.
"""
from __future__ import annotations

import math

import numpy as np

from ...core.so3 import matrix_from_rotation_vector

__all__ = ["refine_camera_orientations", "ecompass_attitudes", "madgwick_marg"]


def _project(X, C, t, K, dist, *, jacobian: bool = False):
    """OpenCV's pinhole + (k1, k2, p1, p2, k3) distortion model (no skew), batched: pixels (M, N, 2)
    of points X (N, 3) seen from poses ``x = C X + t`` (C (M, 3, 3), t (M, 3)); with ``jacobian``,
    also their derivatives (M, 6, 2, N) by the pose's change ``(w, dt)``: ``C -> exp(w) C``, ``t ->
    t + dt``."""
    # C X as three contiguous (M, N) arrays: one matrix product
    qx, qy, qz = np.ascontiguousarray(np.moveaxis((C.reshape(-1, 3) @ X.T).reshape(C.shape[:-1] + (len(X),)), 1, 0))
    Px, Py, Pz = qx + t[:, :1], qy + t[:, 1:2], qz + t[:, 2:]
    x, y = Px / Pz, Py / Pz
    k1, k2, p1, p2, k3 = dist
    r2 = x * x + y * y
    radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x)
    yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y
    uv = np.stack([K[0, 0] * xd + K[0, 2], K[1, 1] * yd + K[1, 2]], axis=-1)          # no skew, as OpenCV
    if not jacobian:
        return uv
    d_radial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2)                      # d radial / d r2
    dxd = (radial + 2.0 * x * x * d_radial + 2.0 * p1 * y + 6.0 * p2 * x,     # d xd / d (x, y)
           2.0 * x * y * d_radial + 2.0 * p1 * x + 2.0 * p2 * y)
    dyd = (2.0 * x * y * d_radial + 2.0 * p1 * x + 2.0 * p2 * y,             # d yd / d (x, y)
           radial + 2.0 * y * y * d_radial + 6.0 * p1 * y + 2.0 * p2 * x)
    du = (K[0, 0] * dxd[0], K[0, 0] * dxd[1])                            # d (u, v) / d (x, y)
    dv = (K[1, 1] * dyd[0], K[1, 1] * dyd[1])
    inv = 1.0 / Pz
    # d (x, y) / d (Px, Py, Pz), then d P / d w = -[C X]x and d P / d t = I
    dP = [(du[0] * inv, du[1] * inv, -(du[0] * x + du[1] * y) * inv),
          (dv[0] * inv, dv[1] * inv, -(dv[0] * x + dv[1] * y) * inv)]
    J = np.empty((len(C), 6, 2, len(X)))                                  # (M, 6, 2, N): contiguous per pose
    for i, (gx, gy, gz) in enumerate(dP):
        J[:, 0, i], J[:, 1, i], J[:, 2, i] = gz * qy - gy * qz, gx * qz - gz * qx, gy * qx - gx * qy   # q x g
        J[:, 3, i], J[:, 4, i], J[:, 5, i] = gx, gy, gz
    return uv, J


def refine_camera_orientations(uv, rig, C0, t0, *, iterations: int = 3) -> np.ndarray:
    """PnP's least squares (reprojection error, as ``cv2.solvePnPRefineLM``) solved for many images
    at once.

    Gauss-Newton from a nearby pose (each image's own, e.g. the PnP pose of the mean pixels of a
    static orientation), with the analytic Jacobian of :func:`_project`; converges to the pose
    :func:`~replication.study.lab.chain.camera_orientations` finds
    (``tests/study/test_lab_claims.py``) at a fraction of its cost per image.

    Parameters
    ----------
    uv : array_like, shape (M, N, 2)
        Pixels of the N wand markers in M images.
    rig : dict
        ``camera_matrix``, ``dist_coeffs``, ``wand_points``.
    C0, t0 : array_like, shapes (M, 3, 3) and (M, 3)
        Starting poses (:func:`~replication.study.lab.chain.camera_poses`).
    iterations : int
        Gauss-Newton steps (from a static orientation's mean pose each takes about two digits off
        the angle to OpenCV's answer: three leave about 1e-5 deg,
        ``tests/study/test_lab_claims.py``).

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)

    Raises
    ------
    ValueError
        If the refined poses leave a reprojection error above 5 px.
    """
    K = np.asarray(rig["camera_matrix"], dtype=float)
    dist = np.asarray(rig["dist_coeffs"], dtype=float)
    X = np.asarray(rig["wand_points"], dtype=float)
    return _gauss_newton_pnp(np.asarray(uv, dtype=float), X, K, dist, np.array(C0, dtype=float),
                             np.array(t0, dtype=float), iterations)[0]


def _gauss_newton_pnp(uv, X, K, dist, C, t, iterations):
    """Gauss-Newton on the reprojection error from the poses ``(C, t)``; ``(C, t)`` refined, checked
    to 5 px."""
    for _ in range(iterations):
        proj, J = _project(X, C, t, K, dist, jacobian=True)
        r, J = np.swapaxes(proj - uv, -1, -2).reshape(len(uv), -1, 1), J.reshape(len(uv), 6, -1)   # (u.., v..)
        step = -np.linalg.solve(J @ np.swapaxes(J, -1, -2), J @ r)[..., 0]
        C, t = matrix_from_rotation_vector(step[:, :3]) @ C, t + step[:, 3:]
    rms = np.sqrt(np.mean(np.sum((_project(X, C, t, K, dist) - uv) ** 2, axis=-1), axis=-1))
    if not (rms <= 5.0).all():
        m = int(np.argmax(~(rms <= 5.0)))
        raise ValueError(f"image {m}: PnP failed (reprojection RMS {rms[m]:.3g} px); check the intrinsics, the marker "
                         "order and that pixels are in px")
    return C, t


def ecompass_attitudes(acc, mag) -> np.ndarray:
    """:func:`static_sensor_orientations` on arrays: ``ahrs``' ``ecompass`` (ENU) for many samples
    at once.

    Parameters
    ----------
    acc, mag : array_like, shape (M, 3)

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
        ``I_t`` (body-from-world): columns ``m x a``, ``a x (m x a)``, ``a`` normalised, as
        ``ecompass``'s rows.
    """
    acc, mag = np.asarray(acc, dtype=float), np.asarray(mag, dtype=float)
    z = acc / np.linalg.norm(acc, axis=-1, keepdims=True)
    m = mag / np.linalg.norm(mag, axis=-1, keepdims=True)
    x = np.cross(m, z)
    y = np.cross(z, x)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y /= np.linalg.norm(y, axis=-1, keepdims=True)
    return np.stack([x, y, z], axis=-1)


def madgwick_marg(gyr, acc, mag, rate_hz: float, gain: float = 0.041) -> np.ndarray:
    """``ahrs.filters.Madgwick(gyr, acc, mag, frequency=rate_hz).Q`` transcribed to plain Python
    floats.

    The same operations in the same order as ``Madgwick.updateMARG`` (and ``updateIMU`` where the
    magnetometer reads zero), started like it by ``ecompass(acc[0], mag[0], frame="NED",
    representation="quaternion")``; about 8 times faster, because it skips ``ahrs``' per-sample
    array checks and small-array overheads. It agrees with ``ahrs`` to rounding where the
    accelerometer or magnetometer is noisy (``tests/study/test_lab_claims.py``); without noise on
    either, both follow rounding (:attr:`LabSettings.noise_free_dynamic_attitude`).

    Returns
    -------
    numpy.ndarray, shape (M, 4)
        Quaternions ``(w, x, y, z)`` (``world_from_sensor``).
    """
    from ahrs.common.orientation import ecompass

    gyr, acc, mag = (np.asarray(v, dtype=float) for v in (gyr, acc, mag))
    if not gyr.shape == acc.shape == mag.shape or gyr.ndim != 2 or gyr.shape[1] != 3:
        raise ValueError(f"gyr, acc and mag must have the same shape (M, 3), got {gyr.shape}, {acc.shape}, "
                         f"{mag.shape}")
    dt, beta = 1.0 / rate_hz, float(gain)
    Q = np.empty((len(gyr), 4))
    Q[0] = ecompass(acc[0], mag[0], frame="NED", representation="quaternion")
    w, x, y, z = (float(v) for v in Q[0])
    for k, (g, a, m) in enumerate(zip(gyr.tolist(), acc.tolist(), mag.tolist()), start=0):
        if k == 0:
            continue
        n = math.sqrt(w * w + x * x + y * y + z * z)                     # Quaternion(q) normalises
        w, x, y, z = w / n, x / n, y / n, z / n
        gx, gy, gz = g
        if math.sqrt(gx * gx + gy * gy + gz * gz) == 0:
            Q[k] = w, x, y, z
            continue
        dw = 0.5 * (-x * gx - y * gy - z * gz)                           # 0.5 q (x) (0, gyr)
        dx = 0.5 * (w * gx + y * gz - z * gy)
        dy = 0.5 * (w * gy - x * gz + z * gx)
        dz = 0.5 * (w * gz + x * gy - y * gx)
        ax, ay, az = a
        a_norm = math.sqrt(ax * ax + ay * ay + az * az)
        mx, my, mz = m
        m_norm = math.sqrt(mx * mx + my * my + mz * mz)
        if a_norm > 0:
            ax, ay, az = ax / a_norm, ay / a_norm, az / a_norm
            f = [2.0 * (x * z - w * y) - ax, 2.0 * (w * x + y * z) - ay, 2.0 * (0.5 - x * x - y * y) - az]
            J = [[-2.0 * y, 2.0 * z, -2.0 * w, 2.0 * x], [2.0 * x, 2.0 * w, 2.0 * z, 2.0 * y],
                 [0.0, -4.0 * x, -4.0 * y, 0.0]]
            if m_norm != 0:                                              # updateMARG; else updateIMU
                mx, my, mz = mx / m_norm, my / m_norm, mz / m_norm
                # h = q (x) (0, m) (x) q*
                pw, px, py, pz = -mx * -x - my * -y - mz * -z, mx * w + my * -z - mz * -y, \
                    -mx * -z + my * w + mz * -x, mx * -y - my * -x + mz * w
                hx = w * px + x * pw + y * pz - z * py
                hy = w * py - x * pz + y * pw + z * px
                hz = w * pz + x * py - y * px + z * pw
                bx, bz = math.sqrt(hx * hx + hy * hy), hz
                f += [2.0 * bx * (0.5 - y * y - z * z) + 2.0 * bz * (x * z - w * y) - mx,
                      2.0 * bx * (x * y - w * z) + 2.0 * bz * (w * x + y * z) - my,
                      2.0 * bx * (w * y + x * z) + 2.0 * bz * (0.5 - x * x - y * y) - mz]
                J += [[-2.0 * bz * y, 2.0 * bz * z, -4.0 * bx * y - 2.0 * bz * w, -4.0 * bx * z + 2.0 * bz * x],
                      [-2.0 * bx * z + 2.0 * bz * x, 2.0 * bx * y + 2.0 * bz * w, 2.0 * bx * x + 2.0 * bz * z,
                       -2.0 * bx * w + 2.0 * bz * y],
                      [2.0 * bx * y, 2.0 * bx * z - 4.0 * bz * x, 2.0 * bx * w - 4.0 * bz * y, 2.0 * bx * x]]
            if math.sqrt(sum([v * v for v in f])) > 0:
                grad = [0.0, 0.0, 0.0, 0.0]
                for row, fi in zip(J, f):                                # J^T f
                    grad = [g + r * fi for g, r in zip(grad, row)]
                gn = math.sqrt(grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2] + grad[3] * grad[3])
                dw, dx, dy, dz = (dw - beta * grad[0] / gn, dx - beta * grad[1] / gn, dy - beta * grad[2] / gn,
                                  dz - beta * grad[3] / gn)
        w, x, y, z = w + dw * dt, x + dx * dt, y + dy * dt, z + dz * dt
        n = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / n, x / n, y / n, z / n
        Q[k] = w, x, y, z
    return Q
