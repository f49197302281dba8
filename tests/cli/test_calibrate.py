"""The ``calibrate`` command (``replication/cli/calibrate.py``): its options reach the library, its
help shows every default, its outputs are written in the format asked or a disk error is a message,
and the overlap error names its option."""
import json
import re
import subprocess
import sys
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from conftest import GT_HEADER, MAGIC, TUM_LINES, _calibrate, _disk_full, _run, _write, needs_real, write
from replication import _io
from replication.cli import main
from replication.core import so3
from replication.rig import live
from replication.rig import realdata as rd
from replication.rig.quality import EXIT_FAIL
from replication.rig.realdata import data_root
from replication.rig.streams import GyroStream, OrientationStream
from replication.testing import rig_motion, rig_streams, write_euroc_imu, write_tum_trajectory

SCHEMA = json.loads((Path(__file__).resolve().parents[2] / "docs" / "calibration_report.schema.json").read_text())


@pytest.mark.parametrize("flag, expected", [([], True), (["--no-gyro-bias"], False)])
def test_calibrate_online_passes_the_gyro_bias_switch_to_the_live_rig(tmp_path, monkeypatch, flag, expected):
    seen = {}
    real = live.replay

    def spy(*args, **kwargs):
        seen["gyro_bias"] = kwargs.get("gyro_bias")
        return real(*args, **kwargs)

    monkeypatch.setattr(live, "replay", spy)
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 30.0, 0.05)
    omega = np.column_stack([np.sin(1.3 * t), np.cos(0.7 * t), np.sin(0.9 * t + 1)])
    R = so3.cumulative_product(so3.matrix_from_rotation_vector(omega[:-1] * 0.05))
    R = np.concatenate([np.eye(3)[None], R])
    cam_file, imu_file = tmp_path / "cam.txt", tmp_path / "imu.csv"
    q = so3.quaternion_from_matrix(R)
    np.savetxt(cam_file, np.column_stack([t + 1e3, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    ts = np.arange(0.0, 30.0, 0.005)
    om = np.column_stack([np.sin(1.3 * ts), np.cos(0.7 * ts), np.sin(0.9 * ts + 1)]) + rng.normal(0, 1e-3, (len(ts), 3))
    np.savetxt(imu_file, np.column_stack([np.round((ts + 1e3) * 1e9), om, np.zeros((len(ts), 3))]),
               fmt=["%d"] + ["%.9f"] * 6, delimiter=",")
    main(["calibrate", "--camera", str(cam_file), "--sensor", str(imu_file), "--sensor-kind", "gyro", "--online",
          "--bootstrap", "0", "--quiet", *flag])
    assert seen["gyro_bias"] is expected

# -------------------------------------------------------------------------------------------
# the help, the outputs written, the overlap named with the option (the synthetic rig's files:
# tests/conftest.py)

def test_calibrate_help_shows_every_default_the_solvers_the_formats_and_an_example():
    import argparse

    from replication.cli.calibrate import add_parser
    from replication.core.solvers import available

    out = _run("calibrate", "--help")
    assert out.returncode == 0, out.stderr
    text = " ".join(out.stdout.split())
    for name in available():
        assert name in text
    assert "chordal_optimal (default)" in text and "{solvers}" not in text
    for fmt in ("TUM / ORB-SLAM3 trajectory", "EuRoC / TUM-VI mocap", "imu0/data.csv", "cali.txt", "Kalibr camchain"):
        assert fmt in text
    assert "Examples: # an ORB-SLAM3" in text and "python -m replication calibrate --camera" in text
    for shown in ("--interval INTERVAL seconds between the two poses of a pair (default: 1.0)",
                  "--bootstrap BOOTSTRAP bootstrap replicates (0: none) (default: 200)",
                  "(default: chordal_optimal)", "--accept exit 0 even when the verdict is fail (default: off)"):
        assert shown in text
    # every option's help, as the formatter shows it, names its default
    cal = add_parser(argparse.ArgumentParser().add_subparsers())
    formatter = cal._get_formatter()
    options = [a for a in cal._actions if a.option_strings and a.dest != "help" and not a.required]
    assert len(options) == 25  # all but --camera and --sensor (required: no default)
    for action in options:
        assert "default" in formatter._get_help_string(action), action.option_strings
    # an option without a default whose help does not say so gets no "(default: None)": its help
    # must say it
    bare = cal.add_argument("--x-none", help="no default said")
    assert formatter._get_help_string(bare) == "no default said"


@pytest.mark.parametrize("name", ["fig.png", "fig.pdf", "fig.svg", "FIG.PDF"])
def test_plot_writes_the_format_its_extension_names(files, tmp_path, name, capsys):
    fig = tmp_path / "out" / name
    assert _calibrate(files, "--plot", fig) == 0, capsys.readouterr().err
    data = fig.read_bytes()
    assert data.startswith(MAGIC[fig.suffix.lower()]), data[:20]
    assert not list(fig.parent.glob("*.part"))


@pytest.mark.parametrize("option, name", [("--out", "r.json"), ("--plot", "f.pdf"), ("--track", "t.csv")])
def test_a_disk_error_while_writing_an_output_is_a_message(files, tmp_path, option, name, monkeypatch, capsys):
    """The write itself fails (a full disk), after the checks passed: exit 2 naming the output and
    the reason."""
    import replication.cli.calibrate as cli

    monkeypatch.setattr(cli, "write_atomic", _disk_full)
    monkeypatch.setattr(_io, "write_atomic", _disk_full)  # CalibrationResult.plot's
    target = tmp_path / name
    extra = ("--online",) if option == "--track" else ()
    assert _calibrate(files, *extra, option, target) == 2
    err = capsys.readouterr().err
    assert f"{option} {target}: cannot write (No space left on device)" in err and "Traceback" not in err, err
    assert not target.exists()


def test_the_cli_names_its_max_offset_option(files, capsys):
    assert _calibrate(files, "--max-offset", "100") == 2
    err = capsys.readouterr().err
    assert "--max-offset 100 s is larger than the overlap allows" in err and "camera 40.0 s" in err, err
    assert "e+09" not in err and "max_offset" not in err


def _cli_process(*args):
    return subprocess.run([sys.executable, "-m", "replication", "calibrate", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@needs_real
def test_cli_round_trip_on_the_shared_files(tmp_path):
    d = rd.data_root() / "tumvi_room1_orbslam3mono"
    out = _cli_process("--camera", d / "orbslam3_mono_cam0_traj.txt", "--sensor", d / "imu0_data.csv", "--sensor-kind",
               "gyro", "--method", "two_step_left", "--bootstrap", "20", "--reference", d / "camchain.yaml",
               "--out", tmp_path / "report.json")
    assert out.returncode == 0, out.stderr
    assert "angle to the reference" in out.stdout
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["method"] == "two_step_left" and report["reference_error_deg"] < 0.2
    R = np.array(report["R0_camera_from_sensor"])
    assert so3.angle_between_deg(R, rd.load_reference(d / "camchain.yaml")) < 0.2


def test_cli_rejects_a_malformed_file_and_writes_nothing(tmp_path):
    cam = write(tmp_path, "cam.txt", TUM_LINES + ["1520530313399738752.0 0 0 0 0 0 0"])
    out = _cli_process("--camera", cam, "--sensor", cam, "--out", tmp_path / "report.json")
    assert out.returncode == 2
    assert "cam.txt, line 5: expected 8 columns" in out.stderr
    assert not (tmp_path / "report.json").exists()


def test_cli_help_explains_the_formats():
    out = _cli_process("--help")
    assert out.returncode == 0 and "t tx ty tz qx qy qz qw" in out.stdout and "T_cam_imu" in out.stdout


def _cli_files(tmp_path, angle_deg):
    """A camera TUM trajectory and a 17-column ground truth of the same rig, the latter with one
    time stamp repeated with a pose ``angle_deg`` away."""
    t = 1403636580.0 + np.arange(0.0, 40.0, 0.05)
    R = rig_motion(t)  # the synthetic rig's motion
    q = so3.quaternion_from_matrix(R)
    cam = tmp_path / "cam.txt"
    np.savetxt(cam, np.column_stack([t, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    Q = R @ so3.matrix_from_rotation_vector(np.array([0.3, -0.2, 0.5]))  # world_from_sensor
    rows = [[int(round(tk * 1e9)), 0.0, 0.0, 0.0, *qk, *([0.0] * 9)] for tk, qk in zip(t,
                                                                                       so3.quaternion_from_matrix(Q))]
    twin = list(rows[100])
    twin[4:8] = so3.quaternion_from_matrix(so3.matrix_from_rotation_vector(np.radians([0.0, 0.0, angle_deg])) @ Q[100])
    gt = _write(tmp_path / "data.csv", GT_HEADER, rows[:101] + [twin] + rows[101:])
    return cam, gt


def test_cli_refuses_repeats_naming_repeated_and_counts_them_when_read(tmp_path, capsys):
    cam, gt = _cli_files(tmp_path, 3.0)
    base = ["calibrate", "--camera", str(cam), "--sensor", str(gt), "--bootstrap", "10", "--quiet"]
    assert main(base) == 2
    err = capsys.readouterr().err
    assert "data.csv, line 103" in err and "--repeated keep-first|keep-last|mean" in err
    out = tmp_path / "r.json"
    assert main(base + ["--repeated", "keep-first", "--out", str(out)]) == 0
    assert "--sensor: 1 lines repeat an earlier line's time stamp (1 time stamps, poses up to 3 deg apart)" in (
        capsys.readouterr().out)
    cli = json.loads(out.read_text())["cli"]
    assert cli["repeated"] == "keep-first"
    assert cli["repeats"]["sensor"]["repeated_timestamps"] == 1
    assert cli["repeats"]["sensor"]["repeated_max_deg"] == pytest.approx(3.0, abs=1e-4)
    assert cli["repeats"]["camera"]["repeated_timestamps"] == 0


def test_cli_names_a_ground_truth_given_as_gyro(tmp_path, capsys):
    cam, gt = _cli_files(tmp_path, 0.0)
    assert main(["calibrate", "--camera", str(cam), "--sensor", str(gt), "--sensor-kind", "gyro", "--quiet"]) == 2
    assert "looks like an orientation stream" in capsys.readouterr().err


# -------------------------------------------------------------------------------------------
# a calibration through the command line: its report and figure, the exit code of a fail, bad
# numbers and outputs refused before the work (the synthetic rig of tests/rig/test_calibration.py,
# 60 s, noise-free), and the real recordings end to end


@pytest.fixture(scope="module")
def rig():
    """``(camera, gyro, sensor)`` of the synthetic rig (:func:`replication.testing.rig_streams`),
    noise-free, 60 s."""
    return rig_streams(60.0, phase=0.0)[1:]


@pytest.fixture(scope="module")
def rig_files(rig, tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    camera, gyro, _ = rig
    shifted = OrientationStream(camera.t + 1e3, camera.R, "c")  # EuRoC-like absolute times
    write_tum_trajectory(d / "cam.txt", shifted)
    write_euroc_imu(d / "imu.csv", GyroStream(gyro.t + 1e3, gyro.omega, "g"))
    write_euroc_imu(d / "imu_deg.csv", GyroStream(gyro.t + 1e3, np.degrees(gyro.omega) / 10, "g"))  # slow deg/s
    return d


def _cli(*args):
    return main(["calibrate", *map(str, args), "--bootstrap", "20", "--quiet"])


def test_cli_ok_writes_a_valid_report_and_figure(rig_files, tmp_path):
    out, fig = tmp_path / "new" / "deeper" / "r.json", tmp_path / "new" / "r.png"
    assert _cli("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu.csv", "--sensor-kind", "gyro",
                "--out", out, "--plot", fig, "--stride", 2, "--seed", 3) == 0
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["files"]["camera"]["sha256"] and report["parameters"]["stride"] == 2
    assert report["parameters"]["seed"] == 3 and fig.stat().st_size > 1000


def test_cli_fail_exits_3_unless_accepted(rig_files, tmp_path, capsys):
    args = ("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu_deg.csv", "--sensor-kind", "gyro")
    assert _cli(*args, "--out", tmp_path / "r.json") == EXIT_FAIL
    captured = capsys.readouterr()
    assert "verdict: FAIL" in captured.out and "exit code 3" in captured.err
    assert json.loads((tmp_path / "r.json").read_text())["verdict"]["level"] == "fail"  # the report is still written
    assert _cli(*args, "--accept") == 0


@pytest.mark.parametrize("extra, message", [
    (("--interval", "0"), "must be > 0"),
    (("--interval", "nan"), "not finite"),
    (("--stride", "0"), "must be >= 1"),
    (("--stride", "1.5"), "not an integer"),
    (("--bootstrap", "-1"), "must be >= 0"),
    (("--max-offset", "-0.1"), "must be > 0"),
    (("--seed", "x"), "not an integer"),
])
def test_cli_bad_numbers_exit_2_naming_the_option(rig_files, extra, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["calibrate", "--camera", str(rig_files / "cam.txt"), "--sensor", str(rig_files / "imu.csv"), *extra])
    assert exit_.value.code == 2  # a usage error
    stderr = capsys.readouterr().err
    assert extra[0] in stderr and message in stderr


@pytest.mark.parametrize("case", ["directory", "under a file", "unknown method", "csv in a wrong unit", "empty",
                                  "trailing slash"])
def test_cli_bad_output_or_options_exit_2_before_the_work_leaving_nothing(rig_files, tmp_path, case, capsys,
                                                                          monkeypatch):
    import replication.rig.calibration as cal

    monkeypatch.setattr(cal, "offset_analysis", lambda *a, **k: pytest.fail("work started"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    extra = {"directory": ("--out", tmp_path), "under a file": ("--out", blocker / "r.json"),
             "unknown method": ("--method", "nope"), "csv in a wrong unit": ("--sensor-time-unit", "ms"),
             "empty": ("--out", ""), "trailing slash": ("--out", str(tmp_path / "newdir") + "/")}[case]
    sensor_kind = ("--sensor-kind", "gyro")
    assert _cli("--camera", rig_files / "cam.txt", "--sensor", rig_files / "imu.csv", *sensor_kind, *extra) == 2
    assert "error:" in capsys.readouterr().err
    assert not list(tmp_path.glob("*.part")) and sorted(p.name for p in tmp_path.iterdir()) == ["file"]


@needs_real
def test_cli_robot_pose_sets_calibrate(tmp_path):
    d = data_root() / "tabb_rwhe_ds1"
    out = tmp_path / "tabb.json"
    assert _cli("--poses", "--camera", d / "cali.txt", "--sensor", d / "robot_cali.txt", "--reference",
                d / "transformations.txt", "--out", out) == 0
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["reference_error_deg"] < 1.0 and report["interval_s"] is None
    assert report["inputs"]["camera"]["kind"] == "static poses"


@needs_real
def test_cli_euroc_with_repeated_lines(tmp_path):
    d = data_root() / "euroc_mh01_orbslam3"
    out = tmp_path / "euroc.json"
    args = ("--camera", d / "orbslam3_mono_cam0_traj_runB.txt", "--sensor", d / "gt_body_MH_01_easy_tum.txt",
            "--reference", d / "euroc_cam0_sensor.yaml", "--out", out)
    assert _cli(*args) == 2  # repeated lines are an error unless dropped
    assert _cli(*args, "--drop-repeated") == 0
    assert json.loads(out.read_text())["reference_error_deg"] < 0.5


@needs_real
@pytest.mark.filterwarnings("ignore::replication.core.solvers.ConvergenceWarning")
def test_cli_sqp_on_tumvi_fails_instead_of_answering_170_deg_off(tmp_path, capsys):
    d = data_root() / "tumvi_room1_orbslam3mono"
    code = _cli("--camera", d / "orbslam3_mono_cam0_traj.txt", "--sensor", d / "imu0_data.csv", "--sensor-kind",
                "gyro", "--method", "sqp", "--bootstrap", "0", "--no-gyro-bias")  # the rates as recorded: SQP's trap
    out = capsys.readouterr().out
    assert code == EXIT_FAIL and "away from the certified optimum of eq. (8)" in out
    assert "use the default method chordal_optimal" in out and "LocalMinimumWarning" not in out.split("R0 (")[0]


@needs_real
def test_cli_two_step_left_on_euroc_names_the_near_single_axis_motion_not_the_warning(tmp_path, capsys):
    """Issue 35.3: README's former example. The verdict says why the iteration hit its cap (sigma_2
    / sigma_1 of K 0.9975 > 0.9863 at axis spread 3.2 deg) and what to do; the class stays in the
    report's warnings."""
    d = data_root() / "euroc_mh01_orbslam3"
    out = tmp_path / "euroc.json"
    code = _cli("--camera", d / "orbslam3_mono_cam0_traj_runA.txt", "--sensor", d / "gt_body_MH_01_easy_tum.txt",
                "--method", "two_step_left", "--bootstrap", "0", "--out", out)
    text = capsys.readouterr().out
    verdict = text.split("R0 (")[0]
    assert code == 0 and "IterationCapWarning" not in verdict
    assert "sigma_2 / sigma_1 of K 0.997" in verdict and "> 0.9863" in verdict and "camera axis spread 3.2" in verdict
    assert "use the default method chordal_optimal" in verdict
    report = json.loads(out.read_text())
    assert any(w.startswith("IterationCapWarning") for w in report["warnings"])
    (reason,) = [r for r in report["verdict"]["reasons"] if r["check"] == "solver_warning"]
    assert reason["measured"] > reason["threshold"] == pytest.approx(0.98627, abs=1e-5)

def test_a_gyro_csv_in_seconds_is_refused_naming_the_option_that_then_reads_it(tmp_path, capsys):
    """Float-second stamps in an EuRoC-format gyro CSV: refused as ns (exit 2) naming
    ``--sensor-time-unit s``, which reads them to the R0 of the same file in ns."""
    import json

    from replication.rig.streams import GyroStream, OrientationStream
    from replication.testing import rig_streams, write_euroc_imu, write_tum_trajectory

    _, camera, gyro, _ = rig_streams(30.0, rng=np.random.default_rng(5), camera_noise_deg=0.05, gyro_noise_deg_s=0.2)
    epoch = 1520530308.0
    write_tum_trajectory(tmp_path / "cam.txt", OrientationStream(camera.t + epoch, camera.R, "c"))
    write_euroc_imu(tmp_path / "ns.csv", GyroStream(gyro.t + epoch, gyro.omega, "g"))
    lines = (tmp_path / "ns.csv").read_text().splitlines()
    seconds = [lines[0]] + [f"{int(t) // 10**9}.{int(t) % 10**9:09d},{rest}"
                            for t, rest in (line.split(",", 1) for line in lines[1:])]
    (tmp_path / "s.csv").write_text("\n".join(seconds) + "\n")

    def run(sensor, *extra):
        return main(["calibrate", "--camera", str(tmp_path / "cam.txt"), "--sensor", str(tmp_path / sensor),
                     "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", "--out", str(tmp_path / f"{sensor}.json"),
                     *extra])

    assert run("s.csv") == 2
    assert re.search(r"the time stamp [0-9.]+ has a fraction: not nanoseconds", capsys.readouterr().err)
    assert run("s.csv", "--sensor-time-unit", "s") == 0 and run("ns.csv") == 0
    R = [np.array(json.loads((tmp_path / f"{name}.json").read_text())["R0_camera_from_sensor"])
         for name in ("s.csv", "ns.csv")]
    assert so3.rotation_angle_deg(R[0].T @ R[1]) < 1e-3
