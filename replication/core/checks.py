"""Validators of rotation-matrix input (``check_*``), shared by every public door; re-exported by
:mod:`replication.core.so3`.

Each raises ``ValueError`` naming the argument, the first offending batch index and the measured
violation. Conventions: ``docs/conventions.md``.
"""
from __future__ import annotations

import math

import numpy as np

from .kernels import rotation_violation

__all__ = ["ROTATION_ATOL", "MAX_ROTATION_ATOL", "det3", "check_matrices", "check_rotation_matrices", "check_init",
           "check_range", "check_rotation_flat",
           "check_atol", "check_number"]

#: Default tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` for accepting a rotation.
ROTATION_ATOL = 1e-6
#: Largest ``atol`` a rotation test accepts. The loosest in the package is 1e-4 (loaders of files
#: that print 4-6 digits); above 1e-2 a "rotation" may be scaled or sheared by half a percent, a
#: third of the paper's noise per motion (``||v|| < 0.02``, chordal distance up to 0.028), and the
#: algebra of eq. (8) that every solver relies on (``||A_j R||_F = ||R||_F``, ``||K||_2 <= 1``) no
#: longer holds: such matrices are not rotation data.
MAX_ROTATION_ATOL = 1e-2


def _first_index(mask: np.ndarray) -> tuple:
    """Index (over the leading dimensions) of the first True entry of ``mask`` (``()`` for a
    scalar)."""
    mask = np.asarray(mask)
    return tuple(int(i) for i in np.argwhere(mask)[0]) if mask.ndim else ()


def _index_words(idx: tuple) -> str:
    """An index for a message: ``7`` along one leading dimension, ``(1, 2)`` along several."""
    return str(idx[0]) if len(idx) == 1 else str(idx)


def det3(M) -> np.ndarray:
    """Determinants of 3x3 matrices, batched: (..., 3, 3) -> (...), as the triple product of the
    rows.

    Elementwise (no LAPACK call per matrix), so much faster than ``numpy.linalg.det`` on large
    batches of 3x3 matrices; same value to rounding.
    """
    M = np.asarray(M, dtype=float)
    a, b, c = M[..., 0, :], M[..., 1, :], M[..., 2, :]
    return (a[..., 0] * (b[..., 1] * c[..., 2] - b[..., 2] * c[..., 1])
            - a[..., 1] * (b[..., 0] * c[..., 2] - b[..., 2] * c[..., 0])
            + a[..., 2] * (b[..., 0] * c[..., 1] - b[..., 1] * c[..., 0]))


