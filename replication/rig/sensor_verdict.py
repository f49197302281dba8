"""The verdict on a gyro's sensor model (:mod:`replication.rig.sensor_model`) and its place in
:func:`replication.rig.calibration.calibrate`: estimated before everything else
(:func:`model_or_note`), its fields and reasons added to the result (:func:`with_sensor_model`,
:func:`sensor_reasons`, :data:`SENSOR_THRESHOLDS`).
"""
from __future__ import annotations

import math

import numpy as np

from .gyro_held import held_reasons, triangular_words
from .sensor_model import BIAS_CHANGE_LEVEL, MAX_FIT_RATIO, SCALE_RESOLUTION, SensorModel, estimate_sensor_model

__all__ = ["SENSOR_THRESHOLDS", "sensor_reasons", "model_or_note", "with_sensor_model", "drift_beside_steps"]

#: ``(warning, fail)`` bounds of the checks on the sensor model (the reasoning in
#: :func:`sensor_reasons`):
#:
#: * ``gyro_bias_to_motion`` (bias modelled): ``|b| T`` (the rotation the bias adds to a pair of
#: interval ``T``)
#: over the median motion per pair, above: ``R0`` rests on the bias estimate, and the radius of
#: ``R0`` (the pairs' noise) does not hold the bias estimate's error, which every pair shares;
#: * ``gyro_bias_left`` (bias not modelled): the same ratio, above: the pairs carry the bias (the
#: residual checks'
#:   own bounds, 0.1 and 0.3 of the motion);
#: * ``clock_drift_share``: half the offset's change over the overlap (the pairs' timing error at
#: its ends, one offset
#: being applied) over the pairing interval, above, where the drift's interval excludes 0: 0.005 is
#: 5 ms at 1 s (the bound on an offset left in, ``offset_left_ms``), 200 ppm over 60 s at 1 s;
#: * ``offset_disagreement_share``: the offset the pairs fit best (the model's, at the middle) minus
#: the one applied
#: (the speeds' correlation) over the pairing interval, above, where outside the pairs' interval:
#: the drift's bound (a rig turning steadily about one axis while it rocks: 7.5-9.8 ms against 0.2
#: ms, R0 0.23-0.30 deg off, ok);
#: * ``gyro_bias_change_R0_deg``: where the halves' biases differ beyond their noise, how far half
#: the difference
#: moves ``R0`` (deg), above: the test alone flags differences too small to matter (the real
#: recordings, where the slow turn of a SLAM trajectory's frame is indistinguishable from a bias:
#: chi-square 13 and 20 > 11.3, but 0.006 deg on TUM-VI room1 and 0.0002 deg on EuRoC MH01 with a
#: synthetic constant bias); 0.05 deg is 8 times the larger and a seventh of EuRoC's reference floor
#: (0.343 deg);
#: * ``gyro_scale_error``: where an axis's scale is resolved and its interval excludes 1, ``|s -
#: 1|`` (the largest
#: axis), above: the gyro's scale factor is off (its intrinsics), which the model removes but a
#: reader of the raw rates (a VIO with scale 1) does not. Left at 1, a 1 % error on the x axis moves
#: R0 by 0.13-0.25 deg on 30 synthetic rigs (``scale_R0_deg``, first order; seeds 60000-60029 of the
#: red team's 60 s generator), below EuRoC's reference floor (0.343 deg), and a 2 % error by twice
#: that (0.27-0.49 deg), beyond it on some; a 5 % error by 0.67-1.20 deg: a scale more than 1 % off
#: is one the calibration had to remove to stay within the floor.
#: * ``gyro_misalignment_error``: where a misalignment term (``T_g``'s symmetric off-diagonal) is
#: resolved and its
#: interval excludes 0, ``|mu|`` (the largest term), above: the gyro's axes are not orthogonal,
#: which the model removes but a reader of the raw rates (a VIO with ``T_g = I``) does not. Left at
#: 0, terms of 0.5 % on all three pairs (random signs) move R0 by 0.06-0.37 deg
#: (``misalignment_R0_deg``, first order; 24 40 s rigs, seeds 72000-72023 of
#: ``benchmarks/bench_sensor_model.py --misalignment-runs``), of 2 % by 0.25-1.49 deg: terms at the
#: 0.4 % bound move it by at most 0.30 deg, below EuRoC's reference floor (0.343 deg), as the
#: scale's 1 % does (0.13-0.25 deg); a term beyond it is one the calibration had to remove to stay
#: within the floor.
#: * ``gyro_scale_held_R0_deg``: where an axis's scale is held at 1 (the motion does not resolve
#: it), how far a scale anywhere in its 95 % interval moves ``R0`` (deg, first order, the free
#: scales, bias, offset and drift re-fitted; the held axes' effects added), plus the 95 % radius of
#: ``R0`` that the estimated scales' uncertainty carries (named ``gyro_scale_spread`` where no axis
#: is held: 15 s about one axis, a clean gyro, every scale resolved, gave ``ok`` with ``R0`` 0.37
#: and 0.42 deg off, that radius 0.30 and 0.33 deg), above: the bound the
#: scale's 1 % and the misalignment's 0.4 % keep ``R0`` within (0.25 and 0.30 deg), below EuRoC's
#: reference floor (0.343 deg). 15 s of motion about one axis, its scale 10 % high and held at 1,
#: left ``R0`` 2.2-3.4 deg off, the error taken up by another axis's scale.
SENSOR_THRESHOLDS = {
    "gyro_bias_to_motion": (1.0, None),
    "gyro_bias_left": (0.1, 0.3),
    "clock_drift_share": (0.005, None),
    "offset_disagreement_share": (0.005, None),
    "gyro_bias_change_R0_deg": (0.05, None),
    "gyro_scale_error": (0.01, None),
    "gyro_misalignment_error": (0.004, None),
    "gyro_scale_held_R0_deg": (0.3, None),
}


