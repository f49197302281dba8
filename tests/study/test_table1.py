from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from replication.core.handeye import handeye_cost, operator_T, operator_T_adjoint
from replication.core.so3 import frobenius_error, matrix_from_rotation_vector, nearest_rotation
from replication.core.solvers import chordal_optimal
from replication.core.stats import share_range, wilson_interval
from replication.study import paper
from replication.study.simulation import MATCHED_MOTIONS_DEG, matched_start, simulate
from replication.study.table1 import (
    EARLY,
    HALF_STEP_ORDERS,
    ONE_PERCENT,
    PRINTED_HALF_UNIT,
    PRINTED_ORDER,
    RISE_TOL,
    Z_AGREE,
    at_other_minimum,
    bracket_ci,
    compact,
    converged_at,
    convergence_by_setting,
    convergence_summary,
    cost_against_minimum,
    cost_scale_study,
    diverting_runs,
    diverting_table,
    failure_display,
    failure_table,
    first_below,
    fresh_mismatch,
    fresh_seed_counts,
    interval_text,
    iterate_errors,
    paper_left_farther,
    paper_settled,
    paper_two_step_means,
    per_setting_text,
    printed_z,
    scales_text,
    sensitivity_grid,
    share_ci,
    share_text,
    shown_convergence,
    shown_cost_scales,
    sqp_failures,
    sqp_per_setting_text,
    table1,
    two_step_means,
    versus_paper,
)


def test_iterate_errors_shapes_and_noise_free_convergence():
    sim = simulate(2, 4, noise_camera=0.0, noise_sensor=0.0)
    errs = iterate_errors(sim, iterations=30, sqp_variants=("analytic", "capped"), sqp_runs={"capped": 2})
    assert set(errs) == {"optimization (analytic)", "optimization (capped)", "ours_right", "ours_left"}
    assert errs["ours_right"].shape == (4, 30) and errs["optimization (capped)"].shape == (2, 30)
    # measured: 7e-16 and (SLSQP's ftol) 8e-9
    assert errs["ours_right"][:, -1].max() < 1e-13 and errs["optimization (analytic)"][:, -1].max() < 1e-7
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
        cols[(m, "mean")], cols[(m, "std")], cols[(m, "se")] = (means.copy(), np.zeros_like(means),
                                                                np.full_like(means, se))
    return pd.DataFrame(cols, index=pd.Index(paper.TABLE1_ITERATIONS, name="iteration"))


def test_versus_paper_compares_in_standard_errors():
    ours = _ours_equal_to_paper(1e-4)
    assert (versus_paper(ours)["verdict"] == "agrees").all()
    # at the noise floor the paper's SE is 0.0055 / sqrt(1000) = 1.7e-4 (its std at the top of its
    # rounding): 0.002 off is 0.0015 beyond the rounding, about 7.5 SE, a difference
    ours.loc[50, ("ours_left", "mean")] += 0.002
    # the old relative tolerance max(0.005, 0.25 x paper) would have accepted it
    ours.loc[20, ("ours_right", "mean")] += 0.0004  # inside the paper's rounding: z 0, agrees
    cmp = versus_paper(ours)
    assert cmp.loc[(50, "ours_left"), "verdict"] == "differs" and cmp.loc[(50, "ours_left"), "z"] > 5
    assert cmp.loc[(20, "ours_right"), "verdict"] == "agrees" and cmp.loc[(20, "ours_right"), "z"] == 0
    assert cmp.loc[(20, "ours_right"), "z as printed"] > 2 and cmp.loc[(50, "ours_left"), "z as printed"] > 10
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
    assert convergence_summary({"w": np.tile(err, (5, 1))}, np.random.default_rng(0),
                               n_boot=5).loc["w", "error_rises"] == 1


