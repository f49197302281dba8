"""A simulated version of the paper's lab experiment (Sec. III-B, Fig. 6-7, Table II).

The paper's recordings (a BSN node on a robot's top camera, a 9-marker calibration
wand) are not public. This module simulates that lab from first principles, so that
the full chain of the experiment runs from raw data:

* **camera**: a pinhole camera with lens distortion looks at a wand of 9 markers at
  known, non-coplanar 3-D positions; marker pixels come from ``cv2.projectPoints``
  plus pixel noise; the camera orientation is recovered with ``cv2.solvePnP`` (the
  role of the paper's ref. [38]) using the *calibrated* intrinsics, which carry a
  residual calibration error;
* **IMU**: accelerometer, gyroscope and magnetometer samples at 100 Hz with white
  noise, bias, scale and axis misalignment of the size the parts' datasheets give
  (ADXL330, ITG-3200, HMC5843; see :class:`LabSettings`);
* **static protocol**: ``n_sets`` data sets of 10-20 static orientations facing the
  wand, at least 5 s each; the mean of the measurements at each orientation gives
  one camera orientation (PnP on the mean marker pixels) and one sensor orientation
  (accelerometer + magnetometer, ``ahrs.common.orientation.ecompass``);
* **dynamic trial**: slow rotations within a small volume; the sensor orientation
  comes from a Madgwick MARG filter (``ahrs.filters.Madgwick``) and is projected to
  the camera frame as ``R0 Delta R_i R0^T`` (the paper's Sec. III-B).

Conventions
-----------
* ``R0`` is ``camera_from_sensor``: ``v_camera = R0 v_sensor``. The paper's ``C_t``
  and ``I_t`` are body-from-world attitudes, ``C_t = R0 I_t`` (eq. (1)), and the
  relative rotations are ``Delta R_c = C_k C_t^T``, ``Delta R_i = I_k I_t^T`` (eqs. (3)-(4)),
  so that ``Delta R_c R0 = R0 Delta R_i`` (eq. (5)); see
  :func:`replication.handeye.relative_rotations`.
* The wand frame ``W`` is the camera's world: x right, y up, z out of the wand
  towards the camera. ``solvePnP`` returns ``camera_from_wand``, i.e. ``C_t``.
* The sensor's world is the local gravity / magnetic frame of ``ecompass`` and of
  the Madgwick filter; only relative rotations are used, so the two worlds need not
  be related.
* Roll, pitch, yaw are the intrinsic ``z-y'-x''`` angles of a relative rotation,
  ``Delta R = Rz(yaw) Ry(pitch) Rx(roll)``, in degrees.

Every random draw comes from a ``numpy.random.Generator`` seeded by
``LabSettings.seed``; switching an error source off (:meth:`LabSettings.without`)
keeps every other draw unchanged, so the ablation compares like with like.
"""
from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field

import cv2
import numpy as np
import pandas as pd
from scipy.spatial.transform import Rotation

from .handeye import relative_rotations
from .realdata import OrientationStream
from .so3 import angle_between_deg, log_map, nearest_rotation, quaternion_to_matrix, rotation_angle_deg
from .solvers import ReplicationWarning, solve

__all__ = [
    "GRAVITY", "WAND_POINTS", "SOURCES", "PARTS", "TABLE2_SOLVERS", "LabSettings", "LabRecording", "LabResult",
    "simulate_lab", "camera_orientations", "static_sensor_orientations", "dynamic_sensor_orientations",
    "ACC_COLUMNS", "GYR_COLUMNS", "MAG_COLUMNS", "IMU_COLUMNS", "UNITS", "marker_pixels", "static_hold_seconds",
    "static_motions", "euler_rpy_deg", "attitude_statistics", "run_lab", "summarize", "ablation", "sensitivity",
    "table2_versus_paper",
]

#: Standard gravity (m/s^2).
GRAVITY = 9.80665

#: The calibration wand: 9 markers in the wand frame (metres), a 3 x 3 grid of 25 cm
#: pitch whose markers stand 0-20 cm proud of the board at distinct heights, so the
#: points are not coplanar and no rotation of the wand maps it onto itself (the
#: marker identities are unambiguous).
WAND_POINTS = np.array(
    [[-0.25, 0.25, 0.00], [0.00, 0.25, 0.10], [0.25, 0.25, 0.05],
     [-0.25, 0.00, 0.10], [0.00, 0.00, 0.20], [0.25, 0.00, 0.00],
     [-0.25, -0.25, 0.05], [0.00, -0.25, 0.00], [0.25, -0.25, 0.15]]
)

#: Nominal mounting of the node on the camera: sensor x forward, y left, z up;
#: camera x right, y down, z forward (columns: the sensor axes in camera coordinates).
NOMINAL_CAMERA_FROM_SENSOR = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])

