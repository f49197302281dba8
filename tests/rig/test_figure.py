"""The diagnostic figure of a calibration (``replication.rig.figure``, through
``CalibrationResult.plot``): it names its recording and states R0, the radius and the reference,
has no empty panel and says what a pose set lacks, its headline without a finite radius or a
reference matrix, the names the command line passes it, and the offset panel zoomed to the
interval with the full search in an inset."""
import dataclasses
import math

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest

from conftest import _drawn, _texts
from replication.cli import main
from replication.rig.calibration import calibrate
from replication.rig.figure import headline, offset_zoom_ms
from replication.rig.poses import calibrate_poses
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import RIG_R0, rig_streams, write_euroc_imu, write_tum_trajectory

matplotlib.use("Agg")
R0 = RIG_R0


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
