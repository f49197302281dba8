"""Testing helpers shared by the test suite (and usable in a user's own tests)."""
from __future__ import annotations

import numpy as np

from .core.checks import check_matrices
from .core.so3 import angle_between_deg, quaternion_from_matrix

__all__ = ["assert_rotations_close", "write_tum_trajectory", "write_euroc_imu"]


def assert_rotations_close(R, R_ref, atol_deg: float, *, name: str = "R") -> None:
    """Raise ``AssertionError`` unless every rotation of ``R`` is within ``atol_deg`` of ``R_ref``.

    The message names the worst index and its angle. ``R`` and ``R_ref`` broadcast.

    >>> import numpy as np
    >>> assert_rotations_close(np.eye(3), np.eye(3), 1e-9)
    """
    R = check_matrices(R, name)
    R_ref = check_matrices(R_ref, "R_ref")
    angle = np.atleast_1d(angle_between_deg(R, R_ref))
    idx = np.unravel_index(int(np.argmax(angle)), angle.shape)
    if not angle[idx] <= atol_deg:
        raise AssertionError(
            f"{name} differs from the reference by {float(angle[idx]):.3g} deg at index "
            f"{tuple(int(i) for i in idx)} (> {atol_deg:g} deg; {int(np.sum(angle > atol_deg))} of {angle.size} off)"
        )


def write_tum_trajectory(path, stream) -> None:
    """Write an orientation stream (``t`` in s, ``R`` world_from_body) as a TUM trajectory (zero positions, quaternion
    x y z w), as ``calibrate --camera`` reads it."""
    q = quaternion_from_matrix(stream.R)
    rows = np.column_stack([stream.t, np.zeros((len(stream.t), 3)), q[:, 1:], q[:, :1]])
    np.savetxt(path, rows, fmt="%.9f")


def write_euroc_imu(path, gyro) -> None:
    """Write a gyro stream (``t`` in s, ``omega`` in rad/s) as an EuRoC ``imu0/data.csv`` (ns stamps, a constant
    accelerometer), as ``calibrate --sensor ... --sensor-kind gyro`` reads it."""
    rows = np.column_stack([np.round(gyro.t * 1e9), gyro.omega, np.tile([0.0, 0.0, 9.81], (len(gyro.t), 1))])
    np.savetxt(path, rows, fmt=["%d"] + ["%.9f"] * 6, delimiter=",", header="timestamp,w,w,w,a,a,a")