#: Table II's columns: the registered solver behind each and its options. The two-step
#: method runs to its limit (its default ``iterations="auto"``; the paper does not state
#: its iteration count, and between poses that all face the wand the motions are at most
#: about 60 deg, which needs 70-95 iterations). SQP starts at the identity, like the
#: two-step method.
TABLE2_SOLVERS = {
    "optimization": ("sqp", {}),
    "ours_right": ("two_step_right", {}),
    "ours_left": ("two_step_left", {}),
}

#: Error sources of the ablation: name -> the settings switched off (set to zero).
SOURCES = {
    "pixel noise": ("pixel_noise_px",),
    "intrinsics calibration error": ("focal_error", "principal_point_error_px", "k1_error"),
    "accelerometer errors": ("acc_noise_density_ug", "acc_bias_mg", "acc_scale_error", "acc_misalignment_deg"),
    "gyroscope errors": ("gyr_noise_dps", "gyr_bias_dps", "gyr_scale_error", "gyr_misalignment_deg"),
    "magnetometer errors": ("mag_noise_ut", "mag_hard_iron_ut", "mag_soft_iron", "mag_misalignment_deg"),
    "magnetic field deflection": ("field_deflection_deg",),
    "lever-arm acceleration": ("lever_arm_m",),
}

#: Parts of an error source, for finer interventions (:meth:`LabSettings.without` takes these names too):
#: the magnetometer's random noise apart from its residual calibration errors.
PARTS = {
    "magnetometer noise": ("mag_noise_ut",),
    "magnetometer calibration errors": ("mag_hard_iron_ut", "mag_soft_iron", "mag_misalignment_deg"),
}


