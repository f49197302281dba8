"""Settings of the simulated lab: the rig, the error sources and their sizes, Table II's solvers.

Every setting is a field of :class:`LabSettings` with its default and the reason for it;
:data:`SOURCES` and :data:`PARTS` name the error sources that :meth:`LabSettings.without`
switches off. Frames and conventions: ``docs/conventions.md``.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

__all__ = ["GRAVITY", "WAND_POINTS", "NOMINAL_CAMERA_FROM_SENSOR", "TABLE2_SOLVERS", "SOURCES", "PARTS", "LabSettings"]

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

#: Parts of an error source, for finer interventions (:meth:`LabSettings.without` takes these names
#: too): the magnetometer's random noise apart from its residual calibration errors.
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

    def without(self, *sources: str) -> LabSettings:
        """These settings with the named error sources (keys of :data:`SOURCES` or :data:`PARTS`)
        switched off."""
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
        (demonstrated in ``tests/study/test_lab.py``). With either noise on they do not.
        """
        return not np.any(self.acc_noise_density_ug) and not self.mag_noise_ut

    def exact(self) -> LabSettings:
        """Every error source switched off (the chain must then recover ``R0``)."""
        return self.without(*SOURCES)
