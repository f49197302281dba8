"""The lab's ledger records of notebook 05 (``replication.study.lab.claims``), built from the
synthetic seed studies of ``tests/study/lab_inputs.py`` on two sets of seeds: the claim ids,
verdicts and numbers, both seed sets named, the fresh seeds disjoint from the first, and each check
raising just past its threshold (on the fresh seeds too) and not just before it. The seed study and
its findings: test_lab_study.py; the chain: test_lab_chain.py, test_lab_fastchain.py."""
import re

import numpy as np
import pandas as pd
import pytest
from lab_inputs import CAL, NOISE, SQP_RUNS, lab_study, pitch_frame

from conftest import _valid
from replication.study.lab import claims
from replication.study.lab.seed_sets import LAB_SETTING, found_setting
from replication.study.lab.study import seed_findings, seed_spread

#: Notebook 05's declared bounds of SQP's failure shares.
BOUNDS = {"failed": 0.1, "at limit": 0.75, "seeds": 0.5, "failed, 1000": 0.15, "failed, per pair": 0.05}


# --------------------------------------------------------------------- the records and their checks

def lab_claims_inputs():
    """The keyword arguments of :func:`lab_claims` (the notebook's calls above): synthetic seed
    studies (seeds 1-20 and fresh 21-40) and the committed draw's quantities."""
    frames = pd.DataFrame({"pitch mean": [-4.09, -1.58, 1.43, 0.2]},
                          index=pd.MultiIndex.from_tuples([("true R0", 0.0), ("true R0", 5.0), ("true R0", 10.0),
                                                           ("ours_right", 0.0)], names=["R0", "reference time (s)"]))
    table2 = pd.DataFrame({"correlation": [0.61, 0.93, 0.999, 0.4]},
                          index=pd.MultiIndex.from_tuples([("roll", "sensor_frame"), ("pitch", "sensor_frame"),
                                                           ("roll", "ours_right"), ("yaw", "sensor_frame")],
                                                          names=["angle", "method"]))
    return dict(
        study=lab_study(range(1, 21)), fresh=lab_study(range(21, 41)), poses=pd.Series([10, 14, 20], index=[1, 2, 3]),
        held=pd.Series([5.04, 6.0]), summary=pd.DataFrame({"spread_mean_deg": [1.234]}, index=["ours_right"]),
        ablation_table=pd.DataFrame({"spread_ours_right": [0.456]}, index=["without magnetic field deflection"]),
        sensitivity_table=pd.DataFrame({"rms_ours_right": [0.81, 1.5, 2.71]}), table2=table2,
        checks={"ours and SQP agree (largest RMS difference between methods, deg)": 0.012}, pitch_true=-4.09,
        frames=frames, bounds=BOUNDS, sqp_runs=SQP_RUNS,
        pitch_cal=(pitch_frame(range(900001, 900121)), pitch_frame(range(910001, 910121))))


def lab_claims(study, fresh, *, poses, held, summary, ablation_table, sensitivity_table, table2, checks, pitch_true,
               frames, bounds, sqp_runs, pitch_cal):
    """The lab's ten records as notebook 05 makes them, one call per claim with its numbers (in the
    notebook's cells: "The recordings", "The lab over 20 seeds", "The lab over fresh seeds" and the
    pitch-bias intervention), listed in the ledger's order."""
    records = [
        claims.lab_protocol(poses, held),
        claims.fig6_consistency(study, summary.loc["ours_right", "spread_mean_deg"],
                                ablation_table.loc["without magnetic field deflection", "spread_ours_right"]),
        claims.table2_rms(study, sensitivity_table["rms_ours_right"]),
        claims.fig7_projection(study, table2.xs("sensor_frame", level="method")["correlation"]),
        claims.lab_averaging(study, fresh), claims.fig6_accuracy(study, fresh), claims.table2_reduction(study, fresh),
        claims.table2_correlation(study, fresh),
        claims.table2_methods_agree(
            study, fresh, largest_rms_difference=checks["ours and SQP agree (largest RMS difference between methods, "
                                                        "deg)"], bounds=bounds, sqp_runs=sqp_runs),
        claims.table2_measures_calibration(study, fresh, pitch_true=pitch_true,
                                           true_r0_pitch=frames.loc["true R0", "pitch mean"], pitch_cal=pitch_cal),
    ]
    return sorted(records, key=lambda r: list(claims.SECTIONS).index(r["claim"]))