def test_diverting_runs_with_an_absolute_bar_and_feasibility():
    err = np.array([[1.0, 0.5, 0.8, 0.01], [1.0, 0.5, 0.02, 0.03]])
    cost = np.array([[9.0, 5.0, 4.0, 1.0], [9.0, 5.0, 4.0, 3.0]])   # always falling
    assert diverting_runs(err, cost).tolist() == [True, True]
    assert diverting_runs(err, cost, min_error=0.05).tolist() == [True, False]   # the second rise is at 0.03
    off = np.array([[True, True, False, True], [True] * 4])                        # the first rise is off SO(3)
    assert diverting_runs(err, cost, min_error=0.05, feasible=off).tolist() == [False, False]
    with pytest.raises(ValueError, match="same shape"):
        diverting_runs(err, cost[:, :3])


# --- the studies of notebook 03
# ---------------------------------------------------------------------------------

def test_compact_shows_ours_with_z_beside_the_paper():
    ours = _ours_equal_to_paper(1e-4)
    ours.loc[5, ("optimization (analytic)", "mean")] = 1e5
    table = compact(versus_paper(ours))
    assert list(table.columns[:2]) == ["paper ours_right", "paper optimization"]
    assert table.loc[2, "paper ours_right"] == "2.339 ± 0.275" and table.loc[2, "paper optimization"] == "3.488 ± 0.250"
    assert table.loc[2, "ours_right"] == "2.339 ± 0.000 (z +0)"
    assert table.loc[5, "optimization (analytic)"] == "infeasible (mean > 10)"


def test_two_step_means_mismatch_is_the_mean_absolute_log_ratio():
    pm = paper_two_step_means()
    assert pm.shape == (7, 2) and pm.loc[2, "ours_right"] == 2.339 and pm.loc[10, "ours_left"] == 0.062
    sim = simulate(3, 3)
    means, _, agreeing = two_step_means(sim, None, pm)
    assert agreeing == 0  # Haar motions from the identity: no early cell near Table I's
    # a "paper" e times ours on one side and equal on the other: |log| is 1 on half of the cells (no
    # rounding)
    fake = means[["ours_right", "ours_left"]].copy()
    fake["ours_right"] *= np.e
    assert two_step_means(sim, None, fake, half_unit=0.0)[1] == pytest.approx(0.5)


#: Crafted means of the fake two-step runs, per (motion range, start, noise distribution): R^r and
#: R^l at iterations 2, 5, 10, 20, 50 and the mismatch. Cells not listed sit at their floor from
#: iteration 2 on.
_ITERS = (2, 5, 10, 20, 50)
_CELLS = {
    (None, None, "uniform"): ([0.5, 0.3, 0.2, 0.1, 0.1], [0.5, 0.29, 0.1, 0.1, 0.1], 0.25),
    # R^r @2 just above twice the floor (counted), @5 exactly twice (not: "above"), @10 just below
    # (not)
    ((0.0, 90.0), "far", "sphere"): ([0.2 + 1e-9, 0.2, 0.2 - 1e-9, 0.15, 0.1], [0.1] * 5, 0.75),
}
_FLOOR = ([0.1] * 5, [0.1] * 5, 0.5)


@pytest.fixture
def fake_runs(monkeypatch):
    """simulate and two_step_means replaced by fakes that record their calls and return
    :data:`_CELLS`."""
    import replication.study.table1.grid as study

    calls = {"simulate": [], "means": []}

    def fake_simulate(seed, n_runs, *, motion_angle_range_deg=None, noise_distribution="uniform"):
        calls["simulate"].append((seed, n_runs, motion_angle_range_deg, noise_distribution))
        return SimpleNamespace(key=(motion_angle_range_deg, noise_distribution), draw=len(calls["simulate"]))

    def fake_means(problems, start, paper_means, *, reversed_halves=False):
        calls["means"].append((problems.draw, start) + ((True,) if reversed_halves else ()))
        right, left, mismatch = _CELLS.get((problems.key[0], start, problems.key[1]), _FLOOR)
        return pd.DataFrame({"ours_right": right, "ours_left": left}, index=_ITERS), mismatch, int(10 * mismatch)

    monkeypatch.setattr(study, "simulate", fake_simulate)
    monkeypatch.setattr(study, "two_step_means", fake_means)
    return calls