@dataclass(frozen=True)
class LabSettings:
    """Every setting of the simulated lab, with its default and the reason for it.

    Datasheet figures (typical values) are marked [ADXL330], [ITG-3200], [HMC5843]:
    Analog Devices ADXL330 data sheet Rev. A (2007); InvenSense ITG-3200 Product
    Specification Rev. 1.4 (2010); Honeywell HMC5843 data sheet (2009). The node was
    "properly calibrated" (Sec. III), so biases, scales and misalignments are the
    *residuals after calibration*; their sizes are our assumptions, stated per field.

    Attributes
    ----------
    seed : int
        Seed of the one ``numpy.random.Generator`` behind every draw.
    n_sets : int
        Data sets (paper: 10).
    poses_per_set : tuple of int
        Inclusive range of static orientations per set (paper: 10-20).
    static_seconds : float
        Recorded seconds per static orientation (paper: at least 5 s).
    imu_rate_hz, camera_rate_hz : float
        Sample rates. 100 Hz for the IMU (issue; BSN nodes stream at about 100 Hz);
        25 Hz for the camera (assumption: a PAL-rate robot camera).
    mag_rate_hz : float
        HMC5843 output rate; its fastest is 50 Hz [HMC5843], so each magnetometer
        sample is held for two IMU samples.
    dynamic_seconds : float
        Length of the dynamic trial.
    dynamic_amplitude_deg, dynamic_period_s : tuple of 3 float
        Pan, tilt and roll of the dynamic trial: sinusoids of these amplitudes and
        periods ("rotated slowly", keeping the wand in view).
    image_size : tuple of int
        (width, height) in pixels; VGA (assumption).
    focal_px : float
        Focal length; 450 px gives a 70 degree horizontal field of view (assumption).
    distortion : tuple of 5 float
        True lens distortion (k1, k2, p1, p2, k3): a moderate barrel lens (assumption).
    focal_error, principal_point_error_px, k1_error : float
        Error of the *calibrated* intrinsics that PnP uses: 0.5 % focal length,
        2 px principal point, 0.01 in k1 (assumption: a typical checkerboard
        calibration residual).
    pixel_noise_px : float
        Standard deviation of the marker centroid noise per axis (assumption: 0.3 px
        for blob centroids).
    distance_m : tuple of float
        Range of camera-wand distances of the static orientations (assumption).
    max_roll_deg : float
        Largest roll about the optical axis of a static orientation (assumption).
    acc_noise_density_ug : tuple of 3 float
        280, 280, 350 micro-g/sqrt(Hz) for x, y, z [ADXL330], over a 50 Hz bandwidth.
    acc_bias_mg : float
        Residual bias per axis (standard deviation); 0 g offset drifts about
        1 mg/degC [ADXL330], so a few degrees of warm-up leave about 5 mg (assumption).
    acc_scale_error : float
        Residual scale error per axis; the nonlinearity is 0.3 % of full scale [ADXL330].
    acc_misalignment_deg : float
        Residual non-orthogonality per axis pair; inter-axis alignment 0.1 deg [ADXL330].
    gyr_noise_dps : float
        White noise per sample: total RMS noise 0.38 deg/s [ITG-3200].
    gyr_bias_dps : float
        Residual bias per axis after a still-period calibration; the zero-rate output
        drifts with temperature (ZRO +-40 deg/s over -40..85 degC [ITG-3200]), so we
        assume 0.5 deg/s.
    gyr_scale_error : float
        Residual scale error; sensitivity tolerance is 6 % before calibration
        [ITG-3200], 0.5 % after (assumption).
    gyr_misalignment_deg : float
        Residual cross-axis misalignment; cross-axis sensitivity is 2 % (1.1 deg)
        [ITG-3200], 0.5 deg after calibration (assumption).
    mag_noise_ut : float
        Noise per sample: the 7 milli-gauss resolution [HMC5843] = 0.7 micro-tesla.
    mag_hard_iron_ut, mag_soft_iron : float
        Residual hard-iron offset (micro-tesla per axis) and soft-iron scale/cross
        terms after an ellipsoid calibration (assumption: 1 uT, 1 %).
    mag_misalignment_deg : float
        Misalignment of the magnetometer axes to the accelerometer's (assumption: 0.5 deg;
        the HMC5843 is a separate package on the sensor board).
    field_ut, inclination_deg : float
        Earth's field in London, where the BSN was developed (about 49 uT, inclination
        66 deg; World Magnetic Model).
    field_deflection_deg : float
        Lab disturbance: the field direction differs between static orientations by
        this standard deviation per axis (steel furniture, the robot's motors;
        assumption). It is constant during the dynamic trial ("a small volume").
    lever_arm_m : float
        Distance from the camera's centre of rotation to the node; it turns rotation
        into linear acceleration that the accelerometer also sees (assumption: 8 cm).
    mount_error_deg : float
        How far the true ``R0`` is from the nominal mounting (assumption: 3 deg).
    """

    seed: int = 20130501
    n_sets: int = 10
    poses_per_set: tuple = (10, 20)
    static_seconds: float = 5.2
    imu_rate_hz: float = 100.0
    camera_rate_hz: float = 25.0
    mag_rate_hz: float = 50.0
    dynamic_seconds: float = 60.0
    dynamic_amplitude_deg: tuple = (15.0, 10.0, 40.0)
    dynamic_period_s: tuple = (17.0, 11.0, 13.0)
    image_size: tuple = (640, 480)
    focal_px: float = 450.0
    distortion: tuple = (-0.25, 0.08, 0.001, -0.001, 0.0)
    focal_error: float = 0.005
    principal_point_error_px: float = 2.0
    k1_error: float = 0.01
    pixel_noise_px: float = 0.3
    distance_m: tuple = (1.5, 2.5)
    max_roll_deg: float = 45.0
    acc_noise_density_ug: tuple = (280.0, 280.0, 350.0)
    acc_bias_mg: float = 5.0
    acc_scale_error: float = 0.003
    acc_misalignment_deg: float = 0.1
    gyr_noise_dps: float = 0.38
    gyr_bias_dps: float = 0.5
    gyr_scale_error: float = 0.005
    gyr_misalignment_deg: float = 0.5
    mag_noise_ut: float = 0.7
    mag_hard_iron_ut: float = 1.0
    mag_soft_iron: float = 0.01
    mag_misalignment_deg: float = 0.5
    field_ut: float = 49.0
    inclination_deg: float = 66.0
    field_deflection_deg: float = 1.0
    lever_arm_m: float = 0.08
    mount_error_deg: float = 3.0

    def without(self, *sources: str) -> "LabSettings":
        """These settings with the named error sources (keys of :data:`SOURCES` or :data:`PARTS`) switched off."""
        known = {**SOURCES, **PARTS}
        unknown = [s for s in sources if s not in known]
        if unknown:
            raise ValueError(f"unknown error source(s) {unknown}; known: {list(known)}")
        off = {}
        for s in sources:
            for name in known[s]:
                value = getattr(self, name)
                off[name] = tuple(0.0 for _ in value) if isinstance(value, tuple) else 0.0
        return dataclasses.replace(self, **off)

    @property
    def noise_free_dynamic_attitude(self) -> bool:
        """Whether the accelerometer and magnetometer carry no random noise.

        The Madgwick filter's correction is a *normalised* gradient step of fixed size; with
        noise-free accelerometer and magnetometer the gradient is zero up to rounding and its
        direction, hence the filter's chatter in the dynamic trial, is set by rounding: Table II's
        statistics then change at the 1e-3 deg level between CPUs and BLAS kernels
        (demonstrated in ``tests/test_lab.py``). With either noise on they do not.
        """
        return not np.any(self.acc_noise_density_ug) and not self.mag_noise_ut

    def exact(self) -> "LabSettings":
        """Every error source switched off (the chain must then recover ``R0``)."""
        return self.without(*SOURCES)


