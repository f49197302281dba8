"""Calibrate a real rig: ``R0`` from a camera orientation stream and a sensor stream. Theory and
measured numbers: ``docs/judging.md``, section ``replication.rig.calibration``."""
from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np

from ..core.checks import check_number
from ..core.handeye import pair_residual_deg, relative_rotations
from ..core.so3 import canonical_axis, rotation_angle_deg
from .association import (  # re-exported: public names here
    motion_pairs,
    offset_analysis,
)
from .bias_change import bias_change_of, named_in
from .camera_jumps import found_and_glued, jump_reasons, spanning
from .quality import THRESHOLDS, Verdict
from .report import CalibrationResult  # re-exported: a public name here
from .saturation import saturation_of
from .sensor_verdict import drift_beside_steps, model_or_note, with_sensor_model
from .solve_and_judge import (
    Provenance,
    Resampling,
    check_common,
    check_options,
    first_reference,
    solve_pairs,
    with_reasons,
)
from .streams import (  # integrate_gyro re-exported: a public name
    PLAUSIBLE_SPAN_S,
    GyroStream,
    OrientationStream,
    integrate_gyro,
    time_unit_mismatch,
)

__all__ = ["calibrate", "OverlapError"]


#: A stream has a gap where more than this many of its median sample intervals pass without a
#: sample.
GAP_FACTOR = 5.0
#: Resolution of the clock-offset search (s), as
#: :func:`replication.rig.association.estimate_time_offset` uses.
OFFSET_RESOLUTION = 0.5e-3


def _gaps(t) -> np.ndarray:
    """``(start, end)`` of every gap of a stream: more than :data:`GAP_FACTOR` median intervals
    without a sample."""
    dt = np.diff(t)
    k = np.flatnonzero(dt > GAP_FACTOR * np.median(dt))
    return np.stack([t[k], t[k + 1]], axis=-1)


def _span(stream) -> dict:
    return {"kind": type(stream).__name__, "source": stream.source, "samples": int(len(stream.t)),
            "start_s": float(stream.t[0]), "end_s": float(stream.t[-1]), "span_s": float(stream.t[-1] - stream.t[0]),
            "median_rate_hz": float(1.0 / np.median(np.diff(stream.t)))}


class OverlapError(ValueError):
    """The streams overlap in too few camera samples for the clock-offset search.

    The message names the option that sets the search (``max_offset`` from the API; the command line
    shows its own ``--max-offset`` with :meth:`named`) and gives the spans as durations.
    """

    def __init__(self, template: str, option: str = "max_offset"):
        self.template, self.option = template, option
        super().__init__(template.format(option=option))

    def __str__(self) -> str:
        return self.template.format(option=self.option)

    def __reduce__(self):
        return type(self), (self.template, self.option)

    def named(self, option: str) -> OverlapError:
        """The same error naming the option as ``option`` (e.g. ``"--max-offset"``)."""
        return type(self)(self.template, option)


def _duration(seconds: float) -> str:
    return f"{seconds:.1f} s" if abs(seconds) >= 1 else f"{seconds:.3g} s"


def _overlap_samples(camera, sensor, max_offset) -> int:
    """Camera samples inside the sensor's span shrunk by ``max_offset`` at each end (what the search
    compares)."""
    lo, hi = max(camera.t[0], sensor.t[0] + max_offset), min(camera.t[-1], sensor.t[-1] - max_offset)
    return int(np.sum((camera.t >= lo) & (camera.t <= hi)))


