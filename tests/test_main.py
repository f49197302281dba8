import errno
import hashlib
import json
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import jsonschema
import nbformat
import numpy as np
import pytest

import replication.rig.calibration as cal
import replication.rig.poses as poses
from replication import _io
from replication.cli import main
from replication.core import so3
from replication.rig import fetch
from replication.rig.calibration import OverlapError, calibrate
from replication.testing import rig_streams


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
    """(That the committed data/lab equal the generator's output is tests/study/test_lab.py's
    check.)"""
    from replication.cli import main
    from replication.study.lab import load_lab

    assert main(["generate-lab", "--out", str(tmp_path / "a"), "--seed", "7"]) == 0
    assert "seed 7" in capsys.readouterr().out
    rec = load_lab(tmp_path / "a")
    assert rec.truth["camera_from_sensor"].shape == (3, 3)
    assert main(["generate-lab", "--out", str(tmp_path / "b"), "--seed", "8"]) == 0
    assert (tmp_path / "a" / "static_imu.csv").read_text() != (tmp_path / "b" / "static_imu.csv").read_text()


# ------------------------------------------------------------------- a rig user's command line

def _run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "replication", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


def test_version_prints_the_package_version():
    from replication._version import __version__

    out = _run("--version")
    assert out.returncode == 0 and out.stdout == f"replication {__version__}\n"


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


def _imu_like_csv(path, n_columns, rows=4):
    """``rows`` lines of ``n_columns`` comma-separated numbers after a ``#`` header (EuRoC / TUM-VI
    style): time in ns, then zeros with a unit quaternion where an orientation line (8 columns) has
    it."""
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
    from replication.cli import main

    camera = tmp_path / "cam.txt"
    camera.write_text("".join(f"{t} 0 0 0 0 0 0 1\n" for t in range(4)))
    sensor = _imu_like_csv(tmp_path / "data.csv", n_columns)
    expected = "8 or 17" if kind == "orientation" else 7  # 17: EuRoC's ground truth as shipped
    assert main(["calibrate", "--camera", str(camera), "--sensor", str(sensor), "--sensor-kind", kind]) == 2
    err = capsys.readouterr().err
    assert f"data.csv, line 2: expected {expected} columns" in err and f"got {n_columns}" in err
    assert (hint in err) if hint else ("looks like" not in err and "--sensor-kind" not in err)


def test_the_files_of_the_hints_are_what_they_are_said_to_look_like(tmp_path):
    """The control of the hints: the 7-column file loads as a gyro, the 8-column one as
    orientations."""
    from replication.rig.realdata import load_stream

    assert load_stream(_imu_like_csv(tmp_path / "imu.csv", 7), "gyro").omega.shape == (4, 3)
    assert load_stream(_imu_like_csv(tmp_path / "pose.csv", 8), "orientation").R.shape == (4, 3, 3)


def test_an_imu_file_given_as_the_camera_says_where_it_goes(tmp_path, capsys):
    from replication.cli import main

    imu = _imu_like_csv(tmp_path / "data.csv", 7)
    assert main(["calibrate", "--camera", str(imu), "--sensor", str(imu), "--sensor-kind", "gyro"]) == 2
    assert "--camera takes the camera's orientations; a gyro goes to --sensor with --sensor-kind gyro" in (
        capsys.readouterr().err)


def test_a_solver_warning_reaches_the_terminal_once_on_one_line(tmp_path):
    """Nearly single-axis motion: the solver's ObservabilityWarning, as ``warning: <Class>:
    <message>``."""
    import numpy as np

    from replication.core import so3

    t = np.arange(0.0, 30.0, 0.05)
    Q = so3.matrix_from_rotation_vector(np.stack([np.sin(0.7 * t), 0.003 * np.sin(0.45 * t), 0.003 * np.cos(0.3 * t)],
                                                 axis=-1))
    from replication.testing import RIG_R0 as R0
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

    from replication.cli import _one_line_warnings
    from replication.core.solvers import AccuracyWarning, ObservabilityWarning

    show, file = _one_line_warnings(), io.StringIO()
    show(ObservabilityWarning("a  weak\n  motion"), ObservabilityWarning, "/x/_registry.py", 212, file=file)
    show(ObservabilityWarning("a weak motion"), ObservabilityWarning, "/x/estimate.py", 139, file=file)  # the same
    show(AccuracyWarning("a weak motion"), AccuracyWarning, "/x/_registry.py", 212, file=file)  # another class
    assert file.getvalue() == ("warning: ObservabilityWarning: a weak motion\n"
                               "warning: AccuracyWarning: a weak motion\n")