@dataclass
class LabRecording:
    """What the lab records: the rig description and four tables of raw samples.

    Attributes
    ----------
    rig : dict
        ``camera_matrix`` (3 x 3), ``dist_coeffs`` (5), ``image_size`` (w, h) -- the
        *calibrated* intrinsics --, ``wand_points`` (N x 3, metres), ``imu_rate_hz``,
        ``camera_rate_hz`` and ``units``. Schema: ``data/README.md``.
    static_imu, dynamic_imu : pandas.DataFrame
        Columns ``set, pose`` (static only), ``t`` (s), ``acc_x..z`` (m/s^2),
        ``gyr_x..z`` (rad/s), ``mag_x..z`` (micro-tesla), in the sensor frame.
    static_markers, dynamic_markers : pandas.DataFrame
        Columns ``set, pose`` (static only), ``t`` (s), ``u0..u{N-1}``, ``v0..v{N-1}``
        (pixels, distorted image).
    truth : dict
        Simulation only (a real recording has none): ``camera_from_sensor`` (3 x 3).
    """

    rig: dict
    static_imu: pd.DataFrame
    static_markers: pd.DataFrame
    dynamic_imu: pd.DataFrame
    dynamic_markers: pd.DataFrame
    truth: dict = field(default_factory=dict)


# ----------------------------------------------------------------------------- simulation

def _small_rotations(rng, sigma_deg, size):
    """Rotations with rotation vectors ~ N(0, sigma^2 I) (degrees), shape size + (3, 3)."""
    rotvec = rng.normal(0.0, 1.0, size + (3,)) * np.deg2rad(sigma_deg)
    return Rotation.from_rotvec(rotvec.reshape(-1, 3)).as_matrix().reshape(size + (3, 3))


def _sensor_error_matrix(rng, scale_error, misalignment_deg):
    """``I + diag(scale) + off-diagonal misalignment``: maps true to measured vectors."""
    scale = rng.normal(0.0, 1.0, 3) * scale_error
    cross = rng.normal(0.0, 1.0, (3, 3)) * np.deg2rad(misalignment_deg)
    np.fill_diagonal(cross, 0.0)
    return np.eye(3) + np.diag(scale) + cross


def _look_at(position, target, roll_deg):
    """``camera_from_wand`` of a camera at ``position`` looking at ``target``, rolled about its axis."""
    z = target - position
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    x = np.cross(z, np.array([0.0, 1.0, 0.0]))
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    C = np.stack([x, y, z], axis=-2)
    return Rotation.from_euler("z", np.reshape(roll_deg, (-1, 1)), degrees=True).as_matrix().reshape(C.shape) @ C


def _project(settings, C, position, rng, n_frames):
    """Marker pixels of ``n_frames`` frames of each pose (``C``, ``position``): shape (P, F, N, 2)."""
    w, h = settings.image_size
    K = np.array([[settings.focal_px, 0, w / 2], [0, settings.focal_px, h / 2], [0, 0, 1.0]])
    dist = np.array(settings.distortion, dtype=float)
    clean = np.empty((len(C), len(WAND_POINTS), 2))
    for p, (Cp, pos) in enumerate(zip(C, position)):
        rvec, _ = cv2.Rodrigues(Cp)
        pts, _ = cv2.projectPoints(WAND_POINTS, rvec, -Cp @ pos, K, dist)
        clean[p] = pts[:, 0, :]
    margin = 10.0
    inside = (clean[..., 0] > margin) & (clean[..., 0] < w - margin) & (clean[..., 1] > margin) & (clean[..., 1] < h - margin)
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
        """Raw samples ``(n, 9)``: acc (m/s^2), gyr (rad/s), mag (uT) from true signals in the sensor frame."""
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


ACC_COLUMNS, GYR_COLUMNS, MAG_COLUMNS = (["acc_x", "acc_y", "acc_z"], ["gyr_x", "gyr_y", "gyr_z"],
                                         ["mag_x", "mag_y", "mag_z"])
IMU_COLUMNS = ACC_COLUMNS + GYR_COLUMNS + MAG_COLUMNS


def _marker_columns(n):
    return [f"u{i}" for i in range(n)] + [f"v{i}" for i in range(n)]


def marker_pixels(markers: pd.DataFrame, n: int) -> np.ndarray:
    """Columns ``u0..u{n-1}, v0..v{n-1}`` of a marker table as pixels, shape (M, n, 2)."""
    uv = markers[_marker_columns(n)].to_numpy(dtype=float)
    return np.stack([uv[:, :n], uv[:, n:]], axis=-1)


def static_hold_seconds(static_imu: pd.DataFrame, imu_rate_hz: float) -> pd.Series:
    """How long each static orientation was recorded: ``t_last - t_first + 1 / rate``, indexed by (set, pose)."""
    t = static_imu.groupby(["set", "pose"])["t"]
    return t.last() - t.first() + 1.0 / imu_rate_hz


