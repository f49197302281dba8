"""The one solver loop of notebooks 06 and 07 (replication.study.baselines: compare, sweep) on
small inputs; the lab's studies are tests/study/test_lab_study.py's, Table II beside the paper's
test_table2.py's, the studies of the real recordings test_real_study.py's."""
import numpy as np
import pytest

from replication.core import so3
from replication.core.solvers import ObservabilityWarning
from replication.study.baselines import compare, sweep
from replication.study.simulation import simulate

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
