"""The ``claims`` command (``replication/cli/claims.py``): ``--check`` passes on the project's
ledger and on a copy, fails on a stale README and ``--readme`` brings it up to date; ``--summary``
prints the compact table; a missing or unmarked README, an edited record, a truncated notebook, a
README it cannot write and a malformed claims file are exit 2 with the message on stderr, never a
traceback and never a README changed; conflicting flags are refused before any work."""
import os
import re
import subprocess
import sys

import pytest

from conftest import _copy, _edit, _where
from replication._io import PROJECT_ROOT
from replication.study import ledger, paper

NOTEBOOKS = sorted((PROJECT_ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
S, E = ledger.README_START, ledger.README_END
HEADER = ",".join(paper.CLAIM_COLUMNS) + "\n"


@pytest.fixture(scope="module")
def collected():
    return ledger.collect()


@pytest.fixture
def project(tmp_path, monkeypatch):
    """A copy of the project's notebooks, README and claims file; ``python -m replication claims``
    reads it."""
    (tmp_path / "notebooks").mkdir()
    for path in NOTEBOOKS:
        _copy(path, tmp_path / "notebooks")
    _copy(PROJECT_ROOT / "README.md", tmp_path)
    (tmp_path / "data" / "paper").mkdir(parents=True)
    _copy(PROJECT_ROOT / "data" / "paper" / "claims.csv", tmp_path / "data" / "paper")
    monkeypatch.setattr(ledger, "PROJECT_ROOT", tmp_path)
    monkeypatch.setenv("REPLICATION_DATA_DIR", str(tmp_path / "data"))
    return tmp_path


def _claims_cli(*args):
    from replication.cli import main

    return main(["claims", *args])


def _in_copy(project, collected, claim):
    source, cell = _where(collected, claim)
    return project / "notebooks" / source.name, cell


def test_cli_check_passes_on_a_copy_and_fails_on_a_stale_readme(project, capsys):
    assert _claims_cli("--check") == 0
    assert "matches" in capsys.readouterr().out
    readme = project / "README.md"
    text = readme.read_text(encoding="utf-8")
    readme.write_text(text.replace("| `theorem1` |", "| `theorem1 (edited)` |"), encoding="utf-8")
    assert _claims_cli("--check") == 1
    assert "out of date: run 'python -m replication claims --readme'" in capsys.readouterr().err
    assert _claims_cli("--readme") == 0
    assert readme.read_text(encoding="utf-8") == text
    assert _claims_cli("--check") == 0


@pytest.mark.parametrize("readme_text, message", [
    (None, r"README\.md: no such file"),
    ("# no markers\n", rf"README\.md: no claims marker {S} and no {E}"),
    (f"{S}\n", rf"README\.md: no claims marker {E}"),
    (f"{E}\n{S}\n", rf"README\.md, line 1: the claims marker {E} \(line 1\) comes before"),
])
@pytest.mark.parametrize("flag", ["--check", "--readme"])
def test_cli_names_a_missing_or_unmarked_readme(project, capsys, readme_text, message, flag):
    readme = project / "README.md"
    if readme_text is None:
        readme.unlink()
    else:
        readme.write_text(readme_text, encoding="utf-8")
    assert _claims_cli(flag) == 2
    err = capsys.readouterr().err
    assert re.match(r"error: .*" + message, err), err
    assert not readme.exists() if readme_text is None else readme.read_text(encoding="utf-8") == readme_text


@pytest.mark.parametrize("claim, changes, message", [
    ("fig5_resilience", dict(verdict="probably"), r"cell {cell}: claim 'fig5_resilience': verdict must be one of"),
    ("fig5_resilience", dict(evidence=""), r"cell {cell}: claim 'fig5_resilience': evidence is blank"),
    ("fig5_resilience", dict(evidence=" \t"), r"cell {cell}: claim 'fig5_resilience': evidence is blank"),
    ("fig5_resilience", dict(claim="theorem_1"),
     r"cell {cell}: unknown claim 'theorem_1' .*close known ids: theorem1"),
    ("convex_problem", dict(claim="theorem1", verdict="holds"),
     r"cell {cell}: a second record of claim 'theorem1' \('holds'\) contradicts the one in 01_derivation_check"),
])
@pytest.mark.parametrize("flag", ["--check", "--readme"])
def test_cli_refuses_edited_records_and_leaves_readme_alone(project, collected, capsys, claim, changes, message,
                                                            flag):
    path, cell = _in_copy(project, collected, claim)
    _edit(path, claim, **changes)
    before = (project / "README.md").read_text(encoding="utf-8")
    assert _claims_cli(flag) == 2
    err = capsys.readouterr().err
    assert re.match("error: " + re.escape(str(path)) + ": " + message.format(cell=cell), err), err
    assert (project / "README.md").read_text(encoding="utf-8") == before


def test_cli_reports_a_readme_it_cannot_write(project, capsys, monkeypatch):
    readme = project / "README.md"
    before = readme.read_text(encoding="utf-8").replace("| `theorem1` |", "| `x` |")
    readme.write_text(before, encoding="utf-8")
    import replication._io as io

    def refuse(src, dst):
        raise PermissionError(13, "Permission denied", str(dst))

    monkeypatch.setattr(io.os, "replace", refuse)  # the atomic write's rename fails, as in a read-only folder
    assert _claims_cli("--readme") == 2
    assert capsys.readouterr().err.startswith("error: ")
    assert readme.read_text(encoding="utf-8") == before and not list(project.glob("README.md.*.part"))


def test_cli_names_a_truncated_notebook(project, collected, capsys):
    path, _ = _in_copy(project, collected, "theorem1")
    path.write_bytes(path.read_bytes()[:-100])
    assert _claims_cli("--check") == 2
    assert re.match("error: " + re.escape(str(path)) + r", line \d+, column \d+: not a notebook: not valid JSON",
                    capsys.readouterr().err)


def test_cli_names_a_malformed_claims_file_in_a_fresh_process(tmp_path):
    """In a subprocess: exit 2 and one line on stderr, no traceback."""
    (tmp_path / "paper").mkdir()
    (tmp_path / "paper" / "claims.csv").write_text(HEADER + "theorem1,s,w,,\ntheorem1,t,w,,\n", encoding="utf-8")
    env = {**os.environ, "REPLICATION_DATA_DIR": str(tmp_path)}
    out = subprocess.run([sys.executable, "-m", "replication", "claims", "--check"], capture_output=True, text=True,
                         timeout=120, env=env, cwd=PROJECT_ROOT)
    assert out.returncode == 2, out.stderr
    assert "Traceback" not in out.stderr
    assert re.fullmatch(r"error: .*claims\.csv, line 3, column 'claim': claim id 'theorem1' repeated "
                        r"\(first on line 2\)\n", out.stderr), out.stderr


def test_the_repository_ledger_passes_check():
    out = subprocess.run([sys.executable, "-m", "replication", "claims", "--check"], capture_output=True, text=True,
                         timeout=120, cwd=PROJECT_ROOT, env={k: v for k, v in os.environ.items()
                                                            if k != "REPLICATION_DATA_DIR"})
    assert out.returncode == 0, out.stderr
    assert out.stdout == ("README's claims table matches the records stored in the executed notebooks (that each "
                          "record is what its cell computes is checked by strict nbval: bash scripts/test)\n")


@pytest.mark.parametrize("flags", [("--summary", "--readme"), ("--readme", "--summary"), ("--check", "--readme"),
                                   ("--check", "--summary"), ("--check", "--readme", "--summary")])
def test_conflicting_claims_flags_are_refused_naming_them_before_any_work(flags, capsys, monkeypatch):
    from replication.study import ledger as ledger_module

    monkeypatch.setattr(ledger_module, "collect", lambda *a, **k: pytest.fail("work done despite the conflict"))
    assert _claims_cli(*flags) == 2
    err = capsys.readouterr().err
    ordered = [f for f in ("--check", "--readme", "--summary") if f in flags]
    assert f"error: {' and '.join(ordered)} cannot be used together" in err and "give one of them" in err


@pytest.mark.parametrize("flag", ["--summary", "--readme", "--check"])
def test_each_claims_flag_alone_is_not_refused_as_a_conflict(flag, capsys, monkeypatch):
    from replication.study import ledger as ledger_module

    monkeypatch.setattr(ledger_module, "collect", lambda *a, **k: (_ for _ in ()).throw(ValueError("collected")))
    assert _claims_cli(flag) == 2  # it reached the work (which this test makes fail), not the conflict check
    assert "error: collected" in capsys.readouterr().err


def test_cli_claims_summary_prints_the_compact_table(collected, capsys):
    from replication.cli import main

    assert main(["claims", "--summary"]) == 0
    assert capsys.readouterr().out == ledger.summary_from_ledger(collected)
