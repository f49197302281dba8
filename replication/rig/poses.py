"""Calibrate from static pose sets: ``R0`` from poses measured by both sides at the same stations
(e.g. a robot and a chessboard camera, Tabb & Ahmad Yousef's data), with a verdict.

Every pair of stations ``(i, j)`` (or consecutive ones) gives a motion pair (eqs. (3)-(4)); the
solve, the residuals and the verdict are :func:`replication.rig.solve_and_judge.solve_pairs`'s, the
bootstrap resamples *stations* (each station's measurement error is in every pair that uses it),
each station's median residual is reported, and an outlying station is named in the verdict. The
pose direction is always checked (:func:`replication.rig.diagnose.pose_direction`). Conventions:
``docs/conventions.md``.
"""
from __future__ import annotations

import numpy as np

from ..core.checks import check_number, check_rotation_matrices
from ..core.handeye import relative_rotations
from ..core.so3 import rotation_angle_deg
from .report import CalibrationResult
from .solve_and_judge import (
    Provenance,
    Resampling,
    check_common,
    check_options,
    first_reference,
    solve_pairs,
    with_reasons,
)

__all__ = ["calibrate_poses", "pose_pairs", "repeated_stations", "own_residuals_deg",
           "SAME_STATION_FLOOR_DEG"]

#: Two stations are the same (a repeat) when neither side turns more than ``min_motion_deg`` between
#: them (a pair of them carries noise, not motion, and is dropped), and at least when neither turns
#: more than this (deg): the same pose given twice, to rounding, with ``min_motion_deg = 0``.
SAME_STATION_FLOOR_DEG = 1e-6


def calibrate_poses(camera_attitudes, sensor_attitudes, *, method: str = "chordal_optimal",
                    pairs: str = "all", min_motion_deg: float = 2.0, n_bootstrap: int = 200, seed: int = 0,
                    reference=None, diagnose: bool = True, progress: bool = False, **options) -> CalibrationResult:
    """``R0`` from static poses measured by both sides (e.g. a robot and a chessboard camera), with
    a verdict.

    Parameters
    ----------
    camera_attitudes : array_like (N, 3, 3)
        ``camera_from_world`` (e.g. ``R_target2cam``: chessboard = world).
    sensor_attitudes : array_like (N, 3, 3)
        ``sensor_from_world`` (e.g. a robot's ``base -> hand`` rotation: base = world).
    pairs : {"all", "consecutive"}
        ``"all"``: every ``(i, j)``, ``i < j``, with ``A = C_j C_i^T``, ``B = S_j S_i^T``
        (eqs. (3)-(4)); ``"consecutive"``: ``(i, i + 1)`` only (the OpenCV wrappers rebuild the
        pose chain from these and form all pairs themselves).
    min_motion_deg : float
        Drop pairs whose sensor rotation is smaller than this.
    n_bootstrap, seed, reference, progress, **options
        As in :func:`replication.rig.calibration.calibrate`. The bootstrap resamples stations (with
        ``pairs="all"``; blocks of two pairs with ``"consecutive"``): see
        :mod:`replication.rig.solve_and_judge`.
    diagnose : bool
        Also calibrate with either pose set inverted, and fail naming the pose direction when one of
        them fits clearly better (:func:`replication.rig.diagnose.pose_direction`). Both sets
        inverted is a consistent problem for another unknown: only a reference reveals it.
    """
    references = check_common(method, n_bootstrap, seed, reference)  # one, or two (2, 3, 3)
    reference = first_reference(references)
    check_options(method, options)
    check_number("min_motion_deg", min_motion_deg, minimum=0, strict=False)
    C = check_rotation_matrices(camera_attitudes, "camera_attitudes", atol=1e-5)
    S = check_rotation_matrices(sensor_attitudes, "sensor_attitudes", atol=1e-5)
    if C.shape != S.shape or C.ndim != 3:
        raise ValueError(f"need two (N, 3, 3) arrays of the same N, got {C.shape} and {S.shape}")
    A, B, i, j = pose_pairs(C, S, pairs=pairs, min_motion_deg=min_motion_deg, stations=True)
    labels = repeated_stations(C, S, max(min_motion_deg, SAME_STATION_FLOOR_DEG))
    parameters = {"method": method, "pairs": pairs, "min_motion_deg": min_motion_deg, "n_bootstrap": n_bootstrap,
                  "seed": seed, "solver_options": {k: repr(v) for k, v in options.items()}}
    inputs = {"camera": {"kind": "static poses", "samples": int(len(C))},
              "sensor": {"kind": "static poses", "samples": int(len(S))}, "reference_camera_from_sensor": reference}
    if len(A) < 2:
        raise ValueError(f"{len(A)} pose pairs left after dropping those under min_motion_deg = {min_motion_deg:g}; "
                         f"lower it or give poses that differ more")
    own = (lambda R: own_residuals_deg(C, S, R)) if pairs == "consecutive" else None
    result = solve_pairs(A, B, method=method, options=options, reference=references, evidence={},
                         resampling=Resampling(n_bootstrap=n_bootstrap, seed=seed, stations=(i, j, len(C), labels),
                                               station_residual=own, progress=progress),
                         provenance=Provenance(parameters=parameters, inputs=inputs))
    if diagnose:
        from .diagnose import pose_direction

        found = pose_direction(C, S, base_residual_deg=result.residual_deg["median"], pairs=pairs,
                               min_motion_deg=min_motion_deg, calibrate_poses=calibrate_poses, reference=reference)
        if found:
            result = with_reasons(result, found)
    return result


