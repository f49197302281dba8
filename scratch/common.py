"""Shared helpers of the RT6 probes (names as in the current replication.core.so3)."""
import numpy as np

from replication.core.so3 import matrix_from_rotation_vector as exp_map  # noqa: F401
from replication.core.so3 import rotation_vector_from_matrix as log_map  # noqa: F401
from replication.core.stats import wilson_interval

FLOOR = 0.343


def W(k, n):
    lo, hi = wilson_interval(k, n)
    return f"{k}/{n} [{lo:.2f},{hi:.2f}]"
