"""The ledger records of ``notebooks/05_table2_experiment.ipynb``: one function per claim of the lab
experiment, each taking only the numbers its verdict rests on and called from the notebook cell that
measures them. Each checks those numbers first (:func:`replication.study.ledger.check_evidence`), on
both sets of seeds where it has both (the seeds of
:class:`~replication.study.lab.seed_sets.SeedSets`), and returns the keyword arguments of
:func:`replication.study.ledger.record`.
"""
from __future__ import annotations

import pandas as pd

from ...core.stats import declared_bound
from ..ledger import check_evidence
from .seed_sets import LAB_SETTING, SeedSets, check_disjoint, found_setting
from .study import (
    ALL_MINUS_MEAN_BOUND,
    RESOLVE_DEG,
    check_sqp_shares,
    intervention_finding,
    seed_range,
    seed_spread,
    sqp_shares,
)

__all__ = ["SECTIONS", "lab_protocol", "lab_averaging", "fig6_consistency", "fig6_accuracy", "table2_reduction",
           "table2_correlation", "table2_methods_agree", "table2_measures_calibration", "table2_rms",
           "fig7_projection"]

_FIG6, _SEEDS, _FRESH = "Fig. 6 — `R0` across the 10 data sets", "The lab over 20 seeds", "The lab over fresh seeds"
#: The notebook section (its heading) where each record's evidence is measured: the seed study's
#: findings are put beside their fresh-seed confirmation (with their intervals) in "The lab over
#: fresh seeds".
SECTIONS = {
    "lab_protocol": "The recordings", "lab_averaging": _FRESH, "fig6_consistency": _SEEDS, "fig6_accuracy": _FRESH,
    "table2_reduction": _FRESH, "table2_correlation": _FRESH, "table2_methods_agree": _FRESH,
    "table2_measures_calibration": _FRESH, "table2_rms": "Sensitivity to the magnetometer noise",
    "fig7_projection": _SEEDS,
}

_ANGLES = ("roll", "pitch", "yaw")
_NOISE, _CAL = "_without_magnetometer_noise", "_without_magnetometer_calibration_errors"


def _record(claim: str, verdict: str, **fields) -> dict:
    return dict(claim=claim, verdict=verdict, **fields, section=SECTIONS[claim])


def _plus_se(f: pd.DataFrame, key: str, sign: float) -> float:
    """A mean finding's value moved by two standard errors (``sign`` +1 or -1)."""
    return f.loc[key, "value"] + sign * 2 * f.loc[key, "se"]


def lab_protocol(poses: pd.Series, held: pd.Series) -> dict:
    """``lab_protocol``: the recordings follow the paper's protocol by construction. ``poses``:
    orientations per static data set; ``held``: :func:`~replication.study.lab.static_hold_seconds`
    of the recordings."""
    return _record(
        "lab_protocol", "undecidable from the text",
        evidence=f"a description of the authors' recordings, which are not public; our simulated lab follows it by "
                 f"construction ({len(poses)} data sets of {poses.min()}-{poses.max()} orientations, each held "
                 f"{held.min():.1f} s or more, the mean of each orientation's measurements used)",
        uncertainty="counts exact (data/lab)", setting=LAB_SETTING + "; the committed recordings")


