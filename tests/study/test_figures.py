"""The notebooks' figures (``replication.study.figures``), each one a reader can use alone: one
fixed colour per solver, panels with titles, units, N per point and intervals, labelled target
lines. The calibration's diagnostic figure: tests/rig/test_figure.py."""
import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba

from conftest import _drawn, _texts
from replication.core.solvers import _registry, available, register
from replication.study import figures
from replication.study.figures import METHOD_STYLE, live_figure, method_style, sqp_config_style, sweep_figure

matplotlib.use("Agg")


# ---------------------------------------------------------------------------- one colour per solver

def test_every_registered_solver_has_its_own_colour_and_the_papers_names_share_their_solvers():
    colours = {name: to_rgba(METHOD_STYLE[name]["color"]) for name in available()}  # KeyError: a solver without one
    assert len(set(colours.values())) == len(colours)
    for paper_name, solver in (("ours_right", "two_step_right"), ("ours_left", "two_step_left"),
                               ("optimization", "sqp")):
        assert method_style(paper_name)["color"] == method_style(solver)["color"]
    # the paper's Fig. 7 describes its projections as cyan, magenta and blue
    assert [figures.FIG7_STYLE[m]["color"] for m in ("ours_right", "ours_left", "optimization")] == ["c", "m", "b"]
    # SQP's configurations are SQP: its colour
    assert {method_style(k)["color"] for k in METHOD_STYLE if k.startswith("optimization")} == {"b"}
    assert sqp_config_style("stopped early: 7 iterations") == {"color": "b", "ls": ":", "marker": "D"}
    assert sqp_config_style("something new")["marker"] == "*"


def _sweeps(methods, n=100, sd=0.1):
    rows = [{"parameter": p, "value": v, "method": m, "mean_deg": 0.5 * v + 0.1 * k, "sd_deg": sd, "n_solved": n}
            for p in ("noise_deg", "n_motions", "outlier_fraction") for v in (1.0, 2.0)
            for k, m in enumerate(methods)]
    return pd.DataFrame(rows)


def _bar_ends(fig, method) -> tuple:
    """The lower and upper end of ``method``'s first error bar in the first panel."""
    bars = {c.get_label(): c for c in fig.axes[0].containers}[method]
    return tuple(bars.lines[2][0].get_segments()[0][:, 1])


def _line_colours(fig) -> dict:
    ax = fig.axes[0]
    return {c.get_label(): to_rgba(c.lines[0].get_color()) for c in ax.containers}


def test_adding_a_solver_keeps_every_other_solvers_colour(monkeypatch):
    before = {name: method_style(name) for name in available()}
    old = _line_colours(sweep_figure(_sweeps(available())))
    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    register("a_new_baseline", reference="test")(lambda motions, **_: motions.A[..., 0, :, :])
    assert "a_new_baseline" in available()
    assert {name: method_style(name) for name in before} == before
    new = _line_colours(sweep_figure(_sweeps(["a_new_baseline", *before])))
    assert {label: new[label] for label in old} == old  # the same colours, though a solver came first
    known = {to_rgba(s["color"]) for s in METHOD_STYLE.values()}
    assert new[method_style("a_new_baseline")["label"]] not in known  # an unknown name takes a spare colour
    assert method_style("a_new_baseline") == method_style("a_new_baseline")  # fixed by its name
    plt.close("all")


# ------------------------------------------------------------------------------------------------
# the sweep panels

def test_sweep_panels_have_titles_units_n_per_point_and_intervals():
    df = _sweeps(["chordal_optimal", "two_step_right"], n=100, sd=0.5)
    df.loc[(df["parameter"] == "n_motions") & (df["method"] == "chordal_optimal") & (df["value"] == 2.0),
           "n_solved"] = 97
    fig = sweep_figure(df)
    assert len(fig.axes) == 3 and all(_drawn(ax) for ax in fig.axes)  # the fourth slot is removed, not left empty
    titles = [ax.get_title() for ax in fig.axes]
    assert titles == ["(a) against the noise: N = 100 problems per point",
                      "(b) against the number of motion pairs: N = 97-100 problems per point",
                      "(c) against outlier pairs: N = 100 problems per point"]
    assert fig.axes[0].get_xlabel() == "noise bound on each rotation (deg)" and "(deg)" in fig.axes[0].get_ylabel()
    assert "95 % interval of the mean" in fig.axes[0].get_ylabel()
    # chordal_optimal at 1 deg: mean 0.5, half-width 1.96 * 0.5 / 10 = 0.098 (below the mean: drawn
    # whole)
    low, high = _bar_ends(fig, "chordal_optimal")
    assert (low, high) == pytest.approx((0.5 - 0.098, 0.5 + 0.098))
    # a half-width above the mean is cut just above 0 (log scale), the upper end kept
    fig = sweep_figure(_sweeps(["chordal_optimal"], n=4, sd=1.0))  # mean 0.5, half-width 0.98
    low, high = _bar_ends(fig, "chordal_optimal")
    assert low == pytest.approx(0.5 * 0.001) and high == pytest.approx(1.48)
    assert fig.axes[0].get_ylim()[0] > 10 * low  # it runs off the bottom: the axis is set by the other ends
    fig = sweep_figure(_sweeps(["chordal_optimal"], n=4, sd=0.5))  # half-width 0.49, just below the mean
    low, _ = _bar_ends(fig, "chordal_optimal")
    assert low == pytest.approx(0.01) and fig.axes[0].get_ylim()[0] < 0.01  # drawn whole
    plt.close("all")


def test_live_figure_labels_its_target_lines_and_names_each_recording():
    t = np.arange(30.0)
    track = pd.DataFrame({"t": t, "n_pairs": np.arange(1, 31), "error_deg": np.linspace(1, 0.1, 30),
                          "radius_deg": np.linspace(2, 0.2, 30)})
    fig = live_figure({"rig A": (track, {"ready_t": 12.0, "error_at_ready_deg": 0.5})}, (0.5, 0.2))
    text = _texts(fig)
    assert "target 0.5 deg" in text and "target 0.2 deg" in text and "rig A: 30 pairs" in text
    assert "VINS-Mono rule: done,\n0.50 deg off" in text and fig.axes[0].get_ylabel() == "angle (deg)"
    plt.close(fig)
