"""Fig. 5 (``replication.study.fig5``): the noise sweep over the grid of settings, its tables,
growth ratios and figure, the resilience over all runs, the stop-short SQPs matched to Table I, the
problem sets and fresh seeds, the evidence's texts and declared bounds, and the growth ratio over
motion ranges. The ledger record: test_fig5_claims.py."""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from replication.core.stats import share_range
from replication.study.fig5 import (
    confirmation_table,
    fig5_figure,
    match_to_table1,
    matching_display,
    noise_sweep,
    problem_sets,
    ratio_range,
    resilience,
    sqp_configs_for,
    summary_table,
    sweep_grid,
    two_step_growth,
    variants_of,
)


def test_sqp_configs_for_the_grid():
    assert sqp_configs_for("Haar", "identity", "uniform norm") == ["analytic"]
    assert sqp_configs_for("0-90 deg", "identity", "uniform in ball") == ["analytic", "cost / 100J"]
    assert sqp_configs_for("Haar", "identity", "uniform in ball") == ["analytic", "cost / 100J", "finite-difference",
                                                                      "capped"]
    assert sqp_configs_for("0-90 deg", "150 deg from R0", "uniform in ball")[2:] == ["finite-difference", "capped"]
    assert sqp_configs_for("Haar", "150 deg from R0", "uniform in ball") == ["analytic", "cost / 100J"]


def test_sweep_grid_runs_each_setting_in_order_with_one_generator():
    configs = {"analytic": ("analytic", None), "cost / 100J": ("analytic", {"cost": 1 / 2000})}
    sweeps, per_level, growth = sweep_grid(
        [1.0, 10.0], 3, 50, np.random.default_rng(0), motions={"Haar": None}, starts={"identity": None},
        noise={"ball": "uniform", "sphere": "sphere"}, configs=configs,
        variants_for=lambda m, s, n: ["analytic", "cost / 100J"] if n == "ball" else ["analytic"], n_boot=20)
    keys = [("Haar", "identity", "ball", "analytic"), ("Haar", "identity", "ball", "cost / 100J"),
            ("Haar", "identity", "sphere", "analytic")]
    assert list(sweeps) == keys
    assert per_level.index.names == ["motions", "start", "noise", "SQP variant", "sensor noise (deg)"]
    assert len(per_level) == 6 and list(growth.index) == sorted(keys)
    # the same as running noise_sweep + resilience by hand, drawing the bootstrap in the loop order
    rng = np.random.default_rng(0)
    for (m, s, n, v) in keys:
        sw = noise_sweep([1.0, 10.0], 3, 50, noise_distribution={"ball": "uniform", "sphere": "sphere"}[n],
                         sqp_options=configs[v][1])
        assert np.array_equal(sw[10.0]["two_step"], sweeps[(m, s, n, v)][10.0]["two_step"])
        lv, gr = resilience(sw, rng, n_boot=20)
        pd.testing.assert_frame_equal(per_level.loc[(m, s, n, v)], lv, check_names=False)
        assert growth.loc[(m, s, n, v), "ratio"] == gr["ratio"] and growth.loc[(m, s, n, v), "low"] == gr["low"]


def _synthetic():
    idx = pd.MultiIndex.from_product([["Haar", "0-90 deg"], ["identity"], ["ball"], ["analytic"], [1.0, 10.0]],
                                     names=["motions", "start", "noise", "SQP variant", "sensor noise (deg)"])
    per_level = pd.DataFrame({"two_step": [0.01, 0.1, 0.02, 0.2], "two_step_se": [0.001] * 4,
                              "ratio": [1.5, 1.3, np.nan, 1.1], "ratio_low": [1.4, 1.2, np.nan, 1.0],
                              "ratio_high": [1.6, 1.4, np.nan, 1.2]}, index=idx).sort_index()
    gidx = idx.droplevel(-1).unique()
    growth = pd.DataFrame({"sqp_failed_share": [0.0, 0.83], "ratio": [1.25, np.nan], "low": [1.111, np.nan],
                           "high": [1.4, np.nan]}, index=gidx).sort_index()
    return per_level, growth


def test_summary_table_texts():
    per_level, growth = _synthetic()
    s = summary_table(per_level, growth)
    assert list(s.columns) == ["SQP not at the global minimum", "ratio at 1 deg", "ratio at 10 deg",
                               "growth ratio 1 -> 10 deg"]
    assert s.loc[("0-90 deg", "identity", "ball", "analytic")].tolist() == [share_range(0.83), "-",
                                                                            "1.10 [1.00, 1.20]", "-"]
    assert s.loc[("Haar", "identity", "ball", "analytic")].tolist() == ["none", "1.50 [1.40, 1.60]",
                                                                        "1.30 [1.20, 1.40]", "1.25 [1.11, 1.40]"]