def test_sensitivity_grid_order_values_and_left_closer(fake_runs):
    motions, starts = {"Haar": None, "0-90": (0.0, 90.0)}, {"identity": None, "far": "far"}
    noise = {"ball": "uniform", "sphere": "sphere"}
    sens, left_closer = sensitivity_grid(7, 3, motions, starts, noise, paper_two_step_means())
    # noise outermost, start innermost; one draw per (noise, motions), the same seed for all, shared
    # by the starts
    assert fake_runs["simulate"] == [(7, 3, None, "uniform"), (7, 3, (0.0, 90.0), "uniform"),
                                     (7, 3, None, "sphere"), (7, 3, (0.0, 90.0), "sphere")]
    assert fake_runs["means"] == [(1, None), (1, "far"), (2, None), (2, "far"), (3, None), (3, "far"),
                                  (4, None), (4, "far")]
    order = "(14) then (15)"  # the default: the printed order only
    assert list(sens.index) == [(m, s, n, order) for n in noise for m in motions for s in starts]
    assert sens.index.names == ["motions", "start", "noise", "half-steps"]
    assert list(sens.columns) == ["R^r @2", "R^r @5", "R^r @10", "R^r @20", "R^r @50", "mismatch",
                                  "early cells agreeing"]
    assert sens.loc[("Haar", "identity", "ball", order)].tolist() == [0.5, 0.3, 0.2, 0.1, 0.1, 0.25, 2]
    assert sens.loc[("0-90", "far", "sphere", order), "mismatch"] == 0.75 and sens.loc[("Haar", "far", "ball", order),
                                                                                         "mismatch"] == 0.5
    # counted: (Haar, identity, ball) @2 (R^l equal: not closer) and @5 (closer); (0-90, far,
    # sphere) @2 only
    assert left_closer.tolist() == [False, True, True]
    assert list(left_closer.index) == [("Haar", "identity", "ball", order, 2), ("Haar", "identity", "ball", order, 5),
                                       ("0-90", "far", "sphere", order, 2)]


def test_fresh_mismatch_averages_over_noise_distributions(fake_runs):
    noise = {"ball": "uniform", "sphere": "sphere"}
    fresh = fresh_mismatch([("Haar", "identity", "(14) then (15)"), ("0-90", "far", "(14) then (15)")], 9, 3,
                           {"Haar": None, "0-90": (0.0, 90.0)}, {"identity": None, "far": "far"}, noise,
                           paper_two_step_means())
    assert fresh["mismatch"].tolist() == [pytest.approx((0.25 + 0.5) / 2), pytest.approx((0.5 + 0.75) / 2)]
    assert fresh["early cells agreeing"].tolist() == [5, 7]  # the most over the noise distributions
    assert fresh["R^l closer"].tolist() == [1, 1] and fresh["early cells"].tolist() == [2, 1]
    assert [c[:2] for c in fake_runs["simulate"]] == [(9, 3)] * 4
    assert [c[2:] for c in fake_runs["simulate"]] == [(None, "uniform"), (None, "sphere"), ((0.0, 90.0), "uniform"),
                                                      ((0.0, 90.0), "sphere")]


def test_failure_table_and_its_display():
    fails = failure_table({"a": {"optimization (x)": np.array([[1.0, 0.01], [1.0, 0.2]]),
                                 "ours_right": np.array([0.1, 0.0, 0.0, 0.0])},
                           "b": {"optimization (x)": np.zeros(3)}}, fail=0.05)
    assert fails.loc["a", "optimization (x)"] == 0.5 and fails.loc["a", "ours_right"] == 0.25
    assert fails.loc["b", "optimization (x)"] == 0.0 and np.isnan(fails.loc["b", "ours_right"])
    shown = failure_display(fails.assign(**{"optimization (x)": [0.52, 0.0]}), lambda row, col: 100)
    # SQP strictly inside (0, 1): a bracket, with a Wilson interval covering it (50 and 54 of 100)
    assert shown.loc["a", "optimization (x)"] == share_range(0.52) + " [40, 63]"
    assert shown.loc["a", "ours_right"] == "25.0% [17.5, 34.3]"                # Wilson, 25 of 100
    assert shown.loc["b", "optimization (x)"] == "0.0% [0.0, 3.7]" and shown.loc["b", "ours_right"] == ""


