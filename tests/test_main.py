"""The entry (``replication/__main__.py``, ``python -m replication``): two lines that run
:func:`replication.cli.main`, defining nothing and running nothing when imported. The commands'
tests: tests/cli/ (one file per command) and tests/test_cli.py (the top parser)."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


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