def test_two_step_growth_and_ratio_range():
    sweeps = {"k": {1.0: {"two_step": np.array([0.01, 0.03])}, 10.0: {"two_step": np.array([0.1, 0.2])}}}
    assert two_step_growth(sweeps, ["k"]) == pytest.approx({"k": 0.13})
    per_level, _ = _synthetic()
    assert ratio_range(per_level, "Haar") == (1.3, 1.5)
    assert ratio_range(per_level, "0-90 deg") == (1.1, 1.1)         # NaN (SQP failed) is skipped


def test_fig5_figure_draws_two_step_with_error_bars_and_every_sqp_variant():
    per_level, _ = _synthetic()
    runs = {lv: {"sqp": np.array([lv, 3 * lv])} for lv in (1.0, 10.0)}       # means 2 and 20
    sweeps = {("Haar", "identity", "ball", v): runs for v in ("analytic", "capped")}
    fig = fig5_figure(per_level, sweeps, [1.0, 10.0], [("left", ("Haar", "identity", "ball")),
                                                       ("right", ("Haar", "identity", "ball"))],
                      variants=(("analytic", "-"), ("capped", ":")))
    left, right = fig.axes
    assert left.get_title() == "left\nN = 2 runs per point" and right.get_title().startswith("right\n")
    assert left.get_yscale() == "log"
    bars = left.containers[0]                                                   # ours: mean with +- 1.96 SE bars
    assert bars.lines[0].get_ydata().tolist() == [0.01, 0.1]
    segments = bars.lines[2][0].get_segments()
    assert segments[0][:, 1] == pytest.approx([0.01 - 1.96e-3, 0.01 + 1.96e-3])
    sqp_a, sqp_c = [line for line in left.lines if line.get_label().startswith("SQP")]
    assert sqp_a.get_ydata() == pytest.approx([2.0, 20.0]) and sqp_c.get_linestyle() == ":"
    assert sqp_a.get_color() == sqp_c.get_color() == "b" and bars.lines[0].get_color() == "c"  # fixed colours
    assert sqp_a.get_marker() != sqp_c.get_marker()
    assert [t.get_text() for t in left.get_legend().get_texts()] == ["SQP (analytic), all runs",
                                                                     "SQP (capped), all runs", "ours, $R^r$"]
    assert fig.get_suptitle() == "Fig. 5 (replicated)"
    plt.close(fig)


# ---- resilience over all runs, and the changes of the mean errors
# ------------------------------------------------

def _sweep(at_minimum=True):
    rng = np.random.default_rng(3)
    out = {}
    for lv, scale in ((1.0, 0.01), (10.0, 0.1)):
        out[lv] = {"two_step": scale * (1.5 + rng.random(40)), "sqp": scale * (1.0 + rng.random(40)),
                   "sqp_at_minimum": np.full(40, at_minimum)}
    return out


def test_resilience_all_runs_gives_ratios_where_sqp_stopped_short():
    sw = _sweep(at_minimum=False)
    per_level, growth = resilience(sw, np.random.default_rng(0), n_boot=200)
    assert per_level["ratio"].isna().all() and np.isnan(growth["ratio"])
    per_level, growth = resilience(sw, np.random.default_rng(0), n_boot=200, all_runs=True)
    assert per_level["sqp_failed"].tolist() == [40, 40] and per_level["ratio"].notna().all()
    d_ours = sw[10.0]["two_step"].mean() - sw[1.0]["two_step"].mean()
    d_sqp = sw[10.0]["sqp"].mean() - sw[1.0]["sqp"].mean()
    assert growth["ratio"] == pytest.approx(d_ours / d_sqp) and growth["low"] < growth["ratio"] < growth["high"]
    assert growth["sqp_change"] == pytest.approx(d_sqp) and growth["two_step_change"] == pytest.approx(d_ours)
    assert growth["sqp_change_low"] < d_sqp < growth["sqp_change_high"]
    assert growth["two_step_change_low"] < d_ours < growth["two_step_change_high"]


def test_resilience_gives_the_changes_where_sqp_failed_without_a_growth_ratio():
    per_level, growth = resilience(_sweep(at_minimum=False), np.random.default_rng(0), n_boot=200)
    assert np.isnan(growth["ratio"]) and np.isfinite(growth["sqp_change_low"])
    assert growth["sqp_all_highest"] - growth["sqp_all_lowest"] == pytest.approx(growth["sqp_change"])