def lab_averaging(study: pd.DataFrame, fresh: pd.DataFrame) -> dict:
    """``lab_averaging`` fails: the mean of each orientation gains nothing over every sample (its
    gain, plus two standard errors, below 1 % of the error on both sets of seeds), while one sample
    per orientation is worse by more than two standard errors. ``study``, ``fresh``: the seed
    studies (:class:`SeedSets`)."""
    s = SeedSets(study, fresh)
    for label, (_, f) in s.sets.items():
        mean_gain = -f.loc["all_minus_mean", "value"]
        check_evidence(_plus_se(f, "all_minus_mean", +1) < 0.01 * f.loc["true_mean", "value"], "lab_averaging",
                       f"the mean's gain over every sample, plus two standard errors, below 1 % of the error on "
                       f"{label} (gain {mean_gain:.4f} ± {f.loc['all_minus_mean', 'se']:.4f} deg, error "
                       f"{f.loc['true_mean', 'value']:.2f} deg)")
        check_evidence(_plus_se(f, "single_minus_mean", -1) > 0, "lab_averaging",
                       f"one sample per orientation worse than the mean by more than two standard errors on {label} "
                       f"({f.loc['single_minus_mean', 'text']} deg)")

    def share(f):  # the change with every sample, as a share of the error: a declared bound (see seed_findings)
        return declared_bound(100 * abs(f.loc['all_minus_mean', 'value']) / f.loc['true_mean', 'value'], high=0.5,
                              margin=0.05, what="lab_averaging: the change with every sample (% of the error)") + " %"

    # seed_findings declared the change's bound on both sets, with a margin from 0 that exceeds its
    # spread between machines, so its sign is the bound's (every sample the more accurate)
    lo, hi = ALL_MINUS_MEAN_BOUND
    changes = f"between {lo:g} and {hi:g}"
    f1, f2 = s.found, s.confirmed
    return _record(
        "lab_averaging", "fails",
        evidence="against the alternative the paper names, all the measurements (every IMU sample with the camera "
                 "frame at or before it; the j-th samples of consecutive orientations as one motion), the mean of "
                 "each orientation gains nothing: the two-step estimates' mean error to the true R0 is "
                 f"{f1.loc['true_mean', 'value']:.2f} and {f2.loc['true_mean', 'value']:.2f} deg with the means, and "
                 f"with every sample it changes by {changes} deg on the first and {changes} deg on the fresh "
                 f"seeds ({share(f1)} and {share(f2)} of the error; every sample the more accurate; bounds declared "
                 "in advance, as the change moves by up to 0.0005 deg between machines, as much as its standard "
                 "error). The noise the mean does reduce is that of one sample: with the first sample "
                 f"of each orientation instead, the error grows by {s.deg('single_minus_mean')}, a comparison the "
                 "paper does not make. Scope: that every sample is the (slightly) more accurate here is a property "
                 "of this lab's noise model (datasheet sensor noise, the filter's correlated attitude errors) and of "
                 "how its samples are paired into motions, not a law: a referee's independent white-noise model "
                 "(issue 36, not run here) finds the two indistinguishable at 0.2-3 deg per sample and the mean "
                 "1.2 % better at 6 deg. The verdict rests on the mean gaining nothing measurable over all the "
                 "measurements in this lab, not on all the measurements being better",
        uncertainty=f"mean ± SE of the paired differences over {s.n} seeds per set; the change with every sample as "
                    "a declared bound checked with a margin of 0.0008 deg",
        setting=s.setting)


def fig6_consistency(study: pd.DataFrame, committed_spread: float, without_deflection_spread: float) -> dict:
    """``fig6_consistency``: 'very small' is not quantified. ``study``: the seed study (the first
    seeds); ``committed_spread``: the committed draw's mean spread of the two-step estimates (deg);
    ``without_deflection_spread``: the same without the field's deflection between poses (the
    ablation)."""
    n = len(study)
    return _record(
        "fig6_consistency", "undecidable from the text",
        evidence="'very small' is not quantified, and the spread depends on error sizes the paper does not give: in "
                 f"our lab the 10 two-step estimates lie on average {seed_spread(study['spread_ours_right'])} deg "
                 f"from their mean ({n} seeds; committed draw {committed_spread:.2f} deg, "
                 f"{without_deflection_spread:.2f} deg without the field's deflection between poses)",
        uncertainty=f"mean, SD and range over {n} seeds; the deflection case on one draw", setting=found_setting(study))


