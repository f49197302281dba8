"""The ``calibrate`` command's inputs and outputs (``replication/cli/calibrate_inputs.py``): every
path checked before any work, a file of the other kind named with the option that reads it, an
input read once (a pipe too) and hashed, and every file-system problem a clear message with exit
code 2, never a traceback.

Each refused run is checked for its exit code, its message on standard error, no work done (the
calibration replaced by a failure) and its inputs byte-identical afterwards. The synthetic rig's
files: tests/conftest.py.
"""
import hashlib
import json
import os
import re
import subprocess
import sys
import threading
from pathlib import Path

import jsonschema
import pytest

from conftest import _calibrate, _snapshot
from replication.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "calibration_report.schema.json").read_text())


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


@pytest.mark.parametrize("name", ["fig.jpg", "fig", "fig.png.bak"])
def test_an_unknown_plot_extension_is_refused_before_any_work(files, tmp_path, name, no_work, capsys):
    before = _snapshot(files)
    assert _calibrate(files, "--plot", tmp_path / name, "--out", tmp_path / "r.json") == 2
    err = capsys.readouterr().err
    assert "--plot" in err and "unknown figure format" in err and "supported: .png, .pdf, .svg" in err, err
    assert _snapshot(files) == before and sorted(p.name for p in tmp_path.iterdir()) == ["in"]


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


def test_a_pipe_keeps_its_names_extension_for_the_loaders(files, tmp_path, cli_rig, rig_bytes, capsys):
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


# -------------------------------------------------------------------------------------------
# file-system errors

@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_an_output_in_an_unwritable_folder_is_refused_before_any_work(files, locked, option, no_work, capsys):
    target = locked / ("r.json" if option == "--out" else "f.png")
    assert _calibrate(files, option, target) == 2
    assert f"{option} {target}: cannot write in {locked} (Permission denied)" in capsys.readouterr().err
    assert not list(locked.iterdir())