@pytest.mark.parametrize("share, ok", [(0.52, True), (0.53, True), (0.51, False), (0.54, False)])
def test_a_far_start_sqp_share_keeps_two_runs_from_its_brackets_edges(share, ok):
    fails = pd.DataFrame({"optimization (x)": [share]}, index=["a"])
    if ok:
        assert failure_display(fails, lambda row, col: 100).loc["a", "optimization (x)"].startswith("50-55 %")
    else:
        with pytest.raises(ValueError, match="of an edge of its bracket 50-55 %"):
            failure_display(fails, lambda row, col: 100)


def test_sqp_failures_and_other_minimum():
    sim = simulate(2, 3, noise_camera=0.0, noise_sensor=0.0)
    res, failed, at_limit = sqp_failures(sim.A, sim.B, sim.R0)
    assert not failed.any() and not at_limit.any() and not at_other_minimum(res, sim.A, sim.B).any()
    # fake SQP answers: stopped early on a rotation 120 deg from the minimiser (another minimum);
    # the same at the limit; the same but its last raw iterate off SO(3); and at the minimiser
    R0 = sim.R0[0]
    far = R0 @ matrix_from_rotation_vector(np.array([0.0, 0.0, np.deg2rad(120.0)]))
    R = np.stack([far, far, far, R0])
    last = R.copy()
    last[2] = 2.0 * far
    fake = SimpleNamespace(R=R, history=SimpleNamespace(iterates=last[:, None]), iterations=np.array([10, 50, 10, 10]))
    A, B = np.repeat(sim.A[:1], 4, axis=0), np.repeat(sim.B[:1], 4, axis=0)
    assert at_other_minimum(fake, A, B).tolist() == [True, False, False, False]


def test_cost_scale_study_noise_free():
    sim = simulate(4, 3, noise_camera=0.0, noise_sensor=0.0)
    table, runs = cost_scale_study({"s": (sim, None)}, {"as printed": 1.0, "/ 40": 1 / 40},
                                   np.random.default_rng(0), n_runs=2, at=(30, 50))
    assert table.index.names == ["setting", "eq. (8) times"]
    assert list(table.index) == [("s", "as printed"), ("s", "/ 40")]
    assert list(table.columns) == ["failed", "below_1pct", "below_1pct_low", "below_1pct_high", "settled",
                                   "settled_low", "settled_high", "mean @30", "mean @50"]
    assert (table["failed"] == 0).all() and (table["mean @50"] < 1e-7).all()  # measured 4e-9
    r, e = runs[("s", "/ 40")]
    assert e.shape == (2, 50) and table.loc[("s", "/ 40"), "mean @30"] == e.mean(axis=0)[29]


def test_interval_and_share_texts():
    row = pd.Series({"k": 5.0, "k_low": 4.0, "k_high": 6.4}, name="ours_right")
    assert interval_text(row, "k") == "5 [4, 6]"
    never = pd.Series({"k": np.nan, "k_low": np.nan, "k_high": np.nan}, name=("matched", "optimization (capped)"))
    assert interval_text(never, "k") == "never"
    assert interval_text(never, "k", {"optimization (capped)": 30}) == "never (30 iterations)"
    assert interval_text(never.rename("ours_right"), "k", {}) == "never (50 iterations)"
    far = pd.Series({"p": 0.5, "q": 0.0}, name=("matched (fresh seeds)", "optimization (analytic)"))
    assert share_text(far, "p") == "varies †" and share_text(far, "q") == share_range(0.0)
    assert share_text(far.rename(("defaults", "optimization (analytic)")), "p") == "50%"
    frames = (("d", pd.DataFrame({"k": [3.0, np.nan], "k_low": [3.0, np.nan], "k_high": [4.0, np.nan]},
                                 index=["ours_right", "optimization (a)"])),)
    assert per_setting_text(frames * 2, "ours_right", "k") == "d 3 [3, 4]; d 3 [3, 4]"
    assert sqp_per_setting_text(frames, ["optimization (a)"], "k", {}) == "d: a never (50 iterations)"
    scales = pd.DataFrame({"settled": [8.0, np.nan], "settled_low": [7.0, np.nan], "settled_high": [9.0, np.nan]},
                          index=pd.MultiIndex.from_tuples([("s", "x1"), ("s", "x2")]))
    assert scales_text(scales, "s", ["x1", "x2"]) == "x1 8 [7, 9], x2 never"