def fig6_accuracy(study: pd.DataFrame, fresh: pd.DataFrame) -> dict:
    """``fig6_accuracy`` holds only if consistency means repeatability: the 10 estimates share most
    of their error (above spread / sqrt(10) in most seeds), which falls without the magnetometer's
    calibration errors and not without its noise, on both sets of seeds."""
    s = SeedSets(study, fresh)
    for label, (_, f) in s.sets.items():
        check_evidence(f.loc["shared_exceeds_independent", "low"] > 0.5, "fig6_accuracy",
                       f"the error of the mean of the 10 estimates above spread / sqrt(10) in most seeds of {label} "
                       f"({f.loc['shared_exceeds_independent', 'text']})")
        check_evidence(_plus_se(f, "shared_bias_change" + _CAL, +1) < 0, "fig6_accuracy",
                       f"the shared error falling, by more than two standard errors, without the magnetometer's "
                       f"calibration errors on {label} ({f.loc['shared_bias_change' + _CAL, 'text']} deg)")
        check_evidence(abs(f.loc["shared_bias_change" + _NOISE, "value"]) < 0.1 * f.loc["shared_bias", "value"],
                       "fig6_accuracy", f"the shared error changed by less than 10 % without the magnetometer's noise "
                       f"on {label} ({f.loc['shared_bias_change' + _NOISE, 'text']} deg)")
    f1, f2 = s.found, s.confirmed
    return _record(
        "fig6_accuracy", "holds only if",
        condition="'robustness and reproducibility' mean repeatability over data sets: the consistency does not show "
                  "accuracy, because the 10 estimates share most of their error",
        evidence=f"the mean of the 10 two-step (R^r) estimates is {s.spread('study', 'shared_bias_ours_right')} deg "
                 f"from the true R0 on the first seeds and {s.spread('fresh', 'shared_bias_ours_right')} deg on the "
                 f"fresh ones: more than the spread / sqrt(10) that independent per-set errors would leave in "
                 f"{s.both('shared_exceeds_independent')} (median ratio "
                 f"{f1.loc['shared_ratio_median', 'text']} and {f2.loc['shared_ratio_median', 'text']}). "
                 "Intervention: this shared error follows the magnetometer's calibration errors (an assumed size, "
                 "the paper gives none): switched off, it falls from "
                 f"{f1.loc['shared_bias', 'text']} to {f1.loc['shared_bias' + _CAL, 'text']} deg on the first seeds "
                 f"and from {f2.loc['shared_bias', 'text']} to {f2.loc['shared_bias' + _CAL, 'text']} deg on the "
                 f"fresh ones (paired changes {f1.loc['shared_bias_change' + _CAL, 'text']} and "
                 f"{f2.loc['shared_bias_change' + _CAL, 'text']} deg); the magnetometer's noise switched off changes "
                 f"it by {s.deg('shared_bias_change' + _NOISE)}",
        uncertainty=f"mean, SD and range over {s.n} seeds per set; counts with Wilson 95 % intervals; the "
                    f"interventions as mean ± SE over the same {s.n} seeds per set", setting=s.setting)


def table2_reduction(study: pd.DataFrame, fresh: pd.DataFrame) -> dict:
    """``table2_reduction`` holds: the calibrated RMS below the sensor frame's in most seeds of both
    sets."""
    s = SeedSets(study, fresh)
    for label, (_, f) in s.sets.items():
        check_evidence(f.loc["calibration_reduces", "low"] > 0.5, "table2_reduction",
                       f"the calibrated RMS below the sensor frame's in most seeds of {label} "
                       f"({f.loc['calibration_reduces', 'text']})")
    return _record(
        "table2_reduction", "holds",
        evidence=f"Table II RMS, mean over angles: calibrated {s.spread('study', 'rms_ours_right')} deg vs sensor "
                 f"frame {s.spread('study', 'rms_sensor_frame')} deg on the first seeds, "
                 f"{s.spread('fresh', 'rms_ours_right')} vs {s.spread('fresh', 'rms_sensor_frame')} deg on the fresh "
                 f"ones; smaller after calibration in {s.both('calibration_reduces')}",
        uncertainty=f"mean, SD and range over {s.n} seeds per set; counts with Wilson 95 % intervals",
        setting=s.setting)


def table2_correlation(study: pd.DataFrame, fresh: pd.DataFrame) -> dict:
    """``table2_correlation``: every correlation after calibration above 0.95, the roll correlation
    reaching the paper's 0.999 in no seed, on both sets of seeds; the paper's values depend on
    settings it does not give."""
    s = SeedSets(study, fresh)
    for label, (frame, f) in s.sets.items():
        corr_min = {a: float(frame[f"corr_{a}_ours_right"].min()) for a in _ANGLES}
        check_evidence(min(corr_min.values()) > 0.95, "table2_correlation",
                       f"every correlation after calibration (two-step R^r) above 0.95 on {label} (smallest per "
                       f"angle: { {a: f'{v:.6f}' for a, v in corr_min.items()} })")
        check_evidence(f.loc["corr_roll_at_paper", "value"] == 0, "table2_correlation",
                       f"the roll correlation reaching the paper's 0.999 in no seed of {label} "
                       f"({f.loc['corr_roll_at_paper', 'text']})")
    return _record(
        "table2_correlation", "undecidable from the text",
        evidence="like the RMS (table2_rms), the correlations depend on lab settings the paper does not give (sensor "
                 "noise, the trial's motion). In our lab after calibration (two-step R^r), first seeds: "
                 + "; ".join(f"{a} {s.spread('study', f'corr_{a}_ours_right', digits=4)}" for a in _ANGLES)
                 + ". The paper's 0.999 and above is reached for "
                 + "; ".join(f"{a} in {s.both(f'corr_{a}_at_paper')}" for a in _ANGLES),
        uncertainty=f"mean, SD and range over {s.n} seeds; counts of seeds with Wilson 95 % intervals",
        setting=s.setting + "; one dynamic trial per seed")


