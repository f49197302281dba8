"""Input mistakes that only a reference shows (issue 34 point 5): the IMU's own trajectory given as the camera file,
and the camera and sensor files swapped, named where the reference check would otherwise blame permuted gyro axes
or a reference for another rig; at the bounds of :data:`replication.rig.diagnose.IMU_AS_CAMERA_DEG`."""
import warnings

import numpy as np
import pytest

from replication import calibrate
from replication.core import so3
from replication.rig import diagnose
from replication.rig.diagnose import IMU_AS_CAMERA_DEG, reference_mistakes
from replication.rig.quality import THRESHOLDS
from replication.rig.streams import GyroStream, OrientationStream

#: A camera-IMU rotation far from the identity (a camera's reference).
R_CAM = so3.matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))
FAIL = THRESHOLDS["reference_error_deg"][1]
Z = np.array([0.0, 0.0, 1.0])


def _turn(deg, axis=Z):
    return so3.matrix_from_rotation_vector(np.radians(deg) * np.asarray(axis))


def _world_from_imu(t):
    w = np.stack([0.9 * np.sin(0.7 * t), 0.8 * np.sin(0.45 * t + 1.0), 0.7 * np.cos(0.3 * t)], axis=-1)
    return so3.matrix_from_rotation_vector(w)


@pytest.fixture(scope="module")
def imu():
    """The IMU's trajectory (20 Hz, as a VIO output or ground truth) and its gyro (200 Hz), 40 s."""
    t = np.arange(0.0, 40.0, 0.05)
    t_imu = np.arange(-1.0, 41.0, 0.005)
    Q = _world_from_imu(t_imu)
    omega = so3.rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    return OrientationStream(t, _world_from_imu(t), "imu pose"), GyroStream(0.5 * (t_imu[1:] + t_imu[:-1]), omega,
                                                                            "gyro")


def _run(camera, sensor, reference, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(camera, sensor, reference=reference, n_bootstrap=0, **kw)


def _checks(result):
    return {r.check: r for r in result.verdict.reasons}


@pytest.mark.parametrize("tilt, named", [(0.0, True), (IMU_AS_CAMERA_DEG - 0.3, True),
                                         (IMU_AS_CAMERA_DEG + 0.3, False)])
def test_the_imu_trajectory_as_camera_is_named_within_the_bound(imu, tilt, named):
    """The 'camera' is the IMU body turned by ``tilt`` (R0 = that turn): named just inside the bound, not past it
    (there the reference check's own reason stays the only word)."""
    pose, gyro = imu
    camera = OrientationStream(pose.t, pose.R @ _turn(tilt).T, "imu pose as camera")
    r = _run(camera, gyro, R_CAM)
    assert so3.rotation_angle_deg(r.R) == pytest.approx(tilt, abs=0.01)
    checks = _checks(r)
    assert checks["reference_error_deg"].level == "fail" and r.verdict.level == "fail"
    assert ("imu_as_camera" in checks) is named
    if named:
        reason = checks["imu_as_camera"]
        assert reason.level == "fail" and reason.measured == pytest.approx(tilt, abs=0.01)
        assert "looks like the IMU's own trajectory" in reason.message
        assert f"R0 within {reason.measured:.3g} deg of the identity" in reason.message and "np." not in reason.message


def test_not_named_without_a_reference_or_without_diagnosis(imu):
    pose, gyro = imu
    assert "imu_as_camera" not in _checks(_run(pose, gyro, None))
    assert "imu_as_camera" not in _checks(_run(pose, gyro, R_CAM, diagnose=False))


@pytest.mark.parametrize("reference_deg, named", [(2 * IMU_AS_CAMERA_DEG - 0.3, False),
                                                  (2 * IMU_AS_CAMERA_DEG + 0.3, True)])
def test_a_reference_near_the_identity_does_not_make_an_identity_estimate_suspect(reference_deg, named):
    """R0 at the identity against a reference just within / past twice the bound from the identity."""
    found = reference_mistakes(np.eye(3), _turn(reference_deg, [1.0, 0.0, 0.0]))
    assert [r.check for r in found] == (["imu_as_camera"] if named else [])


def test_an_estimate_that_agrees_with_the_reference_names_nothing():
    assert reference_mistakes(_turn(1.0), _turn(1.0 + FAIL - 0.1)) == []
    assert reference_mistakes(R_CAM @ _turn(FAIL - 0.1), R_CAM) == []
    assert reference_mistakes(R_CAM, None) == [] and reference_mistakes(None, R_CAM) == []


@pytest.mark.parametrize("off, named", [(0.0, True), (FAIL - 0.3, True), (FAIL + 0.3, False)])
def test_swapped_files_are_named_within_the_reference_checks_bound(imu, off, named):
    """The camera's trajectory given as the sensor and the IMU's as the camera: R0 is the reference's inverse; a
    reference turned by ``off`` puts the estimate that far from its inverse."""
    pose, _ = imu
    camera = OrientationStream(pose.t, pose.R @ R_CAM.T, "camera")  # v_cam = R_CAM v_imu
    r = _run(pose, camera, R_CAM @ _turn(off))
    checks = _checks(r)
    assert so3.angle_between_deg(r.R, R_CAM.T) < 0.01
    assert ("files_swapped" in checks) is named and "imu_as_camera" not in checks
    if named:
        assert "the camera and sensor files look swapped" in checks["files_swapped"].message
        assert checks["files_swapped"].measured == pytest.approx(off, abs=0.01)


def test_named_beside_the_re_run_hypotheses(monkeypatch):
    """``input_mistakes`` returns the reference's findings even when no re-run fits (the stand-in fits nothing)."""
    class Trial:
        residual_deg = {"median": 1.0}
        diagnostics = {"motion_median_deg": 1.0}
        R = np.eye(3)
        time_offset_correlation = 0.9

    pose = OrientationStream(np.arange(3.0), np.tile(np.eye(3), (3, 1, 1)), "c")
    found = diagnose.input_mistakes(pose, pose, base_residual_deg=1.0, motion_deg=1.0, interval=1.0, max_offset=0.1,
                                    calibrate=lambda *a, **k: Trial(), reference=R_CAM, R=np.eye(3))
    assert [r.check for r in found] == ["imu_as_camera"]
