"""The quality verdict of a calibration: ``ok``, ``warning`` or ``fail``, with every reason
measured. Theory and measured numbers: ``docs/judging.md``, section ``replication.rig.quality``."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["LEVELS", "EXIT_FAIL", "Reason", "Verdict", "Evidence", "judge", "THRESHOLDS", "p_with_level"]

#: Verdict levels, best first.
LEVELS = ("ok", "warning", "fail")
#: Exit code of ``python -m replication calibrate`` for a ``fail`` verdict (2 is bad input).
EXIT_FAIL = 3

#: ``(warning, fail)`` bounds of each check (see the module notes for the reasoning).
THRESHOLDS = {
    "offset_correlation": (0.9, 0.5),          # below
    "offset_at_bound_resolutions": (None, 2),  # within this many resolutions of the bound: fail
    "offset_peak_margin": (0.1, 0.01),         # below: another clock offset matches the speeds almost as well
    "blocks": (10, 3),                         # below
    "overlap_intervals": (10, 2),              # below
    "residual_to_motion": (0.1, 0.3),          # above
    "residual_median_deg": (2.0, 10.0),        # above
    "bootstrap_deg": (1.0, 5.0),               # above
    "axis_spread_deg": (1.0, None),            # below
    "excitation_deg": (1.0, None),             # below (online: the motion so far does not determine R0)
    "motion_median_deg": (1.0, 0.5),           # below
    "pose_residual_ratio": (3.0, None),        # above: a station's median residual / the stations' median
    "gap_share_dropped": (0.0, 0.5),           # above
    "gyro_rate_hz": (50.0, None),              # below
    "gyro_samples_per_interval": (None, 5.0),  # below
    "n_pairs": (30, 10),                       # below
    "reference_error_deg": (1.0, 5.0),         # above
    "remount_deg": (0.5, 0.75),                # above, where the change test is significant
    "offset_left_ms": (5.0, None),             # above (an offset measured but not removed)
    "mirror_fit_ratio": (3.0, None),           # below: the sensor's frame mirrored fits almost as well
}

_FAIL_WARNINGS = ("LocalMinimumWarning", "AccuracyWarning")


@dataclass(frozen=True)
class Reason:
    """One finding: ``check`` measured ``measured`` against ``threshold`` and reached ``level``."""

    check: str
    level: str
    measured: float | None
    threshold: float | None
    message: str

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Verdict:
    """``level`` (the worst of the reasons, ``ok`` if none) and the ``reasons``."""

    level: str
    reasons: tuple

    @classmethod
    def of(cls, reasons) -> Verdict:
        reasons = tuple(reasons)
        level = max((r.level for r in reasons), key=LEVELS.index, default="ok")
        return cls(level, reasons)

    def to_dict(self) -> dict:
        return {"level": self.level, "reasons": [r.to_dict() for r in self.reasons]}

    def lines(self) -> list[str]:
        """The verdict and one line per reason, for a summary."""
        return [f"verdict: {self.level.upper()}"] + [f"  {r.level}: {r.message}" for r in self.reasons]


@dataclass(frozen=True)
class Evidence:
    """What a calibration measured about itself (``None`` where it does not apply, e.g. static
    poses)."""

    n_pairs: int
    residual_median_deg: float | None
    motion_median_deg: float | None
    bootstrap_deg: float | None
    axis_spread_deg: float | None = None
    warnings: tuple = ()
    offset_s: float | None = None
    offset_correlation: float | None = None
    max_offset_s: float | None = None
    offset_resolution_s: float | None = None
    blocks: float | None = None
    overlap_s: float | None = None
    interval_s: float | None = None
    pairs_dropped_at_gaps: int = 0
    pairs_before_gaps: int | None = None
    gyro_rate_hz: float | None = None
    reference_error_deg: float | None = None
    bootstrap_failed: str | None = None
    offset_applied: bool = True
    radius_kind: str = "bootstrap"          # what the radius is: "bootstrap" (batch) or "curvature" (online)
    excitation_deg: float | None = None     # online: RMS rotation about axes perpendicular to the least-excited one
    offset_peak_margin: float | None = None  # correlation at the offset minus the best other peak's (NaN: none)
    second_peak_offset_s: float | None = None
    change: object | None = None            # streams: replication.rig.changepoint.ChangeTest (t relative to the camera)
    change_sides_fit: float | None = None   # the larger median residual / median motion of its two sides
    repeated_pairs: int = 0                 # online: pairs refused as repeats of earlier ones
    pose_residual_medians_deg: tuple | None = None  # static pose sets: each station's median pair residual
    pose_residual_kind: str = "median residual of its pairs"  # or "its own residual" (consecutive pairs)
    mirror_fit_ratio: float | None = None   # the fit with the sensor's frame mirrored: its median residual / ours
    mirror_normal: tuple | None = None      # the sensor axis turned about least
    spectral_ratio: float | None = None     # sigma_2 / sigma_1 of K (the two-step iteration's rate: its square)
    method: str | None = None               # the solver that answered (named in what to do about its warnings)


def p_with_level(p_value: float, level: float | None, significant: bool) -> str:
    """A test's p-value next to its level, e.g. ``p = 0.049 >= the test's level 0.01`` (a p of 0.049
    is "within the noise" at level 0.01); as many digits as keep ``p`` and the level apart; without
    a level, ``p`` alone."""
    if level is None:
        return f"p = {p_value:.2g}"
    digits = 2
    while digits < 6 and float(f"{p_value:.{digits}g}") == float(level):
        digits += 1
    if (p_value < level) != significant:  # at the boundary, the threshold decided: no comparison that reads wrong
        return f"p = {p_value:.{digits}g}, at the test's level {level:g} (its threshold decided)"
    return f"p = {p_value:.{digits}g} {'<' if significant else '>='} the test's level {level:g}"


def _above(check, value, name, unit, why):
    warn, fail = THRESHOLDS[check]
    if value is None:
        return None
    for level, bound in (("fail", fail), ("warning", warn)):
        if bound is not None and value > bound:
            return Reason(check, level, float(value), float(bound),
                          f"{name} {value:.3g}{unit} > {bound:g}{unit}: {why}")
    return None


def _below(check, value, name, unit, why):
    warn, fail = THRESHOLDS[check]
    if value is None:
        return None
    for level, bound in (("fail", fail), ("warning", warn)):
        if bound is not None and value < bound:
            return Reason(check, level, float(value), float(bound),
                          f"{name} {value:.3g}{unit} < {bound:g}{unit}: {why}")
    return None


def _quaternion(R) -> str:
    from ..core.so3 import quaternion_from_matrix

    return "(" + ", ".join(f"{v:.4f}" for v in quaternion_from_matrix(R)) + ")"


def _outlying_poses(medians, kind="median residual of its pairs"):
    """A warning naming the stations whose pairs' median residual exceeds the threshold share of the
    stations'."""
    factor = THRESHOLDS["pose_residual_ratio"][0]
    finite = np.isfinite(medians)
    base = float(np.median(np.asarray(medians)[finite])) if finite.any() else np.nan  # no station: nothing to compare
    if not base > 0:
        return None
    ratio = medians / base
    bad = np.flatnonzero(ratio > factor)
    if not len(bad):
        return None
    bad = bad[np.argsort(-ratio[bad])]
    named = ", ".join(f"{int(k)} ({medians[k]:.3g} deg)" for k in bad[:5]) + (f" and {len(bad) - 5} more"
                                                                                if len(bad) > 5 else "")
    return Reason("pose_outliers", "warning", float(ratio[bad[0]]), factor,
                  f"outlying pose{'s' if len(bad) > 1 else ''} (0-based index, {kind}): "
                  f"{named} > {factor:g} x the stations' median {base:.3g} deg = {factor * base:.3g} deg: "
                  f"a bad measurement at that station (a target detection, a robot pose); its pairs pull R0")


