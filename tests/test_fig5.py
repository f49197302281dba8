import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from replication.core.stats import share_range
from replication.study.fig5 import (
    fig5_figure,
    noise_sweep,
    ratio_range,
    resilience,
    sqp_configs_for,
    summary_table,
    sweep_grid,
    two_step_growth,
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
    assert left.get_title() == "left" and right.get_title() == "right" and left.get_yscale() == "log"
    bars = left.containers[0]                                                   # ours: mean with +- 1.96 SE bars
    assert bars.lines[0].get_ydata().tolist() == [0.01, 0.1]
    segments = bars.lines[2][0].get_segments()
    assert segments[0][:, 1] == pytest.approx([0.01 - 1.96e-3, 0.01 + 1.96e-3])
    sqp_a, sqp_c = [line for line in left.lines if line.get_label().startswith("SQP")]
    assert sqp_a.get_ydata() == pytest.approx([2.0, 20.0]) and sqp_c.get_linestyle() == ":"
    assert [t.get_text() for t in left.get_legend().get_texts()] == ["SQP (analytic), all runs",
                                                                     "SQP (capped), all runs", "ours, $R^r$"]
    assert fig._suptitle.get_text() == "Fig. 5 (replicated)"
    plt.close(fig)
