"""The lab's chain (``replication.study.lab.chain``): exact with every error source off, PnP from
the wand's pixels, ecompass and Madgwick in their conventions (the transcribed Madgwick the same
stream as ``ahrs``'s), the fast run the default run, and the all-sample calibration's motions (one
per sample pair, the mean's on an exact lab)."""
import dataclasses

import cv2
import numpy as np
import pandas as pd
import pytest

from conftest import SMALL_LAB
from replication.core import so3
from replication.core.handeye import relative_rotations
from replication.study import lab
from replication.study.lab import chain
from replication.study.lab.simulate import _look_at


@pytest.fixture(scope="module")
def small_recording():
    return lab.simulate_lab(SMALL_LAB)


def test_exact_lab_recovers_r0_and_the_camera_attitude():
    """With every error source off, the chain is exact up to the AHRS filter's lag."""
    rec = lab.simulate_lab(dataclasses.replace(lab.LabSettings().exact(), n_sets=3))
    res = chain.run_lab(rec, {k: v for k, v in lab.TABLE2_SOLVERS.items() if k != "optimization"})
    assert res.per_set["true_error_deg"].max() < 1e-3
    t2 = res.table2.xs("ours_right", level="method")
    assert t2["rms_deg"].max() < 0.3 and t2["correlation"].min() > 0.999
    assert res.table2.xs("sensor_frame", level="method")["rms_deg"].min() > 5  # R0 is far from identity



def test_pnp_recovers_camera_from_wand_exactly():
    rig = {"camera_matrix": [[450.0, 0, 320], [0, 450.0, 240], [0, 0, 1]],
           "dist_coeffs": [-0.25, 0.08, 0.001, -0.001, 0], "wand_points": lab.WAND_POINTS}
    C = _look_at(np.array([[0.5, 0.3, 2.0], [-0.6, -0.2, 1.8]]), np.zeros((2, 3)), np.array([30.0, -20.0]))
    uv = []
    for Cp, p in zip(C, [[0.5, 0.3, 2.0], [-0.6, -0.2, 1.8]]):
        pts, _ = cv2.projectPoints(lab.WAND_POINTS, cv2.Rodrigues(Cp)[0], -Cp @ np.array(p),
                                   np.array(rig["camera_matrix"]), np.array(rig["dist_coeffs"]))
        uv.append(pts[:, 0])
    np.testing.assert_allclose(chain.camera_orientations(np.array(uv), rig), C, atol=1e-7)
    with pytest.raises(ValueError, match="image 0: PnP failed .*marker order"):
        chain.camera_orientations(np.array(uv)[:, [1, 0, 2, 3, 4, 5, 6, 7, 8]], rig)  # two markers swapped



def test_ecompass_gives_body_from_world_and_madgwick_a_world_from_body_stream():
    rng = np.random.default_rng(1)
    I = so3.random_rotations(rng, 2)  # sensor_from_world
    up, b = np.array([0, 0, 1.0]), np.array([0.0, 20.0, -44.0])
    est = chain.static_sensor_orientations((I @ (lab.GRAVITY * up)), I @ b)
    np.testing.assert_allclose(relative_rotations(est), relative_rotations(I), atol=1e-12)
    # Madgwick on a noise-free constant-rate rotation about the sensor's x axis
    rate, n = np.deg2rad(20.0), 400
    t = np.arange(n) / 100.0
    Q = so3.matrix_from_rotation_vector(np.outer(rate * t, [1.0, 0, 0]))  # world_from_sensor
    acc = np.einsum("nji,j->ni", Q, lab.GRAVITY * up)
    mag = np.einsum("nji,j->ni", Q, b)
    imu = pd.DataFrame(np.hstack([t[:, None], acc, np.tile([rate, 0, 0], (n, 1)), mag]),
                       columns=["t"] + lab.IMU_COLUMNS)
    est = chain.dynamic_sensor_orientations(imu, 100.0)
    assert np.array_equal(est.t, t)
    truth = relative_rotations(Q, reference=0, convention="world_from_body")
    err = so3.angle_between_deg(relative_rotations(est.world_from_body, reference=0, convention="world_from_body"),
                                truth)
    assert err.max() < 0.5
    # read in the other convention, the motions would be off by up to 2 x 80 deg
    assert so3.angle_between_deg(relative_rotations(est.world_from_body, reference=0), truth).max() > 90


