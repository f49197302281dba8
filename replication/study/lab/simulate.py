"""The simulated lab of Sec. III-B from first principles: camera, wand, IMU and the protocol. Theory
and measured numbers: ``docs/studies.md``, section ``replication.study.lab.simulate``."""
from __future__ import annotations

import cv2
import numpy as np
import pandas as pd

from ...core.so3 import matrix_from_euler, matrix_from_rotation_vector, rotation_vector_from_matrix
from .recording import IMU_COLUMNS, UNITS, LabRecording, _marker_columns
from .settings import GRAVITY, NOMINAL_CAMERA_FROM_SENSOR, WAND_POINTS, LabSettings

__all__ = ["simulate_lab"]


def _small_rotations(rng, sigma_deg, size):
    """Rotations with rotation vectors ~ N(0, sigma^2 I) (degrees), shape size + (3, 3)."""
    rotvec = rng.normal(0.0, 1.0, size + (3,)) * np.deg2rad(sigma_deg)
    return matrix_from_rotation_vector(rotvec)


def _sensor_error_matrix(rng, scale_error, misalignment_deg):
    """``I + diag(scale) + off-diagonal misalignment``: maps true to measured vectors."""
    scale = rng.normal(0.0, 1.0, 3) * scale_error
    cross = rng.normal(0.0, 1.0, (3, 3)) * np.deg2rad(misalignment_deg)
    np.fill_diagonal(cross, 0.0)
    return np.eye(3) + np.diag(scale) + cross


def _look_at(position, target, roll_deg):
    """``camera_from_wand`` of a camera at ``position`` looking at ``target``, rolled about its
    axis."""
    z = target - position
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    x = np.cross(z, np.array([0.0, 1.0, 0.0]))
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    C = np.stack([x, y, z], axis=-2)
    return matrix_from_euler("z", np.reshape(roll_deg, (-1, 1)), degrees=True).reshape(C.shape) @ C


def _project(settings, C, position, rng, n_frames):
    """Marker pixels of ``n_frames`` frames of each pose (``C``, ``position``): shape (P, F, N,
    2)."""
    w, h = settings.image_size
    K = np.array([[settings.focal_px, 0, w / 2], [0, settings.focal_px, h / 2], [0, 0, 1.0]])
    dist = np.array(settings.distortion, dtype=float)
    clean = np.empty((len(C), len(WAND_POINTS), 2))
    for p, (Cp, pos) in enumerate(zip(C, position)):
        rvec, _ = cv2.Rodrigues(Cp)
        pts, _ = cv2.projectPoints(WAND_POINTS, rvec, -Cp @ pos, K, dist)
        clean[p] = pts[:, 0, :]
    margin = 10.0
    inside = ((clean[..., 0] > margin) & (clean[..., 0] < w - margin)
              & (clean[..., 1] > margin) & (clean[..., 1] < h - margin))
    noise = rng.normal(0.0, 1.0, (len(C), n_frames) + clean.shape[1:]) * settings.pixel_noise_px
    return clean[:, None] + noise, inside.all(axis=-1)


def _calibrated_intrinsics(settings, rng):
    """The intrinsics a checkerboard calibration would report (true ones plus a residual error)."""
    w, h = settings.image_size
    f = settings.focal_px * (1.0 + settings.focal_error * rng.normal())
    c = np.array([w / 2, h / 2]) + settings.principal_point_error_px * rng.normal(size=2)
    dist = np.array(settings.distortion, dtype=float)
    dist[0] += settings.k1_error * rng.normal()
    # rounded to 1e-6, as a calibration file would store them (and so the written rig equals this)
    return np.round(np.array([[f, 0, c[0]], [0, f, c[1]], [0, 0, 1.0]]), 6), np.round(dist, 6)