def test_shown_cost_scales_adds_the_papers_row():
    scales = pd.DataFrame({"failed": [0.0, 0.5], "below_1pct": [3.0, np.nan], "below_1pct_low": [3.0, np.nan],
                           "below_1pct_high": [4.0, np.nan], "settled": [5.0, np.nan], "settled_low": [5.0, np.nan],
                           "settled_high": [6.0, np.nan], "mean @15": [0.1234, np.nan], "mean @30": [0.01, np.nan],
                           "mean @50": [0.001, np.nan]},
                          index=pd.MultiIndex.from_tuples([("s", "1"), ("s", "2")], names=["setting", "eq. (8) times"]))
    shown = shown_cost_scales(scales)
    assert shown.loc[("s", "1")].tolist() == ["0%", "3 [3, 4]", "5 [5, 6]", "0.123", "0.010", "0.001"]
    assert shown.loc[("s", "2")].tolist() == [share_range(0.5), "never", "never", "-", "-", "-"]
    assert shown.loc[("paper's Table I", "?")].tolist() == ["-", "-", "-", "0.451", "0.053", "0.015"]


def test_convergence_by_setting_stacks_summaries_in_order():
    curve = np.array([2.0, 1.0, 0.5, 0.02, 0.012, 0.0104, 0.0101, 0.01])
    big = np.tile(curve * 2000, (6, 1))                           # final mean 20 > DIVERGED
    settings = {"defaults": (None, {"ours_right": np.tile(curve, (6, 1))}, {"ours_right": np.tile(curve, (6, 1))}),
                "matched (x)": (None, {"optimization (a)": big}, {"optimization (a)": big})}
    conv = convergence_by_setting(settings, np.random.default_rng(3))
    rng = np.random.default_rng(3)
    first = convergence_summary(settings["defaults"][1], rng, costs=settings["defaults"][2])
    second = convergence_summary(settings["matched (x)"][1], rng, costs=settings["matched (x)"][2])
    assert conv.index.names == ["setting", "method"]
    pd.testing.assert_frame_equal(conv.loc["defaults"], first, check_names=False)
    pd.testing.assert_frame_equal(conv.loc["matched (x)"][second.columns], second, check_names=False,
                                  check_dtype=False)
    shown = shown_convergence(conv)
    assert shown.loc[("defaults", "ours_right"), "final error"] == "0.0100 ± 0.0000"
    assert shown.loc[("defaults", "ours_right"), "below 1 %"].startswith("5 [")
    assert shown.loc[("matched (x)", "optimization (a)"), "final error"] == "infeasible (mean > 10)"
    assert shown.loc[("defaults", "ours_right"), "error rises"] == "0%"


def test_cost_against_minimum_ratios():
    sim = simulate(5, 4)
    floor = chordal_optimal(sim.A, sim.B).cost
    cost = np.tile(2.0 * floor[:, None], (1, 50))
    cost[:, 0] *= 4.0                                               # cost at iteration 1 four times that at 10
    shown, ratios, minima = cost_against_minimum({"s": (sim, None, {"ours_right": cost})}, np.random.default_rng(0))
    assert ratios["s"]["@10 / @1"] == pytest.approx(0.25)
    assert ratios["s"]["@10 / minimum"] == pytest.approx((2.0, 2.0, 2.0))
    assert np.allclose(minima["s"].cost, floor)
    assert list(shown.columns) == ["cost @1", "cost @10", "cost @50", "certified minimum of (8)", "@10 / minimum",
                                   "@50 / minimum"]
    assert shown.loc["s", "@50 / minimum"] == "2.000 [2.000, 2.000]"


