"""Figures a reader can use alone: one fixed colour per solver, panels with titles, units, N per
point and intervals, labelled target lines, and a calibration figure that names its recording and
states R0, the radius and the reference, without empty panels."""
import math

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.colors import to_rgba

from replication.cli import main
from replication.core.solvers import _registry, available, register
from replication.rig.calibration import calibrate
from replication.rig.poses import calibrate_poses
from replication.rig.streams import GyroStream, OrientationStream
from replication.study import figures
from replication.study.figures import METHOD_STYLE, live_figure, method_style, sqp_config_style, sweep_figure
from replication.testing import RIG_R0, rig_streams, write_euroc_imu, write_tum_trajectory

matplotlib.use("Agg")
R0 = RIG_R0


def _drawn(ax) -> int:
    """The data an axes shows: lines, collections, patches, images, texts, error bars."""
    return len(ax.lines) + len(ax.collections) + len(ax.patches) + len(ax.images) + len(ax.texts) + len(ax.containers)


def _texts(fig) -> str:
    """Every text of a figure: its title, each axes' title, labels, texts, annotations and legend
    entries."""
    out = [fig.get_suptitle()] + [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()] + [t.get_text() for t in ax.texts]
        if ax.get_legend():
            out += [t.get_text() for t in ax.get_legend().get_texts()]
    return "\n".join(out)


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


# --------------------------------------------------------------------------- the calibration figure

@pytest.fixture(scope="module")
def rig():
    return rig_streams(30.0, sensor_step=1)[1:]


def _poses(rig):
    camera, _, sensor = rig
    return np.swapaxes(camera.R[::30], -1, -2), np.swapaxes(sensor.at(camera.t[::30]), -1, -2)


def test_calibration_figure_names_the_recording_and_states_r0_the_radius_and_the_reference(rig):
    camera, gyro, _ = rig
    r = calibrate(camera, gyro, n_bootstrap=20, reference=R0)
    fig = r.plot(name="my rig, run 3", reference_name="camchain.yaml")
    text = _texts(fig)
    assert fig.get_suptitle() == (f"my rig, run 3: R0 (camera_from_sensor) by chordal_optimal, {r.n_pairs} "
                                  f"pairs 1 s apart")
    q = ", ".join(f"{v:+.6f}" for v in r.quaternion_wxyz)
    assert f"R0: quaternion (w, x, y, z) = ({q}); yaw / pitch / roll (intrinsic z-y'-x'') = " in text
    assert " / ".join(f"{v:.3f}" for v in r.euler_zyx_deg) + " deg" in text
    assert f"95 % bootstrap radius {r.bootstrap_ci95_deg:.3g} deg (resampling pairs in moving blocks" in text
    assert "covers the pairs' own noise only" in " ".join(text.split())
    assert "reference (camchain.yaml): quaternion (w, x, y, z) = (" + q in text  # the reference is R0 itself
    assert "sensor clock offset d (ms; d > 0: the sensor clock reads ahead)" in text  # the offset's sign
    assert f"angle between R0 and it: {r.reference_error_deg:.3f} deg" in " ".join(text.split())
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert [t[:3] for t in titles] == ["(a)", "(b)", "(c)", "(d)", "(e)", "(f)"]
    assert titles[1].startswith("(b) clock offset") and titles[5] == "(f) verdict"
    assert "chosen: " in text and " ms" in text
    assert all(_drawn(ax) for ax in fig.axes)
    plt.close(fig)


def test_calibration_figure_of_a_pose_set_has_no_empty_panel_and_says_what_it_lacks(rig):
    C, S = _poses(rig)
    r = calibrate_poses(C, S, n_bootstrap=0)
    fig = r.plot()
    text = _texts(fig)
    assert fig.get_suptitle().startswith(f"calibration: R0 (camera_from_sensor) by chordal_optimal, {r.n_pairs} "
                                         "pairs of static poses")
    assert "reference: none given" in text and "95 % bootstrap radius: not available" in text
    assert "clock offset" not in text and "angular speed" not in text and "bootstrap estimates" not in text
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles[0] == "(a) residual by station" and titles[1] == "(b) residual of each station pair"
    assert titles[-1] == "(e) verdict"  # no bootstrap: no cloud panel, the letters follow on
    assert all(_drawn(ax) for ax in fig.axes)
    with_boot = calibrate_poses(C, S, n_bootstrap=10, reference=R0)
    fig = with_boot.plot()
    assert [ax.get_title() for ax in fig.axes if ax.get_title()][-2:] == ["(e) bootstrap estimates about R0",
                                                                           "(f) verdict"]
    assert all(_drawn(ax) for ax in fig.axes) and "reference: quaternion" in _texts(fig)
    plt.close("all")


