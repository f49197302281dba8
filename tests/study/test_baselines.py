"""The study layer on small inputs: the one solver loop (baselines.compare, sweep), the lab's
studies (summarize, ablation, sensitivity), Table II beside the paper's, and the studies of the real
recordings (real_study) on a synthetic rig whose R0 is known."""
import dataclasses

import numpy as np
import pandas as pd
import pytest

from replication.core import so3
from replication.core.solvers import ObservabilityWarning
from replication.rig.streams import OrientationStream
from replication.study import lab
from replication.study.baselines import compare, sweep
from replication.study.paper import TABLE2_ANGLES, TABLE2_METHODS
from replication.study.real_study import (
    calibration_table,
    calibrations,
    protocol_table,
    sensitivity_table,
    solver_tables,
)
from replication.study.simulation import simulate
from replication.study.table2 import table2_versus_paper

SMALL = dataclasses.replace(lab.LabSettings(), n_sets=2, poses_per_set=(5, 5), dynamic_seconds=6.0)


# ------------------------------------------------------------------------------------------------
# the solver loop

def test_compare_rows_errors_and_ratio_on_noise_free_problems():
    sim = simulate(3, 4, noise_camera=0.0, noise_sensor=0.0)
    table = compare(sim.A, sim.B, sim.R0, methods=["two_step_right", "park_martin"], ratio_to="park_martin",
                    rng=np.random.default_rng(0))
    assert list(table.index) == ["two_step_right", "park_martin"]
    assert (table["max_deg"] < 1e-9).all() and (table["failures"] == 0).all()  # measured 1.1e-11 (two-step)
    assert (table["n_pairs"] == sim.A.shape[-3]).all()
    assert table.loc["park_martin", "ratio"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match="ratio_to must be one of the methods"):
        compare(sim.A, sim.B, sim.R0, methods=["park_martin"], ratio_to="park_martin")


def test_compare_takes_one_problem_other_pairs_per_method_and_ignores_named_warnings(problem, rng):
    R0, A, B = problem
    # other pairs for park_martin: those of another R0, so its error shows that they were used
    R1 = so3.random_rotations(rng, ())
    other = (A[:5], R1.T @ A[:5] @ R1)
    table = compare(A, B, R0, methods=["chordal_optimal", "park_martin"], pairs_for={"park": other})
    assert table.loc["chordal_optimal", "mean_deg"] < 1e-10 and table.loc["chordal_optimal", "n_pairs"] == 20  # 3e-14
    assert table.loc["park_martin", "mean_deg"] == pytest.approx(float(so3.angle_between_deg(R1, R0)), abs=1e-9)
    assert table.loc["park_martin", "n_pairs"] == 5
    # nearly single-axis motions: the data set's ObservabilityWarning is listed unless ignored
    axis = np.array([1.0, 0.0, 0.0]) + 1e-4 * rng.normal(size=(8, 3))
    A1 = so3.matrix_from_rotation_vector(axis * np.linspace(0.2, 1.0, 8)[:, None])
    B1 = R0.T @ A1 @ R0
    assert "ObservabilityWarning" in compare(A1, B1, R0, methods=["chordal_optimal"])["warnings"].iloc[0]
    quiet = compare(A1, B1, R0, methods=["chordal_optimal"], ignore_warnings=(ObservabilityWarning,))
    assert "ObservabilityWarning" not in quiet["warnings"].iloc[0]


def test_sweep_is_compare_at_each_value():
    out = sweep("noise_deg", [0.5, 2.0], n_runs=3, seed=11, methods=["chordal_optimal", "two_step_left"])
    assert len(out) == 4 and set(out["value"]) == {0.5, 2.0} and (out["parameter"] == "noise_deg").all()
    by_value = out.pivot(index="method", columns="value", values="mean_deg")
    assert (by_value[2.0] > by_value[0.5]).all()  # more noise, larger error


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


def test_table2_versus_paper_sits_beside_the_paper_in_its_order():
    result = lab.run_lab(lab.simulate_lab(SMALL))
    out = table2_versus_paper(result)
    assert list(out.index) == [(a, m) for a in TABLE2_ANGLES for m in TABLE2_METHODS]
    assert {"paper_rms_deg", "ours_rms_deg", "true_r0_error_deg"} <= set(out.columns)
    np.testing.assert_allclose(out.xs("sensor_frame", level="method")["true_r0_error_deg"],
                               float(so3.rotation_angle_deg(result.truth)))
    np.testing.assert_allclose(out.loc[("pitch", "ours_right"), "ours_rms_deg"],
                               result.table2.loc[("pitch", "ours_right"), "rms_deg"])


# ------------------------------------------------------------------------------------------------
# real-data studies

@pytest.fixture(scope="module")
def synthetic_rig():
    """A camera stream and a sensor stream of the same rigid motion, sensor = camera rotated by R0
    (no noise)."""
    rng = np.random.default_rng(5)
    R0 = so3.random_rotations(rng, ())
    t = np.arange(0.0, 40.0, 0.05)
    w = np.stack([np.sin(0.7 * t), np.sin(0.45 * t + 1.0), np.cos(0.3 * t)], axis=-1)
    world_from_camera = so3.matrix_from_rotation_vector(w)
    camera = OrientationStream(t, world_from_camera, "camera")
    sensor = OrientationStream(t, world_from_camera @ R0, "sensor")  # world_from_sensor = world_from_camera R0
    return R0, camera, sensor


def test_real_studies_recover_a_known_r0_and_shape_their_tables(synthetic_rig):
    R0, camera, sensor = synthetic_rig
    streams, refs = {"rig": (camera, sensor, "truth")}, {"truth": R0}
    C = np.swapaxes(camera.R[::40], -1, -2)  # body_from_world attitudes of 20 static poses
    poses = {"poses": (C, np.swapaxes(sensor.R[::40], -1, -2), "truth")}
    head = calibration_table(calibrations(streams, poses, refs, ("chordal_optimal",), seed=1))
    assert list(head.index) == [("rig", "chordal_optimal"), ("poses", "chordal_optimal")]
    # noise-free streams, interpolated between samples: errors measured up to 2.3e-7 deg
    assert (head["error_deg"] < 1e-5).all() and np.isnan(head.loc[("poses", "chordal_optimal"), "offset_ms"])
    solvers = solver_tables(streams, {}, refs)
    assert list(solvers.columns) == ["error_deg", "n_pairs", "warnings", "seconds"]
    assert solvers.loc[("rig", "chordal_optimal"), "error_deg"] < 1e-5
    assert solvers.loc[("rig", "opencv_park"), "n_pairs"] < solvers.loc[("rig", "chordal_optimal"), "n_pairs"]
    proto = protocol_table(streams, refs, intervals=(1.0,))
    assert proto.index.names == ["data", "interval (s)"] and proto.loc[("rig", 1.0), "default: error (deg)"] < 1e-5
    sens = sensitivity_table(camera, sensor, R0, intervals=(0.5,), shares=(0.5,), methods=("chordal_optimal",),
                             n_bootstrap=5, seed=1)
    assert len(sens) == 2 and (sens["error_deg"] < 1e-5).all()
