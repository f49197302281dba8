"""Causes the online estimator names, as the batch verdict does (issue 33, point 7): a rig turning
at constant speed (:func:`constant_speed`), time stamps of the two streams in different units
(:func:`time_unit_by_rate`), and a clock offset beyond the search (:func:`offset_beyond_search`).
Each returns a :class:`replication.rig.quality.Reason` (``fail``) with its measured number, or None.
Theory and measured numbers: ``docs/judging.md``, section ``replication.rig.online_causes``."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["run_diagnosis", "constant_speed", "constant_speed_stream", "time_unit_by_rate", "offset_beyond_search",
           "CONSTANT_SPEED_SPREAD", "CONSTANT_SPEED_MIN_DEG", "PLAUSIBLE_INTERVAL_RATIO", "WIDE_SEARCH_SHARE",
           "WIDE_CORRELATION", "WIDE_GAIN"]

#: Relative spread (median absolute deviation over the median) of the recent camera motion angles
#: below which the rig turns at constant speed (noise of 0.05-0.5 deg on 10-60 deg motions: 0.1-3 %;
#: a hand-held or robot motion: tens of %).
CONSTANT_SPEED_SPREAD = 0.05
#: Median motion per pair (deg) above which constant speed is named (below, the rig is near rest:
#: its own check).
CONSTANT_SPEED_MIN_DEG = 1.0
#: Plausible range of (sensor sample interval) / (camera sample interval): a 2000 Hz gyro beside a
#: 0.1 Hz camera (a SLAM keyframe trajectory; 1/20000) to an orientation sensor ten times slower
#: than the camera (10). Camera stamps in ms beside a 200 Hz gyro (1e-4) lie inside: those the
#: streams' spans show, at the end (as the batch's check).
PLAUSIBLE_INTERVAL_RATIO = (1 / 20000, 10.0)
#: The wider offset search spans this share of the offset window on each side (5 s of the default 20
#: s window: the search keeps half the window's camera samples).
WIDE_SEARCH_SHARE = 0.25
#: Correlation the wider search's peak needs to be named, and its least gain over the correlation
#: found.
WIDE_CORRELATION, WIDE_GAIN = 0.9, 0.1

#: A typical rig's ratio of sample intervals (a 200 Hz gyro beside a 20 Hz camera): of the units
#: that bring a ratio into the plausible range, the one nearest it is named.
TYPICAL_INTERVAL_RATIO = 0.1
_UNITS = {1e3: "ms", 1e6: "us", 1e9: "ns"}


def constant_speed(motions_deg, excitation_deg: float, min_excitation_deg: float, weak_axis):
    """A ``constant_speed`` fail reason when the motion does not determine ``R0`` and the camera
    motion angles ``motions_deg`` (recent pairs, at least 10) agree within
    :data:`CONSTANT_SPEED_SPREAD`, else None."""
    from .quality import Reason

    m = np.asarray(motions_deg, dtype=float)
    if len(m) < 10 or not excitation_deg < min_excitation_deg:
        return None
    median = float(np.median(m))
    if not median > CONSTANT_SPEED_MIN_DEG:
        return None
    spread = float(np.median(np.abs(m - median))) / median
    if not spread < CONSTANT_SPEED_SPREAD:
        return None
    axis = "" if weak_axis is None else f" (sensor frame {np.round(np.asarray(weak_axis), 3).tolist()})"
    return Reason("constant_speed", "fail", spread, CONSTANT_SPEED_SPREAD,
                  f"the rig turns at a constant speed: every pair is the same motion, {median:.3g} deg +- "
                  f"{100 * spread:.2g} % about one axis{axis}; R0 about that axis is not determined and no clock "
                  f"offset can be measured (the angular speed never varies); rotate about other axes, at varying "
                  f"speed")


def constant_speed_stream(t, world_from_camera, interval: float):
    """:func:`constant_speed` on a camera stream's own motions (samples ``t``,
    ``world_from_camera``): the angles turned over successive ``interval`` spans. Named where every
    pair repeats (a noise-free camera turning at constant speed gives the same pair again and again,
    refused as repeats, so the estimator's own motions stay few)."""
    from ..core.so3 import angle_between_deg

    t = np.asarray(t, dtype=float)
    if len(t) < 2 or not t[-1] - t[0] >= 10 * interval:
        return None
    k = np.searchsorted(t, np.arange(t[0], t[-1], interval))
    angles = angle_between_deg(world_from_camera[k[:-1]], world_from_camera[k[1:]])
    return constant_speed(angles, 0.0, 1.0, None)


def time_unit_by_rate(camera_dt: float | None, sensor_dt: float | None):
    """A ``time_unit`` fail reason when the ratio of the streams' typical sample intervals is 1e3,
    1e6 or 1e9 times outside :data:`PLAUSIBLE_INTERVAL_RATIO` (one stream's stamps read in another
    unit), else None."""
    from .quality import Reason

    if not camera_dt or not sensor_dt or not camera_dt > 0 or not sensor_dt > 0:
        return None
    ratio = sensor_dt / camera_dt
    low, high = PLAUSIBLE_INTERVAL_RATIO
    if low <= ratio <= high:
        return None
    # of the units that bring the ratio into the plausible range, the one that brings it nearest a
    # typical rig's (the range spans more than one factor of 1000: camera stamps in us also fit it
    # read as ms, at its edge)
    fits = [(abs(math.log(scaled / TYPICAL_INTERVAL_RATIO)), factor, unit, side)
            for factor, unit in _UNITS.items()
            for side, scaled in (("sensor", ratio / factor), ("camera", ratio * factor)) if low <= scaled <= high]
    if not fits:
        return None
    _, factor, unit, side = min(fits)
    return Reason("time_unit", "fail", float(ratio), factor,
                  f"the sensor's samples come every {sensor_dt:.4g} s and the camera's every {camera_dt:.4g} s, a "
                  f"ratio of {ratio:.3g}: the {side} time stamps are likely in {unit} read as seconds (TUM "
                  f"trajectories: --camera-time-unit / --sensor-time-unit; EuRoC / TUM-VI CSV files are in ns by "
                  f"format)")


def offset_beyond_search(camera, sensor, *, max_offset: float, window: float, found_correlation, resolution: float):
    """An ``offset_beyond_search`` fail reason when the clock offset searched on ``camera`` and
    ``sensor`` (:class:`replication.rig.streams.OrientationStream`, the first ``window`` seconds)
    over ``+-WIDE_SEARCH_SHARE x window`` lies beyond ``max_offset`` with a correlation of at least
    :data:`WIDE_CORRELATION` and :data:`WIDE_GAIN` above ``found_correlation``, else None."""
    from .association import estimate_time_offset
    from .quality import Reason

    wide = WIDE_SEARCH_SHARE * window
    if not wide > max_offset:
        return None
    try:
        offset, correlation = estimate_time_offset(camera, sensor, max_offset=wide, resolution=resolution)
    except ValueError:
        return None
    found = -1.0 if found_correlation is None or not math.isfinite(found_correlation) else found_correlation
    if abs(offset) <= max_offset or not correlation >= max(WIDE_CORRELATION, found + WIDE_GAIN):
        return None
    bound = abs(offset) >= wide - 2 * resolution
    return Reason("offset_beyond_search", "fail", float(offset), float(max_offset),
                  f"the clock offset is beyond the search (+-{max_offset:g} s): the angular speeds match best at "
                  f"{offset:+.3f} s (correlation {correlation:.3f}, against {found:.3f} within the search"
                  + (f"; at the bound of a search over +-{wide:g} s: the offset may be larger still" if bound else "")
                  + f"); raise max_offset (--max-offset) above {abs(offset):.3g} s")


def run_diagnosis(rig, resolution: float) -> None:
    """The usual input mistakes, tried on the live rig's (:class:`replication.rig.live.LiveRig`)
    first ``offset_window`` seconds (once; ``resolution`` that of its offset search); what is found
    is judged with the estimator's evidence from then on."""
    import warnings

    from .calibration import calibrate
    from .diagnose import input_mistakes

    rig._diagnosis = []
    try:
        camera, sensor = rig._streams()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            base = calibrate(camera, sensor, interval=rig.interval, max_offset=rig.max_offset, n_bootstrap=0,
                             diagnose=False)
    except ValueError:
        return
    rig._diagnosis = input_mistakes(camera, sensor, base_residual_deg=base.residual_deg["median"],
                                     motion_deg=base.diagnostics["motion_median_deg"], interval=rig.interval,
                                     max_offset=rig.max_offset, calibrate=calibrate)
    if not rig._diagnosis and not rig.offset_given:  # a clock offset beyond the search, named if found wider
        from .streams import integrate_gyro

        wide = offset_beyond_search(camera, integrate_gyro(sensor) if rig._kind == "gyro" else sensor,
                                    max_offset=rig.max_offset, window=rig.offset_window,
                                    found_correlation=rig.offset_correlation, resolution=resolution)
        rig._diagnosis = [wide] if wide is not None else []
    if rig._diagnosis:
        rig.calibrator.set_context(extra=tuple(rig._causes) + tuple(rig._diagnosis))