def _marker_frame(uv):
    """(F, N, 2) pixels -> (F, 2N) columns u0..u{N-1}, v0..v{N-1}."""
    return np.concatenate([uv[..., 0], uv[..., 1]], axis=-1)


def _static_poses(settings, rng, n):
    """``n`` random camera poses facing the wand (camera_from_wand, position), all markers in view."""
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
        # body-fixed pan (camera y), tilt (camera x), roll (camera z): world_from_camera = C0^T Ry Rx Rz
        motion = Rotation.from_euler("YXZ", angles).as_matrix()
        return np.swapaxes(C0.T @ motion, -1, -2)

    def sensor_position(t):
        return pivot + np.swapaxes(camera_from_wand(t), -1, -2) @ lever

    h = 1e-3
    I_dyn = r0.T @ camera_from_wand(t_imu)
    Ip, Im = r0.T @ camera_from_wand(t_imu + h), r0.T @ camera_from_wand(t_imu - h)
    # body rate from world_from_sensor Q = I^T: Q(t+h) = Q(t-h) exp([w] 2h)
    rate = Rotation.from_matrix(Im @ np.swapaxes(Ip, -1, -2)).as_rotvec() / (2 * h)
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


#: Units of the recordings (checked by the loader).
UNITS = {"t": "s", "acc": "m/s^2", "gyr": "rad/s", "mag": "uT", "uv": "px", "wand_points": "m"}


# ----------------------------------------------------------------------------- the chain

def camera_orientations(uv, rig) -> np.ndarray:
    """Camera attitudes ``C = camera_from_wand`` from marker pixels by PnP (the paper's ref. [38]).

    Parameters
    ----------
    uv : array_like, shape (M, N, 2)
        Pixels of the N wand markers in M images (distorted, as detected).
    rig : dict
        ``camera_matrix``, ``dist_coeffs``, ``wand_points`` (see :class:`LabRecording`).

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
        ``C_t`` (body-from-world, the wand frame being the camera's world).

    Raises
    ------
    ValueError
        If PnP fails or leaves a reprojection error above 5 px (wrong intrinsics,
        marker order or units).
    """
    K = np.asarray(rig["camera_matrix"], dtype=float)
    dist = np.asarray(rig["dist_coeffs"], dtype=float)
    X = np.asarray(rig["wand_points"], dtype=float)
    uv = np.ascontiguousarray(uv, dtype=float)
    out = np.empty((len(uv), 3, 3))
    for m, x in enumerate(uv):
        ok, rvec, tvec = cv2.solvePnP(X, x, K, dist, flags=cv2.SOLVEPNP_SQPNP)
        if ok:
            rvec, tvec = cv2.solvePnPRefineLM(X, x, K, dist, rvec, tvec)
            proj, _ = cv2.projectPoints(X, rvec, tvec, K, dist)
            rms = float(np.sqrt(np.mean(np.sum((proj[:, 0] - x) ** 2, axis=-1))))
        if not ok or rms > 5.0:
            raise ValueError(f"image {m}: PnP failed (reprojection RMS {rms if ok else float('nan'):.3g} px); "
                             "check the intrinsics, the marker order and that pixels are in px")
        out[m] = cv2.Rodrigues(rvec)[0]
    return out


def static_sensor_orientations(acc, mag) -> np.ndarray:
    """Sensor attitudes ``I = sensor_from_world`` from accelerometer + magnetometer (static).

    Uses ``ahrs.common.orientation.ecompass`` (ENU): the world's z axis is the measured
    specific force (up), x the horizontal part of the field.

    Parameters
    ----------
    acc, mag : array_like, shape (M, 3)
        Mean accelerometer (m/s^2) and magnetometer (any unit) vectors, sensor frame.

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
        ``I_t`` (body-from-world).
    """
    from ahrs.common.orientation import ecompass

    acc, mag = np.asarray(acc, dtype=float), np.asarray(mag, dtype=float)
    # ecompass returns the world_from_sensor matrix; I_t is its transpose
    Q = np.array([ecompass(a, m, frame="ENU", representation="rotmat") for a, m in zip(acc, mag)])
    return np.swapaxes(Q, -1, -2)


def dynamic_sensor_orientations(imu: pd.DataFrame, rate_hz: float) -> np.ndarray:
    """Sensor attitudes ``I = sensor_from_world`` of a moving node from a Madgwick MARG filter.

    ``ahrs.filters.Madgwick`` (S. Madgwick, "An efficient orientation filter for
    inertial and inertial/magnetic sensor arrays", 2010) with its default MARG gain
    0.041, started by ``ecompass`` on the first sample.

    Returns
    -------
    numpy.ndarray, shape (M, 3, 3)
    """
    from ahrs.filters import Madgwick

    q = Madgwick(gyr=imu[GYR_COLUMNS].to_numpy(), acc=imu[ACC_COLUMNS].to_numpy(), mag=imu[MAG_COLUMNS].to_numpy(),
                 frequency=rate_hz).Q
    return np.swapaxes(quaternion_to_matrix(q), -1, -2)  # Madgwick's q is world_from_sensor (w, x, y, z)


