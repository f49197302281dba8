"""Testing helpers shared by the test suite (and usable in a user's own tests)."""
from __future__ import annotations

import numpy as np

from .core.checks import check_matrices
from .core.so3 import angle_between_deg

__all__ = ["assert_rotations_close"]


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