def test_transcribed_madgwick_is_ahrs_madgwick(small_recording):
    imu = small_recording.dynamic_imu
    a = chain.dynamic_sensor_orientations(imu, 100.0)
    b = chain.dynamic_sensor_orientations(imu, 100.0, madgwick="transcribed")
    assert np.array_equal(a.t, b.t) and so3.angle_between_deg(a.R, b.R).max() < 1e-9
    with pytest.raises(ValueError, match="madgwick must be"):
        chain.dynamic_sensor_orientations(imu, 100.0, madgwick="fast")



def test_fast_run_is_the_default_run(small_recording):
    slow, fast = chain.run_lab(small_recording), chain.run_lab(small_recording, fast=True)
    assert np.abs((fast.table2 - slow.table2).to_numpy()).max() < 1e-6
    reused = chain.run_lab(small_recording, fast=True, dynamic_camera=fast.dynamic["camera_from_world"])
    pd.testing.assert_frame_equal(reused.table2, fast.table2)
    with pytest.raises(ValueError, match="dynamic_camera must have shape"):
        chain.run_lab(small_recording, dynamic_camera=fast.dynamic["camera_from_world"][1:])



def test_every_sample_gives_one_motion_per_sample_pair(small_recording):
    mean, every = chain.static_motions(small_recording), chain.static_motions(small_recording, sample="all")
    per_pose = small_recording.static_imu.groupby(["set", "pose"]).size()
    for k, (A, B) in every.items():
        n = per_pose.loc[k].to_numpy()
        assert A.shape == B.shape == (int(np.minimum(n[:-1], n[1:]).sum()), 3, 3)
        # the first orientation pair's motions scatter (one sample's noise) about its mean motion,
        # not about the identity (a motion within one orientation)
        j = int(n[0])
        for per_sample, of_means in ((A[:j], mean[k][0][0]), (B[:j], mean[k][1][0])):
            centre = so3.nearest_rotation(per_sample.sum(axis=0))
            assert so3.angle_between_deg(centre, of_means) < 0.5 < so3.rotation_angle_deg(of_means)
            assert np.median(so3.angle_between_deg(per_sample, of_means)) > 1e-3



def test_every_sample_of_an_exact_lab_is_the_mean():
    rec = lab.simulate_lab(dataclasses.replace(SMALL_LAB.exact(), n_sets=1))
    (A, B), = chain.static_motions(rec, sample="all").values()
    (Am, Bm), = chain.static_motions(rec).values()
    j = len(A) // len(Am)
    np.testing.assert_allclose(A, np.repeat(Am, j, axis=0), atol=1e-9)
    np.testing.assert_allclose(B, np.repeat(Bm, j, axis=0), atol=1e-12)
    with pytest.raises(ValueError, match="'mean', 'single' or 'all'"):
        chain.static_motions(rec, sample="median")


def test_single_sample_protocol_equals_the_mean_without_noise_and_is_validated(small_recording):
    rec = lab.simulate_lab(dataclasses.replace(lab.LabSettings().exact(), n_sets=2, poses_per_set=(4, 4),
                                               dynamic_seconds=4.0))
    mean, single = chain.static_motions(rec), chain.static_motions(rec, sample="single")
    for k in mean:
        assert np.abs(mean[k][0] - single[k][0]).max() < 1e-12 and np.abs(mean[k][1] - single[k][1]).max() < 1e-12
    noisy = small_recording
    assert np.abs(chain.static_motions(noisy)[0][1] - chain.static_motions(noisy, sample="single")[0][1]).max() > 1e-5
    with pytest.raises(ValueError, match="sample"):
        chain.static_motions(rec, sample="median")