def test_diverting_table_with_fake_runs():
    err = np.array([[1.0, 0.5, 0.8, 0.01], [1.0, 0.5, 0.02, 0.03]])
    cost = np.array([[9.0, 5.0, 4.0, 1.0], [9.0, 5.0, 4.0, 3.0]])   # always falling: every error rise diverts
    iterates = np.broadcast_to(np.eye(3), (2, 4, 3, 3)).copy()
    iterates[0, 2] *= 2.0                                           # run 0's rise (iteration 3) is off SO(3)
    # the projected iterates read against R0 = I: run 0's projected error only falls, run 1's rises
    # at iteration 3
    proj_err = np.array([[1.0, 0.5, 0.4, 0.01], [1.0, 0.5, 0.6, 0.7]])
    angles = 2 * np.arcsin(proj_err / (2 * np.sqrt(2)))
    projected = matrix_from_rotation_vector(angles[..., None] * np.array([0.0, 0.0, 1.0]))
    history = SimpleNamespace(iterates=iterates, cost=cost, projected=projected)
    scale_runs = {("s", "as printed"): (SimpleNamespace(history=history), err)}
    settings = {"s": (SimpleNamespace(R0=np.broadcast_to(np.eye(3), (2, 3, 3))), {"ours_right": err[::-1]},
                      {"ours_right": cost[::-1]})}
    div = diverting_table(scale_runs, settings, ["s"], scale_names=("as printed",), bar=0.05, n_runs=1)
    assert list(div.columns) == ["diverts, error > 0.05", "... and on a rotation", "... read on projected iterates"]
    assert div.loc[("s", "SQP, eq. (8) as printed")].tolist() == [0.5, 0.0, 0.5]
    assert div.loc[("s", "two-step R^r")].tolist() == [0.0, 0.0, 0.0]   # its first run rises to 0.03 only


# --------------------------------------------------------------------------------------------------
# Comparisons with Table I that take its three printed decimals as a bound, shares of runs with
# Wilson intervals, the half-steps in either order, and the counts again on fresh seeds.

# ---- the paper's rounding
# -----------------------------------------------------------------------------------------

def test_printed_z_takes_the_nearest_value_the_rounding_allows():
    h, n = PRINTED_HALF_UNIT, 1000
    se_top = (0.004 + h) / np.sqrt(n)  # the paper's std at the top of its rounding interval
    bound, uniform, as_printed = printed_z(0.0065, 1e-4, 0.009, 0.004)
    assert bound == pytest.approx(-(0.0025 - h) / np.hypot(1e-4, se_top))
    assert uniform == pytest.approx(-0.0025 / np.sqrt(1e-8 + 0.004 ** 2 / n + h ** 2 / 3))
    assert as_printed == pytest.approx(-0.0025 / np.hypot(1e-4, 0.004 / np.sqrt(n)))
    assert abs(uniform) < abs(bound) < abs(as_printed)  # at the noise floor the rounding dominates the SE
    assert printed_z(0.0094, 1e-4, 0.009, 0.004)[0] == 0.0 and printed_z(0.0086, 1e-4, 0.009, 0.004)[0] == 0.0
    assert printed_z(0.0125, 1e-4, 0.009, 0.004)[0] > 0 > printed_z(0.0055, 1e-4, 0.009, 0.004)[0]
    assert printed_z(0.0125, 1e-4, 0.009, 0.004, half_unit=0.0)[0] == pytest.approx(as_printed * -1.4, rel=1e-12)