def test_headline_without_a_finite_radius_or_a_reference_matrix(rig):
    import dataclasses

    from replication.rig.figure import headline

    C, S = _poses(rig)
    r = calibrate_poses(C, S, n_bootstrap=10, reference=R0)
    assert math.isfinite(r.bootstrap_ci95_deg)
    _, lines = headline(dataclasses.replace(r, bootstrap_ci95_deg=math.nan, inputs={}))
    assert lines[1].startswith("95 % bootstrap radius: not available")
    assert lines[2] == f"reference; angle between R0 and it: {r.reference_error_deg:.3f} deg"


def test_cli_names_the_recording_and_the_reference_file_in_the_figure(rig, tmp_path, monkeypatch):
    import replication.rig.figure as figure

    camera, gyro, _ = rig
    write_tum_trajectory(tmp_path / "room1_cam.txt", OrientationStream(camera.t + 1e3, camera.R, "c"))
    write_euroc_imu(tmp_path / "room1_imu.csv", GyroStream(gyro.t + 1e3, gyro.omega, "g"))
    T = np.eye(4)
    T[:3, :3] = R0
    (tmp_path / "camchain.yaml").write_text("cam0:\n  T_cam_imu:\n" + "".join(f"  - {row.tolist()}\n" for row in T))
    seen = {}

    def spy(result, **kwargs):
        seen.update(kwargs)
        return plt.figure()

    monkeypatch.setattr(figure, "calibration_figure", spy)
    args = ["calibrate", "--camera", tmp_path / "room1_cam.txt", "--sensor", tmp_path / "room1_imu.csv",
            "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", "--plot", tmp_path / "f.png"]
    assert main([str(a) for a in args]) in (0, 3)
    assert seen == {"name": "room1_cam + room1_imu", "reference_name": None}
    assert main([str(a) for a in args + ["--reference", tmp_path / "camchain.yaml"]]) in (0, 3)
    assert seen == {"name": "room1_cam + room1_imu", "reference_name": "camchain.yaml"}
    plt.close("all")


def test_the_offset_panel_is_zoomed_to_the_interval_with_the_full_search_in_an_inset(rig):
    """Issue 35.4: a sub-ms offset and its interval were invisible on a +-200 ms axis."""
    import dataclasses

    from replication.rig.figure import offset_zoom_ms

    camera, gyro, _ = rig
    r = calibrate(camera, gyro, n_bootstrap=0)
    euroc = dataclasses.replace(r, time_offset_s=-0.25e-3, time_offset_ci95_s=(-0.59e-3, 0.33e-3))
    assert offset_zoom_ms(euroc) == pytest.approx((-1.05, 0.79))
    narrow = dataclasses.replace(r, time_offset_ci95_s=(0.1e-3, 0.2e-3))  # 0.1 ms wide: widened to 0.5 ms
    assert offset_zoom_ms(narrow) == pytest.approx((-0.1, 0.4))
    fig = euroc.plot()
    (ax,) = [a for a in fig.axes if a.get_title().startswith("(b) clock offset")]
    assert ax.get_title() == "(b) clock offset, zoomed to its 95 % interval"
    assert ax.get_xlim() == pytest.approx((-1.05, 0.79))
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "95 % interval [-0.59, +0.33] ms" in legend and "0 (clocks agree): inside the interval" in legend
    (inset,) = ax.child_axes
    bound = 1e3 * r.parameters["max_offset_s"]
    assert inset.get_xlim()[0] <= -0.9 * bound and inset.get_xlim()[1] >= 0.9 * bound  # the full search
    assert "full search +-200 ms" in [t.get_text() for t in inset.texts]
    excluded = dataclasses.replace(r, time_offset_s=12.3e-3, time_offset_ci95_s=(12.1e-3, 12.5e-3)).plot()
    (ax,) = [a for a in excluded.axes if a.get_title().startswith("(b) clock offset")]
    assert "0 (clocks agree)" in [t.get_text() for t in ax.get_legend().get_texts()]  # 0 outside: no "inside"
    none = dataclasses.replace(r, time_offset_ci95_s=(math.nan, math.nan)).plot()
    (ax,) = [a for a in none.axes if a.get_title().startswith("(b) clock offset")]
    assert ax.get_title().endswith("(no finite interval: the full search)") and not ax.child_axes
    assert ax.get_xlim()[0] <= -bound and ax.get_xlim()[1] >= bound
    plt.close("all")
