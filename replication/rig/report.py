"""What a calibration returns (:class:`CalibrationResult`): the estimate, its evidence, its verdict,
its report.

``to_dict()`` is the self-describing JSON report (strict JSON: ``null`` where a number is undefined;
schema: ``docs/calibration_report.schema.json``); ``summary()`` the human-readable one; ``plot()``
the diagnostic figure. Conventions (``R0 = camera_from_sensor``, quaternions ``(w, x, y, z)``, yaw /
pitch / roll): ``docs/conventions.md``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.motions import MotionObservability
from .association import offset_in_words
from .gyro_held import held_lines
from .quality import Verdict, p_with_level

__all__ = ["CalibrationResult", "OFFSET_CONVENTION", "RADIUS_COVERS", "json_safe"]

#: The sign convention of the clock offset, in words (stored in every report).
OFFSET_CONVENTION = ("time_offset_s = d means the sensor sample stamped t + d matches the camera sample stamped t "
                     "(d > 0: the sensor clock runs d ahead of the camera's; d < 0: behind by |d|); Kalibr's "
                     "timeshift_cam_imu (t_imu = t_cam + shift) is d; the pairs use sensor times t + d when the offset "
                     "is applied")
#: What every radius of this package covers, and what it does not (stated in reports, summaries and
#: figures).
RADIUS_COVERS = ("the pairs' own noise only (their scatter about the estimate); errors every pair shares (a "
                 "trajectory's bias, a clock or scale error, the reference's own error) are not in it")


def json_safe(value):
    """``value`` with NumPy types made native and every NaN or infinity made ``None`` (strict
    JSON)."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


_SENSOR_KEYS = ("gyro_bias_rad_s", "gyro_bias_ci95_rad_s", "clock_drift_ppm", "clock_drift_ci95_ppm", "gyro_scale",
                "gyro_scale_ci95", "gyro_misalignment", "gyro_misalignment_ci95", "sensor_model")


def _sensor_fields(model) -> dict:
    """The report's sensor-model fields (all null for an orientation sensor)."""
    return {key: None if model is None else model.get(key) for key in _SENSOR_KEYS}


def _sensor_lines(model) -> list:
    """The summary's (and the figure's) lines on a gyro's bias and the clock's drift, from a
    report's ``sensor_model`` fields (none for an orientation sensor)."""
    if model is None:
        return []
    if model.get("gyro_bias_rad_s") is None:
        return [f"gyro bias: not estimated ({model['sensor_model'].get('note')})"]
    ci = np.degrees(model["gyro_bias_ci95_rad_s"])
    axes = ", ".join(f"{np.degrees(b):+.3f} [{lo:+.3f}, {hi:+.3f}]" for b, (lo, hi) in zip(model["gyro_bias_rad_s"],
                                                                                           ci))
    details = model["sensor_model"]
    if model.get("clock_drift_ppm") is None:  # beside a clock step (sensor_verdict.drift_beside_steps)
        drift = f"clock drift: {details.get('drift_note', 'not measured')}"
    else:
        lo, hi = model["clock_drift_ci95_ppm"]
        drift = (f"clock drift: {model['clock_drift_ppm']:+.1f} ppm, 95 % interval [{lo:+.1f}, {hi:+.1f}] ppm"
                 + ("" if details["drift_resolved"] else " (not resolved: it includes 0)"))
    return [f"gyro bias (x, y, z), deg/s with 95 % intervals: {axes} "
            f"({'removed' if details['bias_applied'] else 'measured, not removed'})", drift] + _scale_lines(model)


def _scale_lines(model) -> list:
    """The summary's line on the gyro's scale per axis (held at 1 where the motion does not resolve
    it)."""
    if model.get("gyro_scale") is None:
        return []
    held = model["sensor_model"].get("scale_held_ci95") or [None] * 3
    axes = ", ".join(f"{s:.4f} [{ci[0]:.4f}, {ci[1]:.4f}]" if ci is not None else "1 (held: not resolved" + (
        f"; fitted free, it lies in [{h[0]:.4f}, {h[1]:.4f}])" if h is not None else ")")
        for s, ci, h in zip(model["gyro_scale"], model["gyro_scale_ci95"], held))
    note = model["sensor_model"].get("scale_note")
    applied = "removed" if model["sensor_model"]["bias_applied"] else "measured, not removed"
    lines = [f"gyro scale (x, y, z) with 95 % intervals: {axes} ({applied}" + (f"; {note})" if note else ")")]
    if model.get("gyro_misalignment") is not None:
        terms = ", ".join(f"{m:+.4f} [{ci[0]:+.4f}, {ci[1]:+.4f}]" if ci is not None else "0 (held: not resolved)"
                          for m, ci in zip(model["gyro_misalignment"], model["gyro_misalignment_ci95"]))
        lines.append(f"gyro misalignment (xy, xz, yz; T_g's symmetric off-diagonal) with 95 % intervals: {terms} "
                     f"({applied})")
    lines += held_lines(model["sensor_model"])
    return lines