def _at_iteration_50(offset: float):
    """Our Table I equal to the paper's but R^r at iteration 50 moved by ``offset``, SE 1e-4."""
    ref = paper.load_table1().xs("ours_right", level="method")
    tab = pd.DataFrame({("ours_right", "mean"): ref["mean"].to_numpy(), ("ours_right", "std"): 0.0,
                        ("ours_right", "se"): 1e-4}, index=pd.Index(paper.TABLE1_ITERATIONS, name="iteration"))
    tab.loc[50, ("ours_right", "mean")] += offset
    return versus_paper(tab).loc[(50, "ours_right")]


def test_versus_paper_agrees_up_to_three_rounding_aware_standard_errors():
    # |z| = 3 at h + 3 sqrt(se^2 + ((0.004 + h) / sqrt(1000))^2) from the printed 0.009
    edge = PRINTED_HALF_UNIT + Z_AGREE * np.hypot(1e-4, 0.0045 / np.sqrt(1000))
    inside, outside = _at_iteration_50(edge - 2e-6), _at_iteration_50(edge + 2e-6)
    assert inside["verdict"] == "agrees" and outside["verdict"] == "differs"
    assert inside["z as printed"] > 5  # the printed digits taken as exact would have said "differs"
    assert list(outside.index) == ["ours", "paper", "ratio", "z", "z uniform", "z as printed", "verdict"]


def test_two_step_means_mismatch_is_against_the_nearest_rounded_value():
    sim = simulate(3, 3)
    means, _, _ = two_step_means(sim, None, paper_two_step_means())
    ours = means[["ours_right", "ours_left"]]
    assert two_step_means(sim, None, ours + 0.9 * PRINTED_HALF_UNIT)[1] == 0.0  # within the rounding
    beyond = two_step_means(sim, None, ours + 1.1 * PRINTED_HALF_UNIT)[1]
    assert beyond == pytest.approx(np.mean(np.abs(np.log(ours / (ours + 0.1 * PRINTED_HALF_UNIT)))), rel=1e-9)


def test_paper_left_farther_whatever_the_rounding():
    ref = paper.load_table1()
    assert paper_left_farther(ref)
    for gap, expected in ((2 * PRINTED_HALF_UNIT + 1e-6, True), (2 * PRINTED_HALF_UNIT - 1e-6, False)):
        changed = ref.copy()
        changed.loc[(5, "ours_left"), "mean"] = changed.loc[(5, "ours_right"), "mean"] + gap
        assert paper_left_farther(changed) is expected


def test_paper_settled_at_both_ends_of_the_rounding():
    ref = paper.load_table1()
    assert paper_settled(ref, "ours_right") == (15, 15) and paper_settled(ref, "optimization") == (50, 50)
    assert paper_settled(ref, "ours_left") == (15, 20)  # R^l's 0.016 at 15 is 0.006 from 0.010: 0.004-0.008
    for value, expected in ((0.0129, (15, 15)), (0.0131, (15, 20)), (0.0151, (20, 20))):
        changed = ref.copy()
        changed.loc[(15, "ours_right"), "mean"] = value  # 0.009 at 20-50: within 0.005 by 0.0039, 0.0041, 0.0061
        assert paper_settled(changed, "ours_right") == expected


# ---- shares of runs
# ------------------------------------------------------------------------------------------------

def test_share_ci_gives_the_wilson_interval():
    low, high = wilson_interval(25, 100)
    assert share_ci(0.25, 100, 1) == f"25.0% [{100 * low:.1f}, {100 * high:.1f}]" == "25.0% [17.5, 34.3]"
    assert share_ci(0.5, 1000) == "50% [47, 53]" and share_ci(0.0, 300, 1) == "0.0% [0.0, 1.3]"


def test_bracket_ci_covers_every_count_in_the_bracket():
    # 0.82 of 1000: the bracket 80-85 % holds 800 ... 849 runs
    assert bracket_ci(0.82, 1000) == (f"80-85 % [{100 * wilson_interval(800, 1000)[0]:.0f}, "
                                      f"{100 * wilson_interval(849, 1000)[1]:.0f}]") == "80-85 % [77, 87]"
    assert bracket_ci(0.84, 300) == "80-85 % [75, 88]"  # 240 ... 254 of 300
    assert bracket_ci(0.0, 300) == "none of 300 [0, 1.3]" and bracket_ci(1.0, 300) == "all of 300 [98.7, 100]"
    assert bracket_ci(0.97, 100) == "95-100 % [89, 100]"  # the last bracket stops at n - 1 runs: 95 ... 99