def test_the_warning_formatter_is_installed_only_while_a_command_runs(tmp_path):
    import warnings

    from replication.cli import main

    before = warnings.showwarning
    assert main(["fetch-data", str(tmp_path), "--check"]) == 1
    assert warnings.showwarning is before
    code = ("import warnings; before = warnings.showwarning; import replication.__main__, "
            "replication.cli.calibrate; print(warnings.showwarning is before)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout == "True\n"

# --------------------------------------------------------------------------------------------------
# The command line never destroys its inputs or one output with another, reads a pipe once, and ends
# every file-system problem in a clear message with exit code 2, never a traceback.
#
# Each refused run is checked for its exit code, its message on standard error, no work done (the
# calibration, the downloads or the notebooks replaced by a failure) and its inputs byte-identical
# afterwards. The synthetic rig (:func:`replication.testing.rig_streams`) is written as a TUM
# trajectory and an EuRoC IMU CSV on Unix-like absolute times (1.52e9 s), the scale at which the old
# overlap message printed ``1.52053e+09..1.52053e+09``.


ROOT = Path(__file__).resolve().parent.parent
SCHEMA = json.loads((ROOT / "docs" / "calibration_report.schema.json").read_text())
T0 = 1.52053e9  # absolute times, as a real recording has
MAGIC = {".png": (b"\x89PNG",), ".pdf": (b"%PDF",), ".svg": (b"<?xml", b"<svg")}


@pytest.fixture(scope="module")
def rig():
    return rig_streams(40.0, rng=np.random.default_rng(11), camera_noise_deg=0.05, gyro_noise_deg_s=0.05)


def _tum_bytes(camera) -> bytes:
    q = so3.quaternion_from_matrix(camera.R)
    rows = np.column_stack([camera.t + T0, np.zeros((len(camera.t), 3)), q[:, 1:], q[:, :1]])
    return "".join(" ".join(f"{v:.9f}" for v in row) + "\n" for row in rows).encode()


def _imu_bytes(gyro) -> bytes:
    ns = np.round(gyro.t * 1e9).astype(np.int64) + int(T0 * 1e9)
    return "".join(f"{n}," + ",".join(f"{v:.9f}" for v in (*w, 0.0, 0.0, 9.81)) + "\n"
                   for n, w in zip(ns, gyro.omega)).encode()


def _camchain_text(R0) -> str:
    T = np.eye(4)
    T[:3, :3] = R0
    return "cam0:\n  T_cam_imu:\n" + "".join(f"  - [{', '.join(f'{v:.12f}' for v in row)}]\n" for row in T)


@pytest.fixture(scope="module")
def rig_bytes(rig):
    R0, camera, gyro, _ = rig
    return {"cam.txt": _tum_bytes(camera), "imu.csv": _imu_bytes(gyro), "camchain.yaml": _camchain_text(R0).encode()}


@pytest.fixture
def files(tmp_path, rig_bytes):
    """A private copy of the rig's files (tests may link, chmod or replace them)."""
    d = tmp_path / "in"
    d.mkdir()
    for name, data in rig_bytes.items():
        (d / name).write_bytes(data)
    return d


def _snapshot(folder: Path) -> dict:
    """Every file under ``folder`` (links followed) and the SHA-256 of its bytes; folders as
    ``None``."""
    return {str(p.relative_to(folder)): (hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


@pytest.fixture
def no_work(monkeypatch):
    """Make the calibration fail the test if it is reached."""
    def reached(*args, **kwargs):
        pytest.fail("the calibration ran: the check must come before any work")

    monkeypatch.setattr(cal, "calibrate", reached)
    monkeypatch.setattr(poses, "calibrate_poses", reached)


def _calibrate(files, *extra):
    return main(["calibrate", "--camera", str(files / "cam.txt"), "--sensor", str(files / "imu.csv"),
                 "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", *map(str, extra)])


# -------------------------------------------------------------------------------------------
# outputs vs inputs

def _link(files, kind):
    link = files / f"{kind}-link.txt"
    (os.symlink if kind == "sym" else os.link)(files / "cam.txt", link)
    return link


CLASHES = {  # case: (extra arguments given the input folder, the message)
    "out is the camera": (lambda d: ["--out", d / "cam.txt"], "--out is the --camera input file: "),
    "out is the sensor": (lambda d: ["--out", d / "imu.csv"], "--out is the --sensor input file: "),
    "out is the reference": (lambda d: ["--reference", d / "camchain.yaml", "--out", d / "camchain.yaml"],
                             "--out is the --reference input file: "),
    "plot is the camera": (lambda d: ["--plot", d / "cam.png", "--camera", d / "cam.png"],
                           "--plot is the --camera input file: "),
    "track is the sensor": (lambda d: ["--online", "--track", d / "imu.csv"], "--track is the --sensor input file: "),
    "out is the track": (lambda d: ["--online", "--out", d / "r.json", "--track", d / "r.json"],
                         "--track and --out are the same file: "),
    "plot is the out": (lambda d: ["--out", d / "r.png", "--plot", d / "r.png"],
                        "--plot and --out are the same file: "),
    "track is the plot": (lambda d: ["--online", "--plot", d / "r.png", "--track", d / ".." / d.name / "r.png"],
                          "--track and --plot are the same file: "),
    "a symlink to the camera as out": (lambda d: ["--out", _link(d, "sym")],
                                       "--out is the --camera input file: .*sym-link.txt \\(resolves to "),
    "a hard link to the camera as out": (lambda d: ["--out", _link(d, "hard")],
                                         "--out is the --camera input file: .*hard-link.txt \\(a hard link to "),
}


@pytest.mark.parametrize("case", list(CLASHES))
def test_an_output_that_is_an_input_or_another_output_is_refused_before_any_work(files, case, no_work, capsys):
    extra, message = CLASHES[case]
    args = extra(files)
    if "--camera" in map(str, args):  # the camera file under another name
        (files / "cam.png").write_bytes((files / "cam.txt").read_bytes())
    before = _snapshot(files)
    assert _calibrate(files, *args) == 2
    err = capsys.readouterr().err
    assert re.search(message, err) and "Traceback" not in err, err
    assert _snapshot(files) == before  # the inputs byte-identical, nothing written


def test_an_outputs_temporary_name_never_touches_an_input(files, rig_bytes, capsys):
    """An output writes through a temporary sibling: it must not be an existing file (here the
    camera input, named like the report's old temporary name ``r.json.part``)."""
    camera = files / "r.json.part"
    (files / "cam.txt").rename(camera)
    code = main(["calibrate", "--camera", str(camera), "--sensor", str(files / "imu.csv"), "--sensor-kind", "gyro",
                 "--bootstrap", "0", "--quiet", "--out", str(files / "r.json")])
    assert code == 0, capsys.readouterr().err
    assert camera.read_bytes() == rig_bytes["cam.txt"]
    assert json.loads((files / "r.json").read_text())["files"]["camera"]["path"] == str(camera)
    assert not [p.name for p in files.iterdir() if p.name.endswith(".part") and p != camera]


@pytest.mark.parametrize("name", ["fig.png", "fig.pdf", "fig.svg", "FIG.PDF"])
def test_plot_writes_the_format_its_extension_names(files, tmp_path, name, capsys):
    fig = tmp_path / "out" / name
    assert _calibrate(files, "--plot", fig) == 0, capsys.readouterr().err
    data = fig.read_bytes()
    assert data.startswith(MAGIC[fig.suffix.lower()]), data[:20]
    assert not list(fig.parent.glob("*.part"))


@pytest.mark.parametrize("name", ["fig.jpg", "fig", "fig.png.bak"])
def test_an_unknown_plot_extension_is_refused_before_any_work(files, tmp_path, name, no_work, capsys):
    before = _snapshot(files)
    assert _calibrate(files, "--plot", tmp_path / name, "--out", tmp_path / "r.json") == 2
    err = capsys.readouterr().err
    assert "--plot" in err and "unknown figure format" in err and "supported: .png, .pdf, .svg" in err, err
    assert _snapshot(files) == before and sorted(p.name for p in tmp_path.iterdir()) == ["in"]


def test_the_api_plot_honours_the_extension_or_refuses_before_drawing(rig, tmp_path, monkeypatch):
    _, camera, gyro, _ = rig
    result = calibrate(camera, gyro, n_bootstrap=0)
    for suffix, magic in MAGIC.items():
        result.plot(tmp_path / f"f{suffix}")
        assert (tmp_path / f"f{suffix}").read_bytes().startswith(magic)
    import replication.rig.figure as figures

    monkeypatch.setattr(figures, "calibration_figure", lambda *a: pytest.fail("drawn before the format was checked"))
    with pytest.raises(ValueError, match=r"f\.jpeg: unknown figure format \.jpeg; supported: \.png, \.pdf, \.svg"):
        result.plot(tmp_path / "f.jpeg")
    assert not (tmp_path / "f.jpeg").exists()


# -------------------------------------------------------------------------- pipes and special files

class _Feeder:
    """Write ``data`` into the FIFO ``path`` once, from a thread (a writer blocks until the reader
    opens)."""

    def __init__(self, path, data):
        self.thread = threading.Thread(target=self._feed, args=(path, data), daemon=True)
        self.thread.start()

    @staticmethod
    def _feed(path, data):
        try:
            with open(path, "wb") as f:
                f.write(data)
        except BrokenPipeError:
            pass


def _run_reading_a_fifo(fifo, args, timeout=120.0):
    """``main(args)`` in a thread; if it is still waiting on the FIFO after ``timeout`` (it opened
    the pipe a second time), release it with an empty write and fail."""
    box = {}
    runner = threading.Thread(target=lambda: box.update(code=main(args)), daemon=True)
    runner.start()
    runner.join(timeout)
    if runner.is_alive():
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        runner.join(60)
        pytest.fail("the command opened the pipe a second time")
    return box.get("code")


def test_a_fifo_input_is_read_once_and_recorded_as_a_pipe(files, tmp_path, rig_bytes, capsys):
    fifo = tmp_path / "camera-pipe.txt"
    os.mkfifo(fifo)
    _Feeder(fifo, rig_bytes["cam.txt"])
    out = tmp_path / "r.json"
    code = _run_reading_a_fifo(fifo, ["calibrate", "--camera", str(fifo), "--sensor", str(files / "imu.csv"),
                                      "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    data = rig_bytes["cam.txt"]
    assert report["files"]["camera"] == {"pipe": True, "given": str(fifo), "bytes": len(data),
                                         "sha256": hashlib.sha256(data).hexdigest()}
    assert report["files"]["sensor"]["path"] == str(files / "imu.csv")
    assert report["inputs"]["camera"]["source"] == str(fifo)  # not the temporary copy's name


def test_a_malformed_fifo_input_is_refused_naming_the_pipe_with_no_output(files, tmp_path, rig_bytes, capsys):
    fifo = tmp_path / "camera-pipe.txt"
    os.mkfifo(fifo)
    lines = rig_bytes["cam.txt"].split(b"\n")
    lines[2] = b"x" + lines[2]
    _Feeder(fifo, b"\n".join(lines))
    out, fig = tmp_path / "out" / "r.json", tmp_path / "out" / "f.png"
    code = _run_reading_a_fifo(fifo, ["calibrate", "--camera", str(fifo), "--sensor", str(files / "imu.csv"),
                                      "--sensor-kind", "gyro", "--quiet", "--out", str(out), "--plot", str(fig)])
    err = capsys.readouterr().err
    assert code == 2 and f"{fifo} (a pipe, read once), line 3, column 1 ('t'): not a number" in err, err
    assert not out.exists() and not fig.exists() and not list(tmp_path.rglob("*.part"))


def test_dev_stdin_as_a_pipe_calibrates_and_is_recorded(files, tmp_path, rig_bytes):
    """The campaign's case: ``--camera <(cat traj.txt)`` ran the whole calibration, then failed
    hashing the pipe's path again (FileNotFoundError, no report). Through ``/dev/stdin`` in a fresh
    process."""
    out = tmp_path / "r.json"
    run = subprocess.run([sys.executable, "-m", "replication", "calibrate", "--camera", "/dev/stdin", "--sensor",
                          str(files / "imu.csv"), "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet", "--out",
                          str(out)], input=rig_bytes["cam.txt"], capture_output=True, timeout=300, cwd=ROOT,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 0 and b"Traceback" not in run.stderr, run.stderr.decode()
    entry = json.loads(out.read_text())["files"]["camera"]
    assert entry["pipe"] is True and entry["given"] == "/dev/stdin" and "path" not in entry
    assert entry["sha256"] == hashlib.sha256(rig_bytes["cam.txt"]).hexdigest()


def test_the_same_pipe_twice_is_refused(files, tmp_path, rig_bytes, no_work, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    _Feeder(fifo, rig_bytes["cam.txt"])
    code = _run_reading_a_fifo(fifo, ["calibrate", "--camera", str(fifo), "--sensor", str(fifo), "--quiet"],
                               timeout=30.0)
    assert code == 2
    assert f"--sensor is the same pipe as --camera ({fifo}): a pipe can be read once" in capsys.readouterr().err
    os.close(os.open(fifo, os.O_RDONLY | os.O_NONBLOCK))  # release the feeder: nothing was read


@pytest.mark.parametrize("target", ["/dev/stdout", os.devnull])
def test_an_output_onto_standard_output_or_a_device_is_refused(files, tmp_path, target):
    """``--out /dev/stdout`` with standard output redirected to a file would replace that file (and
    what was printed to it); a device is no file to replace. Both are refused before any work."""
    log = tmp_path / "stdout.txt"
    log.write_bytes(b"earlier output\n")
    with open(log, "ab") as stdout:
        run = subprocess.run([sys.executable, "-m", "replication", "calibrate", "--camera", str(files / "cam.txt"),
                              "--sensor", str(files / "imu.csv"), "--sensor-kind", "gyro", "--out", target],
                             stdout=stdout, stderr=subprocess.PIPE, timeout=300, cwd=ROOT,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
    message = ("is this command's standard output" if target == "/dev/stdout"
               else "exists and is not a regular file (a pipe or a device)")
    assert run.returncode == 2 and f"--out {target}: {message}".encode() in run.stderr, run.stderr.decode()
    assert log.read_bytes() == b"earlier output\n"


@pytest.mark.parametrize("case, message", [
    ("missing", "--camera {path}: no such file"),
    ("directory", "--camera {path}: is a directory, not a file"),
    ("device", "--camera {path}: is a character device, not a regular file or a pipe"),
    ("under a file", "--camera {path}: no such file"),
])
def test_an_input_that_is_not_a_readable_file_is_refused(files, tmp_path, case, message, no_work, capsys):
    path = {"missing": tmp_path / "nope.txt", "directory": tmp_path, "device": Path(os.devnull),
            "under a file": files / "imu.csv" / "cam.txt"}[case]
    before = _snapshot(files)
    assert main(["calibrate", "--camera", str(path), "--sensor", str(files / "imu.csv"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert message.format(path=path) in err and "Traceback" not in err, err
    assert _snapshot(files) == before


def test_an_unreadable_input_is_refused(files, no_work, capsys):
    camera = files / "cam.txt"
    camera.chmod(0)
    try:
        if os.access(camera, os.R_OK):
            pytest.skip("file permissions are not enforced for this user (root)")
        assert _calibrate(files) == 2
        assert f"--camera {camera}: cannot be read (Permission denied)" in capsys.readouterr().err
    finally:
        camera.chmod(0o644)


def test_an_output_onto_a_pipe_is_refused(files, no_work, capsys):
    """``--out >(gzip > r.gz)``: the path names a pipe (``/dev/fd/N``), not a file to replace."""
    read, write = os.pipe()
    try:
        target = f"/dev/fd/{write}"
        assert _calibrate(files, "--out", target) == 2
        assert f"--out {target}: exists and is not a regular file (a pipe or a device)" in capsys.readouterr().err
    finally:
        os.close(read)
        os.close(write)


# -------------------------------------------------------------------------------------------
# file-system errors

@pytest.fixture
def locked(tmp_path):
    """A folder this user cannot write in (skipped where permissions are not enforced: root),
    restored afterwards."""
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("folder permissions are not enforced for this user (root)")
        yield folder
    finally:
        folder.chmod(0o700)


@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_an_output_in_an_unwritable_folder_is_refused_before_any_work(files, locked, option, no_work, capsys):
    target = locked / ("r.json" if option == "--out" else "f.png")
    assert _calibrate(files, option, target) == 2
    assert f"{option} {target}: cannot write in {locked} (Permission denied)" in capsys.readouterr().err
    assert not list(locked.iterdir())


def _disk_full(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


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


def test_a_read_only_folder_refuses_the_write_and_leaves_nothing(locked):
    """:func:`replication._io.write_atomic` in a folder it cannot write: an ``OSError``, no file, no
    temporary."""
    with pytest.raises(PermissionError, match="Permission denied"):
        _io.write_atomic(locked / "r.json", "{}")
    assert not list(locked.iterdir())


# -------------------------------------------------------------------------------------------
# fetch-data

@pytest.fixture
def one_entry(monkeypatch):
    """A manifest of one small file, served by a stub: no network, and the download counted."""
    content = b"t w x y z\n1 2 3 4 5\n"
    entry = fetch.ManifestEntry("f", "a.txt", len(content), fetch.sha256_of(content), "o/r", "0" * 40, "p/a.txt",
                                "MIT", "x")
    served = []
    monkeypatch.setattr(fetch, "load_manifest", lambda *a: [entry])
    monkeypatch.setattr(fetch, "_download", lambda url, timeout: served.append(url) or content)
    return served


def test_fetch_data_into_a_path_under_a_file_is_refused_before_downloading(tmp_path, one_entry, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("keep")
    assert main(["fetch-data", str(blocker / "real")]) == 2
    err = capsys.readouterr().err
    assert f"DEST {blocker / 'real'}: cannot create this folder (Not a directory)" in err, err
    assert not one_entry and blocker.read_text() == "keep"
    assert main(["fetch-data", str(blocker)]) == 2
    assert f"{blocker}: exists and is not a directory" in capsys.readouterr().err
    assert not one_entry and blocker.read_text() == "keep"


def test_fetch_data_into_a_read_only_folder_is_refused_before_downloading(locked, one_entry, capsys):
    assert main(["fetch-data", str(locked / "real")]) == 2
    assert f"DEST {locked / 'real'}: cannot create this folder (Permission denied)" in capsys.readouterr().err
    assert main(["fetch-data", str(locked)]) == 2
    assert f"cannot write in {locked} (Permission denied)" in capsys.readouterr().err
    assert not one_entry


def test_fetch_data_reports_a_disk_error_while_writing(tmp_path, one_entry, monkeypatch, capsys):
    monkeypatch.setattr(fetch, "write_atomic", _disk_full)
    assert main(["fetch-data", str(tmp_path / "real")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'real' / 'f' / 'a.txt'}: cannot write (No space left on device)" in err
    assert "Traceback" not in err and not (tmp_path / "real" / "f" / "a.txt").exists()


def test_fetch_data_refuses_its_mirror_as_destination(tmp_path, one_entry, capsys):
    mirror = tmp_path / "mirror"
    (mirror / "f").mkdir(parents=True)
    (mirror / "f" / "a.txt").write_bytes(b"a stale copy")
    assert main(["fetch-data", str(mirror), "--mirror", str(mirror)]) == 2
    assert f"{mirror} is the --mirror folder {mirror}" in capsys.readouterr().err
    link = tmp_path / "dest"
    (link / "f").mkdir(parents=True)
    os.symlink(mirror / "f" / "a.txt", link / "f" / "a.txt")
    assert main(["fetch-data", str(link), "--mirror", str(mirror)]) == 2
    assert f"{link / 'f' / 'a.txt'} is the --mirror file {mirror / 'f' / 'a.txt'}" in capsys.readouterr().err
    assert (mirror / "f" / "a.txt").read_bytes() == b"a stale copy"


# -------------------------------------------------------------------------------------------
# reproduce

@pytest.fixture
def notebook_folder(tmp_path, monkeypatch):
    import nbformat

    import replication.cli.reproduce as entry

    folder = tmp_path / "nb"
    folder.mkdir()
    nbformat.write(nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1")]), folder / "01_a.ipynb")
    monkeypatch.setattr(entry, "execute_notebook", lambda *a, **k: pytest.fail("a notebook ran"))
    return folder


@pytest.mark.parametrize("case, message", [
    ("the notebooks folder", "--results {results} is the --notebooks folder"),
    ("a notebook", "--results is the notebook 01_a.ipynb input file: {results}"),
    ("under a file", "--results {resolved}: cannot create this folder (Not a directory)"),
])
def test_reproduce_refuses_a_results_folder_that_clashes_or_cannot_be_made(notebook_folder, case, message, capsys):
    results = {"the notebooks folder": notebook_folder, "a notebook": notebook_folder / "01_a.ipynb",
               "under a file": notebook_folder / "01_a.ipynb" / "results"}[case]
    before = _snapshot(notebook_folder)
    assert main(["reproduce", "--notebooks", str(notebook_folder), "--results", str(results)]) == 2
    err = capsys.readouterr().err
    assert message.format(results=results, resolved=results.resolve()) in err, err
    assert _snapshot(notebook_folder) == before


# ------------------------------------------------------------------------------ the overlap message

def test_a_max_offset_beyond_the_overlap_is_named_with_durations(rig):
    _, camera, gyro, _ = rig
    from replication.rig.streams import GyroStream, OrientationStream

    cam = OrientationStream(camera.t + T0, camera.R, "camera")
    imu = GyroStream(gyro.t + T0, gyro.omega, "imu")
    with pytest.raises(OverlapError, match=r"the streams overlap by 40\.0 s \(camera 40\.0 s, sensor 42\.0 s long\)"
                       r".*max_offset 30 s is larger than the overlap allows.*\(above [\d.]+ s;") as err:
        calibrate(cam, imu, max_offset=30.0, n_bootstrap=0)
    assert "e+09" not in str(err.value) and "1520" not in str(err.value)  # durations, no absolute times
    bound = float(re.search(r"\(above ([\d.]+) s;", str(err.value)).group(1))
    cal._check_overlap(cam, imu, bound)  # the bound said is the bound: 10 samples at it, fewer just above
    with pytest.raises(OverlapError, match="max_offset"):
        cal._check_overlap(cam, imu, bound + 1.0)
    assert calibrate(cam, imu, max_offset=2.0, n_bootstrap=0).n_pairs > 0


def test_the_cli_names_its_max_offset_option(files, capsys):
    assert _calibrate(files, "--max-offset", "100") == 2
    err = capsys.readouterr().err
    assert "--max-offset 100 s is larger than the overlap allows" in err and "camera 40.0 s" in err, err
    assert "e+09" not in err and "max_offset" not in err


def test_streams_on_different_clocks_keep_the_start_times_that_show_it(rig):
    _, camera, gyro, _ = rig
    from replication.rig.streams import GyroStream, OrientationStream

    cam = OrientationStream(camera.t, camera.R, "camera")  # relative times
    imu = GyroStream(gyro.t + T0, gyro.omega, "imu")  # absolute times
    with pytest.raises(OverlapError, match=r"the sensor starts 15205\d+\.\d s after the camera ends.*the camera starts "
                       r"at t = 0\.000 s, the sensor at t = 1520529999\.00\d s: their clocks differ"):
        calibrate(cam, imu, n_bootstrap=0)


def test_the_overlap_error_survives_pickling_and_renaming():
    import pickle

    err = OverlapError("{option} 2 s is larger than the overlap")
    assert str(pickle.loads(pickle.dumps(err))) == "max_offset 2 s is larger than the overlap"
    assert str(err.named("--max-offset")) == "--max-offset 2 s is larger than the overlap"
    assert isinstance(err, ValueError)


def test_a_pipe_keeps_its_names_extension_for_the_loaders(files, tmp_path, rig, rig_bytes, capsys):
    """The loaders recognise formats by the name's extension (a reference ``.yaml`` is a Kalibr
    camchain): the pipe's temporary copy keeps it."""
    fifo = tmp_path / "camchain-pipe.yaml"
    os.mkfifo(fifo)
    _Feeder(fifo, rig_bytes["camchain.yaml"])
    out = tmp_path / "r.json"
    code = _run_reading_a_fifo(fifo, ["calibrate", "--camera", str(files / "cam.txt"), "--sensor",
                                      str(files / "imu.csv"), "--sensor-kind", "gyro", "--bootstrap", "0", "--quiet",
                                      "--reference", str(fifo), "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    report = json.loads(out.read_text())
    jsonschema.validate(report, SCHEMA)
    assert report["files"]["reference"]["pipe"] is True and report["files"]["reference"]["camera_entry"] == "cam0"
    assert report["reference_error_deg"] < 0.1