def table2_methods_agree(study: pd.DataFrame, fresh: pd.DataFrame, *, largest_rms_difference: float, bounds: dict,
                         sqp_runs) -> dict:
    """``table2_methods_agree`` holds only if SQP converges on every data set.
    ``largest_rms_difference``: the committed draw's largest Table II RMS difference between methods
    (deg); ``bounds``: SQP's declared failure shares (the notebook's ``BOUNDS``), checked on both
    sets of seeds over its runs ``sqp_runs`` (:func:`~replication.study.lab.check_sqp_shares`)."""
    s = SeedSets(study, fresh)
    for label, (frame, _) in s.sets.items():
        check_sqp_shares(sqp_shares(frame, sqp_runs), bounds, label)
    n = s.n
    return _record(
        "table2_methods_agree", "holds only if",
        condition=f"SQP converges on every data set: from the identity on eq. (8) as printed, with SLSQP's "
                  f"100-iteration cap, it stops short (> 10 deg off) on more than {bounds['failed']:.0%} of the "
                  f"{10 * n} data sets (more than {bounds['at limit']:.0%} of them at the iteration limit), in more "
                  f"than {bounds['seeds']:.0%} of the {n} seeds; with 1000 iterations on fewer than "
                  f"{bounds['failed, 1000']:.0%}, with its objective divided by 2J on fewer than "
                  f"{bounds['failed, per pair']:.0%} (each bound on both sets of seeds)",
        evidence="on the committed draw, where SQP reached the global minimum on every data set, the Table II RMS of "
                 f"SQP and the two-step method differ by at most {largest_rms_difference} deg; over the seeds "
                 "SQP fails on some data set in most of them (bounds in the condition, asserted on the first and "
                 "again on the fresh seeds)",
        uncertainty="the RMS difference: one draw; the shares of data sets and seeds: bounds, not intervals, asserted "
                    "on both sets of seeds (which data sets fail changes with the machine's rounding)",
        setting=s.setting)


def _cal_share(found: dict, fresh: dict) -> str:
    """The calibration errors' share of |pitch bias| in words (:func:`intervention_finding` on both
    sets of seeds, each resolved to :data:`RESOLVE_DEG`): what the intervals show decides the
    words."""
    numbers = (f"{found['text']} deg on {found['n']} seeds and {fresh['text']} deg on {fresh['n']} fresh seeds "
               "(mean ± SE [95 % interval])")
    signs = [(p["low"] > 0) - (p["high"] < 0) for p in (found, fresh)]
    largest = max(max(abs(p["low"]), abs(p["high"])) for p in (found, fresh))
    if signs == [0, 0]:
        return (f"{numbers}: resolved from 0 on neither set, and no share larger than {largest:.2f} deg on either; "
                "the noise is the cause")
    if signs[0] == signs[1]:
        return (f"{numbers}: a small share, resolved on both sets ({'a rise' if signs[0] > 0 else 'a fall'}, at "
                f"most {largest:.2f} deg); the noise remains the main cause")
    if 0 not in signs:
        return f"{numbers}: resolved with opposite signs on the two sets: it does not replicate"
    which = "the first" if signs[0] else "the fresh"
    return (f"{numbers}: resolved from 0 on {which} set only, its share not the same on both (at most "
            f"{largest:.2f} deg); the noise remains the main cause")