def _check_overlap(camera, sensor, max_offset):
    """Refuse streams that overlap in fewer than 10 camera samples once the offset search
    (+-max_offset) is allowed for: :class:`OverlapError` with the spans as durations, the largest
    ``max_offset`` that would do where the streams do overlap, and the likely time-unit mistake
    (with the absolute start times that show it) where there is one."""
    if _overlap_samples(camera, sensor, max_offset) >= 10:
        return
    cs, ss = camera.t[-1] - camera.t[0], sensor.t[-1] - sensor.t[0]
    spans = f"camera {_duration(cs)}, sensor {_duration(ss)} long"
    unit = _time_unit_reason(camera, sensor)
    if _overlap_samples(camera, sensor, 0.0) >= 10:
        overlap = min(camera.t[-1], sensor.t[-1]) - max(camera.t[0], sensor.t[0])
        lo, hi = 0.0, float(max_offset)  # the largest max_offset keeping 10 samples lies in [lo, hi)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _overlap_samples(camera, sensor, mid) >= 10 else (lo, mid)
        digits = max(0, 1 - int(np.floor(np.log10(lo)))) if lo > 0 else 3
        largest = np.floor(lo * 10 ** digits) / 10 ** digits
        text = (f"the streams overlap by {_duration(overlap)} ({spans}), but the clock-offset search removes "
                f"{{option}} from each end of the sensor's span: {{option}} {max_offset:g} s is larger than the "
                f"overlap allows and leaves fewer than 10 camera samples to compare (above {largest:.{digits}f} s; "
                f"a useful search stays well below half the overlap, and clock offsets are rarely more than a "
                f"second)")
    else:
        if camera.t[-1] <= sensor.t[0]:
            where = f"the sensor starts {_duration(sensor.t[0] - camera.t[-1])} after the camera ends"
        elif sensor.t[-1] <= camera.t[0]:
            where = f"the sensor ends {_duration(camera.t[0] - sensor.t[-1])} before the camera starts"
        else:
            where = f"they overlap by {_duration(min(camera.t[-1], sensor.t[-1]) - max(camera.t[0], sensor.t[0]))}"
        text = f"the streams overlap in fewer than 10 camera samples ({spans}; {where}; {{option}} {max_offset:g} s)"
        gap = max(sensor.t[0] - camera.t[-1], camera.t[0] - sensor.t[-1])
        if unit is not None or gap > PLAUSIBLE_SPAN_S[1]:
            text += (f"; the camera starts at t = {camera.t[0]:.3f} s, the sensor at t = {sensor.t[0]:.3f} s"
                     + ("" if unit is not None else ": their clocks differ (one relative, one absolute time?)"))
    if unit is not None:
        text += "; " + unit.message.replace("{", "{{").replace("}", "}}")
    raise OverlapError(text)


def _gap_free_window(camera, sensor, max_offset):
    """The camera samples inside the sensor stream's longest stretch without a gap (the whole stream
    if it has none): across a gap the sensor's orientation is interpolated or integrated through
    missing data, and its angular speed there would bias the clock-offset search."""
    gaps = _gaps(sensor.t)
    if not len(gaps):
        return camera
    edges = np.concatenate([[sensor.t[0]], gaps.ravel(), [sensor.t[-1]]]).reshape(-1, 2)  # gap-free stretches
    best = edges[np.argmax(np.diff(edges, axis=1)[:, 0])]
    part = camera.between(best[0] + max_offset, best[1] - max_offset)
    return part if len(part.t) >= 10 else camera


def _time_unit_reason(camera, sensor):
    """A ``fail`` reason when the two streams' spans differ by about 1e3, 1e6 or 1e9
    (:func:`replication.rig.streams.time_unit_mismatch`, which names the units and the stream to
    blame)."""
    from .quality import Reason

    found = time_unit_mismatch(camera, sensor)
    if found is None:
        return None
    ratio, factor, text = found
    return Reason("time_unit", "fail", ratio, factor, text)


#: Two orientation samples closer than this in time (s) and in angle (rad) are the same sample of
#: one recording (a copy re-saved with fewer digits, a line dropped, times shifted by rounding);
#: real camera and sensor streams never agree to 0.006 deg sample after sample.
SAME_SAMPLE_TIME_S, SAME_SAMPLE_ANGLE_RAD = 1e-6, 1e-4