def test_resilience_where_sqp_converged_is_unchanged_by_all_runs():
    sw = _sweep(at_minimum=True)
    a = resilience(sw, np.random.default_rng(5), n_boot=100)
    b = resilience(sw, np.random.default_rng(5), n_boot=100, all_runs=True)
    pd.testing.assert_frame_equal(a[0], b[0])
    assert a[1] == b[1]


# ---- matching stop-short SQPs to Table I
# ------------------------------------------------------------------------

FAMILIES = {"early": {"start": "identity", "knob": "max_iterations", "grid": range(1, 13), "text": "{:g} it"},
            "tol": {"start": "identity", "knob": "ftol", "grid": [1e-3, 1e-1], "text": "ftol {:g}"}}


def _match(target, **kw):
    return match_to_table1(7, 6, target, motions={"Haar": None}, starts={"identity": None},
                           noise={"ball": "uniform"}, families=FAMILIES, **kw)


def test_match_to_table1_picks_the_grid_value_closest_to_the_target():
    matching, configs, keys = _match(0.05)
    early = matching.loc[("early", "Haar", "ball")]
    k = int(early["value"])
    assert 1 < k < 12 and early["knob"] == "max_iterations" and early["label"] == f"early: {k} it"
    for neighbour in (early["mean below"], early["mean above"]):           # no neighbour is closer on a log scale
        assert abs(np.log(neighbour / 0.05)) >= abs(np.log(early["SQP mean"] / 0.05))
    assert early["matched"] == (np.exp(abs(np.log(early["SQP mean"] / 0.05))) <= 1.25)
    # the configuration runs SQP stopped after k iterations: the same errors as the matching read
    # from the history
    from replication.core.so3 import frobenius_error
    from replication.core.solvers import sqp
    from replication.study.simulation import simulate
    sim = simulate(7, 6)
    if early["matched"]:
        assert configs[early["label"]] == ("analytic", {"max_iterations": k})
        assert ("Haar", "identity", "ball", early["label"]) in keys
    with pytest.warns(Warning):
        res = sqp(sim.A, sim.B, max_iterations=k)
    assert frobenius_error(res.R, sim.R0).mean() == pytest.approx(early["SQP mean"], rel=1e-9)
    tol = matching.loc[("tol", "Haar", "ball")]
    assert tol["knob"] == "ftol" and tol["value"] in (1e-3, 1e-1) and np.isnan(tol["mean below"] if
                                                                              tol["value"] == 1e-3 else
                                                                              tol["mean above"])


def test_match_to_table1_matches_within_the_factor_and_not_past_it():
    matching, _, _ = _match(0.05)
    mean = matching.loc[("early", "Haar", "ball"), "SQP mean"]
    factor = np.exp(abs(np.log(mean / 0.05)))
    m_in, configs_in, keys_in = _match(0.05, max_mismatch=factor * 1.001)
    m_out, configs_out, keys_out = _match(0.05, max_mismatch=factor * 0.999)
    assert m_in.loc[("early", "Haar", "ball"), "matched"] and not m_out.loc[("early", "Haar", "ball"), "matched"]
    label = m_in.loc[("early", "Haar", "ball"), "label"]
    assert label in configs_in and label not in configs_out
    assert len(keys_in) == len(keys_out) + 1


def test_matching_display_texts():
    idx = pd.MultiIndex.from_tuples([("early", "Haar", "ball"), ("far", "Haar", "ball")],
                                    names=["family", "motions", "noise"])
    matching = pd.DataFrame({"knob": ["max_iterations"] * 2, "value": [7, 1], "SQP mean": [0.01346, 2.7339],
                             "SQP SE": [0.0023, 0.0001], "SQP SD": [0.0282, 0.001], "mean below": [0.048, np.nan],
                             "mean above": [0.0058, 2.74], "two-step mean": [0.00654, 0.00654],
                             "matched": [True, False], "label": ["early: 7 iterations", "far: 1 iterations"]},
                            index=idx)
    out = matching_display(matching, 0.015)
    assert out.columns.name == "Table I: 0.015"
    assert out.loc[("early", "Haar", "ball")].tolist() == ["7 iterations", "0.0135 ± 0.0023", "0.028",
                                                           "0.0480 / 0.0058", "0.0065"]
    assert out.loc[("far", "Haar", "ball")].tolist() == ["no match (best: 1 iterations)", "2.73", "-", "-", "0.0065"]


