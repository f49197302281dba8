import dataclasses
import shutil

import numpy as np
import pytest

from replication.core.so3 import random_rotations
from replication.study.lab.settings import LabSettings


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def problem(rng):
    """A noise-free problem: R0, camera motions A (J=20, Haar), sensor motions B = R0^T A R0."""
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, 20)
    return R0, A, R0.T @ A @ R0


#: A small simulated lab (2 data sets of 4 poses, a 4 s dynamic trial) for the loader and chain
#: tests.
SMALL_LAB = dataclasses.replace(LabSettings(), n_sets=2, poses_per_set=(4, 4), dynamic_seconds=4.0)


@pytest.fixture(scope="session")
def lab_recording(tmp_path_factory):
    """A folder written by ``write_lab`` from :data:`SMALL_LAB` (shared: do not modify, use
    ``lab_dir``)."""
    from replication.study.lab import simulate_lab, write_lab

    return write_lab(simulate_lab(SMALL_LAB), tmp_path_factory.mktemp("lab") / "rec")


@pytest.fixture
def lab_dir(lab_recording, tmp_path):
    """A private copy of :func:`lab_recording` that a test may corrupt."""
    shutil.copytree(lab_recording, tmp_path / "rec")
    return tmp_path / "rec"


def exact_problem(seed=0, J=8):
    """``(R0, A, B)``: ``J`` random camera motions and the sensor motions ``R0^T A R0`` they imply
    (no noise)."""
    rng = np.random.default_rng(seed)
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, J)
    return R0, A, np.swapaxes(R0, -1, -2) @ A @ R0


def noisy_problem(seed=2, J=30, noise_deg=0.2):
    """:func:`exact_problem` with ``noise_deg`` (deg per axis) of noise on each sensor motion."""
    from replication.core.so3 import matrix_from_rotation_vector

    rng = np.random.default_rng(seed)
    R0, A, B = exact_problem(seed, J)
    B = B @ matrix_from_rotation_vector(np.radians(noise_deg) * rng.standard_normal((J, 3)))
    return R0, A, B


def drift_pairs(seed, n_before=400, n_drift=1500, rate_deg=0.002, noise_deg=0.3):
    """Pairs of :func:`replication.study.live_study.pair_stream`: ``n_before`` at a random ``R0``,
    then ``n_drift`` whose ``R0`` turns ``rate_deg`` a pair about a random axis."""
    from replication.core import so3
    from replication.study.live_study import pair_stream

    rng = np.random.default_rng([seed, 7])
    R0 = so3.random_rotations(rng, ())
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    A, B = pair_stream(rng, n_before, R0, noise_deg=noise_deg)
    more = [pair_stream(rng, 1, R0 @ so3.matrix_from_rotation_vector(np.radians(rate_deg * (k + 1)) * axis),
                        noise_deg=noise_deg)
            for k in range(n_drift)]
    return np.concatenate([A] + [m[0] for m in more]), np.concatenate([B] + [m[1] for m in more])


def one_axis_rig(scale, seed, wobble=0.05, seconds=15.0, bias=(0.03, -0.02, 0.04)):
    """``(camera, gyro)``: a rig turning about the camera's z axis (1.2 rad amplitude) and rocking
    by ``wobble`` rad about the other two, camera 20 Hz (0.05 deg noise), gyro 200 Hz (0.2 deg/s)
    reading ``scale * omega + bias`` in the frame of ``replication.testing.RIG_R0`` (the motion's
    phases drawn from ``seed``): the motion that does not separate the gyro's scales."""
    from replication.core.so3 import matrix_from_rotation_vector, rotation_vector_from_matrix
    from replication.rig.streams import GyroStream, OrientationStream
    from replication.testing import RIG_R0

    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 3)

    def motion(t):
        v = np.stack([wobble * np.sin(0.9 * t + phase[1]), wobble * np.cos(0.5 * t + phase[2]),
                      1.2 * np.sin(0.6 * t + phase[0])], axis=-1)
        return matrix_from_rotation_vector(v)

    t_cam = np.arange(0.0, seconds, 0.05)
    noise = rng.normal(0.0, np.radians(0.05) / np.sqrt(3.0), (len(t_cam), 3))
    C = motion(t_cam) @ matrix_from_rotation_vector(noise)
    t = np.arange(-1.0, seconds + 1.0, 0.005)
    Q = motion(t) @ RIG_R0
    omega = rotation_vector_from_matrix(np.swapaxes(Q[:-1], -1, -2) @ Q[1:]) / 0.005
    omega = omega * np.asarray(scale, float) + np.asarray(bias, float) + rng.normal(0.0, np.radians(0.2), omega.shape)
    return OrientationStream(t_cam, C, "camera"), GyroStream(0.5 * (t[1:] + t[:-1]), omega, "gyro")
