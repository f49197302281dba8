"""The ledger records of ``notebooks/05_table2_experiment.ipynb``, its last section ("The paper's claims about the
lab experiment"): each claim's verdict, evidence, uncertainty and setting, built from the quantities the notebook
measured on the committed recordings and over the 20-seed study.

:func:`lab_claims` returns the keyword arguments of :func:`replication.study.ledger.record`; the notebook records
them. The numbers a verdict rests on are checked first (:func:`replication.study.ledger.check_evidence`).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from ..ledger import check_evidence
from .study import seed_spread

__all__ = ["SECTIONS", "lab_claims"]

_FIG6, _SEEDS = "Fig. 6 — `R0` across the 10 data sets", "The lab over 20 seeds"
_CONCLUSIONS = "Which of the paper's conclusions hold here?"
#: The notebook section (its heading) where each record's evidence is measured.
SECTIONS = {
    "lab_protocol": "The recordings", "lab_averaging": _SEEDS, "fig6_consistency": _FIG6, "fig6_accuracy": _FIG6,
    "table2_reduction": _CONCLUSIONS, "table2_correlation": _CONCLUSIONS, "table2_methods_agree": _SEEDS,
    "table2_measures_calibration": "What Table II measures", "table2_rms": "Sensitivity to the magnetometer noise",
    "fig7_projection": "Fig. 7 — the dynamic trial",
}

#: The setting of every record of the lab.
_LAB_SETTING = "simulated lab (LabSettings defaults: datasheet noise, residual calibration errors as documented)"
#: ... and of the records that rest on the seed study.
_SEEDS_SETTING = f"{_LAB_SETTING}; seeds 1-20 (and the committed draw, seed 20130501)"
_ANGLES = ("roll", "pitch", "yaw")


def lab_claims(study: pd.DataFrame, *, poses: pd.Series, held: pd.Series, summary: pd.DataFrame,
               ablation_table: pd.DataFrame, sensitivity_table: pd.DataFrame, table2: pd.DataFrame, checks: dict,
               single_gain, shared: dict, pitch: dict, pitch_true: float, frames: pd.DataFrame,
               at_paper: pd.DataFrame, worse_true: int, reversed_loses: int, beats_true: dict,
               no_cal: pd.DataFrame, worse_true_no_cal: int, bounds: dict, n_sets: int) -> list[dict]:
    """The records of the lab's ten claims, from ``lab_protocol`` to ``fig7_projection``.

    Notebook 05, "The paper's claims about the lab experiment (ledger)". Every argument is a quantity of an
    earlier section of the notebook, under the notebook's name where it differs.

    Parameters
    ----------
    study : DataFrame
        :func:`replication.study.lab.seed_study` over seeds 1-20 (one row per seed).
    poses : Series
        Orientations per static data set of the committed recordings.
    held : Series
        :func:`replication.study.lab.static_hold_seconds` of those recordings.
    summary : DataFrame
        Fig. 6's spread and true error per method (index ``method``; ``spread_mean_deg``).
    ablation_table : DataFrame
        :func:`replication.study.lab.ablation` (the notebook's ``ab``).
    sensitivity_table : DataFrame
        :func:`replication.study.lab.sensitivity` to the magnetometer noise (the notebook's ``sens``).
    table2 : DataFrame
        Table II of the committed draw (``LabResult.table2``, index ``(angle, method)``).
    checks : dict
        "Which of the paper's conclusions hold here?" (the largest RMS difference between methods).
    single_gain : (float, float)
        Mean and SE over seeds of the true error with the first sample minus with the mean.
    shared, pitch : dict
        Shared error of the 10 estimates / |pitch bias| with the true ``R0``, seeds 1-10, per case ("all error
        sources", "without <part>").
    pitch_true : float
        The pitch bias with the true ``R0`` on the committed draw (deg).
    frames : DataFrame
        :func:`replication.study.table2.reference_frame_dependence` (rows ``"true R0"``, column ``"pitch mean"``).
    at_paper : DataFrame
        Per seed and angle: is the correlation at least the paper's 0.999 (columns ``corr_<angle>_ours_right``)?
    worse_true, reversed_loses : int
        Seeds where the true ``R0`` gives a larger RMS than the estimate; where the reversed error gives a larger
        RMS than the true ``R0``.
    beats_true : dict
        Angle turned (deg) -> seeds where ``R0`` so turned gives a larger RMS than the true ``R0``.
    no_cal : DataFrame
        The seed study without the magnetometer's calibration errors (seeds 1-10).
    worse_true_no_cal : int
        ``worse_true`` there.
    bounds : dict
        SQP's asserted bounds (the notebook's ``BOUNDS``: ``"failed"``, ``"at limit"``, ``"seeds"``,
        ``"failed, 1000"``, ``"failed, per pair"``).
    n_sets : int
        Data sets over the seeds.

    Returns
    -------
    list of dict
        The keyword arguments of :func:`replication.study.ledger.record`, in the notebook's order.

    Raises
    ------
    ValueError
        A check of the numbers a verdict rests on failing (claim and condition named): every correlation after
        calibration above 0.95, and the paper's 0.999 reached for roll in no seed.
    """
    def spread(col, digits=2):
        return seed_spread(study[col], digits)

    corr_min = {a: study[f"corr_{a}_ours_right"].min() for a in _ANGLES}
    check_evidence(min(corr_min.values()) > 0.95, "table2_correlation",
                   f"every correlation after calibration (two-step R^r) is above 0.95 (smallest per angle: {corr_min})")
    roll_at_paper = at_paper["corr_roll_ours_right"].sum()
    check_evidence(roll_at_paper == 0, "table2_correlation",
                   f"the roll correlation reaches the paper's 0.999 in no seed (reached in {roll_at_paper})")
    excess = study["shared_bias_ours_right"] / (study["spread_ours_right"] / np.sqrt(10))
    records = [dict(
        claim="lab_protocol", verdict="undecidable from the text",
        evidence=f"a description of the authors' recordings, which are not public; our simulated lab follows it by "
                 f"construction ({len(poses)} data sets of {poses.min()}-{poses.max()} orientations, each held "
                 f"{held.min():.1f} s or more, the mean of each orientation's measurements used)",
        uncertainty="counts exact (data/lab)", setting=_LAB_SETTING + "; the committed recordings"), dict(
        claim="lab_averaging", verdict="holds",
        evidence=f"the two-step estimates' mean error to the true R0 is {study['true_ours_right'].mean():.2f} deg with "
                 f"the mean of each orientation's measurements and {study['true_single_ours_right'].mean():.2f} deg "
                 f"with its first sample alone (paired difference {single_gain[0]:.2f} ± {single_gain[1]:.2f} deg); "
                 "using every sample as a separate orientation was not tried",
        uncertainty="mean ± SE of the paired difference over 20 seeds", setting=_SEEDS_SETTING), dict(
        claim="fig6_consistency", verdict="undecidable from the text",
        evidence="'very small' is not quantified, and the spread depends on error sizes the paper does not give: in "
                 f"our lab the 10 two-step estimates lie on average {spread('spread_ours_right')} deg from their mean "
                 f"(20 seeds; committed draw {summary.loc['ours_right', 'spread_mean_deg']:.2f} deg, "
                 f"{ablation_table.loc['without magnetic field deflection', 'spread_ours_right']:.2f} deg without the "
                 "field's deflection between poses)",
        uncertainty="mean, SD and range over 20 seeds; the deflection case on one draw", setting=_SEEDS_SETTING), dict(
        claim="fig6_accuracy", verdict="holds only if",
        condition="'robustness and reproducibility' mean repeatability over data sets: the consistency does not show "
                  "accuracy, because the 10 estimates share most of their error",
        evidence=f"the mean of the 10 estimates is {spread('shared_bias_ours_right')} deg from the true R0 (two-step "
                 f"R^r), {excess.median():.1f} times (median over seeds) the spread / sqrt(10) that independent "
                 f"per-set errors would leave. The shared part follows the magnetometer's calibration errors: over "
                 f"seeds 1-10 it is " + ", ".join(f"{v:.2f} deg {k}" for k, v in shared.items()),
        uncertainty="mean, SD and range over 20 seeds; means over 10 seeds for the interventions",
        setting=_SEEDS_SETTING), dict(
        claim="table2_reduction", verdict="holds",
        evidence=f"Table II RMS, mean over angles: calibrated {spread('rms_ours_right')} deg vs sensor frame "
                 f"{spread('rms_sensor_frame')} deg (20 seeds)",
        uncertainty="mean, SD and range over 20 seeds", setting=_SEEDS_SETTING), dict(
        claim="table2_correlation", verdict="undecidable from the text",
        evidence="like the RMS (table2_rms), the correlations depend on lab settings the paper does not give (sensor "
                 "noise, the trial's motion). In our lab after calibration (two-step R^r): "
                 + "; ".join(f"{a} {spread(f'corr_{a}_ours_right', digits=4)}" for a in _ANGLES)
                 + f"; the paper's 0.999 and above is reached in {int(at_paper.to_numpy().sum())} of {at_paper.size} "
                 "seed x angle cells (roll in none)",
        uncertainty="mean, SD and range over 20 seeds", setting=_SEEDS_SETTING + "; one dynamic trial per seed"), dict(
        claim="table2_methods_agree", verdict="holds only if",
        condition=f"SQP converges on every data set: from the identity on eq. (8) as printed, with SLSQP's "
                  f"100-iteration cap, it stops short (> 10 deg off) on more than {bounds['failed']:.0%} of the "
                  f"{n_sets} data sets (more than {bounds['at limit']:.0%} of them at the iteration limit), in more "
                  f"than {bounds['seeds']:.0%} of the {len(study)} seeds; with 1000 iterations on fewer than "
                  f"{bounds['failed, 1000']:.0%}, with its objective divided by 2J on fewer than "
                  f"{bounds['failed, per pair']:.0%}",
        evidence="on the committed draw, where SQP reached the global minimum on every data set, the Table II RMS of "
                 "SQP and the two-step method differ by at most "
                 f"{checks['ours and SQP agree (largest RMS difference between methods, deg)']} deg; over the seeds "
                 "SQP fails on some data set in most of them (bounds in the condition)",
        uncertainty="one draw (the RMS difference); shares of data sets and seeds as asserted bounds (which sets fail "
                    "changes with the machine's rounding)", setting=_SEEDS_SETTING)]
    records.append(dict(
        claim="table2_measures_calibration", verdict="fails",
        evidence=f"in our lab Table II prefers the less accurate R0 in most seeds: projected with the two-step "
                 f"estimate (its chordal mean, {study['shared_bias_ours_right'].mean():.1f} deg off on average) the "
                 f"RMS is smaller than with the true R0 in {worse_true} of {len(study)} seeds. Intervention: the same "
                 f"error reversed gives a larger RMS than the truth in {reversed_loses} of {len(study)}, so what "
                 "decides is the error's direction relative to the sensor's own systematic attitude error, not its "
                 "size; without the magnetometer's calibration errors (an assumed size, the paper gives none) the "
                 f"estimate, then {shared['without magnetometer calibration errors']:.1f} deg off, beats the truth in "
                 f"{worse_true_no_cal} of {len(no_cal)} seeds. R0 turned about a camera axis by "
                 f"{', '.join(f'{a:g}' for a in beats_true)} deg gives a larger RMS than the truth in "
                 f"{', '.join(str(n) for n in beats_true.values())} of {len(study)} seeds. The pitch bias is the AHRS "
                 f"attitude error at the reference frame: with the true R0 it is {pitch_true:.2f} deg on the committed "
                 f"draw, changes sign as the reference frame moves ({frames.loc['true R0', 'pitch mean'].min():.2f} "
                 f"to {frames.loc['true R0', 'pitch mean'].max():.2f} deg), and over seeds 1-10 its size is "
                 + ", ".join(f"{v:.2f} deg {k}" for k, v in pitch.items()),
        uncertainty="counts over 20 (and 10) seeds; means of |bias| over 10 seeds per intervention",
        setting=_SEEDS_SETTING + "; the magnetometer's residual errors are assumed sizes (LabSettings)"))
    sensor_frame = table2.xs("sensor_frame", level="method")["correlation"]
    records += [dict(
        claim="table2_rms", verdict="undecidable from the text",
        evidence=f"our calibrated RMS is {spread('rms_ours_right')} deg (20 seeds), above the paper's 0.63-0.99; it "
                 f"follows the magnetometer noise through the filter ({sensitivity_table['rms_ours_right'].min():.2f} "
                 f"deg at 0 to {sensitivity_table['rms_ours_right'].max():.2f} deg at 1.4 uT) and the AHRS error at "
                 "the reference frame, neither given by the paper",
        uncertainty="mean, SD and range over 20 seeds; sensitivity on one draw", setting=_SEEDS_SETTING), dict(
        claim="fig7_projection", verdict="holds",
        evidence=f"after projection the traces follow the camera's (smallest correlation {spread('corr_ours_right')}); "
                 f"the sensor-frame traces do not (Table II sensor-frame correlations {sensor_frame.min():.2f} to "
                 f"{sensor_frame.max():.2f}, committed draw)",
        uncertainty="mean, SD and range over 20 seeds", setting=_SEEDS_SETTING)]
    return [{**r, "section": SECTIONS[r["claim"]]} for r in records]