def test_lab_claims_name_both_seed_sets_and_the_fresh_section():
    records = {r["claim"]: r for r in lab_claims(**lab_claims_inputs())}
    for claim in ("lab_averaging", "fig6_accuracy", "table2_reduction", "table2_correlation", "table2_methods_agree",
                  "table2_measures_calibration"):
        assert records[claim]["section"] == "The lab over fresh seeds"
        assert "found on seeds 1-20, confirmed on fresh seeds 21-40" in records[claim]["setting"]
    assert records["lab_averaging"]["verdict"] == "fails"
    assert "between -0.005 and 0 deg on the first and between -0.005 and 0 deg on the fresh seeds (at most 0.5 % " \
        "and at most 0.5 % of the error" in records["lab_averaging"]["evidence"]
    assert "every sample the more accurate" in records["lab_averaging"]["evidence"]
    measures = records["table2_measures_calibration"]["evidence"]
    assert "above the truth's in 20 of 20 (84-100 %) on the first and 20 of 20 (84-100 %) on the fresh seeds" \
        in measures
    assert "does not replicate" in measures
    inputs = lab_claims_inputs()
    for which in ("study", "fresh"):          # the estimate now beats the truth in every seed of both sets
        inputs[which]["rms_ours_right"] = inputs[which]["rms_true_R0"] - 0.01
    measures = {r["claim"]: r for r in lab_claims(**inputs)}["table2_measures_calibration"]["evidence"]
    assert "smaller RMS is the same on both sets of seeds (the estimate in 20 of 20" in measures
    assert "bounds, not intervals" in records["table2_methods_agree"]["uncertainty"]
    assert "Wilson 95 %" in records["table2_correlation"]["uncertainty"]
    for claim in ("fig6_consistency", "fig7_projection"):
        assert records[claim]["section"] == "The lab over 20 seeds"


def _shift(column, which="fresh", seeds=None):
    """An edit of the inputs: add ``delta`` to ``column`` of the ``which`` study (all seeds, or the
    first ``seeds``), or set it (``seeds`` given with ``set_to``)."""
    def edit(inputs, delta):
        frame = inputs[which]
        rows = frame.index if seeds is None else frame.index[:seeds]
        frame.loc[rows, column] = frame.loc[rows, column] + delta
    return edit


def _critical(inputs, which, key, *, scale_key=None, factor=0.0, sign=1.0, absolute=False):
    """The shift of a finding's value at which ``value + sign * 2 se`` meets ``factor * <scale_key's
    value>``."""
    f = seed_findings(inputs[which])
    target = factor * f.loc[scale_key, "value"] if scale_key else 0.0
    if absolute:
        return target - f.loc[key, "value"]
    return target - f.loc[key, "value"] - sign * 2 * f.loc[key, "se"]


# (claim, column shifted, finding, critical-shift options, a larger shift breaks the check?)
MEAN_CHECKS = [
    ("lab_averaging", "true_single_ours_right", "single_minus_mean", dict(sign=-1.0), False),
    ("fig6_accuracy", "shared_bias_ours_right" + CAL, "shared_bias_change" + CAL, {}, True),
    ("fig6_accuracy", "shared_bias_ours_right" + NOISE, "shared_bias_change" + NOISE,
     dict(scale_key="shared_bias", factor=0.1, absolute=True), True),
    ("table2_measures_calibration", "pitch_bias_true_R0" + NOISE, "abs_pitch_bias_change" + NOISE, {}, True),
]