def _chordal_mean(R):
    return nearest_rotation(np.sum(R, axis=-3))


def static_motions(recording: LabRecording, *, sample: str = "mean") -> dict:
    """Camera and sensor relative rotations of each static data set (the paper's protocol).

    At each static orientation the *mean* of the measurements is used (Sec. III-B, "to increase the
    signal-to-noise ratio"): the mean marker pixels give one PnP attitude ``C_t``, the mean accelerometer and
    magnetometer vectors one ``I_t``. Consecutive orientations give the motions
    ``Delta R_c = C_{t+1} C_t^T`` and ``Delta R_i = I_{t+1} I_t^T`` (eqs. (3)-(4)).

    Parameters
    ----------
    recording : LabRecording
    sample : {"mean", "single"}
        ``"mean"``: the paper's protocol; ``"single"``: the first sample of each orientation instead (the
        intervention that measures what the averaging buys).

    Returns
    -------
    dict
        set id -> ``(A, B)``, each of shape (poses - 1, 3, 3).
    """
    if sample not in ("mean", "single"):
        raise ValueError(f"sample must be 'mean' or 'single', got {sample!r}")
    reduce = (lambda g: g.mean()) if sample == "mean" else (lambda g: g.first())
    n = len(recording.rig["wand_points"])
    C = camera_orientations(marker_pixels(reduce(recording.static_markers.groupby(["set", "pose"])), n), recording.rig)
    im = reduce(recording.static_imu.groupby(["set", "pose"])[IMU_COLUMNS])
    I = static_sensor_orientations(im[ACC_COLUMNS].to_numpy(), im[MAG_COLUMNS].to_numpy())
    sets = im.index.get_level_values("set").to_numpy()
    out = {}
    for k in np.unique(sets):
        sel = sets == k
        out[int(k)] = (relative_rotations(C[sel]), relative_rotations(I[sel]))
    return out


def euler_rpy_deg(R) -> np.ndarray:
    """Roll, pitch, yaw (degrees) of rotations ``R = Rz(yaw) Ry(pitch) Rx(roll)``; shape (..., 3)."""
    R = np.asarray(R, dtype=float)
    ypr = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_euler("ZYX", degrees=True)
    return ypr[:, ::-1].reshape(R.shape[:-2] + (3,))


def attitude_statistics(estimate_deg, reference_deg) -> pd.DataFrame:
    """Table II's statistics of an attitude trace against the camera's.

    Parameters
    ----------
    estimate_deg, reference_deg : array_like, shape (M, 3)
        Roll, pitch, yaw traces (degrees).

    Returns
    -------
    pandas.DataFrame
        Index roll, pitch, yaw; columns ``rms_deg``, ``mean_deg``, ``sd_deg`` of the
        difference ``estimate - reference`` (wrapped to (-180, 180]; population SD, so
        ``rms^2 = mean^2 + sd^2``) and ``correlation`` (Pearson) of the two traces.
    """
    est, ref = np.asarray(estimate_deg, dtype=float), np.asarray(reference_deg, dtype=float)
    d = (est - ref + 180.0) % 360.0 - 180.0
    corr = [np.corrcoef(est[:, i], ref[:, i])[0, 1] for i in range(3)]
    return pd.DataFrame(
        {"rms_deg": np.sqrt(np.mean(d**2, axis=0)), "mean_deg": d.mean(axis=0), "sd_deg": d.std(axis=0),
         "correlation": corr},
        index=pd.Index(["roll", "pitch", "yaw"], name="angle"),
    )


@dataclass
class LabResult:
    """The experiment's results (see :func:`run_lab`).

    Attributes
    ----------
    estimates : dict
        Table II column -> (n_sets, 3, 3) estimates of ``R0`` (camera_from_sensor).
    r0 : dict
        Table II column -> the chordal mean of its estimates (used for the dynamic trial).
    per_set : pandas.DataFrame
        One row per set and column: ``set``, ``method``, ``roll_deg``, ``pitch_deg``,
        ``yaw_deg`` of the estimate; ``dev_x_deg``, ``dev_y_deg``, ``dev_z_deg``: the
        rotation vector of ``R_est R_ref^T`` (degrees, camera axes), ``R_ref`` the true
        ``R0`` if known, else the method's mean; ``from_mean_deg`` (angle to the
        method's mean) and, if the truth is known, ``true_error_deg``.
    traces : pandas.DataFrame
        ``t`` and roll/pitch/yaw of ``camera``, ``sensor_frame`` and each projection.
    table2 : pandas.DataFrame
        Rows (angle, method), columns of :func:`attitude_statistics`.
    truth : numpy.ndarray or None
        The true ``R0`` if the recording carries one (simulation).
    dynamic : dict
        The dynamic trial at the camera times: ``t`` (s), ``camera`` (``C_t``, camera_from_world) and
        ``sensor`` (``I_t``, sensor_from_world, slerped to the camera times), for re-projecting it with
        another ``R0`` or another reference frame (:mod:`replication.table2`).
    """

    estimates: dict
    r0: dict
    per_set: pd.DataFrame
    traces: pd.DataFrame
    table2: pd.DataFrame
    truth: np.ndarray | None = None
    dynamic: dict = field(default_factory=dict)