class _IMU:
    """One simulated node: fixed error parameters, measurements of given true signals."""

    def __init__(self, settings, rng):
        s = settings
        self.s = s
        self.acc_M = _sensor_error_matrix(rng, s.acc_scale_error, s.acc_misalignment_deg)
        self.acc_bias = rng.normal(0.0, 1.0, 3) * s.acc_bias_mg * 1e-3 * GRAVITY
        self.gyr_M = _sensor_error_matrix(rng, s.gyr_scale_error, s.gyr_misalignment_deg)
        self.gyr_bias = rng.normal(0.0, 1.0, 3) * np.deg2rad(s.gyr_bias_dps)
        M = _sensor_error_matrix(rng, s.mag_soft_iron, 0.0)
        self.mag_M = M @ _small_rotations(rng, s.mag_misalignment_deg, ())
        self.mag_bias = rng.normal(0.0, 1.0, 3) * s.mag_hard_iron_ut
        self.acc_sigma = np.array(s.acc_noise_density_ug) * 1e-6 * GRAVITY * np.sqrt(s.imu_rate_hz / 2)

    def measure(self, rng, specific_force, rate, field):
        """Raw samples ``(n, 9)``: acc (m/s^2), gyr (rad/s), mag (uT) from true signals in the
        sensor frame."""
        n = len(specific_force)
        s = self.s
        acc = specific_force @ self.acc_M.T + self.acc_bias + rng.normal(0.0, 1.0, (n, 3)) * self.acc_sigma
        gyr = rate @ self.gyr_M.T + self.gyr_bias + rng.normal(0.0, 1.0, (n, 3)) * np.deg2rad(s.gyr_noise_dps)
        mag = field @ self.mag_M.T + self.mag_bias + rng.normal(0.0, 1.0, (n, 3)) * s.mag_noise_ut
        hold = max(int(round(s.imu_rate_hz / s.mag_rate_hz)), 1)
        mag = mag[(np.arange(n) // hold) * hold]  # HMC5843: at most 50 Hz, each sample held
        return np.hstack([acc, gyr, mag])


def _world_field(settings, rng, size=()):
    """Earth's field in the wand frame (north at a fixed heading), deflected per pose."""
    incl = np.deg2rad(settings.inclination_deg)
    heading = np.deg2rad(30.0)
    north = np.array([np.sin(heading), 0.0, np.cos(heading)])
    up = np.array([0.0, 1.0, 0.0])
    b = settings.field_ut * (np.cos(incl) * north - np.sin(incl) * up)
    return _small_rotations(rng, settings.field_deflection_deg, size) @ b


def _marker_frame(uv):
    """(F, N, 2) pixels -> (F, 2N) columns u0..u{N-1}, v0..v{N-1}."""
    return np.concatenate([uv[..., 0], uv[..., 1]], axis=-1)


def _static_poses(settings, rng, n):
    """``n`` random camera poses facing the wand (camera_from_wand, position), all markers in
    view."""
    C, P = [], []
    while len(C) < n:
        m = 4 * n
        d = rng.uniform(*settings.distance_m, m)
        az = np.deg2rad(rng.uniform(-40, 40, m))
        el = np.deg2rad(rng.uniform(-25, 25, m))
        pos = d[:, None] * np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], axis=-1)
        target = rng.normal(0.0, 0.15, (m, 3))
        roll = rng.uniform(-settings.max_roll_deg, settings.max_roll_deg, m)
        Cm = _look_at(pos, target, roll)
        _, ok = _project(settings, Cm, pos, rng, 0)
        C.extend(Cm[ok])
        P.extend(pos[ok])
    return np.array(C[:n]), np.array(P[:n])