def sensor_reasons(model: SensorModel, *, interval: float, motion_median_deg: float) -> list:
    """The verdict's reasons on the sensor model (:class:`replication.rig.quality.Reason`),
    thresholds in :data:`SENSOR_THRESHOLDS`:

    * the bias large against the motion: modelled, ``R0`` rests on its estimate (warning); not
      modelled, the pairs carry it (warning, fail), named as a gyro bias with what to do;
    * the bias of the two halves differs beyond their noise (warning: it drifts, with temperature);
    * the clock drift resolved (its interval excludes 0) and half its change over the recording
      large against the pairing interval (warning);
    * a gyro axis's scale resolved, its interval excluding 1 and off by more than the bound
      (warning);
    * the scales the motion does not separate: a held axis (``gyro_scale_held``) or the estimated
      scales' uncertainty (``gyro_scale_spread``) that may move ``R0`` beyond the bound (warning);
    * a misalignment term resolved, its interval excluding 0 and beyond the bound (warning);
    * held terms that could move ``R0`` beyond the floor, a triangular ``T_g``'s frame beyond it
      (warnings, :func:`replication.rig.gyro_held.held_reasons`).

    None where the model's pairs fit worse than :data:`MAX_FIT_RATIO` of their motion.
    """
    from .quality import Reason

    out = []
    if not model.fit_ratio <= MAX_FIT_RATIO:  # the model does not fit: the calibration's own reasons say so
        return out
    b = model.bias_rad_s
    per_pair = math.degrees(float(np.linalg.norm(b))) * interval
    ratio = per_pair / motion_median_deg if motion_median_deg > 0 else math.inf
    deg_s = "[" + ", ".join(f"{math.degrees(v):+.2f}" for v in b) + "] deg/s"
    words = (f"the gyro bias {deg_s} ({np.linalg.norm(b):.3g} rad/s) turns each {interval:g} s pair by "
             f"{per_pair:.3g} deg, {ratio:.3g} x the median motion per pair {motion_median_deg:.3g} deg (left in, "
             f"it moves R0 by about {model.bias_R0_deg:.2g} deg)")
    if model.applied:
        warn = SENSOR_THRESHOLDS["gyro_bias_to_motion"][0]
        if ratio > warn:
            out.append(Reason("gyro_bias_to_motion", "warning", float(ratio), warn,
                              f"large gyro bias, removed: {words} > {warn:g}: R0 rests on the bias estimate, whose "
                              f"error every pair shares (not in R0's radius); a longer interval or larger motions "
                              f"lower the share"))
    else:
        warn, fail = SENSOR_THRESHOLDS["gyro_bias_left"]
        level = "fail" if ratio > fail else "warning" if ratio > warn else None
        if level:
            out.append(Reason("gyro_bias_left", level, float(ratio), fail if level == "fail" else warn,
                              f"gyro bias not removed: {words} > {fail if level == 'fail' else warn:g}; the pairs "
                              f"carry it, and their residuals with it: calibrate with the gyro bias model (the "
                              f"default; gyro_bias=True, without --no-gyro-bias)"))
    floor = SENSOR_THRESHOLDS["gyro_bias_change_R0_deg"][0]
    if model.bias_changes and model.change_R0_deg > floor:
        h0, h1 = (", ".join(f"{v:+.3f}" for v in np.degrees(h)) for h in model.halves_rad_s)
        out.append(Reason("gyro_bias_change", "warning", float(model.change_R0_deg), floor,
                          f"the gyro bias changes over the recording: first half [{h0}], second half [{h1}] deg/s, "
                          f"beyond their noise "
                          f"(chi-square {model.change_statistic:.3g} > {model.change_threshold:.3g}, level "
                          f"{BIAS_CHANGE_LEVEL:g}), and half the difference moves R0 by {model.change_R0_deg:.3g} deg "
                          f"> {floor:g} deg: it drifts (with temperature; or the camera trajectory's frame turns "
                          f"slowly, which looks the same), and one bias leaves part of it in the pairs; let the IMU "
                          f"warm up first, or calibrate shorter parts"))
    warn = SENSOR_THRESHOLDS["clock_drift_share"][0]
    change_ms = abs(model.drift_ppm) * 1e-6 * model.span_s * 1e3
    share = 0.5 * change_ms * 1e-3 / interval
    if model.drift_resolved and share > warn:
        lo, hi = model.drift_ci95_ppm
        out.append(Reason("clock_drift", "warning", float(share), warn,
                          f"the sensor clock drifts {model.drift_ppm:+.1f} ppm (95 % interval [{lo:+.1f}, {hi:+.1f}] "
                          f"ppm): the offset changes by {change_ms:.3g} ms over the {model.span_s:.1f} s of pairs, "
                          f"so the one offset applied is off by up to {0.5 * change_ms:.3g} ms at the ends, "
                          f"{share:.3g} of the {interval:g} s pairing interval > {warn:g}; re-stamp the sensor "
                          f"(t - drift (t - t_mid)) or calibrate shorter parts"))
    found = (_scale_reason(model), _held_reason(model), _misalignment_reason(model))
    return out + [x for x in found if x is not None] + held_reasons(model)


