"""The claims ledger: every checkable claim of the paper has a verdict, evidence and uncertainty, and README agrees."""
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from replication._io import PROJECT_ROOT
from replication.rig.datafile import DataFileError, DataFileNotFound
from replication.study import ledger, paper

CLAIMS = paper.load_claim_table()


@pytest.fixture(scope="module")
def collected():
    return ledger.collect()


def test_every_claim_has_a_verdict_evidence_and_uncertainty(collected):
    assert set(collected["claim"]) == set(CLAIMS.index)
    assert collected["verdict"].isin(ledger.VERDICTS).all()
    for col in ("evidence", "uncertainty", "setting", "section"):
        assert (collected[col].str.strip().str.len() > 10).all(), col
    only_if = collected["verdict"] == "holds only if"
    assert (collected.loc[only_if, "condition"].str.len() > 10).all()
    assert (collected.loc[~only_if, "condition"] == "").all()
    # evidence carries numbers (computed in the notebook), not only words
    assert collected["evidence"].map(lambda t: bool(re.search(r"\d", t))).all()


def test_readme_findings_table_is_the_ledger(collected):
    assert ledger.update_readme(collected, check=True), "run: python -m replication claims --readme"


def test_a_missing_claim_is_refused(tmp_path, collected):
    extra = tmp_path / "claims.csv"
    extra.write_text(PROJECT_ROOT.joinpath("data", "paper", "claims.csv").read_text()
                     + 'new_claim,"A statement nobody checked","Sec. IV",,\n')
    with pytest.raises(ValueError, match=r"claims without a verdict and evidence: \['new_claim'\]"):
        ledger.collect(claims_path=extra)