def _same_stream(camera, sensor) -> str | None:
    """Whether the 'sensor' is the camera stream itself: a sentence saying how many samples
    coincide, or None.

    A copy counts too: at least half of the sensor's samples (and 10) lie within
    :data:`SAME_SAMPLE_TIME_S` of a camera sample and within :data:`SAME_SAMPLE_ANGLE_RAD` of its
    orientation (a line dropped, times shifted by a nanosecond, orientations re-saved with 5
    decimals)."""
    if not isinstance(sensor, OrientationStream):
        return None
    j = np.clip(np.searchsorted(camera.t, sensor.t), 1, len(camera.t) - 1)
    j = np.where(np.abs(camera.t[j - 1] - sensor.t) <= np.abs(camera.t[j] - sensor.t), j - 1, j)
    near = np.abs(camera.t[j] - sensor.t) <= SAME_SAMPLE_TIME_S
    if near.sum() < max(10, 0.5 * len(sensor.t)):
        return None
    cos = (np.einsum("nab,nab->n", camera.world_from_body[j[near]], sensor.world_from_body[near]) - 1.0) / 2.0
    same = int(np.sum(cos >= math.cos(SAME_SAMPLE_ANGLE_RAD)))
    if same < max(10, 0.5 * len(sensor.t)):
        return None
    return (f"{same} of the sensor's {len(sensor.t)} samples are camera samples (time within "
            f"{SAME_SAMPLE_TIME_S:g} s, orientation within {math.degrees(SAME_SAMPLE_ANGLE_RAD):.2g} deg)")


#: The residual level the handedness test divides by is at least this (deg): noise-free pairs fit
#: exactly either way.
MIRROR_FLOOR_DEG = 0.01


def _mirror_fit(camera, gyro, A, B, interval, offset, stride, keep) -> dict:
    """How much worse the pairs ``A, B`` fit with the gyro's frame mirrored about the axis it turns
    about least: ``{"mirror_fit_ratio": ratio of the median residuals, "mirror_normal": that
    axis}``, each fit by ``chordal_optimal``; empty where the pairs themselves fit poorly (the
    verdict fails them already, and the diagnosis names a sign-flipped axis) or are too few.

    A gyro with one axis's sign flipped (a left-handed frame, e.g. in a driver) reports ``D omega``
    (``D = diag(1, 1, -1)``). Where the rates stay in one plane (normal ``n``), ``D omega = (D P)
    omega`` with the mirror ``P = I - 2 n n^T``, which leaves them unchanged, and ``D P`` is a
    rotation: the flipped gyro is exactly a right-handed one mounted otherwise, and both fit with
    different R0. Mirroring the rates about the least-turned axis and fitting again measures how far
    the data are from that case (three-axis motion fits far worse)."""
    from ..core.solvers import solve

    def median_residual(A, B):
        with warnings.catch_warnings():  # the mirrored fit may be poor: that is what it measures
            warnings.simplefilter("ignore")
            return float(np.median(pair_residual_deg(solve("chordal_optimal", A, B), A, B)))

    plain = median_residual(A, B) if len(A) >= 3 else math.inf
    if not plain <= THRESHOLDS["residual_to_motion"][0] * float(np.median(rotation_angle_deg(A))):
        return {}
    w = gyro.omega
    n = np.linalg.eigh(w.T @ w)[1][:, 0]
    mirrored = integrate_gyro(GyroStream(gyro.t, w - 2.0 * np.outer(w @ n, n), gyro.source))
    A_m, B_m, _ = motion_pairs(camera, mirrored, interval, offset=offset)
    ratio = median_residual(A_m[::stride][keep], B_m[::stride][keep]) / max(plain, MIRROR_FLOOR_DEG)
    return {"mirror_fit_ratio": ratio, "mirror_normal": tuple(float(v) for v in canonical_axis(n))}


def _pairs_across_gaps(t_start, interval, offset, sensor_t, integrated: bool) -> np.ndarray:
    """Mask of pairs to drop: an end in a gap of the sensor stream (interpolated across it), or, for
    an integrated gyro, any gap within the pair (the integration across it is wrong)."""
    gaps = _gaps(sensor_t)
    s, e = t_start + offset, t_start + interval + offset
    drop = np.zeros(len(t_start), bool)
    for g0, g1 in gaps:
        inside = ((s > g0) & (s < g1)) | ((e > g0) & (e < g1))
        drop |= inside | ((s < g1) & (e > g0)) if integrated else inside
    return drop


