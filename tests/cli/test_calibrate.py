"""The ``calibrate`` command (``replication/cli/calibrate.py``): its options reach the library, its
help shows every default, its outputs are written in the format asked or a disk error is a message,
and the overlap error names its option."""
import numpy as np
import pytest

from conftest import MAGIC, _calibrate, _disk_full, _run
from replication import _io
from replication.cli import main
from replication.core import so3
from replication.rig import live


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