def _off(value, ci95, resolved, nominal: float, bound: float):
    """The resolved terms whose 95 % interval excludes ``nominal`` and which depart from it by more
    than ``bound``: their mask and the largest departure (None where none does)."""
    lo, hi = ci95[:, 0], ci95[:, 1]
    off = resolved & ((lo > nominal) | (hi < nominal)) & (np.abs(value - nominal) > bound)
    return off, (float(np.max(np.abs(value[off] - nominal))) if off.any() else None)


def _scale_reason(model):
    """A warning where a resolved axis's scale departs from 1 beyond its interval and by more than
    the bound (:data:`SENSOR_THRESHOLDS` ``gyro_scale_error``), naming the axes, their scales and
    what it did to ``R0``."""
    from .quality import Reason

    bound = SENSOR_THRESHOLDS["gyro_scale_error"][0]
    off, worst = _off(model.scale, model.scale_ci95, model.scale_resolved, 1.0, bound)
    if worst is None:
        return None
    lo, hi = model.scale_ci95[:, 0], model.scale_ci95[:, 1]
    axes = ", ".join(f"{'xyz'[i]} {model.scale[i]:.4f} [{lo[i]:.4f}, {hi[i]:.4f}]" for i in np.flatnonzero(off))
    what = "removed from the rates" if model.applied else "measured, not removed"
    return Reason("gyro_scale", "warning", worst, bound,
                  f"gyro scale error: axis {axes} (95 % intervals) reads {100 * worst:.3g} % off 1 > "
                  f"{100 * bound:g} %; {what}: left at 1 it moves R0 by about {model.scale_R0_deg:.2g} deg; the "
                  f"gyro's scale factors (its intrinsics, e.g. Kalibr's or OpenVINS's T_g) are off: whatever reads "
                  f"its raw rates with scale 1 inherits the error")


