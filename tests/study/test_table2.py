"""What Table II measures (replication.study.table2): re-projection with any R0 and reference frame,
attitude statistics, and Table II beside the paper's. The seed study: test_lab_study.py; the
single-sample protocol of the chain's static motions: test_lab_chain.py."""
import dataclasses

import numpy as np
import pytest

from replication.core import so3
from replication.core.so3 import matrix_from_rotation_vector
from replication.study import lab
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