def check_matrices(M, name: str = "M") -> np.ndarray:
    """Validate a batch of 3x3 matrices and return it as a float array.

    Parameters
    ----------
    M : array_like, shape (..., 3, 3)
        Matrices to check.
    name : str
        Name used in error messages.

    Returns
    -------
    numpy.ndarray of float64, shape (..., 3, 3)

    Raises
    ------
    ValueError
        If ``M`` is not real-valued numeric, does not end in ``(3, 3)``, or holds NaN/inf.
    """
    if np.iscomplexobj(M):
        raise ValueError(f"{name} must be real-valued; got a complex array")
    try:
        M = np.asarray(M, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a numeric array of 3x3 matrices: {exc}") from None
    if M.ndim < 2 or M.shape[-2:] != (3, 3):
        raise ValueError(f"{name} must have shape (..., 3, 3), got {M.shape}")
    if not np.isfinite(M).all():  # one reduction; the per-matrix mask only to name the first offender
        finite = np.isfinite(M).all(axis=(-2, -1))
        raise ValueError(f"{name} contains NaN or inf (first at index {_index_words(_first_index(~finite))})")
    return M


def check_rotation_matrices(R, name: str = "R", atol: float = ROTATION_ATOL) -> np.ndarray:
    """Validate that every 3x3 block of ``R`` is a proper rotation (in SO(3)).

    A block ``R`` is accepted when ``||R^T R - I||_F <= atol`` and
    ``|det(R) - 1| <= atol`` (eqs. (9)-(10) of the paper as a test).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    name : str
        Name used in error messages.
    atol : float
        Tolerance of the orthonormality and determinant tests: a finite number in
        ``(0, MAX_ROTATION_ATOL]`` (a NaN tolerance would accept anything, 0 refuses rounding).

    Returns
    -------
    numpy.ndarray of float64, shape (..., 3, 3)

    Raises
    ------
    ValueError
        ``atol`` out of range (named); or naming the first offending index: wrong shape, NaN/inf,
        not orthonormal, or a reflection (det = -1).
    """
    check_atol(atol)
    if not np.iscomplexobj(R):
        try:
            fast = np.asarray(R, dtype=float)
        except (TypeError, ValueError):
            fast = None
        # one fused pass (orthonormality, det, finiteness: NaN fails it); the detailed checks below
        # only on failure
        if fast is not None and fast.ndim >= 2 and fast.shape[-2:] == (3, 3) and np.all(
                rotation_violation(fast) <= atol):
            return fast
    R = check_matrices(R, name)
    E = np.swapaxes(R, -1, -2) @ R - np.eye(3)
    ortho = np.sqrt(np.einsum("...ab,...ab->...", E, E))  # ||R^T R - I||_F
    bad = ortho > atol
    if bad.any():
        idx = _first_index(bad)
        raise ValueError(
            f"{name} is not a rotation matrix at index {_index_words(idx)}: "
            f"||R^T R - I||_F = {ortho[idx]:.3g} > {atol:g} ({int(bad.sum())} bad of {bad.size})"
        )
    det = det3(R)
    bad = np.abs(det - 1.0) > atol
    if bad.any():
        idx = _first_index(bad)
        raise ValueError(
            f"{name} is not a rotation matrix at index {_index_words(idx)}: det = {det[idx]:.6g} "
            f"(a reflection; a rotation has det = +1)"
        )
    return R


def check_atol(atol, name: str = "atol"):
    """``atol`` of a rotation test, or ``ValueError`` naming ``name`` unless it is a finite number
    in ``(0, MAX_ROTATION_ATOL]``."""
    check_number(name, atol, minimum=0)
    if atol > MAX_ROTATION_ATOL:
        raise ValueError(f"{name} must be <= {MAX_ROTATION_ATOL:g} (MAX_ROTATION_ATOL: looser matrices are not "
                         f"rotations), got {atol!r}")
    return atol


def check_init(init, batch_shape: tuple, name: str = "init") -> np.ndarray:
    """A start rotation for a batch of problems: ``None`` means the identity; broadcast to
    ``batch_shape``.

    Raises
    ------
    ValueError
        ``init`` is not a rotation, or does not broadcast to ``batch_shape + (3, 3)``.
    """
    if init is None:
        return np.broadcast_to(np.eye(3), tuple(batch_shape) + (3, 3))
    init = check_rotation_matrices(init, name)
    try:
        return np.broadcast_to(init, tuple(batch_shape) + (3, 3))
    except ValueError:
        raise ValueError(
            f"{name} must have shape (3, 3) or broadcast to the batch shape {tuple(batch_shape) + (3, 3)}, "
            f"got {init.shape}"
        ) from None


def _plain(value):
    """``value`` for a message: a NumPy scalar as the Python one (``-1.0``, never
    ``np.float64(-1.0)``)."""
    return value.item() if isinstance(value, np.generic) else value


def check_number(name: str, value, *, minimum=None, integer: bool = False, strict: bool = True):
    """``value``, or ``ValueError`` naming ``name`` unless it is a finite number (an integer if
    asked) above ``minimum`` (``>=`` if not ``strict``). Booleans are refused."""
    ok_type = (isinstance(value, (int, np.integer)) if integer
               else isinstance(value, (int, float, np.integer, np.floating)))
    if isinstance(value, bool) or not ok_type or not math.isfinite(float(value)):
        raise ValueError(f"{name} must be a finite {'integer' if integer else 'number'}, got {_plain(value)!r}")
    if minimum is not None and (value <= minimum if strict else value < minimum):
        raise ValueError(f"{name} must be {'>' if strict else '>='} {minimum:g}, got {_plain(value)!r}")
    return value


def check_range(name: str, value, *, low: float, high: float, low_open: bool = True, high_open: bool = False) -> float:
    """``float(value)``, or ``ValueError`` naming ``name`` unless it is a finite number in the
    interval from ``low`` to ``high`` (open or closed at each end as asked). Booleans are
    refused."""
    check_number(name, value)
    if (value <= low if low_open else value < low) or (value >= high if high_open else value > high):
        raise ValueError(f"{name} must be in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}, "
                         f"got {_plain(value)!r}")
    return float(value)


def check_rotation_flat(name: str, flat, atol: float = ROTATION_ATOL) -> None:
    """The checks of :func:`check_rotation_matrices` on one rotation given as a row-major list of 9
    floats, in plain Python (a per-sample hot path:
    :class:`replication.rig.online.OnlineCalibrator`); the largest entry of ``R^T R - I`` against
    ``atol``."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = flat
    if atol != ROTATION_ATOL:
        check_atol(atol)
    if not math.isfinite(a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7 + a8):
        bad = not all(map(math.isfinite, flat))  # else finite entries whose sum overflows: not a rotation either
        raise ValueError(f"{name} is not a rotation matrix: it holds NaN or inf" if bad else
                         f"{name} is not a rotation matrix: entries of magnitude {max(map(abs, flat)):.3g}")
    err = max(abs(a0 * a0 + a3 * a3 + a6 * a6 - 1.0), abs(a1 * a1 + a4 * a4 + a7 * a7 - 1.0),
              abs(a2 * a2 + a5 * a5 + a8 * a8 - 1.0), abs(a0 * a1 + a3 * a4 + a6 * a7),
              abs(a0 * a2 + a3 * a5 + a6 * a8), abs(a1 * a2 + a4 * a5 + a7 * a8))
    if not err <= atol:
        raise ValueError(f"{name} is not a rotation matrix: max |R^T R - I| = {err:.3g}")
    if a0 * (a4 * a8 - a5 * a7) - a1 * (a3 * a8 - a5 * a6) + a2 * (a3 * a7 - a4 * a6) < 0:
        raise ValueError(f"{name} is a reflection (det -1), not a rotation")
