import os
import subprocess
import sys

import nbformat
import pytest


def test_reproduce_executes_notebooks_in_order_and_writes_results(tmp_path):
    nbdir, results = tmp_path / "nb", tmp_path / "results"
    nbdir.mkdir()
    for name, code in [
        ("01_a.ipynb", "from replication.study.notebook import save_table\nimport pandas as pd\n"
                       "save_table(pd.DataFrame({'x': [1]}), 'first')"),
        ("02_b.ipynb", "from replication.study.notebook import results_dir\n"
                       "assert (results_dir() / 'tables' / 'first.csv').exists()\nprint('ok')"),
    ]:
        nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(code)])
        nb.metadata["kernelspec"] = {"name": "someone-elses-kernel", "display_name": "x", "language": "python"}
        nbformat.write(nb, nbdir / name)
    out = subprocess.run(
        [sys.executable, "-m", "replication", "reproduce", "--notebooks", str(nbdir), "--results", str(results)],
        capture_output=True, text=True, timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert (results / "tables" / "first.csv").exists() and (results / "tables" / "first.md").exists()
    nb = nbformat.read(nbdir / "02_b.ipynb", as_version=4)
    assert nb.cells[0].outputs[0]["text"] == "ok\n"  # executed in place, outputs stored
    assert nb.metadata["kernelspec"]["name"] == "python3"  # kernelspec normalised


def test_reproduce_without_notebooks_fails_clearly(tmp_path):
    out = subprocess.run([sys.executable, "-m", "replication", "reproduce", "--notebooks", str(tmp_path)],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode != 0 and "no numbered notebooks" in out.stderr


def test_reproduce_skips_notebooks_that_need_absent_real_data(tmp_path):
    nbdir = tmp_path / "nb"
    nbdir.mkdir()
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("raise SystemExit('must not run')")])
    nb.metadata["replication"] = {"requires_real_data": True}
    nbformat.write(nb, nbdir / "01_real.ipynb")
    env = {**os.environ, "REPLICATION_REAL_DATA": str(tmp_path / "nowhere")}
    out = subprocess.run([sys.executable, "-m", "replication", "reproduce", "--notebooks", str(nbdir),
                          "--results", str(tmp_path / "results")], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert "skipping 01_real.ipynb" in out.stdout and "nowhere" in out.stdout


def test_generate_lab_writes_a_loadable_recording(tmp_path, capsys):
    """(That the committed data/lab equal the generator's output is tests/test_lab.py's check.)"""
    from replication.__main__ import main
    from replication.study.lab import load_lab

    assert main(["generate-lab", "--out", str(tmp_path / "a"), "--seed", "7"]) == 0
    assert "seed 7" in capsys.readouterr().out
    rec = load_lab(tmp_path / "a")
    assert rec.truth["camera_from_sensor"].shape == (3, 3)
    assert main(["generate-lab", "--out", str(tmp_path / "b"), "--seed", "8"]) == 0
    assert (tmp_path / "a" / "static_imu.csv").read_text() != (tmp_path / "b" / "static_imu.csv").read_text()


# ------------------------------------------------------------------- a rig user's command line (issue 24, part 4)

def _run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "replication", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


def test_version_prints_the_package_version():
    from replication._version import __version__

    out = _run("--version")
    assert out.returncode == 0 and out.stdout == f"replication {__version__}\n"


def test_calibrate_help_shows_every_default_the_solvers_the_formats_and_an_example():
    import argparse

    from replication.core.solvers import available
    from replication.rig.calibrate_cli import add_parser

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
    # an option without a default whose help does not say so gets no "(default: None)": its help must say it
    bare = cal.add_argument("--x-none", help="no default said")
    assert formatter._get_help_string(bare) == "no default said"


def _imu_like_csv(path, n_columns, rows=4):
    """``rows`` lines of ``n_columns`` comma-separated numbers after a ``#`` header (EuRoC / TUM-VI style): time in
    ns, then zeros with a unit quaternion where an orientation line (8 columns) has it."""
    import numpy as np

    body = np.zeros((rows, n_columns - 1))
    if n_columns >= 8:
        body[:, 3] = 1.0  # q_w of t, p_xyz, q_wxyz
    np.savetxt(path, np.column_stack([1e12 + 5e6 * np.arange(rows), body]), fmt="%.0f", delimiter=",",
               header=",".join(f"c{k}" for k in range(n_columns)))
    return path


@pytest.mark.parametrize("kind, n_columns, hint", [
    ("orientation", 6, None),
    ("orientation", 7, "looks like a gyro / IMU stream (t, wx, wy, wz, ax, ay, az: EuRoC / TUM-VI imu0/data.csv); "
                       "give --sensor-kind gyro"),
    ("orientation", 9, None),
    ("gyro", 6, None),
    ("gyro", 8, "looks like an orientation stream (t, px, py, pz, qw, qx, qy, qz: EuRoC / TUM-VI mocap or ground "
                "truth); leave out --sensor-kind gyro"),
    ("gyro", 9, None),
    ("gyro", 17, "looks like an orientation stream (t, px, py, pz, qw, qx, qy, qz: EuRoC / TUM-VI mocap or ground "
                 "truth); leave out --sensor-kind gyro"),  # EuRoC's state_groundtruth_estimate0/data.csv
])
def test_a_sensor_file_of_the_other_kind_names_the_option(tmp_path, capsys, kind, n_columns, hint):
    from replication.__main__ import main

    camera = tmp_path / "cam.txt"
    camera.write_text("".join(f"{t} 0 0 0 0 0 0 1\n" for t in range(4)))
    sensor = _imu_like_csv(tmp_path / "data.csv", n_columns)
    expected = "8 or 17" if kind == "orientation" else 7  # 17: EuRoC's ground truth as shipped
    assert main(["calibrate", "--camera", str(camera), "--sensor", str(sensor), "--sensor-kind", kind]) == 2
    err = capsys.readouterr().err
    assert f"data.csv, line 2: expected {expected} columns" in err and f"got {n_columns}" in err
    assert (hint in err) if hint else ("looks like" not in err and "--sensor-kind" not in err)


def test_the_files_of_the_hints_are_what_they_are_said_to_look_like(tmp_path):
    """The control of the hints: the 7-column file loads as a gyro, the 8-column one as orientations."""
    from replication.rig.realdata import load_stream

    assert load_stream(_imu_like_csv(tmp_path / "imu.csv", 7), "gyro").omega.shape == (4, 3)
    assert load_stream(_imu_like_csv(tmp_path / "pose.csv", 8), "orientation").R.shape == (4, 3, 3)


def test_an_imu_file_given_as_the_camera_says_where_it_goes(tmp_path, capsys):
    from replication.__main__ import main

    imu = _imu_like_csv(tmp_path / "data.csv", 7)
    assert main(["calibrate", "--camera", str(imu), "--sensor", str(imu), "--sensor-kind", "gyro"]) == 2
    assert "--camera takes the camera's orientations; a gyro goes to --sensor with --sensor-kind gyro" in (
        capsys.readouterr().err)


def test_a_solver_warning_reaches_the_terminal_once_on_one_line(tmp_path):
    """Nearly single-axis motion: the solver's ObservabilityWarning, as ``warning: <Class>: <message>``."""
    import numpy as np

    from replication.core import so3

    t = np.arange(0.0, 30.0, 0.05)
    Q = so3.matrix_from_rotation_vector(np.stack([np.sin(0.7 * t), 0.003 * np.sin(0.45 * t), 0.003 * np.cos(0.3 * t)],
                                                 axis=-1))
    R0 = so3.matrix_from_rotation_vector(np.radians([40.0, -70.0, 125.0]))
    for name, R in [("cam.txt", Q), ("sensor.txt", Q @ R0)]:
        q = so3.quaternion_from_matrix(R)
        np.savetxt(tmp_path / name, np.column_stack([t, np.zeros((len(t), 3)), q[:, 1:], q[:, :1]]), fmt="%.9f")
    out = _run("calibrate", "--camera", tmp_path / "cam.txt", "--sensor", tmp_path / "sensor.txt", "--bootstrap", 20)
    assert out.returncode == 0, out.stderr
    lines = out.stderr.splitlines()
    assert len(lines) == 1, out.stderr
    assert lines[0].startswith("warning: ObservabilityWarning: 1 of 1 problems have nearly single-axis motion: axis "
                               "spread down to ")
    assert ".py" not in out.stderr and "warn" not in out.stderr.replace("warning:", "").replace("Warning:", "")


def test_the_warning_formatter_says_each_warning_once_on_one_line():
    import io

    from replication.__main__ import _one_line_warnings
    from replication.core.solvers import AccuracyWarning, ObservabilityWarning

    show, file = _one_line_warnings(), io.StringIO()
    show(ObservabilityWarning("a  weak\n  motion"), ObservabilityWarning, "/x/_registry.py", 212, file=file)
    show(ObservabilityWarning("a weak motion"), ObservabilityWarning, "/x/estimate.py", 139, file=file)  # the same
    show(AccuracyWarning("a weak motion"), AccuracyWarning, "/x/_registry.py", 212, file=file)  # another class
    assert file.getvalue() == ("warning: ObservabilityWarning: a weak motion\n"
                               "warning: AccuracyWarning: a weak motion\n")


def test_the_warning_formatter_is_installed_only_while_a_command_runs(tmp_path):
    import warnings

    from replication.__main__ import main

    before = warnings.showwarning
    assert main(["fetch-data", str(tmp_path), "--check"]) == 1
    assert warnings.showwarning is before
    code = ("import warnings; before = warnings.showwarning; import replication.__main__, "
            "replication.rig.calibrate_cli; print(warnings.showwarning is before)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout == "True\n"