def _check_blindness(s: SeedSets, small: str) -> None:
    """Table II moved less by the estimate's error than by ``small``-degree turns, by more than the
    intervals (and the turns and the reversal losing in most seeds, the noise's share resolved), on
    both sets of seeds."""
    for label, (_, f) in s.sets.items():
        blind = abs(f.loc["rms_estimate_minus_truth", "value"]) + 2 * f.loc["rms_estimate_minus_truth", "se"]
        check_evidence(blind < _plus_se(f, f"rms_turned_{small}_minus_truth", -1), "table2_measures_calibration",
                       f"Table II's RMS moved less by the estimate's error than by {small} deg turns, each by two "
                       f"standard errors, on {label} ({f.loc['rms_estimate_minus_truth', 'text']} vs "
                       f"{f.loc[f'rms_turned_{small}_minus_truth', 'text']} deg)")
        for key in ("reversed_loses", f"turned_{small}_loses"):
            check_evidence(f.loc[key, "low"] > 0.5, "table2_measures_calibration",
                           f"{f.loc[key, 'what']}: most seeds of {label} ({f.loc[key, 'text']})")
        check_evidence(_plus_se(f, "abs_pitch_bias_change" + _NOISE, +1) < 0, "table2_measures_calibration",
                       f"|pitch bias| falling, by more than two standard errors, without the magnetometer's noise on "
                       f"{label} ({f.loc['abs_pitch_bias_change' + _NOISE, 'text']} deg)")


def _pitch_shares(pitch_cal) -> tuple[list, list]:
    """The seeds and :func:`intervention_finding` of each pitch-bias intervention, each checked:
    resolved to :data:`RESOLVE_DEG` and below a quarter of |pitch bias|."""
    check_disjoint(pitch_cal[0].index, pitch_cal[1].index, "the pitch-bias intervention")
    seeds, shares = [seed_range(frame) for frame in pitch_cal], [intervention_finding(frame) for frame in pitch_cal]
    for label, p in zip(seeds, shares):
        check_evidence(p["fine"], "table2_measures_calibration",
                       f"the change of |pitch bias| without the magnetometer's calibration errors resolved to "
                       f"+-{RESOLVE_DEG:g} deg (95 % half-width {1.96 * p['se']:.3f} deg) on {label}")
        check_evidence(abs(p["value"]) < 0.25 * p["abs_pitch_bias"], "table2_measures_calibration",
                       f"|pitch bias| changed by less than a quarter without the magnetometer's calibration errors on "
                       f"{label} ({p['text']} deg of {p['abs_pitch_bias']:.2f})")
    return seeds, shares


