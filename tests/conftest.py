import numpy as np
import pytest

from replication.so3 import random_rotations


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def problem(rng):
    """A noise-free problem: R0, camera motions A (J=20, Haar), sensor motions B = R0^T A R0."""
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, 20)
    return R0, A, R0.T @ A @ R0
