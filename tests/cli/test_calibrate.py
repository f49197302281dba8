"""The ``calibrate`` command (``replication/cli/calibrate.py``): its options reach the library, its
help shows every default, its outputs are written in the format asked or a disk error is a message,
and the overlap error names its option."""
import json
import subprocess
import sys

import numpy as np
import pytest

from conftest import GT_HEADER, MAGIC, TUM_LINES, _calibrate, _disk_full, _run, _write, needs_real, write
from replication import _io
from replication.cli import main
from replication.core import so3
from replication.rig import live
from replication.rig import realdata as rd
from replication.testing import rig_motion


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


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "replication", "calibrate", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@needs_real
def test_cli_round_trip_on_the_shared_files(tmp_path):
    d = rd.data_root() / "tumvi_room1_orbslam3mono"
    out = _cli("--camera", d / "orbslam3_mono_cam0_traj.txt", "--sensor", d / "imu0_data.csv", "--sensor-kind",
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
    out = _cli("--camera", cam, "--sensor", cam, "--out", tmp_path / "report.json")
    assert out.returncode == 2
    assert "cam.txt, line 5: expected 8 columns" in out.stderr
    assert not (tmp_path / "report.json").exists()


def test_cli_help_explains_the_formats():
    out = _cli("--help")
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