def own_residuals_deg(C, S, R) -> np.ndarray:
    """Each station's own residual (deg) at the estimate ``R``: the angle between its ``Y_k = S_k^T
    R^T C_k`` (the target's frame in the robot base's, the same at every station when ``C_k = R0 S_k
    Y``) and a robust centre of them (the chordal mean of the half nearest the station whose median
    angle to the others is least).

    With consecutive pairs a bad station spoils both its pairs and each neighbour shares one of
    them, so the pairs' residuals blame the neighbours too; a station's own residual blames it
    alone."""
    Y = np.swapaxes(S, -1, -2) @ R.T @ C
    angles = rotation_angle_deg(np.swapaxes(Y[:, None], -1, -2) @ Y[None, :])
    medoid = int(np.argmin(np.median(angles, axis=1)))
    near = angles[medoid] <= np.median(angles[medoid])
    U, _, Vt = np.linalg.svd(Y[near].mean(axis=0))
    centre = U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt
    return rotation_angle_deg(np.swapaxes(Y, -1, -2) @ centre)


def repeated_stations(C, S, within_deg: float) -> np.ndarray:
    """Station labels: stations whose camera and sensor attitudes both lie within ``within_deg`` of
    each other (a station given twice, identical or re-measured within the noise) share a label, the
    group's first station; ``labels[k] == k`` for every station that repeats none before it. A
    station joins a group only if it lies within ``within_deg`` of every member (complete linkage):
    a chain of stations each close to the next, spanning more than ``within_deg``, is distinct
    stations, not one."""
    n = len(C)
    i, j = np.triu_indices(n, k=1)
    close = ((rotation_angle_deg(C[j] @ np.swapaxes(C[i], -1, -2)) <= within_deg)
             & (rotation_angle_deg(S[j] @ np.swapaxes(S[i], -1, -2)) <= within_deg))
    same = np.zeros((n, n), dtype=bool)
    same[i, j] = same[j, i] = close
    labels = np.arange(n)
    groups: dict[int, list[int]] = {}
    for k in range(n):
        for first, members in groups.items():  # the earliest group every member of which k repeats
            if same[k, members].all():
                labels[k] = first
                members.append(k)
                break
        else:
            groups[k] = [k]
    return labels


def pose_pairs(C, S, *, pairs: str = "all", min_motion_deg: float = 2.0, stations: bool = False):
    """Relative rotations from static attitudes (see :func:`calibrate_poses`); returns ``(A, B)``,
    and with ``stations`` the two station indices of each pair, ``(A, B, i, j)``."""
    if pairs == "all":
        i, j = np.triu_indices(len(C), k=1)
    elif pairs == "consecutive":
        i, j = np.arange(len(C) - 1), np.arange(1, len(C))
    else:
        shown = str(pairs) if isinstance(pairs, str) else pairs  # np.str_('x') shown as 'x'
        raise ValueError(f"pairs must be 'all' or 'consecutive', got {shown!r}")
    A = relative_rotations(C, pairs=(i, j), atol=1e-5)  # eq. (3)
    B = relative_rotations(S, pairs=(i, j), atol=1e-5)  # eq. (4)
    if pairs == "all":
        keep = rotation_angle_deg(B) > min_motion_deg
        A, B, i, j = A[keep], B[keep], i[keep], j[keep]
    return (A, B, i, j) if stations else (A, B)
