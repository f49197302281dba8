"""The lab's studies (``replication.study.lab.study``): summarize's counts and averages, the
ablation's cases, the sensitivity's field, a seed study's spread in words, the seed study with every
sample and with error sources switched off (the same numbers as the slow chain), the findings with
their Wilson intervals and standard errors and the declared bound of the all-sample change, SQP's
failure shares, and the pitch-bias intervention (the seed study's numbers, its mean and
interval)."""
import dataclasses

import numpy as np
import pandas as pd
import pytest
from lab_inputs import CAL, NOISE, SQP_RUNS, lab_study, pitch_frame

from conftest import SMALL_LAB
from replication.core.stats import wilson_interval
from replication.study import lab
from replication.study.lab.study import (
    ablation,
    count_text,
    intervention_finding,
    pitch_bias_intervention,
    seed_findings,
    seed_range,
    seed_spread,
    seed_study,
    sensitivity,
    sqp_shares,
    summarize,
)

SMALL = dataclasses.replace(lab.LabSettings(), n_sets=2, poses_per_set=(5, 5), dynamic_seconds=6.0)


# ------------------------------------------------------------------------------------------------
# the lab's studies

def _hand_built_result():
    per_set = pd.DataFrame({
        "set": [0, 1, 2, 0, 1, 2],
        "method": ["a"] * 3 + ["b"] * 3,
        "true_error_deg": [1.0, 2.0, 30.0, 0.5, 0.5, 0.5],
        "from_mean_deg": [0.1, 0.2, 0.3, 0.0, 0.0, 0.0],
        "warnings": ["", "", "LocalMinimumWarning", "", "", ""],
    })
    index = pd.MultiIndex.from_product([["roll", "pitch", "yaw"], ["a", "b", "sensor_frame"]],
                                       names=["angle", "method"])
    table2 = pd.DataFrame({"rms_deg": [1.0, 2.0, 9.0, 3.0, 2.0, 9.0, 2.0, 2.0, 9.0]}, index=index)
    return lab.LabResult(estimates={"a": None, "b": None}, r0={}, per_set=per_set, traces=pd.DataFrame(),
                         table2=table2, truth=np.eye(3))


def test_summarize_counts_failures_warnings_and_averages():
    row = summarize(_hand_built_result(), failure_deg=10.0)
    assert row["true_a"] == pytest.approx(11.0) and row["true_clean_a"] == pytest.approx(1.5)
    assert row["failed_a"] == 1 and row["warned_a"] == 1 and row["failed_b"] == 0 and row["warned_b"] == 0
    assert row["spread_a"] == pytest.approx(0.2)
    assert row["rms_a"] == pytest.approx(2.0) and row["rms_b"] == pytest.approx(2.0) and row["rms_sensor_frame"] == 9.0


def test_ablation_runs_every_case_and_switches_sources_off():
    pair = ["pixel noise", "magnetometer errors"]
    out = ablation(SMALL, sources=pair, solvers={"ours_right": lab.TABLE2_SOLVERS["ours_right"]})
    assert list(out.index) == ["all sources", "without pixel noise", "without magnetometer errors",
                               "only pixel noise", "only magnetometer errors", "no sources"]
    # with two sources, "only one" is "without the other": the same draws, the same numbers
    pd.testing.assert_series_equal(out.loc["only pixel noise"], out.loc["without magnetometer errors"],
                                   check_names=False)
    pd.testing.assert_series_equal(out.loc["only magnetometer errors"], out.loc["without pixel noise"],
                                   check_names=False)
    assert out.loc["no sources", "true_ours_right"] != out.loc["all sources", "true_ours_right"]


def test_seed_spread_gives_mean_sd_and_range():
    assert seed_spread(pd.Series([1.0, 2.0, 3.0])) == "2.00 (SD 1.00; 1.00-3.00)"
    assert seed_spread(pd.Series([0.5, 0.25]), digits=4) == "0.3750 (SD 0.1768; 0.2500-0.5000)"


def test_seed_study_with_every_sample_and_parts_switched_off():
    study = seed_study([1], SMALL_LAB, all_samples=True, without=list(lab.PARTS))
    for col in ("true_all_ours_right", "shared_bias_ours_right" + NOISE, "pitch_bias_true_R0" + CAL,
                "rms_true_R0" + NOISE, "true_ours_right" + CAL, "rms_ours_right" + CAL):
        assert col in study.columns, col
    assert study["true_all_ours_right"].iloc[0] > 0
    # the same seed with the ahrs filter and OpenCV's PnP frame by frame: the same numbers
    slow = seed_study([1], SMALL_LAB, fast=False)
    assert np.abs((slow - study[slow.columns]).to_numpy()).max() < 1e-6
    # the camera is reused only where switching a source off leaves the pixels as they were
    with pytest.raises(ValueError, match="changed the marker pixels"):
        seed_study([1], SMALL_LAB, without=["pixel noise"])



def test_count_text_and_seed_range():
    low, high = wilson_interval(15, 20)
    assert count_text(15, 20) == f"15 of 20 ({100 * low:.0f}-{100 * high:.0f} %)" == "15 of 20 (53-89 %)"
    assert count_text(0, 20) == "0 of 20 (0-16 %)"
    assert seed_range(pd.DataFrame(index=range(21, 41))) == "seeds 21-40"
    with pytest.raises(ValueError, match="consecutive"):
        seed_range(pd.DataFrame(index=[1, 2, 4]))



