"""The command line in its own room (``replication/cli``): ``python -m replication ...`` says and returns what it did
before the move, one module per command with ``add_parser`` and ``run``, ``__main__`` only the entry.

The outputs before the move were captured by ``scratch/capture_cli.py`` into ``scratch/cli_before/`` (one JSON per
argv: exit code, stdout, stderr; ``COLUMNS=120``; plus ``shell_*.txt``, ``python -m replication [CMD] --help`` from a
shell). When an option is added on purpose, re-capture them with that script.
"""
import argparse
import importlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from replication.cli import main

ROOT = Path(__file__).resolve().parent.parent
BEFORE = ROOT / "scratch" / "cli_before"
CASES = sorted(BEFORE.glob("*.json"))
COMMANDS = {"reproduce": "reproduce", "calibrate": "calibrate", "export": "export", "generate-lab": "lab",
            "claims": "claims", "fetch-data": "fetch"}


def test_the_captured_outputs_are_there_and_cover_every_help():
    names = {p.stem for p in CASES}
    assert len(CASES) >= 20
    assert {"top_help", "version", "no_command", "bogus"} <= names
    assert {f"{command}_help" for command in COMMANDS} <= names


@pytest.mark.parametrize("path", CASES, ids=lambda p: p.stem)
def test_every_output_exit_code_and_message_is_as_before_the_move(path, monkeypatch, capsys):
    case = json.loads(path.read_text(encoding="utf-8"))
    monkeypatch.setenv("COLUMNS", "120")
    monkeypatch.chdir(ROOT)
    try:
        code = main(case["argv"])
    except SystemExit as err:
        code = err.code
    out = capsys.readouterr()
    assert (code, out.out, out.err) == (case["code"], case["stdout"], case["stderr"])


@pytest.mark.parametrize("command", ["", "calibrate", "export", "fetch-data"])
def test_python_dash_m_replication_prints_the_same_help_from_a_shell(command):
    argv = [sys.executable, "-m", "replication", *([command] if command else []), "--help"]
    out = subprocess.run(argv, capture_output=True, text=True, cwd=ROOT, env={**os.environ, "COLUMNS": "120"})
    assert out.returncode == 0, out.stderr
    assert out.stdout == (BEFORE / f"shell_{command or 'top'}.txt").read_text(encoding="utf-8")


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
    """``main`` runs the ``run`` of the command's own module: a stand-in ``run`` is what it returns."""
    argv = {"reproduce": ["reproduce"], "calibrate": ["calibrate", "--camera", "c", "--sensor", "s"],
            "export": ["export", "r.json", "--to", "ros2"], "generate-lab": ["generate-lab"], "claims": ["claims"],
            "fetch-data": ["fetch-data", "dest"]}
    for i, (command, module) in enumerate(COMMANDS.items()):
        mod = importlib.import_module(f"replication.cli.{module}")
        monkeypatch.setattr(mod, "run", lambda args, i=i: 40 + i)
        # add_parser binds run when the parser is built, so the stand-in is what main dispatches to
        assert main(argv[command]) == 40 + i, command


def test_the_entry_is_two_lines_of_code_and_defines_nothing():
    import ast

    tree = ast.parse((ROOT / "replication" / "__main__.py").read_text(encoding="utf-8"))
    body = [n for n in tree.body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
    assert not [n for n in body if isinstance(n, (ast.FunctionDef, ast.ClassDef, ast.Assign))]
    assert len(body) <= 3  # import sys, the import of the entry, the ``if __name__`` guard


def test_importing_the_entry_runs_nothing():
    code = "import replication.__main__; print('imported')"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert (out.returncode, out.stdout) == (0, "imported\n"), out.stderr