#: The solver a verdict recommends where the chosen one is slowed or misled by the motions
#: (``calibrate``'s default).
DEFAULT_METHOD = "chordal_optimal"
#: The two-step iteration's cap and the relative precision it iterates to (``two_step``'s ``cap``
#: and ``tol``).
_TWO_STEP_CAP, _TWO_STEP_TOL = 1000, 1e-12


def _motion_words(e: Evidence) -> str:
    """The motions' measured shape: camera axis spread (and median motion per pair, where known)."""
    spread = "" if e.axis_spread_deg is None else f"camera axis spread {e.axis_spread_deg:.3g} deg"
    motion = "" if e.motion_median_deg is None else f"median motion per pair {e.motion_median_deg:.3g} deg"
    return ", ".join(w for w in (spread, motion) if w)


def _solver_reason(name: str, level: str, e: Evidence) -> Reason:
    """A solver's warning in the verdict: its measured cause and what to do, not the warning's class
    (the class and the solver's own words stay in the result's ``warnings``)."""
    method = f"solver {e.method!r}" if e.method else "the solver"
    other = (f"use the default method {DEFAULT_METHOD}" if e.method != DEFAULT_METHOD
             else "check the pairs (outliers, mismatched streams)")
    shape = _motion_words(e)
    if name == "IterationCapWarning":
        ratio = e.spectral_ratio
        cap_ratio = math.exp(math.log(_TWO_STEP_TOL) / (2 * _TWO_STEP_CAP))
        known = ratio is not None and math.isfinite(ratio)
        if known and cap_ratio < ratio < 1:
            needed = math.log(_TWO_STEP_TOL) / (2 * math.log(ratio))
            return Reason("solver_warning", level, float(ratio), cap_ratio,
                          f"motions too close to one axis (or too small) for the two-step iteration: sigma_2 / "
                          f"sigma_1 of K {ratio:.4f} > {cap_ratio:.4f} ({shape}), so {method} would need about "
                          f"{needed:.0f} iterations (> its cap of {_TWO_STEP_CAP}) and answers with its limit in "
                          f"closed form instead; {other}, which this does not slow, or add motion about other axes")
        measured = f"sigma_2 / sigma_1 of K {ratio:.4f}, " if known else ""
        return Reason("solver_warning", level, float(ratio) if known else None, cap_ratio if known else None,
                      f"{method} did not reach its limit within its iterations ({measured}{shape}; or its start was "
                      f"orthogonal to the limit: its words in the warnings) and answers with the limit in closed "
                      f"form; {other}, or add motion about other axes")
    causes = {
        "LocalMinimumWarning": (f"the answer of {method} is away from the certified optimum of eq. "
                                f"(8) and costs more (it stopped early or on another stationary point): {other}"),
        "AccuracyWarning": (f"the answer of {method} is far from the certified minimiser of eq. "
                            f"(8) (a closed form off by a half-turn on a motion near 180 deg, or not a rotation): "
                            f"{other}"),
        "ConvergenceWarning": (f"{method} stopped before converging (a fixed iteration count, or "
                               f"its own stop), so its answer is not its fixed point: {other}, or let it iterate"),
        "CertificateWarning": (f"the global optimality of the answer could not be certified (the "
                               f"convex relaxation of eq. (8) was not tight), which motions small for the noise or "
                               f"close to one axis cause ({shape or 'no motion measure'}): add motion about other "
                               f"axes, or check it against a reference"),
    }
    message = causes.get(name, f"{method} warned ({name}; its words in the result's warnings)")
    return Reason("solver_warning", level, None, None, message)


