"""Calibrate a real rig: ``R0`` from a camera orientation stream and a sensor stream.

:func:`calibrate` turns two timestamped streams into motion pairs and solves
``A_j R0 = R0 B_j`` (the paper's eq. (7)) with any registered solver:

1. the sensor stream becomes an orientation stream (raw gyro samples are integrated,
   trapezoidal rate, body frame: ``Q(t + dt) = Q(t) exp([omega] dt)``);
2. the clock offset between the streams is estimated by cross-correlating their
   angular speeds and reported (and by default removed);
3. pairs: for every camera time ``t_i`` the camera time ``t_j`` closest to
   ``t_i + interval``; ``A = Qc_j^T Qc_i``, ``B = Qs(t_j)^T Qs(t_i)`` with ``Qs``
   slerp-interpolated (``Q`` are ``world_from_body``; this is eq. (3)-(4)'s
   ``C_k C_t^T`` with ``C = Q^T``);
4. the solver, the residual of every pair, the observability diagnostic, and a
   moving-block bootstrap over the pairs (overlapping pairs are correlated, so
   blocks span ``interval``) for a confidence radius in degrees.

Conventions (``R0 = camera_from_sensor``, quaternions ``(w, x, y, z)``, yaw / pitch / roll):
``docs/conventions.md``.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .handeye import pair_residual_deg, relative_rotations
from .motions import MotionObservability, prepare_motions
from .so3 import (
    angle_between_deg, as_quaternion, check_rotation_matrices, log_map, rotation_angle_deg, yaw_pitch_roll_deg,
)
from .streams import GyroStream, OrientationStream, integrate_gyro  # integrate_gyro re-exported: a public name here
from .solvers import ReplicationWarning, solve, solver_info

__all__ = [
    "CalibrationResult", "calibrate", "calibrate_poses", "integrate_gyro", "estimate_time_offset", "motion_pairs",
    "stream_pairs", "pose_pairs",
]


@dataclass(frozen=True)
class CalibrationResult:
    """What :func:`calibrate` returns; ``to_dict()`` gives the JSON report.

    Attributes
    ----------
    R : ndarray (3, 3)
        ``camera_from_sensor`` (det +1).
    quaternion_wxyz : ndarray (4,)
        The same rotation, scalar first, ``w >= 0``.
    euler_zyx_deg : ndarray (3,)
        Yaw, pitch, roll (intrinsic z-y'-x''), degrees.
    method : str
    interval_s : float
        Pairing interval.
    n_pairs : int
    time_offset_s, time_offset_correlation : float
        Estimated sensor-clock offset (sensor sample at ``t + offset`` matches the camera at ``t``)
        and the correlation of the angular speeds there.
    time_offset_applied : bool
    residual_deg : dict
        Per-pair residual angle (angle of ``R^T A_j R B_j^T``): mean, median, rms, p95, max.
    bootstrap_ci95_deg : float
        95th percentile of the angle between bootstrap estimates and ``R`` (NaN if no bootstrap).
    observability : MotionObservability
    reference_error_deg : float or None
        Angle to a reference rotation, when one was given.
    """

    R: np.ndarray
    quaternion_wxyz: np.ndarray
    euler_zyx_deg: np.ndarray
    method: str
    interval_s: float
    n_pairs: int
    time_offset_s: float
    time_offset_correlation: float
    time_offset_applied: bool
    residual_deg: dict
    bootstrap_ci95_deg: float
    observability: MotionObservability = field(repr=False)
    reference_error_deg: float | None = None

    def to_dict(self) -> dict:
        """A JSON-serialisable report (conventions included)."""
        obs = self.observability
        return {
            "R0_camera_from_sensor": np.round(self.R, 12).tolist(),
            "quaternion_wxyz": np.round(self.quaternion_wxyz, 12).tolist(),
            "euler_zyx_deg": {"yaw": float(self.euler_zyx_deg[0]), "pitch": float(self.euler_zyx_deg[1]),
                              "roll": float(self.euler_zyx_deg[2])},
            "conventions": "R0 maps sensor-frame vectors into the camera frame (A_j R0 = R0 B_j); "
                           "quaternion scalar first; Euler intrinsic z-y'-x'' (yaw, pitch, roll)",
            "method": self.method,
            "interval_s": self.interval_s,
            "n_pairs": self.n_pairs,
            "time_offset_s": self.time_offset_s,
            "time_offset_correlation": self.time_offset_correlation,
            "time_offset_applied": self.time_offset_applied,
            "residual_deg": self.residual_deg,
            "bootstrap_ci95_deg": self.bootstrap_ci95_deg,
            "observability": {
                "spectral_ratio": float(obs.spectral_ratio),
                "camera_axis_spread_deg": float(obs.camera_axis_spread_deg),
                "sensor_axis_spread_deg": float(obs.sensor_axis_spread_deg),
            },
            "reference_error_deg": self.reference_error_deg,
        }

    def summary(self) -> str:
        """A short human-readable report."""
        yaw, pitch, roll = self.euler_zyx_deg
        lines = [
            f"R0 (camera_from_sensor), {self.method}, {self.n_pairs} pairs at {self.interval_s:g} s:",
            *("  [" + "  ".join(f"{v:+.6f}" for v in row) + "]" for row in self.R),
            f"quaternion (w, x, y, z): {np.array2string(self.quaternion_wxyz, precision=6)}",
            f"yaw / pitch / roll (z-y'-x''): {yaw:.3f} / {pitch:.3f} / {roll:.3f} deg",
            f"time offset: {1e3 * self.time_offset_s:+.1f} ms (correlation {self.time_offset_correlation:.4f}, "
            f"{'applied' if self.time_offset_applied else 'not applied'})",
            f"pair residuals: median {self.residual_deg['median']:.3f} deg, rms {self.residual_deg['rms']:.3f} deg",
            f"bootstrap 95% radius: {self.bootstrap_ci95_deg:.3f} deg; axis spread camera "
            f"{float(self.observability.camera_axis_spread_deg):.1f} deg",
        ]
        if self.reference_error_deg is not None:
            lines.append(f"angle to the reference: {self.reference_error_deg:.3f} deg")
        return "\n".join(lines)


def _speed(Q, times) -> np.ndarray:
    """Angular speed (rad/s) between consecutive orientations along axis -3, batched over leading axes."""
    rel = np.swapaxes(Q[..., :-1, :, :], -1, -2) @ Q[..., 1:, :, :]
    return np.linalg.norm(log_map(rel), axis=-1) / np.diff(times)


def estimate_time_offset(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                         resolution: float = 0.5e-3):
    """Clock offset by cross-correlating angular speeds; returns ``(offset_s, correlation)``.

    The offset ``d`` maximises the correlation between the camera's angular speed over
    ``[t_k, t_{k+1}]`` and the sensor's over ``[t_k + d, t_{k+1} + d]`` (sensor slerped);
    searched on a 10 ms grid in ``[-max_offset, max_offset]``, then refined to ``resolution``.
    """
    lo = max(camera.t[0], sensor.t[0] + max_offset)
    hi = min(camera.t[-1], sensor.t[-1] - max_offset)
    keep = (camera.t >= lo) & (camera.t <= hi)
    t = camera.t[keep]
    if len(t) < 10:
        raise ValueError(f"the streams overlap in fewer than 10 camera samples (overlap {lo:.3f}..{hi:.3f} s)")
    cam = _speed(camera.R[keep], t)

    def corr(offsets):
        Qs = sensor.at((t[None, :] + offsets[:, None]).ravel()).reshape(len(offsets), len(t), 3, 3)
        sen = _speed(Qs, t)
        a = cam - cam.mean()
        b = sen - sen.mean(axis=1, keepdims=True)
        return (b @ a) / (np.linalg.norm(a) * np.linalg.norm(b, axis=1))

    coarse = np.arange(-max_offset, max_offset + 1e-12, 0.01)
    best = coarse[np.argmax(corr(coarse))]
    fine = np.clip(np.arange(best - 0.01, best + 0.01 + 1e-12, resolution), -max_offset, max_offset)
    c = corr(fine)
    k = int(np.argmax(c))
    return float(fine[k]), float(c[k])


def motion_pairs(camera: OrientationStream, sensor: OrientationStream, interval: float, *, offset: float = 0.0):
    """Relative-rotation pairs ``(A, B)`` at ``interval`` seconds (see the module notes).

    Returns
    -------
    (A, B, t_start) : ndarray (J, 3, 3), ndarray (J, 3, 3), ndarray (J,)
    """
    if not interval > 0:
        raise ValueError(f"interval must be positive, got {interval!r}")
    t = camera.t
    inside = (t + offset >= sensor.t[0]) & (t + offset <= sensor.t[-1])
    t, Qc = t[inside], camera.R[inside]
    j = np.clip(np.searchsorted(t, t + interval), 1, len(t) - 1)
    j = np.where(np.abs(t[j - 1] - t - interval) < np.abs(t[j] - t - interval), j - 1, j)
    tol = 0.5 * np.median(np.diff(t))
    i = np.flatnonzero((np.abs(t[j] - t - interval) <= tol) & (j > np.arange(len(t))))
    j = j[i]
    if len(i) < 2:
        raise ValueError(f"fewer than 2 motion pairs at interval {interval:g} s (streams overlap "
                         f"{t[-1] - t[0] if len(t) else 0:.2f} s)")
    A = relative_rotations(Qc, pairs=(i, j), convention="world_from_body", atol=1e-5)  # eq. (3): C_k C_t^T, C = Q^T
    B = relative_rotations(sensor.at(t + offset), pairs=(i, j), convention="world_from_body", atol=1e-5)  # eq. (4)
    return A, B, t[i]


def stream_pairs(camera: OrientationStream, sensor, *, interval: float = 1.0, max_offset: float = 0.2,
                 correct_offset: bool = True):
    """Steps 1-3 of :func:`calibrate`: integrate a gyro, estimate the clock offset, form the pairs.

    Returns
    -------
    (A, B, offset_s, correlation)
    """
    if isinstance(sensor, GyroStream):
        sensor = integrate_gyro(sensor)
    if not isinstance(camera, OrientationStream) or not isinstance(sensor, OrientationStream):
        raise ValueError("camera must be an OrientationStream and sensor an OrientationStream or GyroStream")
    offset, corr = estimate_time_offset(camera, sensor, max_offset=max_offset)
    A, B, _ = motion_pairs(camera, sensor, interval, offset=offset if correct_offset else 0.0)
    return A, B, offset, corr


def calibrate(camera: OrientationStream, sensor, *, method: str = "chordal_optimal", interval: float = 1.0,
              stride: int = 1, max_offset: float = 0.2, correct_offset: bool = True, n_bootstrap: int = 200,
              seed: int = 0, reference=None, **options) -> CalibrationResult:
    """``R0`` (camera_from_sensor) of a real rig from two timestamped streams.

    Parameters
    ----------
    camera : OrientationStream
        Camera ``world_from_camera`` orientations (a SLAM trajectory, PnP poses inverted, ...).
    sensor : OrientationStream or GyroStream
        Sensor ``world_from_sensor`` orientations, or raw body-frame rates (integrated here).
    method : str
        A registered solver (:func:`replication.solvers.available`); the two-step solvers get
        enough iterations to reach their fixed point.
    interval : float
        Seconds between the two orientations of a pair.
    stride : int
        Keep every ``stride``-th pair (pairs start at every camera time and overlap; a stride
        of ``interval`` times the camera rate gives non-overlapping pairs, e.g. for OpenCV,
        which forms all pairs of the pose chain itself).
    max_offset : float
        Largest clock offset searched (s).
    correct_offset : bool
        Shift the sensor clock by the estimated offset before pairing.
    n_bootstrap : int
        Moving-block bootstrap replicates (0: none).
    seed : int
        Seeds the bootstrap.
    reference : None or array_like (3, 3)
        A reference ``R0``; the result then reports the angle to it.
    **options
        Passed to the solver.

    Returns
    -------
    CalibrationResult
    """
    solver_info(method)  # unknown names fail before any work
    A, B, offset, corr = stream_pairs(camera, sensor, interval=interval, max_offset=max_offset,
                                      correct_offset=correct_offset)
    A, B = A[::stride], B[::stride]
    # overlapping pairs are correlated: bootstrap blocks span one interval
    block = max(1, round(interval / np.median(np.diff(camera.t)) / stride))
    return _solve_pairs(A, B, method=method, interval=float(interval), block=block, n_bootstrap=n_bootstrap,
                        seed=seed, reference=reference, time_offset=(offset, corr, bool(correct_offset)),
                        options=options)


def calibrate_poses(camera_attitudes, sensor_attitudes, *, method: str = "chordal_optimal",
                    pairs: str = "all", min_motion_deg: float = 2.0, n_bootstrap: int = 200, seed: int = 0,
                    reference=None, **options) -> CalibrationResult:
    """``R0`` from static poses measured by both sides (e.g. a robot and a chessboard camera).

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
    n_bootstrap, seed, reference, **options
        As in :func:`calibrate`. The bootstrap resamples pairs one by one; pairs that share a
        pose are correlated, so its radius understates the uncertainty.
    """
    C = check_rotation_matrices(camera_attitudes, "camera_attitudes", atol=1e-5)
    S = check_rotation_matrices(sensor_attitudes, "sensor_attitudes", atol=1e-5)
    if C.shape != S.shape or C.ndim != 3:
        raise ValueError(f"need two (N, 3, 3) arrays of the same N, got {C.shape} and {S.shape}")
    A, B = pose_pairs(C, S, pairs=pairs, min_motion_deg=min_motion_deg)
    return _solve_pairs(A, B, method=method, interval=float("nan"), block=1, n_bootstrap=n_bootstrap,
                        seed=seed, reference=reference, time_offset=(0.0, float("nan"), False), options=options)


def pose_pairs(C, S, *, pairs: str = "all", min_motion_deg: float = 2.0):
    """Relative rotations from static attitudes (see :func:`calibrate_poses`); returns ``(A, B)``."""
    if pairs == "all":
        i, j = np.triu_indices(len(C), k=1)
    elif pairs == "consecutive":
        i, j = np.arange(len(C) - 1), np.arange(1, len(C))
    else:
        raise ValueError(f"pairs must be 'all' or 'consecutive', got {pairs!r}")
    A = relative_rotations(C, pairs=(i, j), atol=1e-5)  # eq. (3)
    B = relative_rotations(S, pairs=(i, j), atol=1e-5)  # eq. (4)
    if pairs == "all":
        keep = rotation_angle_deg(B) > min_motion_deg
        A, B = A[keep], B[keep]
    return A, B


def _solve_pairs(A, B, *, method, interval, block, n_bootstrap, seed, reference, time_offset, options):
    """Solve, residuals, moving-block bootstrap; the common end of :func:`calibrate` and :func:`calibrate_poses`."""
    motions = prepare_motions(A, B)  # validated once: the solve and every bootstrap replicate use it
    sol = solve(method, motions, full_output=True, **options)
    R = sol.R
    res = pair_residual_deg(R, A, B)
    ci = float("nan")
    if n_bootstrap:
        rng = np.random.default_rng(seed)
        J = len(A)
        block = int(min(J, block))
        starts = rng.integers(0, J - block + 1, size=(n_bootstrap, -(-J // block)))
        idx = (starts[..., None] + np.arange(block)).reshape(n_bootstrap, -1)[:, :J]
        with warnings.catch_warnings():
            # the resampled pairs were validated above: call the solver's core; the replicates' own
            # warnings would repeat the main solve's
            warnings.simplefilter("ignore", ReplicationWarning)
            R_boot = solver_info(method).core(motions.subset(idx), **options)
        ci = float(np.percentile(angle_between_deg(R_boot, R), 95))
    offset, corr, applied = time_offset
    return CalibrationResult(
        R=R,
        quaternion_wxyz=as_quaternion(R),
        euler_zyx_deg=yaw_pitch_roll_deg(R),
        method=method,
        interval_s=interval,
        n_pairs=int(len(A)),
        time_offset_s=offset,
        time_offset_correlation=corr,
        time_offset_applied=applied,
        residual_deg={"mean": float(res.mean()), "median": float(np.median(res)),
                      "rms": float(np.sqrt(np.mean(res ** 2))), "p95": float(np.percentile(res, 95)),
                      "max": float(res.max())},
        bootstrap_ci95_deg=ci,
        observability=sol.observability,
        reference_error_deg=None if reference is None else float(angle_between_deg(R, np.asarray(reference))),
    )
