"""Time association of two streams, its doors: the clock offset between them (the estimate, its
interval and peak margin, its sign in words) and the motion pairs they share; the offset's numerical
core (the correlation curve, its refined peak, the bootstrap replicates) is
:mod:`replication.rig.offset_search`. Theory and measured numbers: ``docs/reading.md``, section
``replication.rig.association``."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.checks import check_number
from ..core.handeye import relative_rotations
from .offset_search import PEAK_SEPARATION_S, _search, bootstrap_offsets, overlap
from .streams import GyroStream, OrientationStream, integrate_gyro

__all__ = ["OffsetEstimate", "estimate_time_offset", "offset_analysis", "offset_in_words", "motion_pairs",
           "stream_pairs"]


def estimate_time_offset(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                         resolution: float = 0.5e-3, full_output: bool = False):
    """Clock offset by cross-correlating angular speeds; returns ``(offset_s, correlation)``.

    The offset ``d`` maximises the correlation ``r(d)`` between the camera's angular speed over
    ``[t_k, t_{k+1}]`` and the sensor's over ``[t_k + d, t_{k+1} + d]`` (sensor slerped). It is
    searched on a 10 ms grid in ``[-max_offset, max_offset]``, then on a ``resolution`` grid within
    10 ms of the coarse maximum, then on the sub-grid ``h = resolution / SUBGRID_STEPS`` within one
    ``resolution`` of the fine maximum, and refined there by the parabola through the maximum and
    its two neighbours (:func:`~replication.rig.offset_search.vertex`; for a smooth peak its error
    is ``O(h^2 r'''/r'')``, at most 0.0011 ms on the recordings of
    :data:`~replication.rig.offset_search.SUBGRID_STEPS`). Other local maxima of the coarse curve
    within :data:`~replication.rig.offset_search.RIVAL_REFINED_WITHIN` of its maximum (periodic
    motion) are refined the same way, and the highest refined peak is ``d``. ``d`` is Kalibr's
    ``timeshift_cam_imu`` (:func:`offset_in_words`).

    Cost: time ``O((max_offset / 10 ms + 0.02 s / resolution) x camera times)``, the second term
    once more for each rival refined (at most :data:`~replication.rig.offset_search.RIVALS_REFINED`;
    none on the recordings measured); memory bounded by
    :data:`~replication.rig.offset_search.OFFSET_BLOCK_SAMPLES` interpolated samples (~80 MB) plus 8
    bytes per candidate offset, whatever ``max_offset`` is (the candidates are evaluated block by
    block, see :func:`~replication.rig.offset_search.correlations`).

    Parameters
    ----------
    camera, sensor : OrientationStream
    max_offset : float
        Largest offset searched (s), positive and finite.
    resolution : float
        Step of the fine search (s), positive and finite.
    full_output : bool
        Also return the correlation curve: the candidate offsets searched (coarse, fine, sub-grid
        and the refined offset, sorted) and their correlations (for
        :meth:`replication.rig.report.CalibrationResult.plot`).

    Returns
    -------
    (offset_s, correlation) : (float, float)
        The refined offset and ``r`` evaluated at it (one more evaluation, not the parabola's
        value). With ``full_output``: ``(offset_s, correlation, (offsets, correlations))``.

    Where either stream's angular speed does not vary at all (a rig at rest) no offset can be
    estimated: 0 with a NaN correlation (the verdict then fails on the correlation).

    Raises
    ------
    ValueError
        ``max_offset`` or ``resolution`` not a positive finite number; the streams overlap in fewer
        than 10 camera samples once shifted by ``max_offset``.
    """
    s = _search(camera, sensor, max_offset, resolution, keep_rows=False)
    return (s["offset"], s["corr"], s["curve"]) if full_output else (s["offset"], s["corr"])


@dataclass(frozen=True, eq=False)
class OffsetEstimate:
    """A clock offset from :func:`offset_analysis`, with its 95 % interval and the ambiguity of its
    peak.

    Attributes
    ----------
    offset_s : float
        The refined offset ``d`` (s): the sensor sample stamped ``t + d`` matches the camera sample
        stamped ``t`` (Kalibr's ``timeshift_cam_imu``; :func:`offset_in_words`).
    correlation : float
        The correlation of the angular speeds evaluated at ``offset_s``.
    grid_offset_s : float
        The maximum of the fine grid, before the sub-grid refinement.
    ci95_s : (float, float)
        The 2.5 and 97.5 percentiles of the block-bootstrap offsets (the order statistics at or
        outside them); an end is infinite when more than 2.5 % of the replicates peak beyond the
        offsets they are evaluated on (:data:`~replication.rig.offset_search.BOOTSTRAP_SPAN_S`);
        ``(nan, nan)`` without replicates.
    second_peak_offset_s, second_peak_correlation : float
        The highest other peak farther than ``peak_separation_s`` from ``offset_s``: a local maximum
        of the coarse (10 ms) curve, refined like the peak if its coarse correlation is within
        :data:`~replication.rig.offset_search.RIVAL_REFINED_WITHIN` of the coarse maximum (see
        :func:`estimate_time_offset`); NaN if there is none.
    peak_margin : float
        ``correlation - second_peak_correlation``: small when another offset matches the speeds
        almost as well (periodic motion); NaN if there is no other peak in the search.
    curve : (ndarray, ndarray)
        Every offset evaluated (coarse, fine, sub-grid, refined; sorted) and its correlation.
    n_bootstrap : int
    block_s : float
        Length of the bootstrap's blocks (s).
    peak_separation_s : float
        :data:`~replication.rig.offset_search.PEAK_SEPARATION_S`.
    """

    offset_s: float
    correlation: float
    grid_offset_s: float
    ci95_s: tuple
    second_peak_offset_s: float
    second_peak_correlation: float
    peak_margin: float
    curve: tuple
    n_bootstrap: int
    block_s: float
    peak_separation_s: float = PEAK_SEPARATION_S

    def in_words(self) -> str:
        """:func:`offset_in_words` of ``offset_s`` and its interval (a direction only where it
        excludes 0)."""
        return offset_in_words(self.offset_s, ci95_s=self.ci95_s)


def offset_analysis(camera: OrientationStream, sensor: OrientationStream, *, max_offset: float = 0.2,
                    resolution: float = 0.5e-3, n_bootstrap: int = 200, seed: int = 0,
                    block_s: float = 1.0) -> OffsetEstimate:
    """The clock offset of :func:`estimate_time_offset` with a 95 % block-bootstrap interval and its
    peak's margin.

    * ``offset_s``, ``correlation``: as :func:`estimate_time_offset` (the same computation, the same
      values).
    * ``ci95_s``: the camera's angular speeds are resampled in circular blocks of ``block_s``
      seconds (neighbouring speeds share a pose, so their errors are correlated), the correlation
      recomputed for each replicate at every fine and sub-grid offset and at the coarse ones within
      :data:`~replication.rig.offset_search.BOOTSTRAP_SPAN_S`, and its maximum refined the same way;
      the interval is the 2.5 and 97.5 percentiles of the replicates' offsets
      (:func:`~replication.rig.offset_search.bootstrap_offsets`). It describes the spread due to
      the samples; an error every sample shares (a latency of the SLAM front end, a mis-stamped
      stream) is invisible to it.
    * ``peak_margin``: the correlation at the peak minus the highest other local maximum of the 10
      ms coarse curve farther than :data:`~replication.rig.offset_search.PEAK_SEPARATION_S` from it,
      refined if close (NaN if none): periodic motion makes several near-equal peaks, and the margin
      says how close the runner-up came.

    Cost: :func:`estimate_time_offset`'s and the sensor speeds at the ``~2 BOOTSTRAP_SPAN_S / 10
    ms`` coarse offsets again; 8 bytes per camera time for each offset the replicates use (78 at the
    default ``resolution``: 0.6 kB per camera time), plus ``O(n_bootstrap x camera times x
    offsets)`` time for the products, their weights and terms held in chunks of at most
    :data:`~replication.rig.offset_search.OFFSET_BLOCK_SAMPLES` values.

    Parameters
    ----------
    camera, sensor : OrientationStream
    max_offset, resolution : float
        As :func:`estimate_time_offset`.
    n_bootstrap : int
        Replicates, ``>= 0`` (0: no interval).
    seed : int
        Seed of ``numpy.random.default_rng``, ``>= 0``.
    block_s : float
        Block length (s), positive; a block holds ``round(block_s / median camera interval)`` speeds
        (at least one), and the overlap must hold at least two blocks.

    Returns
    -------
    OffsetEstimate

    Raises
    ------
    ValueError
        A parameter out of its range, named; the errors of :func:`estimate_time_offset`.
    """
    n_bootstrap = int(check_number("n_bootstrap", n_bootstrap, minimum=0, integer=True, strict=False))
    seed = int(check_number("seed", seed, minimum=0, integer=True, strict=False))
    block_s = float(check_number("block_s", block_s, minimum=0))
    check_number("resolution", resolution, minimum=0)
    t, _ = overlap(camera, sensor, float(check_number("max_offset", max_offset, minimum=0)))
    block = max(1, int(round(block_s / np.median(np.diff(t)))))
    if 2 * block > len(t) - 1:
        raise ValueError(f"block_s={block_s!r} s makes blocks of {block} camera speeds, more than half of the "
                         f"{len(t) - 1} in the overlap: use a shorter block_s")
    s = _search(camera, sensor, max_offset, resolution, keep_rows=n_bootstrap > 0)
    ci = (float("nan"), float("nan"))
    if n_bootstrap and s["rows"] is not None:
        boot = bootstrap_offsets(s["a"], s["rows"], s["boot_x"], n_bootstrap, block, np.random.default_rng(seed))
        ci = (float(np.nanpercentile(boot, 2.5, method="lower")), float(np.nanpercentile(boot, 97.5, method="higher")))
    second = s["second"]
    return OffsetEstimate(s["offset"], s["corr"], s["grid"], ci, second[0], second[1], s["corr"] - second[1],
                          s["curve"], n_bootstrap, block_s)


def offset_in_words(offset_s: float, decimals: int = 1, ci95_s=None) -> str:
    """The clock offset ``d`` and its sign in words, in ms to ``decimals`` decimals.

    With ``ci95_s`` (its 95 % interval, s) the direction is said only where it excludes 0, else "no
    offset resolved".

    ``d`` is defined by "the sensor sample stamped ``t + d`` matches the camera sample stamped
    ``t``": one instant is stamped ``t_cam`` by the camera and ``t_imu = t_cam + d`` by the sensor,
    so ``d > 0`` means the sensor clock reads ahead of the camera's. That is Kalibr's
    ``timeshift_cam_imu``, documented as "timeshift between camera and IMU timestamps in seconds
    (t_imu = t_cam + shift)" (ethz-asl/kalibr wiki, "yaml formats"), and in ``IccSensors.py``
    (``IccCamera.findTimeshiftCameraImuPrior``: "store the timeshift (t_imu = t_cam +
    timeshiftCamToImuPrior)"; ``addCameraErrorTerms`` evaluates the IMU-time pose spline at
    ``obs.time() + timeshiftCamToImuPrior + cameraTimeToImuTimeDv``, the camera stamp plus the
    shift; ``getResultTimeShift`` returns that sum). Kalibr places the camera sample stamped ``t``
    at IMU time ``t + shift``, where :func:`motion_pairs` reads the sensor for the camera at ``t``:
    ``t + d``. So ``d`` equals Kalibr's shift, sign included.

    >>> print(offset_in_words(-0.0123))  # doctest: +NORMALIZE_WHITESPACE
    -12.3 ms: the sensor sample stamped t - 12.3 ms matches the camera sample stamped t (sensor
    clock behind the camera's by 12.3 ms; Kalibr's timeshift_cam_imu, t_imu = t_cam + shift)
    """
    offset_s = float(check_number("offset_s", offset_s))
    decimals = int(check_number("decimals", decimals, minimum=0, integer=True, strict=False))
    ms = round(1e3 * abs(offset_s), decimals)
    kalibr = "Kalibr's timeshift_cam_imu, t_imu = t_cam + shift"
    def _ms(value_s):  # in ms with its sign; two significant digits where the decimals would print a non-zero as 0
        text = f"{1e3 * value_s:+.{decimals}f}"
        return f"{1e3 * value_s:+.2g}" if value_s != 0 and math.isfinite(value_s) and float(text) == 0 else text
    interval = ""
    if ci95_s is not None:
        lo, hi = (float(v) for v in ci95_s)
        interval = f"[{_ms(lo)}, {_ms(hi)}] ms"
        if math.isnan(lo) or math.isnan(hi):
            missing = "no 95 % interval was measured (no bootstrap)" if math.isnan(lo) and math.isnan(hi) else (
                f"its 95 % interval {interval} is not fully measured")
            return f"{_ms(offset_s)} ms, no direction resolved: {missing}, so the data do not say whether the sensor " \
                f"clock is ahead or behind ({kalibr})"
        if lo <= 0 <= hi:
            return (f"no offset resolved: {_ms(offset_s)} ms, its 95 % interval {interval} includes 0 (the "
                    f"clocks agree within it; {kalibr})")
        interval = f", 95 % interval {interval} excludes 0"
    if ms == 0:
        return (f"{0:.{decimals}f} ms: the sensor sample stamped t matches the camera sample stamped t (the clocks "
                f"agree to {0.5 * 10.0 ** -decimals:g} ms; {kalibr})")
    v = f"{ms:.{decimals}f}"
    sign, side = ("+", "ahead of") if offset_s > 0 else ("-", "behind")
    return (f"{sign}{v} ms: the sensor sample stamped t {sign} {v} ms matches the camera sample stamped t (sensor "
            f"clock {side} the camera's by {v} ms{interval}; {kalibr})")


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
