import numpy as np
import pandas as pd
import pytest

from replication import paper
from replication.simulation import simulate
from replication.tables import (
    ONE_PERCENT, RISE_TOL, converged_at, convergence_summary, diverting_runs, first_below, iterate_errors, table1,
    versus_paper,
)


def test_iterate_errors_shapes_and_noise_free_convergence():
    sim = simulate(2, 4, noise_camera=0.0, noise_sensor=0.0)
    errs = iterate_errors(sim, iterations=30, sqp_variants=("analytic", "capped"), sqp_runs={"capped": 2})
    assert set(errs) == {"optimization (analytic)", "optimization (capped)", "ours_right", "ours_left"}
    assert errs["ours_right"].shape == (4, 30) and errs["optimization (capped)"].shape == (2, 30)
    assert errs["ours_right"][:, -1].max() < 1e-9 and errs["optimization (analytic)"][:, -1].max() < 1e-6
    assert set(iterate_errors(sim, iterations=30, with_sqp=False)) == {"ours_right", "ours_left"}


def test_table1_picks_the_right_iterations_with_standard_errors():
    err = np.tile(np.arange(1.0, 51.0), (3, 1))  # error = iteration number, identical runs
    tab = table1({"ours_right": err})
    assert list(tab.index) == list(paper.TABLE1_ITERATIONS)
    assert np.array_equal(tab[("ours_right", "mean")], paper.TABLE1_ITERATIONS)
    assert np.all(tab[("ours_right", "std")] == 0) and np.all(tab[("ours_right", "se")] == 0)


def _ours_equal_to_paper(se: float):
    ref = paper.load_table1()
    cols = {}
    for m in ("ours_right", "ours_left", "optimization (analytic)"):
        means = ref.xs("optimization" if m.startswith("opt") else m, level="method")["mean"].to_numpy()
        cols[(m, "mean")], cols[(m, "std")], cols[(m, "se")] = means.copy(), np.zeros_like(means), np.full_like(means, se)
    return pd.DataFrame(cols, index=pd.Index(paper.TABLE1_ITERATIONS, name="iteration"))


def test_versus_paper_compares_in_standard_errors():
    ours = _ours_equal_to_paper(1e-4)
    assert (versus_paper(ours)["verdict"] == "agrees").all()
    # at the noise floor the paper's SE is 0.004 / sqrt(1000) = 1.3e-4: 0.001 off is about 6 SE, a difference
    ours.loc[50, ("ours_left", "mean")] += 0.001
    # the old relative tolerance max(0.005, 0.25 x paper) would have accepted it
    ours.loc[20, ("ours_right", "mean")] += 0.0002  # about 1.2 SE: agrees
    cmp = versus_paper(ours)
    assert cmp.loc[(50, "ours_left"), "verdict"] == "differs" and cmp.loc[(50, "ours_left"), "z"] > 5
    assert cmp.loc[(20, "ours_right"), "verdict"] == "agrees"
    assert cmp.loc[(2, "optimization (analytic)"), "paper"] == "3.488 ± 0.250"  # compared with "Optimization"
    ours.loc[5, ("optimization (analytic)", "mean")] = 1e5  # an infeasible SQP iterate has no digits
    assert versus_paper(ours).loc[(5, "optimization (analytic)"), "verdict"] == "infeasible"


def test_convergence_measures():
    curve = np.array([2.0, 1.0, 0.5, 0.02, 0.012, 0.0104, 0.0101, 0.01])
    assert first_below(curve, ONE_PERCENT) == 5 and first_below(curve, 1e-9) is None
    assert converged_at(curve, 0.05) == 6 and converged_at(curve, 0.0, 0.005) == 5
    rising = curve.copy()
    rising[2] = 3.5  # rises above 2 sqrt 2 (off SO(3)) while far above its floor
    errs = {"a": np.tile(curve, (20, 1)), "b": np.tile(rising, (20, 1))}
    summary = convergence_summary(errs, np.random.default_rng(0), n_boot=20)
    assert summary.loc["a", "below_1pct"] == 5 and summary.loc["a", "rises_above_floor"] == 0
    assert summary.loc["b", "rises_above_floor"] == 1 and summary.loc["a", "left_SO3"] == 0
    assert summary.loc["b", "left_SO3"] == 1


def test_convergence_caps_costs_and_diverting_runs():
    err = np.array([2.0, 1.0, 1.5, 0.02, 0.0105, 0.0101, 0.01, 0.0102])  # rises at 3 (above floor) and at 8 (at it)
    cost = np.array([9.0, 5.0, 4.0, 1.0, 0.5, 0.4, 0.3, 0.35])           # falls at 3, rises at 8
    flat = np.tile(np.r_[np.linspace(2.0, 0.01, 5), [0.01] * 3], (10, 1))  # a capped solver padded after 5
    summary = convergence_summary({"d": np.tile(err, (10, 1)), "capped": flat}, np.random.default_rng(1), n_boot=10,
                                  caps={"capped": 5}, costs={"d": np.tile(cost, (10, 1))})
    assert summary.loc["d", "error_rises"] == 1 and summary.loc["d", "cost_rises"] == 1
    assert summary.loc["d", "diverts"] == 1 and summary.loc["d", "diverts_above_floor"] == 1
    assert np.isnan(summary.loc["capped", "cost_rises"])            # no costs given for it
    assert summary.loc["capped", "settled"] is None or pd.isna(summary.loc["capped", "settled"])  # only at its cap
    at_floor = err.copy()
    at_floor[2] = 0.9  # no rise above the floor any more; the one at iteration 8 remains, with the cost rising too
    s2 = convergence_summary({"d": np.tile(at_floor, (10, 1))}, np.random.default_rng(1), n_boot=10,
                             costs={"d": np.tile(cost, (10, 1))})
    assert s2.loc["d", "error_rises"] == 1 and s2.loc["d", "diverts"] == 0 and s2.loc["d", "diverts_above_floor"] == 0


def test_rounding_level_rises_are_not_counted():
    err = np.array([1.0, 0.1, 0.01, 0.01 + 1e-13, 0.01 + 2e-13])     # wobble at its fixed point
    cost = np.array([5.0, 1.0, 0.2, 0.2 * (1 + 1e-12), 0.2])
    s = convergence_summary({"w": np.tile(err, (5, 1))}, np.random.default_rng(0), n_boot=5,
                            costs={"w": np.tile(cost, (5, 1))})
    assert s.loc["w", "error_rises"] == 0 and s.loc["w", "cost_rises"] == 0 and s.loc["w", "diverts"] == 0
    err[3] = 0.01 + 10 * RISE_TOL
    assert convergence_summary({"w": np.tile(err, (5, 1))}, np.random.default_rng(0), n_boot=5).loc["w", "error_rises"] == 1


def test_diverting_runs_with_an_absolute_bar_and_feasibility():
    err = np.array([[1.0, 0.5, 0.8, 0.01], [1.0, 0.5, 0.02, 0.03]])
    cost = np.array([[9.0, 5.0, 4.0, 1.0], [9.0, 5.0, 4.0, 3.0]])   # always falling
    assert diverting_runs(err, cost).tolist() == [True, True]
    assert diverting_runs(err, cost, min_error=0.05).tolist() == [True, False]   # the second rise is at 0.03
    off = np.array([[True, True, False, True], [True] * 4])                        # the first rise is off SO(3)
    assert diverting_runs(err, cost, min_error=0.05, feasible=off).tolist() == [False, False]
    with pytest.raises(ValueError, match="same shape"):
        diverting_runs(err, cost[:, :3])
