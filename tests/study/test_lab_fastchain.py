"""The lab's faster chain (``replication.study.lab.fastchain``), each piece against the one it
replaces: the transcribed Madgwick filter against ``ahrs``'s (every branch), the batched ecompass
against the chain's, the batched projection and its Jacobian against OpenCV's and finite
differences, and the batched PnP refinement against OpenCV's pose."""
import cv2
import numpy as np
import pytest

from conftest import SMALL_LAB
from replication.core import so3
from replication.study import lab
from replication.study.lab import chain, fastchain
from replication.study.lab.recording import marker_pixels


@pytest.fixture(scope="module")
def small_recording():
    return lab.simulate_lab(SMALL_LAB)


def test_transcribed_madgwick_takes_ahrs_branches():
    """A still gyroscope keeps the quaternion, a zero magnetometer falls back to the IMU update, a
    zero accelerometer skips the correction: as in ``ahrs``."""
    from ahrs.filters import Madgwick

    rng = np.random.default_rng(3)
    n = 60
    gyr = rng.normal(0, 0.3, (n, 3))
    acc = np.array([0.0, 0.0, 9.8]) + rng.normal(0, 0.3, (n, 3))
    mag = np.array([20.0, 0.0, -40.0]) + rng.normal(0, 1.0, (n, 3))
    gyr[10] = 0.0
    mag[20:25] = 0.0
    acc[30] = 0.0
    ours = fastchain.madgwick_marg(gyr, acc, mag, 100.0)
    theirs = Madgwick(gyr=gyr, acc=acc, mag=mag, frequency=100.0).Q
    np.testing.assert_allclose(ours, theirs, atol=1e-12)
    with pytest.raises(ValueError, match="same shape"):
        fastchain.madgwick_marg(gyr, acc[:-1], mag, 100.0)



def test_ecompass_on_arrays_is_ahrs_ecompass(small_recording):
    im = small_recording.static_imu.iloc[::37]
    acc, mag = im[lab.ACC_COLUMNS].to_numpy(), im[lab.MAG_COLUMNS].to_numpy()
    np.testing.assert_allclose(fastchain.ecompass_attitudes(acc, mag), chain.static_sensor_orientations(acc, mag),
                               atol=1e-13)



def test_projection_and_its_jacobian_are_opencvs():
    rng = np.random.default_rng(0)
    C = so3.matrix_from_rotation_vector(rng.normal(size=(4, 3)) * 0.3)
    t = np.tile([0.1, -0.1, 2.0], (4, 1))
    K = np.array([[450.0, 0, 320], [0, 452.0, 240], [0, 0, 1]])
    dist = np.array([-0.25, 0.08, 0.001, -0.001, 0.01])
    uv, J = fastchain._project(lab.WAND_POINTS, C, t, K, dist, jacobian=True)
    for m in range(4):
        pts, _ = cv2.projectPoints(lab.WAND_POINTS, cv2.Rodrigues(C[m])[0], t[m], K, dist)
        np.testing.assert_allclose(uv[m], pts[:, 0], atol=1e-9)
    h, numeric = 1e-6, np.empty_like(J)
    for k in range(6):
        d = h * np.eye(6)[k]
        plus = fastchain._project(lab.WAND_POINTS, so3.matrix_from_rotation_vector(d[:3]) @ C, t + d[3:], K, dist)
        minus = fastchain._project(lab.WAND_POINTS, so3.matrix_from_rotation_vector(-d[:3]) @ C, t - d[3:], K, dist)
        numeric[:, k] = np.swapaxes((plus - minus) / (2 * h), -1, -2)
    assert np.abs(J - numeric).max() < 1e-6 * np.abs(J).max()



def test_batched_pnp_finds_opencvs_pose(small_recording):
    rig, markers = small_recording.rig, small_recording.static_markers.iloc[::5]
    uv = marker_pixels(markers, len(rig["wand_points"]))
    opencv = chain.camera_orientations(uv, rig)
    assert so3.angle_between_deg(chain.camera_orientations(uv, rig, refine="batched"), opencv).max() < 1e-5
    # from each static orientation's mean pose, as the all-sample calibration starts
    keys = markers.groupby(["set", "pose"]).ngroup().to_numpy()
    C0, t0 = chain.camera_poses(marker_pixels(markers.groupby(["set", "pose"]).mean(), len(rig["wand_points"])), rig)
    refined = fastchain.refine_camera_orientations(uv, rig, C0[keys], t0[keys])
    assert so3.angle_between_deg(refined, opencv).max() < 1e-5
    assert so3.angle_between_deg(C0[keys], opencv).max() > 1e-3          # the start is not already the answer
    with pytest.raises(ValueError, match="image 0: PnP failed"):
        fastchain.refine_camera_orientations(uv[:, [1, 0, 2, 3, 4, 5, 6, 7, 8]], rig, C0[keys], t0[keys])
    with pytest.raises(ValueError, match="refine must be"):
        chain.camera_orientations(uv, rig, refine="lm")
