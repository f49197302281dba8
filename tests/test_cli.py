"""The command line in its own room (``replication/cli``): one module per command with
``add_parser`` and ``run``, ``__main__`` only the entry."""
import argparse
import importlib
import subprocess
import sys
from pathlib import Path

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