def test_seed_findings_counts_with_wilson_intervals_and_means_with_standard_errors():
    study = lab_study(range(1, 21))
    f = seed_findings(study)
    row = f.loc["reversed_loses"]
    assert (row["kind"], row["value"], row["n"], row["text"]) == ("count", 20, 20, "20 of 20 (84-100 %)")
    assert (row["low"], row["high"]) == pytest.approx(wilson_interval(20, 20))
    diff = study["true_all_ours_right"] - study["true_ours_right"]
    row = f.loc["all_minus_mean"]
    assert row["kind"] == "mean" and row["value"] == pytest.approx(diff.mean())
    assert row["se"] == pytest.approx(diff.std(ddof=1) / np.sqrt(20))
    assert row["text"] == "-0.005 to 0"  # a bound declared in advance: the change moves between machines
    change = study["pitch_bias_true_R0" + NOISE].abs() - study["pitch_bias_true_R0"].abs()
    assert f.loc["abs_pitch_bias_change" + NOISE, "value"] == pytest.approx(change.mean())
    assert f.loc["shared_ratio_median", "value"] == pytest.approx(
        (study["shared_bias_ours_right"] / (1.5 / np.sqrt(10))).median())
    assert {"turned_2_loses", "turned_5_loses", "turned_10_loses", "single_minus_mean",
            "estimate_beats_truth" + CAL, "corr_yaw_at_paper"} <= set(f.index)
    assert "all_minus_mean" not in seed_findings(study.drop(columns="true_all_ours_right")).index



def test_sqp_shares():
    shares = sqp_shares(lab_study(range(1, 21)), SQP_RUNS)
    counts = shares.pop("counts")
    assert shares == pytest.approx({"failed, 100 iterations": 36 / 200, "failed, 1000 iterations": 8 / 200,
                                    "failed, cost (8) / 2J": 0.0, "at limit": 1.0, "seeds": 0.9})
    assert counts == {"data sets": 200, "failed": 36, "seeds": 20}



@pytest.mark.parametrize("mean_change, ok", [(-0.0008, True), (-0.0042, True), (-0.0007, False), (-0.0043, False)])
def test_the_change_with_every_sample_is_a_declared_bound_kept_by_its_margin(mean_change, ok):
    study = lab_study(range(1, 21))
    study["true_all_ours_right"] = study["true_ours_right"] + mean_change
    if ok:
        assert seed_findings(study).loc["all_minus_mean", "text"] == "-0.005 to 0"
    else:
        with pytest.raises(ValueError, match="every sample of each orientation.*inside its declared bound"):
            seed_findings(study)



def test_pitch_bias_intervention_is_the_seed_studys():
    part = "magnetometer calibration errors"
    fast = pitch_bias_intervention([3], part)
    full = seed_study([3], without=[part])
    assert fast.loc[3, "pitch_bias"] == pytest.approx(full.loc[3, "pitch_bias_true_R0"], abs=1e-12)
    assert fast.loc[3, "pitch_bias_without"] == pytest.approx(full.loc[3, "pitch_bias_true_R0" + CAL], abs=1e-12)
    with pytest.raises(ValueError, match="unknown error source or part 'magnetometer'"):
        pitch_bias_intervention([3], "magnetometer")



def test_intervention_finding_mean_se_and_interval():
    f = intervention_finding(pitch_frame(range(1, 121), mean=-0.2, half_width=0.07))
    assert f["value"] == pytest.approx(-0.2) and 1.96 * f["se"] == pytest.approx(0.07)
    assert (f["low"], f["high"]) == pytest.approx((-0.27, -0.13)) and f["resolved"] and f["fine"]
    assert f["n"] == 120 and f["abs_pitch_bias"] == pytest.approx(1.9)
    assert f["text"] == "-0.200 ± 0.036 [-0.270, -0.130]"


def test_sensitivity_names_its_field():
    with pytest.raises(ValueError, match="not a LabSettings field"):
        sensitivity("gremlins", [0])


def test_seed_study_rows_and_interventions():
    study = seed_study([1, 2], SMALL, sqp_runs={"3": {"max_iterations": 3}, "100": {}}, turned_deg=(10.0,),
                       single_sample=True)
    assert list(study.index) == [1, 2]
    for col in ("shared_bias_ours_right", "true_ours_right", "spread_optimization", "failed_ours_left", "rms_true_R0",
                "pitch_bias_true_R0", "corr_roll_ours_right", "rms_turned_10", "failed_sqp_3", "limit_sqp_3",
                "failed_sqp_100", "limit_sqp_100", "true_single_ours_right", "rms_reversed_ours_right"):
        assert col in study.columns, col
    assert (study["rms_turned_10"] > study["rms_true_R0"]).all()       # a 10 deg error is visible in Table II
    assert (study["limit_sqp_3"] <= study["failed_sqp_3"]).all() and study["limit_sqp_3"].sum() >= 1
    assert study["failed_sqp_3"].sum() >= study["failed_sqp_100"].sum()
    assert (study["failed_sqp_100"] == study["failed_optimization"]).all()  # run_lab's SQP is the 100-iteration one
    assert (study["true_single_ours_right"] > 0).all()
    assert (study["rms_reversed_ours_right"] != study["rms_ours_right"]).all()