def _speeds(camera, sensor, offset, lo, hi):
    """Angular speed (deg/s) of the camera and of the sensor at the camera times shifted by
    ``offset``, in the overlap."""
    t = camera.t[(camera.t >= lo) & (camera.t <= hi)]
    if len(t) < 2:
        return None
    cam = camera.at(t)
    sen = sensor.at(t + offset)
    dt = np.diff(t)
    speed = [rotation_angle_deg(relative_rotations(Q, convention="world_from_body", atol=1e-5)) / dt
             for Q in (cam, sen)]
    return 0.5 * (t[1:] + t[:-1]), speed[0], speed[1]


#: The change test's splits leave at least this share of the pairs (and 5 blocks) on each side. 0.15
#: missed re-mounts in the last 8 % of a recording (a verdict ok 4.6 deg off); 0.05 found a 2 or 5
#: deg re-mount at 92 % of 60 s rigs in 20/20 each (0.15: 8/20 and 4/20); false alarms on rigs
#: without a change 1 of 320 (0.15: 2 of 320), two disjoint sets of 160 seeds
#: (benchmarks/bench_change_ends.py).
CHANGE_MIN_SHARE = 0.05


def _change_test(A, B, t_start, block, t0):
    """The change test on the pairs (:func:`replication.rig.changepoint.two_segment_test`), its
    times since ``t0``, and how well each side fits its own estimate (the larger median residual /
    median motion of the two sides: a re-mount leaves each side fitting, an input mistake neither);
    or ``(None, why)`` where it cannot run (too short a recording, one side's motions about one
    axis)."""

    from .changepoint import two_segment_test

    try:
        c = two_segment_test(A, B, t_start, block=block, min_share=CHANGE_MIN_SHARE)
    except ValueError as err:
        return None, f"not run: {err}"
    k = c.split_index
    fit = max(float(np.median(pair_residual_deg(R, a, b)) / max(np.median(rotation_angle_deg(a)), 1e-12))
              for R, a, b in ((c.R_before, A[:max(k - block, 1)], B[:max(k - block, 1)]), (c.R_after, A[k:], B[k:])))
    return dataclasses.replace(c, split_time=c.split_time - t0, split_times=c.split_times - t0), fit


def _analysis_pairs(camera, oriented, offset, integrated, A, B, t_start, interval, stride, block):
    """The pairs the change and segment tests run on: at
    :data:`replication.rig.segments.ANALYSIS_INTERVAL_S`, every camera time, those across a sensor
    gap dropped (the calibration's own pairs where they are these; ``stride`` 0: never, the sensor
    having been re-stamped)."""
    from .segments import ANALYSIS_INTERVAL_S

    if interval == ANALYSIS_INTERVAL_S and stride == 1:
        return A, B, t_start, block
    try:
        As, Bs, ts = motion_pairs(camera, oriented, ANALYSIS_INTERVAL_S, offset=offset)
    except ValueError:
        return A[:0], B[:0], t_start[:0], block
    keep = ~_pairs_across_gaps(ts, ANALYSIS_INTERVAL_S, offset, oriented.t, integrated=integrated)
    return As[keep], Bs[keep], ts[keep], max(1, round(ANALYSIS_INTERVAL_S / np.median(np.diff(camera.t))))


def _change_report(c, fit) -> dict:
    """The change test for the JSON report (times since the camera's first sample)."""
    if c is None:
        return {"run": False, "note": fit}
    return {"run": True, "note": None, "significant": bool(c.significant), "sides_fit": fit, "statistic": c.statistic,
            "threshold": c.threshold, "p_value": c.p_value, "level": c.level, "split_time_s": c.split_time,
            "angle_deg": c.angle_deg, "difference_radius_deg": c.difference_radius_deg, "n_before": c.n_before,
            "n_after": c.n_after, "R0_before": c.R_before.tolist(), "R0_after": c.R_after.tolist(),
            "splits_from_s": float(c.split_times[0]), "splits_to_s": float(c.split_times[-1])}