def _segment_lines(s) -> list:
    """The summary's lines on the segment test and the clock jumps
    (:mod:`replication.rig.segments`)."""
    if s is None:
        return []
    if not s["run"]:
        lines = [f"segments: {s['note']}"]
    else:
        n, bad = len(s["segments"]), s["disagreeing"]
        named = ", ".join(f"{s['segments'][i]['start_s']:.1f}-{s['segments'][i]['end_s']:.1f} s" for i in bad)
        own = ", ".join(f"{s['segments'][i]['p_value']:.2g}" for i in bad)
        lines = [f"segments: {n} of about 10 s (1 s pairs) " + (
                     f"disagree: {named} (each by its own test, p = {own}; all the segments together p = "
                     f"{s['p_value']:.2g})" if bad else f"agree (p = {s['p_value']:.2g})") +
                 f"; 95 % radius from the pairs {s['pairs_radius_deg']:.3f} deg, from the "
                 f"spread between segments {s['between_radius_deg']:.3f} deg"]
    used = s.get("use")
    if used is not None and used.get("kept_s") is not None:
        spans = ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in s.get("consistent_spans_s", []))
        if not used.get("left_out_spans_s"):
            lines.append(f"use='consistent': every segment agrees, nothing left out: R0 from all of {spans} "
                         f"({used['pairs_kept']} pairs)")
        else:
            lines.append(f"use='consistent': R0 from {spans} ({used['pairs_kept']} pairs; the majority, not known to "
                         f"be right: {used.get('R0_moves_deg_if_left_out_part_is_right', math.nan):.2f} deg away if "
                         f"the part left out is)")
    lines += [f"clock jump at {j['time_s']:.1f} s: {1e3 * j['size_s']:+.1f} ms (clock: {j.get('clock', 'sensor')})"
              for j in s.get("clock_jumps", [])]
    return lines