def run_lab(recording: LabRecording, solvers: dict = TABLE2_SOLVERS) -> LabResult:
    """The experiment of Sec. III-B from recordings: calibrate per data set, then the dynamic trial.

    Parameters
    ----------
    recording : LabRecording
        Simulated (:func:`simulate_lab`) or loaded (:func:`replication.lab_io.load_lab`).
    solvers : dict
        Column name -> (registered solver, options); default Table II's three methods
        (:data:`TABLE2_SOLVERS`).

    Returns
    -------
    LabResult

    Notes
    -----
    The paper does not say which of its 10 estimates it projected with in Fig. 7 and
    Table II; we use each method's chordal mean over the data sets.
    The dynamic trial compares relative attitudes to the first camera frame:
    ``Delta R_c = C_k C_0^T`` against ``R0 Delta R_i R0^T`` with
    ``Delta R_i = I_k I_0^T``, the sensor sampled at the camera times by slerp.
    """
    motions = static_motions(recording)
    sets = sorted(motions)
    estimates, warned = {}, {}
    for name, (method, options) in solvers.items():
        out = []
        for k in sets:
            with warnings.catch_warnings(record=True) as caught:  # recorded per data set (a finding), not shown
                warnings.simplefilter("always", ReplicationWarning)
                out.append(solve(method, *motions[k], **options))
            warned[name, k] = ", ".join(sorted({w.category.__name__ for w in caught
                                                 if issubclass(w.category, ReplicationWarning)}))
        estimates[name] = np.stack(out)
    r0 = {name: _chordal_mean(R) for name, R in estimates.items()}
    truth = recording.truth.get("camera_from_sensor")
    rows = []
    for name, R in estimates.items():
        rpy = euler_rpy_deg(R)
        ref = truth if truth is not None else r0[name]
        dev = np.degrees(log_map(R @ ref.T))                           # deviation, camera axes
        for i, k in enumerate(sets):
            row = {"set": k, "method": name, "roll_deg": rpy[i, 0], "pitch_deg": rpy[i, 1], "yaw_deg": rpy[i, 2],
                   "dev_x_deg": dev[i, 0], "dev_y_deg": dev[i, 1], "dev_z_deg": dev[i, 2],
                   "from_mean_deg": float(angle_between_deg(R[i], r0[name])), "warnings": warned[name, k]}
            if truth is not None:
                row["true_error_deg"] = float(angle_between_deg(R[i], truth))
            rows.append(row)
    per_set = pd.DataFrame(rows)

    # dynamic trial
    dm = recording.dynamic_markers
    C = camera_orientations(marker_pixels(dm, len(recording.rig["wand_points"])), recording.rig)
    di = recording.dynamic_imu
    I = dynamic_sensor_orientations(di, recording.rig["imu_rate_hz"])
    t_cam, t_imu = dm["t"].to_numpy(), di["t"].to_numpy()
    if t_cam[0] < t_imu[0] or t_cam[-1] > t_imu[-1]:
        raise ValueError(f"dynamic trial: camera times {t_cam[0]:.3f}..{t_cam[-1]:.3f} s are not inside "
                         f"the IMU's {t_imu[0]:.3f}..{t_imu[-1]:.3f} s")
    I_cam = np.swapaxes(OrientationStream(t_imu, np.swapaxes(I, -1, -2)).at(t_cam), -1, -2)
    dC = relative_rotations(C, reference=0)
    dI = relative_rotations(I_cam, reference=0)
    traces = {"camera": euler_rpy_deg(dC), "sensor_frame": euler_rpy_deg(dI)}
    for name, R in r0.items():
        traces[name] = euler_rpy_deg(R @ dI @ R.T)                     # the paper's R0 Delta R_i R0^T
    tables = {name: attitude_statistics(tr, traces["camera"]) for name, tr in traces.items() if name != "camera"}
    order = list(solvers) + ["sensor_frame"]
    table2 = pd.concat(tables, names=["method"]).swaplevel().reindex(pd.MultiIndex.from_product([["roll", "pitch", "yaw"], order], names=["angle", "method"]))
    frame = {"t": t_cam[1:]}
    for name, tr in traces.items():
        for i, a in enumerate(("roll", "pitch", "yaw")):
            frame[f"{name}_{a}"] = tr[:, i]
    return LabResult(estimates, r0, per_set, pd.DataFrame(frame), table2, truth,
                     {"t": t_cam, "camera": C, "sensor": I_cam})