def judge(e: Evidence, extra=()) -> Verdict:
    """The verdict on a calibration from its evidence (and further reasons ``extra``, e.g.
    diagnoses)."""
    poses = e.pose_residual_medians_deg is not None  # static poses: the remedies are more stations, not a recording
    reasons = [_below("n_pairs", e.n_pairs, "motion pairs", "", "too few for R0 and a check of it (3 unknowns; "
                      + ("more static poses, each turned from the others by more than min_motion_deg)" if poses else
                         "a smaller stride or interval, or a longer recording)"))]
    if e.bootstrap_failed:
        reasons.append(Reason("bootstrap_failed", "warning", None, None, f"no bootstrap radius: a resample of the "
                              f"pairs was refused ({e.bootstrap_failed}); too few or too similar pairs"))
    if e.reference_error_deg is not None:
        reasons.append(_above("reference_error_deg", e.reference_error_deg, "angle to the given reference", " deg",
                              "the data agree with another R0 than the reference: gyro axes permuted or sign-flipped "
                              "(a fixed rotation the data alone cannot show), or a reference for another rig or "
                              "camera"))
    if e.offset_s is not None and not e.offset_applied:
        reasons.append(_above("offset_left_ms", abs(1e3 * e.offset_s), "clock offset measured but not removed", " ms",
                              "the pairs were formed with the clocks as recorded (keep-clock)"))
    if e.offset_correlation is not None and not math.isfinite(e.offset_correlation):
        reasons.append(Reason("offset_correlation", "fail", None, THRESHOLDS["offset_correlation"][1],
                              "no time-offset correlation: a stream's angular speed does not vary (a rig at rest, or "
                              "a constant stream), so no clock offset could be estimated"))
    elif e.offset_correlation is not None:
        reasons.append(_below("offset_correlation", e.offset_correlation, "time-offset correlation", "",
                              "the two streams' angular speeds do not match (unrelated streams, wrong units or "
                              "columns, or a clock offset beyond the search)"))
    if e.offset_peak_margin is not None and math.isfinite(e.offset_peak_margin):
        second = e.second_peak_offset_s
        where = f" ({1e3 * second:+.1f} ms)" if second is not None and math.isfinite(second) else ""
        reasons.append(_below("offset_peak_margin", e.offset_peak_margin, "margin of the time-offset correlation peak "
                              "over the next one", "", f"another clock offset{where} matches the angular speeds "
                              f"almost as well (periodic motion): the offset may be that one; record motion that is "
                              f"not periodic"))
    if e.offset_s is not None and e.max_offset_s is not None:
        margin = THRESHOLDS["offset_at_bound_resolutions"][1] * (e.offset_resolution_s or 0.0)
        if abs(e.offset_s) >= e.max_offset_s - margin:
            reasons.append(Reason("offset_at_bound", "fail", float(e.offset_s), float(e.max_offset_s),
                                  f"the clock offset {1e3 * e.offset_s:+.1f} ms lies at the search bound "
                                  f"+-{1e3 * e.max_offset_s:g} ms: the true offset may be larger (raise max_offset)"))
    if e.blocks is not None:
        reasons.append(_below("blocks", e.blocks, "independent bootstrap blocks", "",
                              "too few for a meaningful bootstrap radius ("
                              + ("more distinct stations)" if poses else "a longer overlap or a shorter interval)")))
    if e.overlap_s is not None and e.interval_s:
        reasons.append(_below("overlap_intervals", e.overlap_s / e.interval_s, "overlap of the streams in pairing "
                              "intervals", "", f"the streams overlap {e.overlap_s:.1f} s only"))
    reasons.append(_below("motion_median_deg", e.motion_median_deg, "median motion per pair", " deg",
                          "the rig barely moves over a pairing interval (at rest, or an interval too short): the "
                          "pairs carry noise, not motion"))
    if e.motion_median_deg is not None and e.residual_median_deg is not None and e.motion_median_deg > 0:
        reasons.append(_above("residual_to_motion", e.residual_median_deg / e.motion_median_deg,
                              "median pair residual / median motion", "",
                              "R0 does not map one stream's motions onto the other's"))
    reasons.append(_above("residual_median_deg", e.residual_median_deg, "median pair residual", " deg",
                          "far above what stream noise leaves with the right R0"))
    radius = "bootstrap 95 % radius" if e.radius_kind == "bootstrap" else "95 % radius (curvature of eq. (8))"
    reasons.append(_above("bootstrap_deg", e.bootstrap_deg, radius, " deg", "the pairs disagree on R0"))
    reasons.append(_below("axis_spread_deg", e.axis_spread_deg, "camera axis spread", " deg",
                          "nearly single-axis motion: the rotation about that axis is poorly determined"))
    reasons.append(_below("excitation_deg", e.excitation_deg, "RMS rotation about the least-excited axes", " deg",
                          "the motion so far does not determine R0 (rotate about other axes)"))
    if e.repeated_pairs:
        reasons.append(Reason("repeated_pairs", "warning", float(e.repeated_pairs), 0.0,
                              f"{e.repeated_pairs} pairs repeated earlier ones (a stalled stream, or data fed twice) "
                              f"and were not counted"))
    for name in sorted(set(e.warnings)):
        level = "fail" if name in _FAIL_WARNINGS else "warning"
        if name == "ObservabilityWarning":
            if e.axis_spread_deg is not None and e.axis_spread_deg < THRESHOLDS["axis_spread_deg"][0]:
                continue  # the axis spread above says it, with its number
            reasons.append(Reason("observability", "warning", None, None,
                                  f"the motions barely determine R0 ({_motion_words(e) or 'no motion measure'}; the "
                                  f"measured leverage is in the warnings): one pair alone carries the rotation about "
                                  f"the dominant axis, or another rotation fits eq. (8) almost as well (motions small "
                                  f"for the noise, outlier pairs, or nearly a second solution); add motion about "
                                  f"other axes, or drop the pair named there"))
            continue
        reasons.append(_solver_reason(name, level, e))
    if e.mirror_fit_ratio is not None:
        normal = "" if e.mirror_normal is None else f" (about {np.round(e.mirror_normal, 2).tolist()}, sensor frame)"
        reasons.append(_below("mirror_fit_ratio", e.mirror_fit_ratio, "median residual with the sensor's frame "
                              "mirrored / this fit's", "", f"a sensor with one axis's sign flipped (a left-handed "
                              f"frame, e.g. in a driver) fits these pairs almost as well, with another R0, so the data "
                              f"cannot show which it is: the sensor turns about axes near one plane "
                              f"and little about its normal{normal}; rotate about that axis too, or check the "
                              f"sensor's axes"))
    if e.pose_residual_medians_deg is not None:
        reasons.append(_outlying_poses(np.asarray(e.pose_residual_medians_deg, dtype=float), e.pose_residual_kind))
    sides_fit = e.change_sides_fit is None or e.change_sides_fit <= THRESHOLDS["residual_to_motion"][1]
    if e.change is not None and e.change.significant and sides_fit:  # a re-mount leaves each side fitting its R0
        c = e.change
        reasons.append(_above("remount_deg", c.angle_deg, f"angle between R0 before and after {c.split_time:.1f} s",
                              " deg", f"the {c.n_before} pairs before and the {c.n_after} after agree on different R0 "
                              f"beyond their noise (change test {p_with_level(c.p_value, c.level, True)}, 95 % noise "
                              f"radius {c.difference_radius_deg:.2g} deg): the sensor re-mounted during the recording, "
                              f"or a trajectory whose frame wanders; R0 before {_quaternion(c.R_before)}, after "
                              f"{_quaternion(c.R_after)} (w, x, y, z); calibrate each part on its own"))
    if e.pairs_dropped_at_gaps:
        share = e.pairs_dropped_at_gaps / max(1, e.pairs_before_gaps or 1)
        reasons.append(_above("gap_share_dropped", share, "share of pairs dropped across stream gaps", "",
                              f"{e.pairs_dropped_at_gaps} pairs spanned a gap in a stream and were dropped"))
    if e.gyro_rate_hz is not None:
        reasons.append(_below("gyro_rate_hz", e.gyro_rate_hz, "gyro rate", " Hz",
                              "integrating a slow gyro leaves an error in every pair"))
        if e.interval_s:
            reasons.append(_below("gyro_samples_per_interval", e.gyro_rate_hz * e.interval_s,
                                  "gyro samples per pairing interval", "",
                                  "too few to integrate the motion of one pair"))
    return Verdict.of([r for r in [*reasons, *extra] if r is not None])