# ---- the half-steps in the other order
# ---------------------------------------------------------------------------

def test_reversed_half_steps_start_with_eq_15():
    sim = simulate(4, 3, motion_angle_range_deg=MATCHED_MOTIONS_DEG)
    start = np.eye(3)  # <start, R0> > 0: the corrected and the printed projections agree
    (e, c), (e_rev, c_rev) = (iterate_errors(sim, iterations=3, init=start, with_sqp=False, return_costs=True,
                                             reversed_halves=flip) for flip in (False, True))
    # printed: R^r_1 from the start by eq. (14); reversed: R^l_1 from the start by eq. (15), R^r_1
    # from its raw iterate by (14) (the iteration carries raw iterates, projected only to be
    # reported)
    r1 = nearest_rotation(operator_T(sim.A, sim.B, start))
    raw_l1 = operator_T_adjoint(sim.A, sim.B, start)
    l1_rev, r1_rev = nearest_rotation(raw_l1), nearest_rotation(operator_T(sim.A, sim.B, raw_l1))
    assert np.allclose(e["ours_right"][:, 0], frobenius_error(r1, sim.R0), atol=1e-12)
    assert np.allclose(e_rev["ours_left"][:, 0], frobenius_error(l1_rev, sim.R0), atol=1e-12)
    assert np.allclose(e_rev["ours_right"][:, 0], frobenius_error(r1_rev, sim.R0), atol=1e-12)
    assert np.allclose(c_rev["ours_right"][:, 0], handeye_cost(r1_rev, sim.A, sim.B), rtol=1e-10)  # cost (8) as ours
    assert not np.allclose(e["ours_left"], e_rev["ours_left"])


def test_the_half_step_order_decides_which_estimate_leads():
    sim = simulate(5, 50, motion_angle_range_deg=MATCHED_MOTIONS_DEG)
    for flip, left_closer in ((False, True), (True, False)):
        means = table1(iterate_errors(sim, init=matched_start(), with_sqp=False, reversed_halves=flip))
        right, left = (means.loc[list(EARLY), (side, "mean")] for side in ("ours_right", "ours_left"))
        assert ((left < right) == left_closer).all()
    assert list(HALF_STEP_ORDERS) == [PRINTED_ORDER, "(15) then (14)"] and not HALF_STEP_ORDERS[PRINTED_ORDER]


# ---- the counts again on fresh seeds
# -----------------------------------------------------------------------------

def test_fresh_seed_counts_layout():
    scales = {"as printed": 1.0, "/ 2J": 0.025, "/ 100J": 0.0005}
    out = fresh_seed_counts(7, 12, 6, scales, np.random.default_rng(0), motions_deg=MATCHED_MOTIONS_DEG,
                            far_start=matched_start())
    assert (out["seed"], out["n_runs"], out["n_sqp"]) == (7, 12, 6)
    assert list(out["conv"].index) == [(s, m) for s in ("defaults", "0-90 deg, identity start")
                                       for m in ("ours_right", "optimization (analytic)")]
    shares = out["conv"][["error_rises", "cost_rises", "rises_above_floor", "diverts_above_floor"]].to_numpy(float)
    assert ((shares >= 0) & (shares <= 1)).all()
    assert list(out["div"].index.get_level_values(1)) == ["SQP, eq. (8) as printed", "SQP, eq. (8) / 2J",
                                                          "two-step R^r"] * 2
    assert list(out["scales"].index) == [("defaults", "as printed"), ("defaults", "/ 2J"),
                                         ("0-90 deg, identity start", "as printed"),
                                         ("0-90 deg, identity start", "/ 2J"), ("matched", "as printed"),
                                         ("matched", "/ 100J")]