def summarize(result: LabResult, *, failure_deg: float = 10.0) -> dict:
    """One line of numbers per experiment: per method the mean true ``R0`` error (``true_``; and
    ``true_clean_`` over the data sets on which the solver issued no warning), the
    number of data sets whose estimate is more than ``failure_deg`` from the truth, the
    number of data sets on which the solver warned, the
    mean spread around the method's mean estimate (Fig. 6) and the Table II RMS averaged
    over roll, pitch and yaw."""
    per = result.per_set.groupby("method", sort=False)
    rms = result.table2["rms_deg"].groupby(level="method", sort=False).mean()
    row = {}
    for name in result.estimates:
        err = per.get_group(name)["true_error_deg"]
        clean = per.get_group(name)["warnings"] == ""
        row[f"true_{name}"] = err.mean()
        row[f"true_clean_{name}"] = err[clean].mean() if clean.any() else np.nan
        row[f"failed_{name}"] = int((err > failure_deg).sum())
        row[f"warned_{name}"] = int((per.get_group(name)["warnings"] != "").sum())
        row[f"spread_{name}"] = per.get_group(name)["from_mean_deg"].mean()
    for name in rms.index:
        row[f"rms_{name}"] = rms[name]
    return row


def ablation(settings: LabSettings = LabSettings(), sources=None, solvers: dict = TABLE2_SOLVERS) -> pd.DataFrame:
    """Rerun the whole simulated experiment with error sources switched off.

    Cases: ``all sources``; ``without <source>`` (one switched off at a time);
    ``only <source>`` (all others off); ``no sources``. Every other random draw stays
    the same (see :func:`simulate_lab`).

    Returns
    -------
    pandas.DataFrame
        Index ``case``; columns ``noise_free_dynamic_attitude`` (see
        :attr:`LabSettings.noise_free_dynamic_attitude`: Table II's statistics of that case are
        set by rounding at the 1e-3 deg level) and those of :func:`summarize`.
    """
    sources = list(SOURCES) if sources is None else list(sources)
    cases = [("all sources", settings)]
    cases += [(f"without {s}", settings.without(s)) for s in sources]
    cases += [(f"only {s}", settings.without(*[o for o in sources if o != s])) for s in sources]
    cases.append(("no sources", settings.without(*sources)))
    rows = [{"case": label, "noise_free_dynamic_attitude": st.noise_free_dynamic_attitude,
             **summarize(run_lab(simulate_lab(st), solvers))} for label, st in cases]
    return pd.DataFrame(rows).set_index("case")


def sensitivity(name: str, values, settings: LabSettings = LabSettings(), solvers: dict = TABLE2_SOLVERS):
    """Rerun the experiment for each value of one :class:`LabSettings` field.

    Returns
    -------
    pandas.DataFrame
        Index the values (named ``name``); columns of :func:`summarize`.
    """
    if name not in {f.name for f in dataclasses.fields(LabSettings)}:
        raise ValueError(f"{name!r} is not a LabSettings field")
    rows = [{name: v, **summarize(run_lab(simulate_lab(dataclasses.replace(settings, **{name: v})), solvers))}
            for v in values]
    return pd.DataFrame(rows).set_index(name)


def table2_versus_paper(result: LabResult) -> pd.DataFrame:
    """Table II of the simulated lab beside the paper's, with each method's true ``R0`` error.

    Returns
    -------
    pandas.DataFrame
        Index (angle, method); columns ``paper_*`` and ``ours_*`` for RMS, mean, SD
        (deg) and correlation, and ``true_r0_error_deg``: the mean angle of the method's
        per-set estimates to the true ``R0`` (for ``sensor_frame``: the angle of the true
        ``R0`` itself, the error of assuming aligned frames). NaN if the truth is unknown.
    """
    from .paper import TABLE2_ANGLES, TABLE2_METHODS, load_table2

    paper = load_table2()  # indexed by (angle, method)
    ours = result.table2.reindex(paper.index)
    out = pd.concat([paper.add_prefix("paper_"), ours.add_prefix("ours_")], axis=1)
    cols = ["rms_deg", "mean_deg", "sd_deg", "correlation"]
    out = out[[f"{w}_{c}" for c in cols for w in ("paper", "ours")]]
    true = {}
    if result.truth is not None:
        true = result.per_set.groupby("method")["true_error_deg"].mean().to_dict()
        true["sensor_frame"] = float(rotation_angle_deg(result.truth))  # ignoring R0 altogether
    out["true_r0_error_deg"] = [true.get(m, np.nan) for m in out.index.get_level_values("method")]
    return out.reindex(pd.MultiIndex.from_product([TABLE2_ANGLES, TABLE2_METHODS], names=["angle", "method"]))