def _held_reason(model):
    """A warning where the scales could move ``R0`` by more than the bound
    (:data:`SENSOR_THRESHOLDS` ``gyro_scale_held_R0_deg``): what the held ones may do to it plus the
    radius that the estimated ones' uncertainty gives it. ``gyro_scale_held`` where an axis is held
    (the axes with their intervals), ``gyro_scale_spread`` where none is."""
    from .quality import Reason

    bound = SENSOR_THRESHOLDS["gyro_scale_held_R0_deg"][0]
    held = np.flatnonzero(~np.asarray(model.scale_resolved, bool))
    effect = float(model.scale_held_R0_deg + model.scale_spread_R0_deg)
    if not effect > bound:
        return None
    spread = (f"; the estimated scales' own uncertainty {model.scale_spread_R0_deg:.2g} deg (95 % radius of R0 "
              f"they carry, not in R0's bootstrap radius)")
    if not len(held):
        return Reason("gyro_scale_spread", "warning", effect, bound,
                      f"gyro scales poorly separated on this motion: their intervals are within the resolution, but "
                      f"correlated with R0{spread} > {bound:g} deg: R0 may be off by that much; turn about every axis "
                      f"while recording")
    ci = model.scale_held_ci95
    axes = ", ".join(f"{'xyz'[i]} [{ci[i, 0]:.4f}, {ci[i, 1]:.4f}]" for i in held)
    free = "; the other axes' intervals include what it leaves unknown" if len(held) < 3 else ""
    return Reason("gyro_scale_held", "warning", effect, bound,
                  f"gyro scales not separable on this motion: axis {axes} (95 % intervals, held at 1) turned too "
                  f"little to resolve its scale (half-width > {100 * SCALE_RESOLUTION:g} %); a scale anywhere in it "
                  f"moves R0 by up to {model.scale_held_R0_deg:.2g} deg{spread}: together {effect:.2g} deg > "
                  f"{bound:g} deg{free}: R0 may be off by that much; turn about every axis (the gyro's "
                  f"{', '.join('xyz'[i] for i in held)} too) while recording")


def _misalignment_reason(model):
    """A warning where a resolved misalignment term departs from 0 beyond its interval and by more
    than the bound (:data:`SENSOR_THRESHOLDS` ``gyro_misalignment_error``), naming the terms and
    what they did to ``R0``."""
    from .quality import Reason

    bound = SENSOR_THRESHOLDS["gyro_misalignment_error"][0]
    mu, lo, hi = model.misalignment, model.misalignment_ci95[:, 0], model.misalignment_ci95[:, 1]
    off, worst = _off(mu, model.misalignment_ci95, model.misalignment_resolved, 0.0, bound)
    if worst is None:
        return None
    terms = ", ".join(f"{('xy', 'xz', 'yz')[i]} {mu[i]:+.4f} [{lo[i]:+.4f}, {hi[i]:+.4f}]" for i in np.flatnonzero(off))
    what = "removed from the rates" if model.applied else "measured, not removed"
    return Reason("gyro_misalignment", "warning", worst, bound,
                  f"gyro axes misaligned: symmetric off-diagonal term {terms} (95 % intervals) of {100 * worst:.3g} % "
                  f"> {100 * bound:g} %; {what}: left at 0 it moves R0 by about {model.misalignment_R0_deg:.2g} deg; "
                  f"the gyro's axes are not orthogonal (the off-diagonal of Kalibr's or OpenVINS's T_g): whatever "
                  f"reads its raw rates with T_g = I inherits the error" + triangular_words(model))


def model_or_note(camera, gyro, interval, max_offset):
    """``(model, None)`` (:func:`estimate_sensor_model`), or ``(None, why it could not be estimated
    or does not fit)``."""
    try:
        model = estimate_sensor_model(camera, gyro, interval=interval, max_offset=max_offset)
    except ValueError as err:
        return None, str(err)
    if not model.fit_ratio <= MAX_FIT_RATIO:  # a bias fitted to streams that disagree would hide what is wrong
        return None, (f"its pairs fit no rig: median residual {model.fit_ratio:.3g} of the median motion > "
                      f"{MAX_FIT_RATIO:g}, so no bias was removed")
    return model, None