def table2_measures_calibration(study: pd.DataFrame, fresh: pd.DataFrame, *, pitch_true: float,
                                true_r0_pitch: pd.Series, pitch_cal) -> dict:
    """``table2_measures_calibration`` fails: Table II does not reward the more accurate ``R0``.

    ``pitch_true``: the committed draw's pitch bias with the true ``R0`` (deg); ``true_r0_pitch``:
    its pitch mean per reference frame
    (:func:`~replication.study.table2.reference_frame_dependence`, rows ``"true R0"``);
    ``pitch_cal``: :func:`~replication.study.lab.pitch_bias_intervention` without the magnetometer's
    calibration errors, on its own seeds and on fresh ones (consecutive), each resolved to
    :data:`~replication.study.lab.study.RESOLVE_DEG` and below a quarter of |pitch bias|.
    """
    s = SeedSets(study, fresh)
    f1, f2 = s.found, s.confirmed
    turned = sorted(float(k[len("turned_"):-len("_loses")]) for k in f1.index
                    if k.startswith("turned_") and k.endswith("_loses"))
    small = f"{turned[0]:g}"
    _check_blindness(s, small)
    pitch_seeds, pitch_shares = _pitch_shares(pitch_cal)
    # a count "replicates" if its Wilson interval lies on the same side of one half on both sets of
    # seeds
    sides = {int(f.loc["estimate_beats_truth", "low"] > 0.5) - int(f.loc["estimate_beats_truth", "high"] < 0.5)
             for f in (f1, f2)}
    preference = "is the same on both sets of seeds" if sides in ({1}, {-1}) else "does not replicate"
    lower = [f.loc["rms_estimate_minus_truth", "value"] < 0 for f in (f1, f2)]
    mean_preference = ("on average it is the estimate's, on both sets (the difference above)" if all(lower) else
                       "on average neither is the lower on both sets")
    return _record(
        "table2_measures_calibration", "fails",
        evidence="Table II does not reward the more accurate R0: with the two-step estimate (its chordal mean, "
                 f"{f1.loc['shared_bias', 'value']:.2f} and {f2.loc['shared_bias', 'value']:.2f} deg off the true R0 "
                 "on average) its RMS (mean over angles, "
                 f"{f1.loc['rms_true', 'value']:.2f} deg with the truth) differs from the truth's by "
                 f"{s.deg('rms_estimate_minus_truth')}, while R0 turned {small} deg about a camera "
                 f"axis raises it by {s.deg(f'rms_turned_{small}_minus_truth')} (larger than the truth's in "
                 f"{s.both(f'turned_{small}_loses')}; "
                 + "; ".join(f"{a:g} deg: {s.both(f'turned_{a:g}_loses')}" for a in turned[1:])
                 + "). Intervention on the direction at the same size: the estimate's error reversed raises the RMS by "
                 f"{s.deg('rms_reversed_minus_truth')}, above the truth's in {s.both('reversed_loses')}: the error's "
                 "sign matters, not only its size; the estimate's error partly cancels the sensor's systematic "
                 f"attitude error, which its reversal adds to. Seed by seed, which of estimate and truth gives the "
                 f"smaller RMS {preference} (the estimate in {s.both('estimate_beats_truth')}); {mean_preference}. "
                 "Table II's pitch bias is the AHRS filter's attitude "
                 f"error at the reference frame, not the calibration's: with the true R0 it is {pitch_true:.2f} deg "
                 "on the committed draw and changes sign as the reference frame moves "
                 f"({true_r0_pitch.min():.2f} to {true_r0_pitch.max():.2f}"
                 " deg); switching the magnetometer's noise off takes |pitch bias| from "
                 f"{f1.loc['abs_pitch_bias', 'text']} to {f1.loc['abs_pitch_bias' + _NOISE, 'text']} deg on the first "
                 f"seeds and from {f2.loc['abs_pitch_bias', 'text']} to {f2.loc['abs_pitch_bias' + _NOISE, 'text']} "
                 "deg on the fresh ones; switching its calibration errors off changes it by "
                 f"{_cal_share(*pitch_shares)}",
        uncertainty=f"counts with Wilson 95 % intervals; RMS differences and |pitch bias| as mean ± SE over {s.n} "
                    f"seeds per set; the calibration errors' share as mean ± SE [95 % interval] over "
                    f"{pitch_shares[0]['n']} seeds per set; the committed draw's pitch bias: one draw",
        setting=s.setting + f"; the magnetometer's calibration errors switched off on {pitch_seeds[0]}, confirmed "
                f"on fresh {pitch_seeds[1]} (the dynamic trial only, the true R0); the magnetometer's residual errors "
                "are assumed sizes (LabSettings)")


def table2_rms(study: pd.DataFrame, sensitivity_rms: pd.Series) -> dict:
    """``table2_rms``: the RMS follows settings the paper does not give. ``study``: the seed study
    (the first seeds); ``sensitivity_rms``: the committed draw's calibrated RMS per magnetometer
    noise level (0 to 1.4 uT)."""
    n = len(study)
    return _record(
        "table2_rms", "undecidable from the text",
        evidence=f"our calibrated RMS is {seed_spread(study['rms_ours_right'])} deg ({n} seeds), above the paper's "
                 f"0.63-0.99; it follows the magnetometer noise through the filter "
                 f"({sensitivity_rms.min():.2f} deg at 0 to {sensitivity_rms.max():.2f} deg at 1.4 uT) and the AHRS "
                 "error at the reference frame, neither given by the paper",
        uncertainty=f"mean, SD and range over {n} seeds; sensitivity on one draw", setting=found_setting(study))


def fig7_projection(study: pd.DataFrame, sensor_frame_correlation: pd.Series) -> dict:
    """``fig7_projection`` holds: after projection the traces follow the camera's. ``study``: the
    seed study (the first seeds); ``sensor_frame_correlation``: Table II's sensor-frame correlations
    on the committed draw."""
    return _record(
        "fig7_projection", "holds",
        evidence=f"after projection the traces follow the camera's (smallest correlation "
                 f"{seed_spread(study['corr_ours_right'])}); the sensor-frame traces do not (Table II sensor-frame "
                 f"correlations {sensor_frame_correlation.min():.2f} to {sensor_frame_correlation.max():.2f}, "
                 "committed draw)",
        uncertainty=f"mean, SD and range over {len(study)} seeds", setting=found_setting(study))
