"""The lab's studies (replication.study.lab.study) on small inputs: summarize's counts and
averages, the ablation's cases, and a seed study's spread in words."""
import dataclasses

import numpy as np
import pandas as pd
import pytest

from replication.study import lab
from replication.study.lab.study import seed_spread

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
    row = lab.summarize(_hand_built_result(), failure_deg=10.0)
    assert row["true_a"] == pytest.approx(11.0) and row["true_clean_a"] == pytest.approx(1.5)
    assert row["failed_a"] == 1 and row["warned_a"] == 1 and row["failed_b"] == 0 and row["warned_b"] == 0
    assert row["spread_a"] == pytest.approx(0.2)
    assert row["rms_a"] == pytest.approx(2.0) and row["rms_b"] == pytest.approx(2.0) and row["rms_sensor_frame"] == 9.0


def test_ablation_runs_every_case_and_switches_sources_off():
    pair = ["pixel noise", "magnetometer errors"]
    out = lab.ablation(SMALL, sources=pair, solvers={"ours_right": lab.TABLE2_SOLVERS["ours_right"]})
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