# ---- problem sets, fresh seeds
# ----------------------------------------------------------------------------------

def test_problem_sets_groups_rows_on_the_same_problems_and_measures_their_differences():
    base = _sweep()
    shifted = {lv: {**d, "sqp": d["sqp"] + 2e-4} for lv, d in base.items()}
    sweeps = {("Haar", "identity", "ball", "a"): base, ("Haar", "identity", "ball", "b"): shifted,
              ("Haar", "far", "ball", "a"): base, ("Haar", "identity", "sphere", "a"): base,
              ("0-90", "identity", "ball", "a"): base}
    growth = pd.DataFrame({"ratio": [1.4, 1.41, 1.456, 1.3, 1.1], "low": [1.2] * 5, "high": [1.6] * 5},
                          index=pd.MultiIndex.from_tuples(list(sweeps)))
    sets = problem_sets(sweeps, growth)
    assert list(sets.index) == [("Haar", "ball"), ("Haar", "sphere"), ("0-90", "ball")]
    haar = sets.loc[("Haar", "ball")]
    assert haar["rows"] == 3 and haar["first"] == ("Haar", "identity", "ball", "a")
    assert haar["SQP difference"] == pytest.approx(2e-4) and haar["two-step difference"] == 0
    assert haar["growth ratio"] == "1.40 [1.20, 1.60]" and haar["growth ratios of the rows"] == "1.40-1.46"
    assert sets.loc[("Haar", "sphere"), "growth ratios of the rows"] == "1.30"


def test_variants_of_runs_exactly_the_given_rows():
    pick = variants_of([("Haar", "identity", "ball", "a"), ("Haar", "identity", "ball", "c"),
                        ("Haar", "far", "ball", "b")])
    assert pick("Haar", "identity", "ball") == ["a", "c"] and pick("Haar", "far", "ball") == ["b"]
    assert pick("0-90", "identity", "ball") == []


def test_confirmation_table_texts_a_bound_where_sqp_failed():
    cols = ["ratio", "low", "high", "sqp_change", "sqp_change_low", "sqp_change_high", "two_step_change",
            "two_step_change_low", "two_step_change_high"]
    idx = pd.MultiIndex.from_tuples([("H", "i", "b", "a"), ("H", "f", "b", "a")])
    found = pd.DataFrame([[1.43, 1.31, 1.57, 0.024, 0.022, 0.026, 0.035, 0.032, 0.038],
                          [np.nan] * 3 + [-0.0012, -0.0179, 0.0151, 0.0346, 0.0319, 0.0374]], index=idx, columns=cols)
    fresh = found.iloc[::-1] * 1.0
    out = confirmation_table(found, fresh)
    assert list(out.index) == list(fresh.index)
    assert out.loc[("H", "i", "b", "a")].tolist() == ["1.43 [1.31, 1.57]"] * 2 + ["0.024 [0.022, 0.026]"] * 2 + [
        "0.035 [0.032, 0.038]"]
    assert out.loc[("H", "f", "b", "a")].tolist() == ["-", "-", "within [-0.6, 0.6]", "within [-0.6, 0.6]",
                                                      "0.035 [0.032, 0.037]"]


def test_fig5_figure_leaves_out_variants_that_did_not_run_in_a_panel():
    per_level, _ = _synthetic()
    runs = {lv: {"sqp": np.array([lv, 3 * lv])} for lv in (1.0, 10.0)}
    sweeps = {("Haar", "identity", "ball", "analytic"): runs, ("0-90 deg", "identity", "ball", "stopped"): runs}
    fig = fig5_figure(per_level, sweeps, [1.0, 10.0], [("a", ("Haar", "identity", "ball")),
                                                       ("b", ("0-90 deg", "identity", "ball")),
                                                       ("c", ("Haar", "identity", "ball"))],
                      variants=(("analytic", "-"), ("stopped", ":")), title="t")
    a, b, c = fig.axes
    assert [t.get_text() for t in a.get_legend().get_texts()] == ["SQP (analytic), all runs", "ours, $R^r$"]
    assert [t.get_text() for t in b.get_legend().get_texts()] == ["SQP (stopped), all runs", "ours, $R^r$"]
    assert fig.get_suptitle() == "t" and fig.get_size_inches()[0] == pytest.approx(13.5)
    plt.close(fig)


