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