@pytest.mark.parametrize("which", ["study", "fresh"])
@pytest.mark.parametrize("claim, column, key, options, larger_breaks", MEAN_CHECKS)
def test_each_mean_check_raises_just_past_its_threshold(which, claim, column, key, options, larger_breaks):
    critical = _critical(lab_claims_inputs(), which, key, **options)
    for eps, raises in ((-1e-9, not larger_breaks), (1e-9, larger_breaks)):
        inputs = lab_claims_inputs()
        _shift(column, which)(inputs, critical + eps)
        if raises:
            with pytest.raises(ValueError, match=f"claim '{claim}'.*the evidence does not bear the verdict"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10


@pytest.mark.parametrize("which", ["study", "fresh"])
def test_table2_blindness_check_raises_just_past_its_threshold(which):
    f = seed_findings(lab_claims_inputs()[which])
    blind = abs(f.loc["rms_estimate_minus_truth", "value"]) + 2 * f.loc["rms_estimate_minus_truth", "se"]
    critical = blind - f.loc["rms_turned_2_minus_truth", "value"] + 2 * f.loc["rms_turned_2_minus_truth", "se"]
    for eps, raises in ((1e-9, False), (-1e-9, True)):
        inputs = lab_claims_inputs()
        _shift("rms_turned_2", which)(inputs, critical + eps)
        if raises:
            with pytest.raises(ValueError, match="claim 'table2_measures_calibration'.*moved less by the estimate"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10


# (claim, column, value that breaks the count in a seed (or its function of the frame), what the
# error names): a Wilson interval of k of 20 lies above one half from k = 15 on, so 5 seeds turned
# against the finding pass, 6 not
COUNT_CHECKS = [
    ("table2_reduction", "rms_sensor_frame", 0.0, "calibrated RMS below the sensor frame's"),
    ("fig6_accuracy", "spread_ours_right", 100.0, "error of the mean of the 10 estimates above"),
    ("table2_measures_calibration", "rms_reversed_ours_right", 0.0, "reversed gives a larger RMS"),
    ("table2_measures_calibration", "rms_turned_2", lambda f: f["rms_true_R0"] - 1e-3,
     "turned by 2 deg gives a larger RMS"),
]


@pytest.mark.parametrize("which", ["study", "fresh"])
@pytest.mark.parametrize("claim, column, broken, named", COUNT_CHECKS)
def test_each_count_check_raises_just_past_its_threshold(which, claim, column, broken, named):
    for seeds, raises in ((5, False), (6, True)):
        inputs = lab_claims_inputs()
        frame = inputs[which]
        value = broken(frame) if callable(broken) else pd.Series(broken, index=frame.index)
        frame.loc[frame.index[-seeds:], column] = value[frame.index[-seeds:]]   # the last seeds; the rest keep theirs
        if raises:
            with pytest.raises(ValueError, match=f"claim '{claim}'.*{named}"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10


@pytest.mark.parametrize("which", ["study", "fresh"])
@pytest.mark.parametrize("column, inside, outside", [
    ("corr_pitch_ours_right", 0.95001, 0.95),   # every correlation above 0.95
    ("corr_roll_ours_right", 0.9989, 0.999),    # the paper's 0.999 reached for roll in no seed
])
def test_each_correlation_check_raises_just_past_its_threshold(which, column, inside, outside):
    for value, raises in ((inside, False), (outside, True)):
        inputs = lab_claims_inputs()
        inputs[which].loc[inputs[which].index[7], column] = value
        if raises:
            with pytest.raises(ValueError, match="claim 'table2_correlation'.*the evidence does not bear the verdict"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10


def _per_seed(*counts):
    """20 per-seed counts: the given ones first, zeros after."""
    return np.array(list(counts) + [0] * (20 - len(counts)), dtype=float)


# SQP's failure counts (columns of the 20 seeds) just inside and just outside one bound's margin of
# 2 data sets (seeds, failed sets), the others kept
SQP_CASES = {
    "more than 10 % of the 200 data sets fail with 100 iterations, by 2: 22 of 200, not 21": (
        {"failed_sqp_100 iterations": _per_seed(2, 2, *[1] * 18),
         "limit_sqp_100 iterations": _per_seed(2, 2, *[1] * 18)},
        {"failed_sqp_100 iterations": _per_seed(2, *[1] * 19), "limit_sqp_100 iterations": _per_seed(2, *[1] * 19)}),
    "more than 75 % of those at the limit, by 2 of 36: 29 of 36, not 28": (
        {"limit_sqp_100 iterations": _per_seed(*[2] * 11, *[1] * 7)},
        {"limit_sqp_100 iterations": _per_seed(*[2] * 10, *[1] * 8)}),
    "in more than half the seeds, by 2: 12 seeds, not 11": (
        {"failed_sqp_100 iterations": _per_seed(*[2] * 12), "limit_sqp_100 iterations": _per_seed(*[2] * 12)},
        {"failed_sqp_100 iterations": _per_seed(*[2] * 11), "limit_sqp_100 iterations": _per_seed(*[2] * 11)}),
    "1000 iterations: fewer than 15 %, by 2: 28 of 200, not 29": (
        {"failed_sqp_1000 iterations": _per_seed(*[2] * 14)}, {"failed_sqp_1000 iterations": _per_seed(*[2] * 14, 1)}),
    "the objective / 2J: fewer than 5 %, by 2: 8 of 200, not 9": (
        {"failed_sqp_cost (8) / 2J": _per_seed(*[1] * 8)}, {"failed_sqp_cost (8) / 2J": _per_seed(*[1] * 9)}),
}


@pytest.mark.parametrize("which", ["study", "fresh"])
@pytest.mark.parametrize("case", list(SQP_CASES))
def test_each_sqp_bound_raises_just_past_it(which, case):
    for columns, raises in zip(SQP_CASES[case], (False, True)):
        inputs = lab_claims_inputs()
        for column, counts in columns.items():
            inputs[which][column] = counts
        if raises:
            with pytest.raises(ValueError, match="table2_methods_agree.*inside its declared bound"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10


# ------------------------------------------------------------- the calibration errors' share of the
# pitch bias: resolved to 0.1 deg, many seeds, the words follow the intervals

@pytest.mark.parametrize("which", [0, 1])
@pytest.mark.parametrize("frame, ok, words", [
    ({"half_width": 0.1 - 1e-6}, True, ""),           # the share resolved to a tenth of a degree, just inside
    ({"half_width": 0.1 + 1e-6}, False, "resolved to [+]-0.1 deg"),
    ({"mean": -0.25 * 1.9 + 1e-6}, True, ""),         # the share below a quarter of |pitch bias|, just inside
    ({"mean": -0.25 * 1.9 - 1e-6}, False, "less than a quarter"),
])
def test_the_pitch_share_must_be_resolved_and_stay_below_a_quarter(which, frame, ok, words):
    inputs = lab_claims_inputs()
    frames = list(inputs["pitch_cal"])
    frames[which] = pitch_frame(frames[which].index, **frame)
    inputs["pitch_cal"] = tuple(frames)
    if ok:
        assert len(lab_claims(**inputs)) == 10
    else:
        with pytest.raises(ValueError, match=f"claim 'table2_measures_calibration'.*{words}"):
            lab_claims(**inputs)


@pytest.mark.parametrize("means, words", [
    ((0.02, -0.03), "resolved from 0 on neither set, and no share larger than 0.08 deg on either; the noise is the"),
    ((0.049, -0.049), "resolved from 0 on neither set"),
    ((0.051, -0.03), "resolved from 0 on the first set only, its share not the same on both (at most 0.10 deg)"),
    ((0.02, -0.051), "resolved from 0 on the fresh set only"),
    ((-0.2, -0.15), "a small share, resolved on both sets (a fall, at most 0.25 deg)"),
    ((0.2, 0.15), "a small share, resolved on both sets (a rise"),
    ((-0.2, 0.15), "resolved with opposite signs on the two sets: it does not replicate"),
])
def test_the_pitch_share_in_words_follows_the_intervals(means, words):
    inputs = lab_claims_inputs()
    inputs["pitch_cal"] = tuple(pitch_frame(f.index, mean=m, half_width=0.05)
                                for f, m in zip(inputs["pitch_cal"], means))
    measures = {r["claim"]: r for r in lab_claims(**inputs)}["table2_measures_calibration"]
    assert words in measures["evidence"]
    assert "seeds 900001-900120, confirmed on fresh seeds 910001-910120" in measures["setting"]


# --------------------------------------------------------------------------------------------------
# Claims where their evidence is: one small function per claim, taking only its numbers, called


def test_the_lab_claims_on_the_first_seeds_need_no_fresh_ones():
    study = lab_study(range(1, 21))
    rec = claims.table2_rms(study, lab_study(range(1, 4))["rms_ours_right"])
    assert rec["setting"] == found_setting(study) == f"{LAB_SETTING}; seeds 1-20 (and the committed draw, seed " \
                                                     "20130501)"
    assert rec["section"] == "Sensitivity to the magnetometer noise" and "(20 seeds)" in rec["evidence"]


def test_a_lab_claim_names_the_fresh_set_where_its_check_fails():
    fresh = lab_study(range(21, 41))
    fresh.loc[fresh.index[-6:], "rms_sensor_frame"] = 0.0   # calibration no longer reduces the RMS in 6 of 20
    with pytest.raises(ValueError, match=r"claim 'table2_reduction'.*most seeds of fresh seeds 21-40"):
        claims.table2_reduction(lab_study(range(1, 21)), fresh)
    fresh.loc[fresh.index[-6], "rms_sensor_frame"] = 24.0   # 5 of 20: still most
    assert claims.table2_reduction(lab_study(range(1, 21)), fresh)["verdict"] == "holds"


@pytest.mark.parametrize("fresh_seeds, shared", [(range(21, 41), None), (range(20, 40), "20"),
                                                 (range(1, 21), "1, 2, 3, 4, 5 ...")])
def test_the_fresh_seeds_of_a_lab_claim_must_be_disjoint_from_the_first(fresh_seeds, shared):
    study, fresh = lab_study(range(1, 21)), lab_study(fresh_seeds)
    if shared is None:
        assert claims.fig6_accuracy(study, fresh)["verdict"] == "holds only if"
    else:
        with pytest.raises(ValueError, match=rf"the seed study.*fresh seeds repeat .*\({re.escape(shared)}\)"
                                             ".*confirmed only on seeds disjoint"):
            claims.fig6_accuracy(study, fresh)


def test_the_pitch_intervention_is_confirmed_on_disjoint_seeds():
    inputs = lab_claims_inputs()
    kw = dict(pitch_true=-4.09, true_r0_pitch=inputs["frames"].loc["true R0", "pitch mean"])
    first, again = inputs["pitch_cal"]
    assert claims.table2_measures_calibration(inputs["study"], inputs["fresh"], pitch_cal=(first, again), **kw)
    with pytest.raises(ValueError, match="pitch-bias intervention.*fresh seeds repeat 120 of"):
        claims.table2_measures_calibration(inputs["study"], inputs["fresh"], pitch_cal=(first, first), **kw)


LAB_IDS = ["lab_protocol", "lab_averaging", "fig6_consistency", "fig6_accuracy", "table2_reduction",
           "table2_correlation", "table2_methods_agree", "table2_measures_calibration", "table2_rms", "fig7_projection"]


# ---- notebook 05
# ---------------------------------------------------------------------------------------------

def _lab_inputs():
    """Synthetic seed studies (seeds 1-20, fresh 21-40) and committed-draw quantities passing every
    check."""
    return lab_claims_inputs()


def test_lab_claims_ids_verdicts_and_numbers():
    inputs = _lab_inputs()
    records = lab_claims(**inputs)
    assert [r["claim"] for r in records] == LAB_IDS
    assert [r["verdict"] for r in records] == [
        "undecidable from the text", "fails", "undecidable from the text", "holds only if", "holds",
        "undecidable from the text", "holds only if", "fails", "undecidable from the text", "holds"]
    _valid(records)
    rec = {r["claim"]: r for r in records}
    study, fresh = inputs["study"], inputs["fresh"]
    spread = seed_spread(study["spread_ours_right"])
    assert "(3 data sets of 10-20 orientations, each held 5.0 s or more" in rec["lab_protocol"]["evidence"]
    assert rec["lab_protocol"]["setting"].endswith("documented); the committed recordings")
    assert "is 2.40 and 2.40 deg with the means" in rec["lab_averaging"]["evidence"]
    assert "grows by 0.35 ± 0.02 deg on the first and 0.35 ± 0.02 deg on the fresh seeds" \
        in rec["lab_averaging"]["evidence"]
    assert (f"lie on average {spread} deg from their mean (20 seeds; committed draw 1.23 deg, 0.46 deg without"
            in rec["fig6_consistency"]["evidence"])
    accuracy = rec["fig6_accuracy"]["evidence"]
    assert f"is {seed_spread(study['shared_bias_ours_right'])} deg from the true R0 on the first seeds" in accuracy
    assert "falls from 2.05 ± 0.03 to 0.70 ± 0.01 deg on the first seeds" in accuracy
    assert "(paired changes -1.350 ± 0.028 and -1.350 ± 0.028 deg)" in accuracy
    sensor_frame = seed_spread(fresh["rms_sensor_frame"])
    assert f"vs {sensor_frame} deg on the fresh ones" in rec["table2_reduction"]["evidence"]
    corr = rec["table2_correlation"]["evidence"]
    assert f"roll {seed_spread(study['corr_roll_ours_right'], 4)}; pitch" in corr
    assert "reached for roll in 0 of 20 (0-16 %) on the first and 0 of 20 (0-16 %) on the fresh seeds" in corr
    assert ("stops short (> 10 deg off) on more than 10% of the 200 data sets (more than 75% of them at the iteration "
            "limit), in more than 50% of the 20 seeds; with 1000 iterations on fewer than 15%, with its objective "
            "divided by 2J on fewer than 5%") in rec["table2_methods_agree"]["condition"]
    assert "differ by at most 0.012 deg" in rec["table2_methods_agree"]["evidence"]
    measures = rec["table2_measures_calibration"]["evidence"]
    assert "(its chordal mean, 2.05 and 2.05 deg off the true R0 on average)" in measures
    assert "differs from the truth's by -0.010 ± 0.002 deg on the first" in measures
    assert "smaller RMS does not replicate (the estimate in 10 of 20 (30-70 %) on the first" in measures
    assert "5 deg: 20 of 20 (84-100 %) on the first and 20 of 20 (84-100 %) on the fresh seeds; 10 deg:" in measures
    assert "it is -4.09 deg on the committed draw and changes sign as the reference frame moves (-4.09 to 1.43 deg)" \
        in measures
    assert "(0.81 deg at 0 to 2.71 deg at 1.4 uT)" in rec["table2_rms"]["evidence"]
    assert "sensor-frame correlations 0.40 to 0.93, committed draw)" in rec["fig7_projection"]["evidence"]
    assert rec["fig7_projection"]["setting"] == (
        "simulated lab (LabSettings defaults: datasheet noise, residual calibration errors as documented); seeds "
        "1-20 (and the committed draw, seed 20130501)")
    assert rec["table2_measures_calibration"]["setting"].startswith(
        "simulated lab (LabSettings defaults: datasheet noise, residual calibration errors as documented); found on "
        "seeds 1-20, confirmed on fresh seeds 21-40 (and the committed draw, seed 20130501)")


@pytest.mark.parametrize("column, inside, outside", [
    ("corr_pitch_ours_right", 0.95001, 0.95),  # every correlation above 0.95
    ("corr_roll_ours_right", 0.9989, 0.999),   # the paper's 0.999 reached for roll in no seed
])
def test_each_lab_check_raises_just_past_its_threshold(column, inside, outside):
    for value, raises in ((inside, False), (outside, True)):
        inputs = _lab_inputs()
        inputs["study"].loc[7, column] = value
        if raises:
            with pytest.raises(ValueError, match="claim 'table2_correlation': the evidence does not bear the verdict"):
                lab_claims(**inputs)
        else:
            assert len(lab_claims(**inputs)) == 10