@dataclass(frozen=True)
class CalibrationResult:
    """What :func:`replication.rig.calibration.calibrate` (and ``calibrate_poses``) return.

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
        Pairing interval (NaN for static pose sets).
    n_pairs : int
    time_offset_s, time_offset_correlation : float
        Estimated sensor-clock offset (see :data:`OFFSET_CONVENTION`) and the correlation of the
        angular speeds there; both NaN (``null`` in the report) for static pose sets, which have no
        clock: no offset was measured, so an export leaves a file's own offset as it was.
    time_offset_applied : bool
    time_offset_ci95_s : (float, float)
        95 % block-bootstrap interval of the offset
        (:func:`replication.rig.association.offset_analysis`; NaN without a bootstrap, infinite at
        an end where the replicates leave the offsets searched).
    time_offset_peak_margin : float
        Correlation at the offset minus that at the best other peak (NaN: no other peak in the
        search).
    residual_deg : dict
        Per-pair residual angle (angle of ``R^T A_j R B_j^T``): mean, median, rms, p95, max.
    bootstrap_ci95_deg : float
        95th percentile of the angle between bootstrap estimates and ``R``; NaN without a bootstrap
        or with too few independent blocks for one to mean anything (see
        :mod:`replication.rig.quality`).
    observability : MotionObservability
    reference_error_deg : float or None
        Angle to a reference rotation, when one was given (with two: to the first).
    reference_errors_deg, reference_disagreement_deg, reference_reading : tuple, float, str or None
        With two references (e.g. two published calibrations): the angle to each, the angle between
        them (the reference floor: an error below it is agreement, not accuracy) and which reading
        applies.
    bootstrap_resamples : str
        What the bootstrap resampled ("pairs in moving blocks of N", "stations", or "none").
    bootstrap_covers : str
        What the radius covers (:data:`RADIUS_COVERS`): the pairs' own noise, not errors every pair
        shares.
    pose_residual_median_deg : list of float or None
        Static pose sets: each station's median pair residual (0-based station order).
    station_repeats : dict or None
        Static pose sets with stations that repeat others
        (:func:`replication.rig.poses.repeated_stations`): ``stations`` given, ``distinct``, and the
        ``groups`` of repeats (0-based); each group is one station in the bootstrap. None otherwise.
    change_test : dict or None
        Streams: the change test (:func:`replication.rig.changepoint.two_segment_test`; did ``R0``
        change during the recording? times since the camera's first sample), or why it was not run;
        None for static pose sets.
    segments : dict or None
        Streams: R0 per segment of the recording and whether the segments agree
        (:func:`replication.rig.segments.segment_test`; times since the camera's first sample), the
        two radii (from the pairs, from the spread between segments), the consistent part and what
        ``use="consistent"`` kept; or why it was not run; None for static pose sets.
    online : dict or None
        ``calibrate --online``: what the online replay found
        (:meth:`replication.rig.live.LiveRig.summary`).
    sensor_model : dict or None
        A gyro sensor: its bias and the clock's drift estimated with ``R0``
        (:mod:`replication.rig.sensor_model`): ``gyro_bias_rad_s`` (3), ``gyro_bias_ci95_rad_s`` (3
        x 2), ``clock_drift_ppm``, ``clock_drift_ci95_ppm`` (None where not estimated, or beside a
        clock step: ``sensor_model["drift_note"]`` says why) and the details under
        ``sensor_model``; None for an orientation sensor.
    verdict : Verdict
        ``ok`` / ``warning`` / ``fail`` and every reason with its measured number and threshold
        (:mod:`replication.rig.quality`).
    warnings : tuple of str
        ``"<class>: <message>"`` of every warning of ours the calibration issued.
    parameters : dict
        Every parameter of the call.
    inputs : dict
        The streams: kind, source, samples, span (s), and their overlap; the reference matrix if
        any.
    diagnostics : dict
        Arrays for :meth:`plot`: ``pair_times`` (s), ``residuals_deg``, ``bootstrap_rotvec_deg``
        (bootstrap estimates as rotation vectors of ``R_boot R^T``), ``offset_curve`` (offsets,
        correlations), ``speeds`` (times, camera and aligned sensor angular speed, deg/s). Not in
        the JSON report.
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
    reference_errors_deg: tuple | None = None
    reference_disagreement_deg: float | None = None
    reference_reading: str | None = None
    time_offset_ci95_s: tuple = (math.nan, math.nan)
    time_offset_peak_margin: float = math.nan
    bootstrap_resamples: str = "none"
    bootstrap_covers: str = RADIUS_COVERS
    pose_residual_median_deg: list | None = None
    station_repeats: dict | None = None
    change_test: dict | None = None
    segments: dict | None = None
    online: dict | None = None
    sensor_model: dict | None = None
    verdict: Verdict = field(default_factory=lambda: Verdict.of(()))
    warnings: tuple = ()
    parameters: dict = field(default_factory=dict)
    inputs: dict = field(default_factory=dict)
    diagnostics: dict = field(default_factory=dict, repr=False)

    def to_dict(self) -> dict:
        """The JSON report: strict JSON (``null``, never NaN), conventions and the offset's sign in
        words."""
        from .._version import __version__

        obs = self.observability
        return json_safe({
            "package": {"name": "replication", "version": __version__},
            "R0_camera_from_sensor": np.round(self.R, 12),
            "quaternion_wxyz": np.round(self.quaternion_wxyz, 12),
            "euler_zyx_deg": {"yaw": self.euler_zyx_deg[0], "pitch": self.euler_zyx_deg[1],
                              "roll": self.euler_zyx_deg[2]},
            "conventions": "R0 maps sensor-frame vectors into the camera frame (A_j R0 = R0 B_j); "
                           "quaternion scalar first; Euler intrinsic z-y'-x'' (yaw, pitch, roll)",
            "verdict": self.verdict.to_dict(),
            "warnings": list(self.warnings),
            "method": self.method,
            "parameters": self.parameters,
            "inputs": self.inputs,
            "interval_s": self.interval_s,
            "n_pairs": self.n_pairs,
            "time_offset_s": self.time_offset_s,
            "time_offset_correlation": self.time_offset_correlation,
            "time_offset_applied": self.time_offset_applied,
            "time_offset_convention": OFFSET_CONVENTION,
            "time_offset_ci95_s": list(self.time_offset_ci95_s),
            "time_offset_peak_margin": self.time_offset_peak_margin,
            "residual_deg": self.residual_deg,
            "bootstrap_ci95_deg": self.bootstrap_ci95_deg,
            "bootstrap_resamples": self.bootstrap_resamples,
            "bootstrap_covers": self.bootstrap_covers,
            "pose_residual_median_deg": self.pose_residual_median_deg,
            "station_repeats": self.station_repeats,
            "change_test": self.change_test,
            "segments": self.segments,
            "online": self.online,
            "observability": {
                "spectral_ratio": float(obs.spectral_ratio),
                "camera_axis_spread_deg": float(obs.camera_axis_spread_deg),
                "sensor_axis_spread_deg": float(obs.sensor_axis_spread_deg),
            },
            "reference_error_deg": self.reference_error_deg,
            "reference_errors_deg": None if self.reference_errors_deg is None else list(self.reference_errors_deg),
            "reference_disagreement_deg": self.reference_disagreement_deg,
            "reference_reading": self.reference_reading,
            **_sensor_fields(self.sensor_model),
        })

    def summary(self) -> str:
        """A short human-readable report, verdict first."""
        yaw, pitch, roll = self.euler_zyx_deg
        pairs = (f"{self.n_pairs} pairs at {self.interval_s:g} s" if math.isfinite(self.interval_s)
                 else f"{self.n_pairs} pairs of static poses")
        boot = (f"{self.bootstrap_ci95_deg:.3f} deg" if math.isfinite(self.bootstrap_ci95_deg)
                else "not available")
        lines = [
            *self.verdict.lines(),
            f"R0 (camera_from_sensor), {self.method}, {pairs}:",
            *("  [" + "  ".join(f"{v:+.6f}" for v in row) + "]" for row in self.R),
            f"quaternion (w, x, y, z): {np.array2string(self.quaternion_wxyz, precision=6)}",
            f"yaw / pitch / roll (z-y'-x''): {yaw:.3f} / {pitch:.3f} / {roll:.3f} deg",
        ]
        if math.isfinite(self.time_offset_correlation):
            words = offset_in_words(self.time_offset_s, decimals=2, ci95_s=self.time_offset_ci95_s)
            lines.append(f"time offset: {words} (correlation {self.time_offset_correlation:.4f}, "
                         f"{'applied' if self.time_offset_applied else 'not applied'})")
        lines += [
            f"pair residuals: median {self.residual_deg['median']:.3f} deg, rms {self.residual_deg['rms']:.3f} deg",
            f"bootstrap 95% radius: {boot} (resampling {self.bootstrap_resamples}); it covers {self.bootstrap_covers}",
            f"axis spread camera {float(self.observability.camera_axis_spread_deg):.1f} deg",
        ]
        c = self.change_test
        if c is not None:
            p_test = p_with_level(c["p_value"], c.get("level"), c["significant"]) if c["run"] else ""
            lines.append(f"change test: {c['note']}" if not c["run"] else (
                f"change test: R0 before and after {c['split_time_s']:.1f} s differ by {c['angle_deg']:.3f} deg, "
                + ("beyond" if c["significant"] else "within") + f" their noise ({p_test}; splits "
                f"tested from {c['splits_from_s']:.1f} to {c['splits_to_s']:.1f} s: a change outside cannot be told)"))
        lines += _sensor_lines(self.sensor_model)
        lines += _segment_lines(self.segments)
        if self.reference_errors_deg is not None:
            e1, e2 = self.reference_errors_deg
            lines.append(f"angle to reference 1: {e1:.3f} deg, to reference 2: {e2:.3f} deg; the references disagree "
                         f"by {self.reference_disagreement_deg:.3f} deg (the reference floor)")
            lines.append(f"reading: {self.reference_reading}")
        elif self.reference_error_deg is not None:
            lines.append(f"angle to the reference: {self.reference_error_deg:.3f} deg")
        return "\n".join(lines)

    def plot(self, path=None, *, name: str | None = None, reference_name: str | None = None):
        """The diagnostic figure (:func:`replication.rig.figure.calibration_figure`; ``name``: the
        recording, in its title; ``reference_name``: where the reference came from); saved to
        ``path`` if given, in the format its extension names (``.png``, ``.pdf``, ``.svg``; another
        extension is refused with a ``ValueError`` before the figure is drawn), written
        atomically."""
        from .._io import figure_bytes, figure_format, write_atomic
        from .figure import calibration_figure

        fmt = figure_format(path) if path is not None else None
        fig = calibration_figure(self, name=name, reference_name=reference_name)
        if path is not None:
            write_atomic(path, figure_bytes(fig, fmt, dpi=110))
        return fig