def test_fig5_figure_shows_table1_beside_ours_and_says_why_only_there():
    per_level, _ = _synthetic()
    runs = {lv: {"sqp": np.array([lv, 3 * lv, lv])} for lv in (1.0, 10.0)}
    sweeps = {("Haar", "identity", "ball", "analytic"): runs}
    paper = pd.DataFrame({"mean": [0.009, 0.015, 0.5], "std": [0.004, 0.003, 0.1]},
                         index=pd.MultiIndex.from_tuples([(50, "ours_right"), (50, "optimization"), (2, "ours_right")]))
    fig = fig5_figure(per_level, sweeps, [1.0, 10.0], [("a", ("Haar", "identity", "ball"))], paper=paper)
    (ax,) = fig.axes
    assert ax.get_title() == "a\nN = 3 runs per point"
    stars = [c for c in ax.containers if c.get_label().startswith("the paper")]
    assert [c.get_label() for c in stars] == ["the paper, $R^r$: Table I, iteration 50 (mean ± SD)",
                                              "the paper, SQP: Table I, iteration 50 (mean ± SD)"]
    (x, y), = stars[0].lines[0].get_xydata()
    assert (x, y) == pytest.approx((0.88, 0.009)) and stars[0].lines[0].get_color() == "c"
    assert stars[1].lines[0].get_xydata()[0] == pytest.approx((1.12, 0.015)) and stars[1].lines[0].get_color() == "b"
    assert stars[1].lines[2][0].get_segments()[0][:, 1] == pytest.approx([0.012, 0.018])  # mean +- SD
    assert any("its Fig. 5 curves are not in the paper's text" in t.get_text() for t in fig.texts)
    plt.close(fig)
    fig = fig5_figure(per_level, sweeps, [1.0, 10.0], [("a", ("Haar", "identity", "ball"))])
    assert not any("Stars" in t.get_text() for t in fig.texts)
    assert not [c for c in fig.axes[0].containers if c.get_label().startswith("the paper")]
    plt.close(fig)


# ---- the evidence's texts and bounds
# ------------------------------------------------------------------------------------------

def test_span_text():
    from replication.study.fig5 import span_text

    assert span_text([1.104, 1.47]) == "1.10-1.47" and span_text([1.104, 1.1049]) == "1.10"
    assert span_text([-0.139, 0.0985]) == "-0.14 to 0.10" and span_text([7, 7], 0) == "7"


@pytest.mark.parametrize("low, high", [
    (-0.3086, 0.2698),  # the interval seen on one machine ...
    (-0.3076, 0.2879),  # ... and under other BLAS kernels: one bound for both
    (-0.4999, 0.4999),  # just inside the margin
    (0.0, 0.0),
])
def test_rounding_bound_is_the_declared_bound_whatever_the_ends(low, high):
    from replication.study.fig5 import rounding_bound

    assert rounding_bound(low, high) == "within [-0.6, 0.6]"


@pytest.mark.parametrize("low, high, end", [(-0.5001, 0.0, "lower end"), (0.0, 0.5001, "upper end")])
def test_an_end_within_the_margin_of_the_declared_bound_is_refused(low, high, end):
    from replication.study.fig5 import rounding_bound

    with pytest.raises(ValueError, match=f"failing SQP's change, {end}.*declare a wider one"):
        rounding_bound(low, high)


# ---- the growth ratio over motion ranges
# ------------------------------------------------------------------------------------------

def test_range_sweep_runs_both_two_step_variants_on_one_set_of_problems():
    from replication.study.fig5 import CONVERGED, range_sweep, range_table

    per_level, growth = range_sweep([1.0, 10.0], 12, 45000, np.random.default_rng(0),
                                    ranges={"0-30 deg": (0.0, 30.0), "0-90 deg": (0.0, 90.0)},
                                    stop_short={"0-30 deg": 50}, n_boot=50)
    assert list(growth.index) == [("0-30 deg", CONVERGED), ("0-30 deg", "50 iterations"), ("0-90 deg", CONVERGED)]
    # the same problems and SQP: only the two-step error differs between the variants of one range
    a, b = (per_level.loc[("0-30 deg", v)] for v in (CONVERGED, "50 iterations"))
    assert np.array_equal(a["sqp"], b["sqp"]) and not np.allclose(a["two_step"], b["two_step"])
    assert (a["two_step"] < b["two_step"]).all()  # stopped at 50 with small motions: farther from R0
    table = range_table(per_level, growth)
    assert list(table.columns) == ["SQP runs off the minimum", "two-step / SQP at 1 deg", "growth ratio"]
    with pytest.raises(ValueError, match="stop_short names ranges"):
        range_sweep([1.0, 10.0], 2, 1, np.random.default_rng(0), ranges={"a": None}, stop_short={"b": 50})