def with_sensor_model(result, camera, gyro, model, note, skip_measure, interval, max_offset):
    """``result`` (of :func:`replication.rig.calibration.calibrate`, a gyro sensor) with the sensor
    model's fields and reasons; with the model off (``model`` None and no ``note``) the bias is
    measured where the verdict is not ``ok`` (unless ``skip_measure``: no diagnosis asked), and
    named if it is large."""
    import dataclasses

    from .quality import Reason
    from .solve_and_judge import with_reasons

    off = model is None and note is None
    if off and not skip_measure and result.verdict.level != "ok":
        try:
            model = estimate_sensor_model(camera, gyro, interval=interval, max_offset=max_offset, applied=False)
        except ValueError as err:
            note = str(err)
    if model is None:
        fields = {"gyro_bias_rad_s": None, "gyro_bias_ci95_rad_s": None, "clock_drift_ppm": None,
                  "clock_drift_ci95_ppm": None, "gyro_scale": None, "gyro_scale_ci95": None,
                  "gyro_misalignment": None, "gyro_misalignment_ci95": None,
                  "sensor_model": {"bias_applied": False, "note": note or "gyro bias model off (gyro_bias=False)"}}
        result = dataclasses.replace(result, sensor_model=fields)
        if note and not off:
            result = with_reasons(result, [Reason("gyro_bias_not_estimated", "warning", None, None,
                                                  f"the gyro bias was not estimated ({note}): the rates are used as "
                                                  f"recorded, bias included")])
        return result
    result = dataclasses.replace(result, sensor_model=model.report())
    result.diagnostics.update(sensor_model=model)
    found = sensor_reasons(model, interval=interval, motion_median_deg=result.diagnostics["motion_median_deg"])
    return with_reasons(result, found + [r for r in [_offsets_disagree(model, result, interval)] if r is not None])


def _offsets_disagree(model, result, interval):
    """A warning where the offset applied (the angular speeds' correlation) lies outside the pairs'
    95 % interval for it (the model's offset at the middle) and by more than the drift's bound share
    of the pairing interval (:data:`SENSOR_THRESHOLDS` ``offset_disagreement_share``)."""
    from .quality import Reason

    if not model.fit_ratio <= MAX_FIT_RATIO or not result.time_offset_applied or model.covariance is None:
        return None
    gap = abs(model.offset_mid_s - result.time_offset_s)
    noise = model.critical * math.sqrt(max(model.covariance[6, 6], 0.0))
    bound = SENSOR_THRESHOLDS["offset_disagreement_share"][0]
    if gap <= noise or gap / interval <= bound:
        return None
    lo, hi = (1e3 * v for v in result.time_offset_ci95_s)
    return Reason("offset_disagreement", "warning", float(gap / interval), bound,
                  f"the pairs fit best with the clock offset at {1e3 * model.offset_mid_s:+.2f} ms (95 % interval "
                  f"+-{1e3 * noise:.2g} ms), the angular speeds' correlation put it at "
                  f"{1e3 * result.time_offset_s:+.2f} ms ([{lo:+.2f}, {hi:+.2f}] ms; applied): {1e3 * gap:.3g} ms "
                  f"apart, {gap / interval:.3g} of the "
                  f"{interval:g} s interval > {bound:g}, an error in every pair that R0's radius does not hold; the "
                  f"speeds mislead the search where they barely vary (a steady turn); check the offset (--keep-clock "
                  f"where the clocks are synchronised)")


def drift_beside_steps(result, jumps, profile, t0: float):
    """``result`` where ``calibrate`` found a clock step (``jumps``, times on the camera's clock;
    ``t0`` the camera's first stamp): the sensor model's drift is the straight line through the
    step and the drift that may run beside it (a +300 ppm drift with a 20 ms step at 40 s of 60 s
    reads as about -150 ppm, its interval excluding the truth), so ``clock_drift_ppm`` and its
    interval are null, ``sensor_model["drift_note"]`` says why and gives the offset profile's
    drift (a step with a drift: its drift, no interval), and no ``clock_drift`` reason is left."""
    import dataclasses

    from .quality import Verdict

    result = dataclasses.replace(result, verdict=Verdict.of(
        tuple(x for x in result.verdict.reasons if x.check != "clock_drift")))
    fields = result.sensor_model
    if fields is None or fields.get("clock_drift_ppm") is None:
        return result
    at = ", ".join(f"{j.time_s - t0:.1f} s" for j in jumps)
    line = fields["clock_drift_ppm"]
    if profile is not None and profile.step_with_drift:
        beside = (f"the offset profile's step with a drift gives {profile.drift_ppm:+.1f} ppm beside it "
                  f"(segments.clock_profile; no interval)")
    else:
        beside = "the offset profile finds no drift beside it (segments.clock_profile)"
    note = (f"not measured beside the clock step at {at}: the sensor model's straight line through the step "
            f"({line:+.1f} ppm) is not the clock's drift; {beside}")
    details = {**fields["sensor_model"], "drift_resolved": False, "drift_note": note,
               "drift_through_steps_ppm": float(line)}
    return dataclasses.replace(result, sensor_model={**fields, "clock_drift_ppm": None, "clock_drift_ci95_ppm": None,
                                                     "sensor_model": details})