def calibrate(camera: OrientationStream, sensor, *, method: str = "chordal_optimal", interval: float = 1.0,
              stride: int = 1, max_offset: float = 0.2, correct_offset: bool = True, n_bootstrap: int = 200,
              seed: int = 0, reference=None, diagnose: bool = True, progress: bool = False, gyro_bias: bool = True,
              use: str = "all", **options) -> CalibrationResult:
    """``R0`` (camera_from_sensor) of a real rig from two timestamped streams, with a verdict on it.

    Parameters
    ----------
    camera : OrientationStream
        Camera ``world_from_camera`` orientations (a SLAM trajectory, PnP poses inverted, ...).
    sensor : OrientationStream or GyroStream
        Sensor ``world_from_sensor`` orientations, or raw body-frame rates (integrated here).
    method : str
        A registered solver (:func:`replication.core.solvers.available`).
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
    reference : None or array_like (3, 3) or (2, 3, 3)
        A reference ``R0``; the result then reports the angle to it. Two references (e.g. two
        published calibrations): the angle to each, their disagreement (the reference floor) and
        which reading applies.
    diagnose : bool
        Where the verdict is not ``ok``, look for the usual input mistakes
        (:mod:`replication.rig.diagnose`).
    progress : bool
        Show a progress bar over the bootstrap (on standard error).
    gyro_bias : bool
        A gyro sensor: estimate its bias (and the clock's drift) with ``R0`` and remove the bias
        from the rates before everything else (:mod:`replication.rig.sensor_model`); False: the
        rates as recorded (the bias is then estimated only where the verdict is not ``ok``, and
        named if it is large).
    use : {"all", "consistent"}
        ``"consistent"``: fit R0 on the pairs of the segments that agree with each other only
        (:mod:`replication.rig.segments`), reported (the seconds used and why); ``"all"``: every
        pair.
    **options
        Passed to the solver.

    Returns
    -------
    CalibrationResult
        With ``verdict``: read it before using ``R``.

    Raises
    ------
    ValueError
        A bad parameter (named), streams of the wrong type, or streams that do not overlap
        (:class:`OverlapError`, naming ``max_offset``, with the spans as durations and the likely
        time-unit mistake when their spans show one).
    """
    references = check_common(method, n_bootstrap, seed, reference)  # one, or two (2, 3, 3)
    reference = first_reference(references)
    check_options(method, options)
    check_number("interval", interval, minimum=0)
    check_number("stride", stride, minimum=1, integer=True, strict=False)
    check_number("max_offset", max_offset, minimum=0)
    if use not in ("all", "consistent"):
        raise ValueError(f"use must be 'all' or 'consistent', got {use!r}")
    if not isinstance(camera, OrientationStream) or not isinstance(sensor, (OrientationStream, GyroStream)):
        raise ValueError("camera must be an OrientationStream and sensor an OrientationStream or GyroStream")
    same = _same_stream(camera, sensor)
    if same:
        raise ValueError(f"the sensor stream is the camera stream itself, or a copy of it: {same}; give the "
                         f"sensor's own recording")
    gyro = sensor if isinstance(sensor, GyroStream) else None
    oriented = integrate_gyro(sensor) if gyro is not None else sensor
    _check_overlap(camera, oriented, max_offset)
    sat = saturation_of(sensor)  # a clipping gyro: its pairs dropped below, a camera step over it no jump
    camera, jumps_cam = found_and_glued(camera, oriented, max_offset, excused=sat)  # lost tracking: pairs dropped
    fit = sat.without(gyro)  # the sensor model's fit: without the clipped samples (their pairs skipped)
    model, model_note = model_or_note(camera, fit, interval, max_offset) if gyro_bias and fit else (None, None)
    if model is not None:  # jumps hidden by fast motion: against R0 (then the model again without them)
        camera, found = found_and_glued(camera, integrate_gyro(model.corrected(gyro)), max_offset, jumps_cam, model.R,
                                        model.offset_mid_s, excused=sat)
        model, model_note = model_or_note(camera, fit, interval, max_offset) if found != jumps_cam else (model, None)
        jumps_cam = found
    bias_step = None
    if model is not None:  # the sensor model: the rates without the gyro's bias (and its change, where it changes)
        gyro = model.corrected(gyro)
        bias_step = bias_change_of(model, camera, integrate_gyro(gyro))
        gyro = bias_step.corrected(gyro) if bias_step else gyro
        oriented = integrate_gyro(gyro)
    window = _gap_free_window(camera, oriented, max_offset)
    span = window.t[-1] - window.t[0]
    clock = offset_analysis(window, oriented, max_offset=max_offset, resolution=OFFSET_RESOLUTION,
                            n_bootstrap=n_bootstrap, seed=seed, block_s=min(1.0, 0.25 * span))
    offset, corr, curve = clock.offset_s, clock.correlation, clock.curve
    used = offset if correct_offset else 0.0
    A, B, t_start = motion_pairs(camera, oriented, interval, offset=used)
    A, B, t_start = A[::stride], B[::stride], t_start[::stride]
    drop = _pairs_across_gaps(t_start, interval, used, oriented.t, integrated=gyro is not None)
    cut, clip = spanning(jumps_cam, t_start, interval), sat.pairs(t_start, interval, used)
    drop |= cut | clip
    before = len(A)
    if drop.all():
        raise ValueError(f"every one of the {before} pairs spans a gap in the sensor stream")
    A, B, t_start = A[~drop], B[~drop], t_start[~drop]
    # overlapping pairs are correlated: bootstrap blocks span one interval
    block = max(1, round(interval / np.median(np.diff(camera.t)) / stride))
    lo, hi = max(camera.t[0], oriented.t[0] - used), min(camera.t[-1], oriented.t[-1] - used)
    parameters = {"method": method, "interval_s": interval, "stride": stride, "max_offset_s": max_offset,
                  "correct_offset": bool(correct_offset), "gyro_bias": bool(gyro_bias), "use": use,
                  "n_bootstrap": n_bootstrap, "seed": seed,
                  "diagnose": bool(diagnose), "solver_options": {k: repr(v) for k, v in options.items()}}
    inputs = {"camera": _span(camera), "sensor": _span(sensor), "overlap_s": float(hi - lo),
              "reference_camera_from_sensor": reference}
    rate = float(1.0 / np.median(np.diff(gyro.t))) if gyro is not None else None
    # --- the change and segment tests: on pairs at segments.ANALYSIS_INTERVAL_S whatever the
    # interval
    from . import clock as clock_mod
    from . import clock_profile
    from . import segments as seg_mod
    clock_parts, jumps, profile, fixed = clock_profile.clock_analysis(  # a clock's step or drift removed for the tests
        camera, oriented, A, B, used, model, max_offset=max_offset, seed=seed)
    As, Bs, ts, bs = _analysis_pairs(camera, fixed or oriented, used, gyro is not None, A, B, t_start, interval,
                                     stride if fixed is None else 0, block)
    keep_a = ~spanning(jumps_cam, ts, seg_mod.ANALYSIS_INTERVAL_S) & ~sat.pairs(ts, seg_mod.ANALYSIS_INTERVAL_S, used)
    As, Bs, ts = As[keep_a], Bs[keep_a], ts[keep_a]
    segs, segs_note = seg_mod.run(As, Bs, ts, bs) if len(As) else (None, "not run: no pairs")
    if use == "consistent" and segs is not None and segs.consistent:  # the change test on the part used
        part = seg_mod.consistent_mask(segs, ts, seg_mod.ANALYSIS_INTERVAL_S)
        As, Bs, ts = As[part], Bs[part], ts[part]
    change, change_fit = _change_test(As, Bs, ts, bs, float(camera.t[0]))
    segs_used = {"kept_s": None, "dropped_s": None, "pairs_kept": len(A)} if use == "consistent" else None
    if use == "consistent" and segs is not None:
        keep = seg_mod.consistent_mask(segs, t_start, interval) if segs.consistent else np.ones(len(A), bool)
        kept_s = float(sum(b - a for a, b in segs.used_spans())) if segs.consistent else None
        segs_used = {"kept_s": kept_s, "dropped_s": 0.0 if kept_s is None else float(
            segs.segments[-1].end_s - segs.segments[0].start_s - kept_s), "pairs_kept": int(keep.sum())}
        A, B, t_start = A[keep], B[keep], t_start[keep]
    # --- end of the change and segment tests
    evidence = dict(change=change, change_sides_fit=change_fit if change is not None else None, offset_s=offset,
                    offset_correlation=corr, offset_peak_margin=clock.peak_margin,
                    second_peak_offset_s=clock.second_peak_offset_s, max_offset_s=max_offset,
                    offset_applied=bool(correct_offset),
                    offset_resolution_s=OFFSET_RESOLUTION, overlap_s=float(hi - lo), interval_s=float(interval),
                    pairs_dropped_at_gaps=int((drop & ~cut & ~clip).sum()), pairs_before_gaps=before, gyro_rate_hz=rate)
    mirror = _mirror_fit(camera, gyro, A, B, interval, used, stride, ~drop) if gyro is not None else {}
    evidence.update(mirror)
    result = solve_pairs(
        A, B, method=method, options=options, reference=references, evidence=evidence,
        resampling=Resampling(n_bootstrap=n_bootstrap, seed=seed, block=block, progress=progress),
        provenance=Provenance(interval=float(interval), time_offset=(offset, corr, bool(correct_offset)),
                              time_offset_ci95_s=clock.ci95_s, time_offset_peak_margin=clock.peak_margin,
                              change_test=_change_report(change, change_fit), parameters=parameters, inputs=inputs,
                              pair_times=t_start, extra_diagnostics=mirror))
    result.diagnostics.update(speeds=_speeds(camera, oriented, used, lo, hi), offset_curve=curve, t0=float(camera.t[0]),
                              change=change)
    segs_report = {**seg_mod.report(segs, segs_note, float(camera.t[0]), segs_used),
                   **clock_mod.clock_report(clock_parts, jumps, float(camera.t[0]), profile),
                   "camera_jumps": [j.to_dict(float(camera.t[0])) for j in jumps_cam],
                   "bias_change": bias_step.to_dict(float(camera.t[0])) if bias_step else None}
    result = with_reasons(dataclasses.replace(result, segments=segs_report),  # the segment test, the clock jumps
                          seg_mod.reasons(segs, float(camera.t[0]), segs_used, segs_note)
                          + clock_mod.clock_reasons(jumps, float(camera.t[0]), offset)
                          + jump_reasons(jumps_cam, float(camera.t[0]), int(cut.sum())) + sat.reasons(clip, before))
    result = with_reasons(result, [x for x in [_time_unit_reason(camera, sensor)] if x is not None])
    if isinstance(sensor, GyroStream):  # the sensor model: its fields and reasons (model off: only where not ok)
        result = with_sensor_model(result, camera, sensor, model, model_note, gyro_bias or not diagnose, interval,
                                   max_offset)
        result = dataclasses.replace(result, verdict=Verdict.of(  # the bias change's time and size
            named_in(result.verdict.reasons, bias_step, float(camera.t[0]))))
        if jumps:  # a step of the clock reads as a drift to the sensor model: named once, as the step
            result = drift_beside_steps(result, jumps, profile, float(camera.t[0]))
    if diagnose and result.verdict.level != "ok":
        import functools

        from .diagnose import input_mistakes

        found = input_mistakes(camera, gyro if model is not None else sensor,  # the sensor model: its bias removed
                               base_residual_deg=result.residual_deg["median"],
                               motion_deg=result.diagnostics["motion_median_deg"], interval=interval,
                               max_offset=max_offset,
                               calibrate=functools.partial(calibrate, gyro_bias=gyro_bias and model is None),
                               reference=reference,
                               R=result.R)  # with a reference: the IMU's own trajectory as camera, files swapped
        if found:
            result = with_reasons(result, found)
    return result