@pytest.mark.parametrize("kwargs, message", [
    (dict(claim="nope", verdict="holds"), "unknown claim 'nope'"),
    (dict(claim="theorem1", verdict="mostly"), "verdict must be one of"),
    (dict(claim="theorem1", verdict="holds only if"), "a condition goes with"),
    (dict(claim="theorem1", verdict="holds", condition="x"), "a condition goes with"),
])
def test_record_refuses_malformed_verdicts(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ledger.record(**{"evidence": "e 1", "uncertainty": "u", "setting": "s", "section": "S", **kwargs})


def test_malformed_claims_file_names_line_and_column(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,,Sec. II,,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'statement': empty"):
        paper.load_claim_table(path)
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,s,w,ten,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'paper_value': not a number"):
        paper.load_claim_table(path)


# ---- the claims file: every problem named with file and line --------------------------------------------------

HEADER = "claim,statement,where,paper_value,unit\n"


@pytest.mark.parametrize("text, message", [
    ("", r"claims.csv, line 1: empty; expected the header"),
    ("claim,statement,where,paper_value\ntheorem1,s,w,\n", r"claims.csv, line 1: columns must be"),
    ("claim,statement,where,unit,paper_value\ntheorem1,s,w,,\n", r"claims.csv, line 1: columns must be"),
    (HEADER + ",s,w,,\n", r"claims.csv, line 2, column 'claim': empty"),
    (HEADER + "   ,s,w,,\n", r"claims.csv, line 2, column 'claim': empty"),
    (HEADER + "theorem1,s,   ,,\n", r"claims.csv, line 2, column 'where': empty"),
    (HEADER + "theorem 1,s,w,,\n", r"claims.csv, line 2, column 'claim': not a claim id"),
    (HEADER + " theorem1,s,w,,\n", r"claims.csv, line 2, column 'claim': not a claim id"),
    (HEADER + "theorem1,s,w,,\nother,s,w,,\ntheorem1,t,w,,\n",
     r"claims.csv, line 4, column 'claim': claim id 'theorem1' repeated \(first on line 2\)"),
    (HEADER + "theorem1,s,w,nan,deg\n", r"claims.csv, line 2, column 'paper_value': not a finite number"),
    (HEADER + "theorem1,s,w,inf,deg\n", r"claims.csv, line 2, column 'paper_value': not a finite number"),
    (HEADER + "theorem1,s,w,ten,deg\n", r"claims.csv, line 2, column 'paper_value': not a number"),
    (HEADER + "theorem1,s,w,1,\n", r"claims.csv, line 2, column 'unit': a unit goes with, and only with"),
    (HEADER + "theorem1,s,w,,deg\n", r"claims.csv, line 2, column 'unit': a unit goes with, and only with"),
    (HEADER + "theorem1,s,w,,,extra\n", r"claims.csv, line 2: expected 5 fields .* got 6"),
    (HEADER + "theorem1,s,w\n", r"claims.csv, line 2: expected 5 fields .* got 3"),
    (HEADER + 'theorem1,"s,w,,\n', r"claims.csv, line 2: not a readable CSV"),
    (HEADER + 'theorem1,"s"x,w,,\n', r"claims.csv, line 2: not a readable CSV"),
    # a statement over two lines, a blank line: the lines counted are the file's
    (HEADER + 'theorem1,"two\nlines",w,,\n\nother,s,w,x,deg\n', r"claims.csv, line 5, column 'paper_value'"),
    (HEADER + 'theorem1,"two\nlines",w,x,deg\n', r"claims.csv, line 2, column 'paper_value'"),  # where it starts
])
def test_malformed_claims_file_is_refused_with_file_and_line(tmp_path, text, message):
    path = tmp_path / "claims.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match=message):
        paper.load_claim_table(path)
    with pytest.raises(DataFileError, match=message):  # and the ledger, which reads it
        ledger.collect([], claims_path=path)


def test_a_well_formed_claims_file_reads_as_text(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + 'theorem1,"two\nlines, a comma",w,,\n\nother,s,w,0.5,deg\n', encoding="utf-8")
    table = paper.load_claim_table(path)
    assert list(table.index) == ["theorem1", "other"]
    assert table.loc["theorem1", "statement"] == "two\nlines, a comma" and table.loc["other", "paper_value"] == "0.5"


def test_a_missing_claims_file_is_named(tmp_path):
    with pytest.raises(DataFileNotFound, match=r"nowhere\.csv: no such file"):
        paper.load_claim_table(tmp_path / "nowhere.csv")


# ---- ledger.record in the notebook: the rules ------------------------------------------------------------------

GOOD = dict(claim="theorem1", verdict="holds", evidence="e 1", uncertainty="u", setting="s", section="S", condition="")


@pytest.mark.parametrize("changes, message", [
    (dict(claim="theorm1"), r"unknown claim 'theorm1' \(not an id of .*claims\.csv\); close known ids: theorem1"),
    (dict(claim="zzz"), r"unknown claim 'zzz' .*no known id is close; known: eq7_relative, theorem1"),
    (dict(verdict="probably"), r"claim 'theorem1': verdict must be one of .*got 'probably'"),
    (dict(verdict="Holds"), r"verdict must be one of"),
    (dict(verdict=""), r"verdict must be one of"),
    (dict(evidence=""), r"claim 'theorem1': evidence is blank"),
    (dict(evidence=" \n\t "), r"claim 'theorem1': evidence is blank"),
    (dict(uncertainty="  "), r"claim 'theorem1': uncertainty is blank"),
    (dict(setting="\n"), r"claim 'theorem1': setting is blank"),
    (dict(section=" "), r"claim 'theorem1': section is blank"),
    (dict(evidence=0.5), r"claim 'theorem1': evidence must be text, got float"),
    (dict(verdict="holds only if"), r"a condition goes with, and only with, 'holds only if'"),
    (dict(verdict="holds only if", condition="   "), r"a condition goes with, and only with"),
    (dict(condition="the data are noise-free"), r"a condition goes with, and only with"),
])
def test_record_refuses_each_broken_rule(changes, message):
    kwargs = {**GOOD, **changes}
    with pytest.raises(ValueError, match=message):
        ledger.record(kwargs.pop("claim"), kwargs.pop("verdict"), **kwargs)


@pytest.mark.parametrize("verdict, condition", [(v, "the data are noise-free" if v == ledger.HOLDS_ONLY_IF else "")
                                                for v in ledger.VERDICTS])
def test_record_accepts_every_verdict_of_the_vocabulary(capsys, verdict, condition):
    ledger.record("theorem1", verdict, evidence="e 1", uncertainty="u", setting="s", section="S", condition=condition)
    assert capsys.readouterr().out.startswith(f"[theorem1] {verdict}")


def test_the_vocabulary_is_the_documented_one():
    assert ledger.VERDICTS == ("holds", "fails", "holds only if", "undecidable from the text")
    assert ledger.HOLDS_ONLY_IF in ledger.VERDICTS


# ---- collecting: stored outputs checked again (they could have been edited) --------------------------------------

NOTEBOOKS = sorted((PROJECT_ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))


def _where(collected, claim):
    row = collected.loc[collected["claim"] == claim].iloc[0]
    return PROJECT_ROOT / "notebooks" / f"{row.notebook}.ipynb", int(row.cell)


def _copy(path, folder, name=None):
    target = folder / (name or Path(path).name)
    shutil.copyfile(path, target)
    return target


def _edit(path, which, **changes):
    """Change the stored record of claim ``which`` in the notebook ``path`` (a copy); ``_DROP`` deletes a field."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    for cell in nb["cells"]:
        for out in cell.get("outputs", []):
            rec = out.get("data", {}).get(ledger.CLAIM_MIME)
            if rec is not None and rec["claim"] == which:
                rec.update(changes)
                for key in [k for k, v in changes.items() if v is _DROP]:
                    del rec[key]
                path.write_text(json.dumps(nb, indent=1, ensure_ascii=False), encoding="utf-8")
                return
    raise AssertionError(f"no record of {which} in {path}")


_DROP = object()


def _notebook(path, *records):
    """A minimal notebook at ``path`` with one cell per stored record (a dict, or any JSON value)."""
    cells = [{"cell_type": "code", "source": "", "metadata": {}, "execution_count": 1,
              "outputs": [{"output_type": "display_data", "metadata": {}, "data": {ledger.CLAIM_MIME: rec}}]}
             for rec in records] + [{"cell_type": "markdown", "source": ["## S"], "metadata": {}}]
    path.write_text(json.dumps({"cells": cells, "metadata": {}, "nbformat": 4, "nbformat_minor": 5}),
                    encoding="utf-8")
    return path


@pytest.mark.parametrize("claim, changes, message", [
    ("fig5_resilience", dict(verdict="probably"), r"cell {cell}: claim 'fig5_resilience': verdict must be one of"),
    ("fig5_resilience", dict(evidence=""), r"cell {cell}: claim 'fig5_resilience': evidence is blank"),
    ("fig5_resilience", dict(evidence="   "), r"cell {cell}: claim 'fig5_resilience': evidence is blank"),
    ("fig5_resilience", dict(uncertainty="\n"), r"cell {cell}: claim 'fig5_resilience': uncertainty is blank"),
    ("fig5_resilience", dict(setting=" "), r"cell {cell}: claim 'fig5_resilience': setting is blank"),
    ("fig5_resilience", dict(evidence=12), r"cell {cell}: claim 'fig5_resilience': evidence must be text"),
    ("fig5_resilience", dict(claim="fig5_resilient"),
     r"cell {cell}: unknown claim 'fig5_resilient' .*close known ids: fig5_resilience"),
    ("fig5_resilience", dict(verdict="holds only if"),
     r"cell {cell}: claim 'fig5_resilience': a condition goes with, and only with, 'holds only if'"),
    ("fig5_resilience", dict(condition="if"), r"cell {cell}: claim 'fig5_resilience': a condition goes with"),
    ("fig5_resilience", dict(setting=_DROP), r"cell {cell}: a stored claim record must have the fields"),
    ("fig5_resilience", dict(note="x"), r"cell {cell}: a stored claim record must have the fields"),
])
def test_collect_refuses_an_edited_stored_record(tmp_path, collected, claim, changes, message):
    source, cell = _where(collected, claim)
    path = _copy(source, tmp_path)
    _edit(path, claim, **changes)
    with pytest.raises(DataFileError, match=re.escape(str(path)) + ": " + message.format(cell=cell)):
        ledger.collect([path], complete=False)


@pytest.mark.parametrize("stored", ["holds", ["theorem1", "holds"], None])
def test_collect_refuses_a_stored_record_that_is_not_an_object(tmp_path, stored):
    path = _notebook(tmp_path / "01_x.ipynb", stored)
    with pytest.raises(DataFileError, match=r"01_x\.ipynb: cell 0: a stored claim record must have the fields"):
        ledger.collect([path], complete=False)


def test_collect_refuses_two_contradicting_records_naming_both_notebooks_and_cells(tmp_path, collected):
    first, first_cell = _where(collected, "fig5_resilience")  # 'fails'
    second, second_cell = _where(collected, "convex_problem")  # 'fails' too: make it contradict
    a, b = _copy(first, tmp_path), _copy(second, tmp_path)
    _edit(b, "convex_problem", claim="fig5_resilience", verdict="holds")
    with pytest.raises(DataFileError, match=re.escape(f"{b}: cell {second_cell}: a second record of claim "
                                                      f"'fig5_resilience' ('holds') contradicts the one in {a.name}, "
                                                      f"cell {first_cell} ('fails'): one record per claim")):
        ledger.collect([a, b], complete=False)


def test_collect_refuses_a_second_record_even_when_it_repeats_the_first(tmp_path, collected):
    source, cell = _where(collected, "eq7_relative")
    a, b = _copy(source, tmp_path), _copy(source, tmp_path, "09_copy.ipynb")
    with pytest.raises(DataFileError, match=re.escape(f"{b}: cell {cell}: a second record of claim 'eq7_relative' "
                                                      f"('holds') repeats the one in {a.name}, cell {cell}")):
        ledger.collect([a, b], complete=False)


def test_collect_refuses_two_records_of_one_claim_in_one_notebook(tmp_path):
    rec = dict(GOOD)
    path = _notebook(tmp_path / "01_x.ipynb", rec, {**rec, "evidence": "other 2"})
    with pytest.raises(DataFileError, match=r"01_x\.ipynb: cell 1: a second record of claim 'theorem1' \('holds'\) "
                                            r"differs from the one in 01_x\.ipynb, cell 0"):
        ledger.collect([path], complete=False)


def test_collect_refuses_a_truncated_notebook_naming_file_line_and_column(tmp_path, collected):
    source, _ = _where(collected, "fig5_resilience")
    path = _copy(source, tmp_path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(DataFileError, match=re.escape(str(path)) + r", line \d+, column \d+: not a notebook: "
                                            r"not valid JSON \(.*; a truncated file\?\)"):
        ledger.collect([path], complete=False)


@pytest.mark.parametrize("text, message", [
    ("", r", line 1, column 1: not a notebook: not valid JSON"),
    ("claims, not JSON\n", r", line 1, column 1: not a notebook: not valid JSON"),
    ('{"cells": [\n  {"outputs": []},\n  {"outputs": [}\n', r", line 3, column 16: not a notebook: not valid JSON"),
    ("[1, 2]", r": not a notebook: no list of 'cells'"),
    ('{"cells": {}}', r": not a notebook: no list of 'cells'"),
    ('{"cells": [{"outputs": {}}]}', r": cell 0: not a notebook cell"),
    ('{"cells": [{"outputs": ["text"]}]}', r": cell 0: an output that is not an object"),
])
def test_collect_refuses_what_is_not_a_notebook(tmp_path, text, message):
    path = tmp_path / "01_broken.ipynb"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match=re.escape(str(path)) + message):
        ledger.collect([path], complete=False)


def test_collect_names_a_missing_notebook(tmp_path):
    with pytest.raises(DataFileNotFound, match=r"01_gone\.ipynb: no such file"):
        ledger.collect([tmp_path / "01_gone.ipynb"], complete=False)


def test_collect_accepts_a_valid_minimal_ledger(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + "theorem1,s,w,,\n", encoding="utf-8")
    nb = _notebook(tmp_path / "01_x.ipynb", dict(GOOD))
    table = ledger.collect([nb], claims_path=path)
    assert table[["claim", "verdict", "notebook", "cell"]].values.tolist() == [["theorem1", "holds", "01_x", 0]]


# ---- README's markers ------------------------------------------------------------------------------------------

S, E = ledger.README_START, ledger.README_END


@pytest.mark.parametrize("text, message", [
    ("# title\nno table\n", rf"README\.md: no claims marker {S} and no {E}"),
    (f"# title\n{S}\n| table |\n", rf"README\.md: no claims marker {E}:"),
    (f"# title\n| table |\n{E}\n", rf"README\.md: no claims marker {S}:"),
    (f"# title\n{E}\n| table |\n{S}\n", rf"README\.md, line 2: the claims marker {E} \(line 2\) comes before {S} "
                                        rf"\(line 4\)"),
    (f"{S}\n{E}\n{S}\n{E}\n", rf"README\.md, line 3: the claims marker {S} appears 2 times \(lines \[1, 3\]\)"),
    (f"{S}\n{E}\ntext {E}\n", rf"README\.md, line 3: the claims marker {E} appears 2 times"),
])
def test_readme_markers_missing_repeated_or_out_of_order_are_named(tmp_path, collected, text, message):
    readme = tmp_path / "README.md"
    readme.write_text(text, encoding="utf-8")
    for check in (True, False):
        with pytest.raises(DataFileError, match=message):
            ledger.update_readme(collected, readme, check=check)
    assert readme.read_text(encoding="utf-8") == text


def test_a_missing_readme_is_named(tmp_path, collected):
    with pytest.raises(DataFileNotFound, match=r"README\.md: no such file \(the README with the claims table\)"):
        ledger.update_readme(collected, tmp_path / "README.md", check=True)


def test_readme_table_is_written_between_the_markers(tmp_path, collected):
    readme = tmp_path / "README.md"
    readme.write_text(f"head\n{S}{E} tail\n", encoding="utf-8")
    assert not ledger.update_readme(collected, readme, check=True)
    assert ledger.update_readme(collected, readme)
    assert readme.read_text(encoding="utf-8") == f"head\n{S}\n{ledger.summary_from_ledger(collected)}{E} tail\n"
    assert ledger.update_readme(collected, readme, check=True)


# ---- the command line: exit 2 and the message on stderr, never a traceback --------------------------------------

@pytest.fixture
def project(tmp_path, monkeypatch):
    """A copy of the project's notebooks, README and claims file; ``python -m replication claims`` reads it."""
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
    from replication.__main__ import main

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


def test_a_reader_that_stops_early_ends_the_output_quietly():
    """``python -m replication ... | head -n 1``: no BrokenPipeError traceback (red team), exit 141 (SIGPIPE's). The
    output (1 MB) is larger than a pipe's buffer, so the pipe does break; without the wrapper it prints a traceback."""
    script = ("import sys, replication.__main__ as m\n"
              "m.main = lambda argv=None: print('| claim |\\n' + 'x' * 100 + '\\n' * 1000000) or 0\n"
              "sys.exit(m._main_closing_pipes() if sys.argv[1] == 'wrapped' else m.main())\n")
    runs = {}
    for how in ("wrapped", "bare"):
        runs[how] = subprocess.run(f"'{sys.executable}' -c \"$S\" {how} | head -n 1; exit ${{PIPESTATUS[0]}}",
                                   shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=60,
                                   env={**os.environ, "S": script})
    assert runs["bare"].returncode != 0 and "BrokenPipeError" in runs["bare"].stderr  # the pipe did break
    out = runs["wrapped"]
    assert out.stdout == "| claim |\n" and out.stderr == "" and out.returncode == 141


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
