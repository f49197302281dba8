"""The command line's top parser (``replication/cli/__init__.py``): one module per command with
``add_parser`` and ``run``, each command dispatched to its module, the version, and the warnings
of a command said once on one line, only while it runs (``__main__``, only the entry:
tests/test_main.py)."""
import argparse
import importlib
import os
import subprocess
import sys
from pathlib import Path

from conftest import _run
from replication.cli import main

ROOT = Path(__file__).resolve().parent.parent


COMMANDS = {"reproduce": "reproduce", "calibrate": "calibrate", "export": "export", "generate-lab": "lab",
            "claims": "claims", "fetch-data": "fetch"}


def _subparsers():
    sub = argparse.ArgumentParser().add_subparsers(dest="command")
    for name in COMMANDS.values():
        importlib.import_module(f"replication.cli.{name}").add_parser(sub)
    return sub.choices


def test_each_command_has_its_module_with_a_parser_and_a_run_function():
    choices = _subparsers()
    assert sorted(choices) == sorted(COMMANDS)
    for command, module in COMMANDS.items():
        func = choices[command].get_default("func")
        assert (func.__module__, func.__name__) == (f"replication.cli.{module}", "run"), command


def test_the_top_parser_dispatches_each_command_to_its_module(monkeypatch):
    """``main`` runs the ``run`` of the command's own module: a stand-in ``run`` is what it
    returns."""
    argv = {"reproduce": ["reproduce"], "calibrate": ["calibrate", "--camera", "c", "--sensor", "s"],
            "export": ["export", "r.json", "--to", "ros2"], "generate-lab": ["generate-lab"], "claims": ["claims"],
            "fetch-data": ["fetch-data", "dest"]}
    for i, (command, module) in enumerate(COMMANDS.items()):
        mod = importlib.import_module(f"replication.cli.{module}")
        monkeypatch.setattr(mod, "run", lambda args, i=i: 40 + i)
        # add_parser binds run when the parser is built, so the stand-in is what main dispatches to
        assert main(argv[command]) == 40 + i, command


def test_version_prints_the_package_version():
    from replication._version import __version__

    out = _run("--version")
    assert out.returncode == 0 and out.stdout == f"replication {__version__}\n"


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


def test_a_reader_that_stops_early_ends_the_output_quietly():
    """``python -m replication ... | head -n 1``: no BrokenPipeError traceback, exit 141
    (SIGPIPE's). The output (1 MB) is larger than a pipe's buffer, so the pipe does break; without
    the wrapper it prints a traceback."""
    script = ("import sys, replication.cli as m\n"
              "m.main = lambda argv=None: print('| claim |\\n' + 'x' * 100 + '\\n' * 1000000) or 0\n"
              "sys.exit(m.main_closing_pipes() if sys.argv[1] == 'wrapped' else m.main())\n")
    runs = {}
    for how in ("wrapped", "bare"):
        runs[how] = subprocess.run(f"'{sys.executable}' -c \"$S\" {how} | head -n 1; exit ${{PIPESTATUS[0]}}",
                                   shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=60,
                                   env={**os.environ, "S": script})
    assert runs["bare"].returncode != 0 and "BrokenPipeError" in runs["bare"].stderr  # the pipe did break
    out = runs["wrapped"]
    assert out.stdout == "| claim |\n" and out.stderr == "" and out.returncode == 141
