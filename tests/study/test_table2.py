"""What Table II measures (replication.study.table2): re-projection with any R0 and reference frame,
the seed study and its interventions, the single-sample protocol of lab.static_motions, and Table
II beside the paper's."""
import dataclasses

import numpy as np
import pytest

from replication.core import so3
from replication.core.so3 import matrix_from_rotation_vector
from replication.study import lab
from replication.study.lab import seed_study
from replication.study.paper import TABLE2_ANGLES, TABLE2_METHODS
from replication.study.table2 import (
    attitude_statistics,
    projection_statistics,
    reference_frame_dependence,
    table2_versus_paper,
)

SMALL = dataclasses.replace(lab.LabSettings(), n_sets=2, poses_per_set=(5, 5), dynamic_seconds=6.0)


@pytest.fixture(scope="module")
def small_result():
    return lab.run_lab(lab.simulate_lab(SMALL))


def test_projection_with_the_used_r0_reproduces_table2(small_result):
    for method in ("ours_right", "optimization"):
        again = projection_statistics(small_result, small_result.r0[method])
        ref = small_result.table2.xs(method, level="method")
        assert np.allclose(again[["rms_deg", "mean_deg", "sd_deg"]], ref[["rms_deg", "mean_deg", "sd_deg"]], atol=1e-9)


def test_a_wrong_r0_shows_in_table2_and_bad_input_is_refused(small_result):
    true = projection_statistics(small_result, small_result.truth)["rms_deg"].mean()
    off = projection_statistics(small_result, small_result.truth @ matrix_from_rotation_vector(np.radians([0.0, 20.0,
                                                                                                           0.0])))
    assert off["rms_deg"].mean() > true + 1.0
    with pytest.raises(ValueError, match="reference_time"):
        projection_statistics(small_result, small_result.truth, reference_time=1e3)
    with pytest.raises(ValueError, match="R0"):
        projection_statistics(small_result, np.eye(3) * 2)


def test_reference_frame_dependence_has_one_row_per_r0_and_time(small_result):
    out = reference_frame_dependence(small_result, {"true": small_result.truth, "est": small_result.r0["ours_right"]},
                                     [0, 2, 4])
    assert out.shape == (6, 6) and list(out.index.get_level_values(1)[:3]) == [0.0, 2.0, 4.0]
    assert np.isclose(out.loc[("true", 0.0), "pitch mean"],
                      projection_statistics(small_result, small_result.truth).loc["pitch", "mean_deg"])


def test_single_sample_protocol_equals_the_mean_without_noise_and_is_validated():
    rec = lab.simulate_lab(dataclasses.replace(lab.LabSettings().exact(), n_sets=2, poses_per_set=(4, 4),
                                               dynamic_seconds=4.0))
    mean, single = lab.static_motions(rec), lab.static_motions(rec, sample="single")
    for k in mean:
        assert np.abs(mean[k][0] - single[k][0]).max() < 1e-12 and np.abs(mean[k][1] - single[k][1]).max() < 1e-12
    noisy = lab.simulate_lab(SMALL)
    assert np.abs(lab.static_motions(noisy)[0][1] - lab.static_motions(noisy, sample="single")[0][1]).max() > 1e-5
    with pytest.raises(ValueError, match="sample"):
        lab.static_motions(rec, sample="median")


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


def test_parts_of_a_source_switch_off_separately():
    s = lab.LabSettings()
    noise_off, cal_off = s.without("magnetometer noise"), s.without("magnetometer calibration errors")
    assert noise_off.mag_noise_ut == 0 and noise_off.mag_hard_iron_ut == s.mag_hard_iron_ut
    assert cal_off.mag_noise_ut == s.mag_noise_ut and cal_off.mag_soft_iron == 0 and cal_off.mag_misalignment_deg == 0
    with pytest.raises(ValueError, match="unknown error source"):
        s.without("magnetometer")


def test_attitude_statistics_wraps_and_adds_up():
    ref = np.array([[179.0, 0, 0], [0, 10, 0], [-90, 20, 5], [45, 30, 10]])
    est = ref + np.array([[2.0, 1, 0], [-1, 1, 0], [0, 1, 0], [1, 1, 0]])
    est[0, 0] = -179.0  # 179 -> -179 is a +2 deg difference, not -358
    s = attitude_statistics(est, ref)
    np.testing.assert_allclose(s.loc["roll", ["mean_deg", "rms_deg"]], [0.5, np.sqrt(1.5)])
    np.testing.assert_allclose(s["rms_deg"] ** 2, s["mean_deg"] ** 2 + s["sd_deg"] ** 2)
    assert s.loc["pitch", "sd_deg"] == 0 and s.loc["yaw", "correlation"] == pytest.approx(1.0)


def test_table2_versus_paper_sits_beside_the_paper_in_its_order():
    result = lab.run_lab(lab.simulate_lab(SMALL))
    out = table2_versus_paper(result)
    assert list(out.index) == [(a, m) for a in TABLE2_ANGLES for m in TABLE2_METHODS]
    assert {"paper_rms_deg", "ours_rms_deg", "true_r0_error_deg"} <= set(out.columns)
    np.testing.assert_allclose(out.xs("sensor_frame", level="method")["true_r0_error_deg"],
                               float(so3.rotation_angle_deg(result.truth)))
    np.testing.assert_allclose(out.loc[("pitch", "ours_right"), "ours_rms_deg"],
                               result.table2.loc[("pitch", "ours_right"), "rms_deg"])