def simulate_lab(settings: LabSettings = LabSettings()) -> LabRecording:
    """Simulate the lab recordings of Sec. III-B (static data sets and the dynamic trial).

    Parameters
    ----------
    settings : LabSettings
        Every setting, with its seed; :meth:`LabSettings.without` switches sources off.

    Returns
    -------
    LabRecording
        Raw samples as recorded, the rig file's contents (calibrated intrinsics), and the
        true ``camera_from_sensor`` in ``truth``.

    Notes
    -----
    Each random stream has its own child generator (``SeedSequence.spawn``), so
    switching one error source off leaves every other draw as it was.
    """
    s = settings
    streams = np.random.SeedSequence(s.seed).spawn(6)
    rng_pose, rng_pix, rng_imu_par, rng_imu, rng_field, rng_rig = (np.random.default_rng(x) for x in streams)

    r0 = _small_rotations(rng_rig, s.mount_error_deg / np.sqrt(3), ()) @ NOMINAL_CAMERA_FROM_SENSOR
    K, dist = _calibrated_intrinsics(s, rng_rig)
    imu = _IMU(s, rng_imu_par)
    lever = np.array([0.0, -1.0, -0.5]) / np.sqrt(1.25) * s.lever_arm_m  # above and behind the pivot
    up = np.array([0.0, 1.0, 0.0])
    n_imu = int(np.ceil(s.static_seconds * s.imu_rate_hz))
    n_cam = int(np.ceil(s.static_seconds * s.camera_rate_hz))

    imu_rows, marker_rows = [], []
    for k in range(s.n_sets):
        n_pose = int(rng_pose.integers(s.poses_per_set[0], s.poses_per_set[1] + 1))
        C, pos = _static_poses(s, rng_pose, n_pose)
        uv, _ = _project(s, C, pos, rng_pix, n_cam)
        I = r0.T @ C                                                   # eq. (1): C = R0 I
        fields = _world_field(s, rng_field, (n_pose,))
        for p in range(n_pose):
            t0 = p * (s.static_seconds + 10.0)                          # 10 s to move between poses
            t_imu = t0 + np.arange(n_imu) / s.imu_rate_hz
            f = np.broadcast_to(I[p] @ (GRAVITY * up), (n_imu, 3))      # at rest: specific force = -g
            raw = imu.measure(rng_imu, f, np.zeros((n_imu, 3)), np.broadcast_to(I[p] @ fields[p], (n_imu, 3)))
            imu_rows.append(np.column_stack([np.full(n_imu, k), np.full(n_imu, p), t_imu, raw]))
            t_cam = t0 + np.arange(n_cam) / s.camera_rate_hz
            marker_rows.append(np.column_stack([np.full(n_cam, k), np.full(n_cam, p), t_cam, _marker_frame(uv[p])]))

    # dynamic trial: pan / tilt / roll sinusoids about a pivot 2 m in front of the wand
    t_imu = np.arange(int(round(s.dynamic_seconds * s.imu_rate_hz))) / s.imu_rate_hz
    t_cam = np.arange(int(round(s.dynamic_seconds * s.camera_rate_hz))) / s.camera_rate_hz
    pivot = np.array([0.3, 0.2, 2.0])
    C0 = _look_at(pivot, np.zeros(3), 0.0)
    amp, period = np.deg2rad(s.dynamic_amplitude_deg), np.array(s.dynamic_period_s)

    def camera_from_wand(t):
        angles = amp * np.sin(2 * np.pi * np.asarray(t)[:, None] / period)
        # body-fixed pan (camera y), tilt (camera x), roll (camera z): world_from_camera = C0^T Ry
        # Rx Rz
        motion = matrix_from_euler("YXZ", angles)
        return np.swapaxes(C0.T @ motion, -1, -2)

    def sensor_position(t):
        return pivot + np.swapaxes(camera_from_wand(t), -1, -2) @ lever

    h = 1e-3
    I_dyn = r0.T @ camera_from_wand(t_imu)
    Ip, Im = r0.T @ camera_from_wand(t_imu + h), r0.T @ camera_from_wand(t_imu - h)
    # body rate from world_from_sensor Q = I^T: Q(t+h) = Q(t-h) exp([w] 2h)
    rate = rotation_vector_from_matrix(Im @ np.swapaxes(Ip, -1, -2)) / (2 * h)
    accel = (sensor_position(t_imu + h) - 2 * sensor_position(t_imu) + sensor_position(t_imu - h)) / h**2
    f = np.einsum("nij,nj->ni", I_dyn, accel + GRAVITY * up)
    b = _world_field(s, rng_field)
    raw = imu.measure(rng_imu, f, rate, np.einsum("nij,j->ni", I_dyn, b))
    C_cam = camera_from_wand(t_cam)
    uv, inside = _project(s, C_cam, np.broadcast_to(pivot, (len(t_cam), 3)), rng_pix, 1)
    if not inside.all():
        raise ValueError("dynamic trial: the wand leaves the image; reduce dynamic_amplitude_deg")

    n_markers = len(WAND_POINTS)
    rig = {
        "camera_matrix": K.tolist(),
        "dist_coeffs": dist.tolist(),
        "image_size": list(s.image_size),
        "wand_points": WAND_POINTS.tolist(),
        "imu_rate_hz": s.imu_rate_hz,
        "camera_rate_hz": s.camera_rate_hz,
        "units": dict(UNITS),
    }
    imu_cols = ["set", "pose", "t"] + IMU_COLUMNS
    marker_cols = ["set", "pose", "t"] + _marker_columns(n_markers)
    static_imu = pd.DataFrame(np.vstack(imu_rows), columns=imu_cols).astype({"set": int, "pose": int})
    static_markers = pd.DataFrame(np.vstack(marker_rows), columns=marker_cols).astype({"set": int, "pose": int})
    dynamic_imu = pd.DataFrame(np.column_stack([t_imu, raw]), columns=imu_cols[2:])
    dynamic_markers = pd.DataFrame(np.column_stack([t_cam, _marker_frame(uv[:, 0])]), columns=marker_cols[2:])
    return LabRecording(rig, static_imu, static_markers, dynamic_imu, dynamic_markers,
                        truth={"camera_from_sensor": r0})
