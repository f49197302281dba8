"""The claims ledger: every checkable claim of the paper has a verdict, evidence and uncertainty,
and README agrees."""
import ast
import json
import re
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import _DROP, _copy, _edit, _where
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


def test_check_evidence_names_the_claim_and_condition_and_passes_what_holds():
    assert ledger.check_evidence(True, "cost_to_zero", "x") is None
    assert ledger.check_evidence(np.bool_(True), "cost_to_zero", "x") is None
    with pytest.raises(ValueError) as err:
        ledger.check_evidence(np.bool_(False), "cost_to_zero", "the cost falls (0.5)")
    assert str(err.value) == ("claim 'cost_to_zero': the evidence does not bear the verdict: expected the cost falls "
                              "(0.5)")


HEADER = ",".join(paper.CLAIM_COLUMNS) + "\n"


@pytest.mark.parametrize("text, message", [
    ("", r"claims.csv, line 1: empty; expected the header"),
    (HEADER + "theorem1,s,w,,\nother,s,w,,\ntheorem1,t,w,,\n",
     r"claims.csv, line 4, column 'claim': claim id 'theorem1' repeated \(first on line 2\)"),
])
def test_collect_names_a_malformed_claims_file_and_line(tmp_path, text, message):
    path = tmp_path / "claims.csv"  # every problem of the file itself: tests/study/test_paper.py
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match=message):
        ledger.collect([], claims_path=path)


# ---- ledger.record in the notebook: the rules
# ------------------------------------------------------------------

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


# ---- collecting: stored outputs checked again (they could have been edited)
# --------------------------------------

def _notebook(path, *records):
    """A minimal notebook at ``path`` with one cell per stored record (a dict, or any JSON
    value)."""
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


@pytest.mark.parametrize("stored, got", [("holds", "str"), (["theorem1", "holds"], "list"), (None, "NoneType")])
def test_collect_refuses_a_stored_record_that_is_not_an_object(tmp_path, stored, got):
    path = _notebook(tmp_path / "01_x.ipynb", stored)
    with pytest.raises(DataFileError, match=r"01_x\.ipynb: cell 0: a stored claim record must have the fields "
                                            rf"\[.*\], got {got}$"):
        ledger.collect([path], complete=False)


def test_collect_names_the_fields_a_stored_record_has(tmp_path):
    path = _notebook(tmp_path / "01_x.ipynb", {**GOOD, "note": "x"})
    with pytest.raises(DataFileError, match=re.escape(f"must have the fields {list(ledger.RECORD_FIELDS)}, got "
                                                      f"{sorted([*GOOD, 'note'])}")):
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
    ('{"cells": [{"outputs": []}, 5]}', r": cell 1: not a notebook cell"),
    ('{"cells": [{"outputs": ["text"]}]}', r": cell 0: an output that is not an object"),
])
def test_collect_refuses_what_is_not_a_notebook(tmp_path, text, message):
    path = tmp_path / "01_broken.ipynb"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match=re.escape(str(path)) + message):
        ledger.collect([path], complete=False)


def test_collect_names_a_missing_notebook(tmp_path):
    with pytest.raises(DataFileNotFound, match=r"01_gone\.ipynb: no such file \(a notebook\)"):
        ledger.collect([tmp_path / "01_gone.ipynb"], complete=False)


def test_collect_accepts_a_valid_minimal_ledger(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + "theorem1,s,w,,\n", encoding="utf-8")
    nb = _notebook(tmp_path / "01_x.ipynb", dict(GOOD))
    table = ledger.collect([nb], claims_path=path)
    assert table[["claim", "verdict", "notebook", "cell"]].values.tolist() == [["theorem1", "holds", "01_x", 0]]


# ---- README's markers
# ------------------------------------------------------------------------------------------

S, E = ledger.README_START, ledger.README_END


@pytest.mark.parametrize("text, message", [
    ("# title\nno table\n", rf"README\.md: no claims marker {S} and no {E}"),
    (f"# title\n{S}\n| table |\n", rf"README\.md: no claims marker {E}:"),
    (f"# title\n| table |\n{E}\n", rf"README\.md: no claims marker {S}:"),
    (f"# title\n{E}\n| table |\n{S}\n", rf"README\.md, line 2: the claims marker {E} \(line 2\) comes before {S} "
                                        rf"\(line 4\)"),
    (f"{S}\n{E}\n{S}\n{E}\n", rf"README\.md, line 3: the claims marker {S} appears 2 times \(lines \[1, 3\]\)"),
    (f"\n{S}\n{E}\n{S}\n", rf"README\.md, line 4: the claims marker {S} appears 2 times \(lines \[2, 4\]\)"),
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


# --------------------------------------------------------------------------------------------------
# The claims ledger's rules that mutation testing found unguarded (scripts/mutation): what
# :func:`record` displays, how :func:`collect` reads records back (which notebook and cell, the
# claims file's order), the Markdown table and the README update.


CLAIMS_CSV = ("claim,statement,where,paper_value,unit\n"
              "zeta,the last id alphabetically comes first,Sec. 1,,\n"
              "alpha,a | pipe in the statement,Eq. (2),0.5,deg\n"
              "mid,a third claim,Table 1,,\n")


def _record(claim, verdict="holds", condition="", evidence="e 1.0", uncertainty="u", setting="s", section="S"):
    return asdict(ledger.ClaimRecord(claim, verdict, evidence, uncertainty, setting, section, condition))


def _notebook_ml(path, cells):
    """A notebook whose cells carry these outputs (a list of output lists; None: a cell without
    outputs)."""
    nb = {"cells": [{"cell_type": "code", "source": ""} if outs is None else
                    {"cell_type": "code", "source": "", "outputs": outs} for outs in cells]
          + [{"cell_type": "markdown", "source": "## S"}]}  # the section every _record names
    path.write_text(json.dumps(nb), encoding="utf-8")
    return path


def _out(rec):
    return {"output_type": "display_data", "data": {"text/plain": "x", ledger.CLAIM_MIME: rec}}


@pytest.fixture
def claims_path(tmp_path):
    p = tmp_path / "claims.csv"
    p.write_text(CLAIMS_CSV)
    return p


@pytest.fixture
def two_notebooks(tmp_path):
    a = _notebook_ml(tmp_path / "01_a.ipynb", [
        None,
        [{"output_type": "stream", "text": "no data"}, _out(_record("alpha", evidence="from a, cell 1"))],
        [{"output_type": "execute_result", "data": {"text/plain": "2"}}],
        [_out(_record("zeta", evidence="z in a"))],
    ])
    b = _notebook_ml(tmp_path / "02_b.ipynb", [
        [{"output_type": "stream", "text": "nothing recorded here"}],
        [_out(_record("mid", "holds only if", condition="J >= 3", evidence="m"))],
    ])
    return [b, a]


def test_record_prints_the_readable_line_outside_a_notebook(capsys):
    ledger.record("theorem1", "holds", evidence="e 1", uncertainty="exact", setting="sim", section="S")
    assert capsys.readouterr().out == ("[theorem1] holds\n  evidence: e 1\n  uncertainty: exact\n  setting: sim\n"
                                       "  measured in: S\n")
    ledger.record("theorem1", "holds only if", evidence="e 2", uncertainty="u", setting="s", section="S",
                  condition="J >= 3")
    assert capsys.readouterr().out == ("[theorem1] holds only if J >= 3\n  evidence: e 2\n  uncertainty: u\n"
                                       "  setting: s\n  measured in: S\n")


def test_record_displays_the_claim_payload_in_a_notebook(monkeypatch):
    import IPython
    import IPython.display

    shown = []
    monkeypatch.setattr(IPython, "get_ipython", lambda: object())
    monkeypatch.setattr(IPython.display, "display", lambda obj, **kw: shown.append((obj, kw)))
    ledger.record("theorem1", "fails", evidence="e 3", uncertainty="u", setting="s", section="S")
    (obj, kw), = shown
    assert kw == {"raw": True}
    assert obj == {"text/plain": "[theorem1] fails\n  evidence: e 3\n  uncertainty: u\n  setting: s\n  measured in: S",
                   ledger.CLAIM_MIME: {"claim": "theorem1", "verdict": "fails", "evidence": "e 3", "uncertainty": "u",
                                       "setting": "s", "section": "S", "condition": ""}}


def test_record_displays_the_condition_and_prints_without_ipython(monkeypatch, capsys):
    import IPython
    import IPython.display

    shown = []
    monkeypatch.setattr(IPython, "get_ipython", lambda: object())
    monkeypatch.setattr(IPython.display, "display", lambda obj, **kw: shown.append(obj))
    ledger.record("theorem1", "holds only if", evidence="e", uncertainty="u", setting="s", section="S",
                  condition="J >= 3")
    assert shown[0][ledger.CLAIM_MIME]["condition"] == "J >= 3"
    assert shown[0]["text/plain"].startswith("[theorem1] holds only if J >= 3\n")
    monkeypatch.setitem(sys.modules, "IPython", None)  # IPython not installed: the record is printed
    ledger.record("theorem1", "fails", evidence="e", uncertainty="u", setting="s", section="S")
    assert capsys.readouterr().out == ("[theorem1] fails\n  evidence: e\n  uncertainty: u\n  setting: s\n"
                                       "  measured in: S\n")
    assert len(shown) == 1


@pytest.mark.parametrize("field", ["evidence", "uncertainty", "setting", "section"])
def test_record_names_the_empty_field(field):
    kwargs = {"evidence": "e", "uncertainty": "u", "setting": "s", "section": "S", field: "  "}
    with pytest.raises(ValueError, match=rf"claim 'theorem1'.*\b{field} is blank"):
        ledger.record("theorem1", "holds", **kwargs)


def test_record_messages_name_the_known_claims_and_verdicts():
    with pytest.raises(ValueError, match=r"unknown claim 'nope' \(not an id of .*claims\.csv\); no known id is close; "
                                         r"known: eq7_relative, theorem1, "):
        ledger.record("nope", "holds", evidence="e", uncertainty="u", setting="s", section="S")
    with pytest.raises(ValueError, match=r"verdict must be one of \('holds', 'fails', .*got 'maybe'"):
        ledger.record("theorem1", "maybe", evidence="e", uncertainty="u", setting="s", section="S")


def test_an_unknown_claim_names_the_claims_file_it_was_checked_against(tmp_path, claims_path):
    fields = dict(verdict="holds", evidence="e", uncertainty="u", setting="s", section="S")
    with pytest.raises(ValueError, match=re.escape(f"(not an id of {claims_path})")):
        ledger.check_record("nope", **fields, claims_path=claims_path)
    with pytest.raises(ValueError, match=re.escape(f"(not an id of {paper.data_dir() / 'paper' / 'claims.csv'})")):
        ledger.check_record("nope", **fields)
    nb = _notebook_ml(tmp_path / "01_a.ipynb", [[_out(_record("nope"))]])
    named = re.escape(f"(not an id of {claims_path})")
    with pytest.raises(DataFileError, match=r"cell 0: unknown claim 'nope' " + named):
        ledger.collect([nb], claims_path=claims_path, complete=False)


def test_check_record_reads_the_claims_it_is_given_else_its_claims_file(claims_path):
    fields = dict(verdict="holds", evidence="e", uncertainty="u", setting="s", section="S")
    assert ledger.check_record("zeta", **fields, claims_path=claims_path).claim == "zeta"  # not in the project's
    assert ledger.check_record("zeta", **fields, claims=paper.load_claim_table(claims_path)).claim == "zeta"


def test_an_unknown_claim_names_at_most_five_close_ids(tmp_path):
    ids = [f"claim_{c}" for c in "abcdef"]  # six ids, all as close to 'claim_x'
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + "".join(f"{i},s,w,,\n" for i in ids), encoding="utf-8")
    with pytest.raises(ValueError, match="close known ids: ") as err:
        ledger.check_record("claim_x", "holds", "e", "u", "s", "S", claims_path=path)
    named = str(err.value).split("close known ids: ")[1].split(", ")
    assert len(named) == 5 and set(named) <= set(ids)


def test_collect_reads_every_record_with_its_notebook_and_cell_in_the_claims_order(two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    assert list(got.columns) == ["claim", "verdict", "condition", "evidence", "uncertainty", "setting", "section",
                                 "notebook", "cell", "anchor", "statement", "where", "paper_value"]
    assert list(got.index) == [0, 1, 2]
    # claims in the claims file's order (zeta, alpha, mid: not alphabetical), not in the notebooks'
    # order
    assert list(got["claim"]) == ["zeta", "alpha", "mid"]
    assert list(got["notebook"]) == ["01_a", "01_a", "02_b"]
    assert list(got["cell"]) == [3, 1, 1]
    assert list(got["evidence"]) == ["z in a", "from a, cell 1", "m"]
    assert list(got["condition"]) == ["", "", "J >= 3"]
    assert got.loc[1, "statement"] == "a | pipe in the statement" and got.loc[1, "paper_value"] == "0.5"


def test_collect_refuses_unknown_and_missing_claims(tmp_path, two_notebooks, claims_path):
    extra = _notebook_ml(tmp_path / "04_x.ipynb", [[_out(_record("ghost"))], [_out(_record("boo"))]])
    with pytest.raises(ValueError, match=r"04_x\.ipynb.*cell 0: unknown claim 'ghost'"):
        ledger.collect(two_notebooks + [extra], claims_path=claims_path)
    partial = [two_notebooks[1]]  # mid has no record there
    with pytest.raises(ValueError, match=r"claims without a verdict and evidence.*\['mid'\]"):
        ledger.collect(partial, claims_path=claims_path)
    got = ledger.collect(partial, claims_path=claims_path, complete=False)
    assert list(got["claim"]) == ["zeta", "alpha"]


def test_collect_without_notebooks_reads_the_projects_own():
    got = ledger.collect()
    assert set(got["notebook"]) <= {p.stem for p in (ledger.PROJECT_ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")}
    assert len(set(got["notebook"])) > 1


def test_markdown_from_ledger_table_escapes_pipes_and_newlines(two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    got.loc[0, "evidence"] = "two\nlines"
    md = ledger.markdown_from_ledger(got).splitlines()
    assert md[:2] == ["| claim | the paper | verdict | evidence | uncertainty | where measured |",
                      "|---|---|---|---|---|---|"]
    assert md[2] == ("| `zeta` | the last id alphabetically comes first (Sec. 1) | holds | two lines | u | "
                     "s; [notebook 01, § S](notebooks/01_a.ipynb#s) |")
    assert md[3] == ("| `alpha` | a \\| pipe in the statement (Eq. (2)) | holds | from a, cell 1 | u | "
                     "s; [notebook 01, § S](notebooks/01_a.ipynb#s) |")
    assert md[4] == ("| `mid` | a third claim (Table 1) | holds only if J >= 3 | m | u | "
                     "s; [notebook 02, § S](notebooks/02_b.ipynb#s) |")
    assert len(md) == 5 and ledger.markdown_from_ledger(got).endswith(" |\n")


def test_summary_from_ledger_gives_the_counts_and_one_compact_row_per_claim(two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    got.loc[0, "statement"] = "two\nlines"
    md = ledger.summary_from_ledger(got).splitlines()
    assert md[:4] == ["**3 claims: 2 hold, 1 hold only if, 0 fail, 0 undecidable from the text.**", "",
                      "| claim | the paper says | verdict | measured in |", "|---|---|---|---|"]
    assert md[4] == "| `zeta` | two lines | holds | [01, § S](notebooks/01_a.ipynb#s) |"
    assert md[5] == "| `alpha` | a \\| pipe in the statement | holds | [01, § S](notebooks/01_a.ipynb#s) |"
    assert md[6] == "| `mid` | a third claim | holds only if | [02, § S](notebooks/02_b.ipynb#s) |"
    assert len(md) == 7 and ledger.summary_from_ledger(got).endswith(" |\n")
    assert ledger.verdict_counts(got) == {"holds": 2, "fails": 0, "holds only if": 1, "undecidable from the text": 0}


def test_summary_gives_the_counts_and_one_row_per_claim(collected):
    summary = ledger.summary_from_ledger(collected)
    per_claim = collected.drop_duplicates("claim")
    counts = {v: int((per_claim["verdict"] == v).sum()) for v in ledger.VERDICTS}
    assert summary.splitlines()[0] == (
        f"**{len(per_claim)} claims: {counts['holds']} hold, {counts[ledger.HOLDS_ONLY_IF]} hold only if, "
        f"{counts['fails']} fail, {counts['undecidable from the text']} undecidable from the text.**")
    rows = [line for line in summary.splitlines() if line.startswith("| `")]
    assert len(rows) == len(per_claim) == sum(counts.values())
    for line, rec in zip(rows, per_claim.itertuples()):
        assert line.startswith(f"| `{rec.claim}` |") and f"| {rec.verdict} |" in line
        assert f"(notebooks/{rec.notebook}.ipynb#{ledger.heading_anchor(rec.section)})" in line



def test_counts_name_every_verdict_even_at_zero(collected):
    one = collected[collected["claim"] == "eq7_relative"]
    assert ledger.counts_in_words(one) == "1 claims: 1 hold, 0 hold only if, 0 fail, 0 undecidable from the text"



def test_readme_holds_the_compact_table_and_is_short():
    text = (PROJECT_ROOT / "README.md").read_text(encoding="utf-8")
    assert ledger.update_readme(ledger.collect(), check=True)
    lines = text.splitlines()
    assert len(lines) <= 150, len(lines)
    assert max(len(line) for line in lines) <= 400
    first_screen = "\n".join(lines[:40])
    assert ledger.counts_in_words(ledger.collect()) in first_screen
    assert "bash scripts/reproduce" in first_screen and "bash scripts/test" in first_screen
    assert "bash scripts/docs" in text and "python -m replication export report.json --to kalibr --base" in text


def test_verdict_counts_counts_each_claim_once_however_many_its_rows():
    rows = pd.DataFrame({"claim": ["a", "a", "b"], "verdict": ["holds", "holds", "fails"],
                         "notebook": ["01_x", "02_y", "01_x"]})
    assert ledger.verdict_counts(rows) == {"holds": 1, "fails": 1, "holds only if": 0, "undecidable from the text": 0}


# ---- first_clause: the evidence's first clause (the book's front page)
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("words, cut", [(5, False), (4, True)])
def test_first_clause_cuts_only_beyond_its_word_limit(words, cut):
    assert ledger.first_clause("one two three four five", max_words=words) == \
        ("one two three four …" if cut else "one two three four five")


def test_first_clause_stops_at_a_clause_outside_brackets_only():
    assert ledger.first_clause("a (b; c) d; e") == "a (b; c) d …"
    assert ledger.first_clause("by eq. (8) it holds") == "by eq. (8) it holds"
    assert ledger.first_clause("it holds. The rest") == "it holds …"
    assert ledger.first_clause("it holds.") == "it holds."


@pytest.mark.parametrize("text, clause", [
    ("", ""),
    ("holds", "holds"),
    ("  one   two  ", "one two"),  # white space between words as one space, none at the ends
    ("it holds; the rest", "it holds …"),
    ("it holds;the rest", "it holds;the rest"),  # a clause ends at "; ", not at ";"
    ("it holds. The rest", "it holds …"),
    ("it holds. the rest", "it holds. the rest"),  # ". " ends a clause only before a capital
    ("by eq. (8) it holds", "by eq. (8) it holds"),  # abbreviations before a bracket, a digit, lower case
    ("see Fig. 5 and e.g. the rest", "see Fig. 5 and e.g. the rest"),
    ("at 0.5 deg. Then more", "at 0.5 deg …"),  # a decimal point is no end; the sentence's is
    ("X; rest", "X …"),
    ("the R0 estimate holds; rest", "the R0 estimate holds …"),  # a capital after no ". " ends nothing
    # a clause that ends the text: nothing follows, no mark
    ("it holds.", "it holds."),
    ("it holds; ", "it holds"),
    ("it holds. ", "it holds."),
    # brackets of each kind, nested, unmatched
    ("a (b; c) d; e", "a (b; c) d …"),
    ("a [b. C] {d; e} f; g", "a [b. C] {d; e} f …"),
    ("f(a (b; c); d) e; g", "f(a (b; c); d) e …"),
    ("(X; b) c; d", "(X; b) c …"),
    ("a) b; c", "a) b …"),  # a closing bracket with none open is passed over
    ("f(a; b", "f(a; b"),  # inside a bracket never closed no clause ends
])
def test_first_clause_ends_at_the_first_clause_end_outside_brackets(text, clause):
    assert ledger.first_clause(text) == clause


_WORDS = [f"w{k}" for k in range(31)]


@pytest.mark.parametrize("text, max_words, clause", [
    (" ".join(_WORDS[:30]), None, " ".join(_WORDS[:30])),  # the default limit, 30 words
    (" ".join(_WORDS), None, " ".join(_WORDS[:30]) + " …"),
    ("one two three", 3, "one two three"),
    ("one two three", 2, "one two …"),
    ("one two three; four", 2, "one two …"),
    ("one two; three", 2, "one two …"),
])
def test_first_clause_keeps_at_most_max_words_words(text, max_words, clause):
    got = ledger.first_clause(text) if max_words is None else ledger.first_clause(text, max_words=max_words)
    assert got == clause


def test_update_readme_writes_the_counts_between_every_pair_of_counts_markers(tmp_path, two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    readme = tmp_path / "README.md"
    start, end = "<!-- counts:start -->", "<!-- counts:end -->"
    readme.write_text(f"**{start}old{end}** and {start}{end}\n{ledger.README_START}\n{ledger.README_END}\n"
                      f"{start} unpaired\n", encoding="utf-8")
    assert ledger.update_readme(got, readme) is True
    counts = f"{start}3 claims: 2 hold, 1 hold only if, 0 fail, 0 undecidable from the text{end}"
    assert readme.read_text(encoding="utf-8").splitlines()[0] == f"**{counts}** and {counts}"
    assert readme.read_text(encoding="utf-8").endswith(f"{start} unpaired\n")
    assert ledger.update_readme(got, readme, check=True) is True


def test_update_readme_writes_between_the_markers_and_checks(tmp_path, two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    readme = tmp_path / "README.md"
    readme.write_text(f"# head\n{ledger.README_START}\nold table\n{ledger.README_END}\ntail\n", encoding="utf-8")
    assert ledger.update_readme(got, readme, check=True) is False
    assert "old table" in readme.read_text()  # check only: nothing written
    assert ledger.update_readme(got, readme) is True
    assert readme.read_text(encoding="utf-8") == (f"# head\n{ledger.README_START}\n{ledger.summary_from_ledger(got)}"
                                                  f"{ledger.README_END}\ntail\n")
    assert ledger.update_readme(got, readme, check=True) is True
    before = readme.stat().st_mtime_ns
    assert ledger.update_readme(got, readme) is True and readme.stat().st_mtime_ns == before
    for text in (f"{ledger.README_START} only", f"{ledger.README_END} only"):
        readme.write_text(text)
        with pytest.raises(ValueError, match="no claims marker"):
            ledger.update_readme(got, readme)


def test_a_section_that_is_no_heading_of_the_notebook_is_refused_naming_the_close_ones(tmp_path, claims_path):
    nb = _notebook_ml(tmp_path / "01_a.ipynb", [[_out(_record("alpha", section="T"))]])
    with pytest.raises(ValueError, match=r"01_a\.ipynb: cell 0: claim 'alpha': the section 'T' is not a heading of "
                                         r"this notebook; its headings: \['S'\]"):
        ledger.collect([nb], claims_path=claims_path, complete=False)
    near = _notebook_ml(tmp_path / "02_b.ipynb", [[_out(_record("alpha", section="S."))]])
    with pytest.raises(ValueError, match=r"the section 'S\.' is not a heading of this notebook; close headings: "
                                         r"\['S'\]"):
        ledger.collect([near], claims_path=claims_path, complete=False)


def test_notebook_headings_passes_over_a_markdown_source_that_is_no_text():
    nb = {"cells": [{"cell_type": "markdown", "source": None}, {"cell_type": "markdown", "source": 5},
                    {"cell_type": "markdown"}, {"cell_type": "markdown", "source": "# One"}]}
    assert ledger.notebook_headings(nb) == ["One"]


def _headed_notebook(path, section, headings):
    """A notebook with one record of 'alpha' measured in ``section`` and a Markdown cell per
    heading."""
    cells = [{"cell_type": "code", "source": "", "outputs": [_out(_record("alpha", section=section))]}]
    path.write_text(json.dumps({"cells": cells + [{"cell_type": "markdown", "source": f"## {h}"} for h in headings]}),
                    encoding="utf-8")
    return path


@pytest.mark.parametrize("section, close", [
    ("Noise and bias.", True),  # similarity to 'Noise' 2 * 5 / (5 + 15) = 0.5: close
    ("Noise and biases", False),  # 2 * 5 / (5 + 16) = 0.48: not close
])
def test_a_section_names_the_headings_at_least_half_alike(tmp_path, claims_path, section, close):
    nb = _headed_notebook(tmp_path / "01_a.ipynb", section, ["Noise"])
    names = r"close headings: \['Noise'\]" if close else r"its headings: \['Noise'\]"
    with pytest.raises(DataFileError, match=rf"is not a heading of this notebook; {names}"):
        ledger.collect([nb], claims_path=claims_path, complete=False)


def test_a_section_names_at_most_three_close_headings(tmp_path, claims_path):
    nb = _headed_notebook(tmp_path / "01_a.ipynb", "Noise 5", ["Noise 1", "Noise 2", "Noise 3", "Noise 4"])
    with pytest.raises(DataFileError, match="close headings: ") as err:
        ledger.collect([nb], claims_path=claims_path, complete=False)
    named = ast.literal_eval(str(err.value).split("close headings: ")[1])
    assert len(named) == 3 and set(named) < {"Noise 1", "Noise 2", "Noise 3", "Noise 4"}


@pytest.mark.parametrize("heading, anchor", [
    ("1. Our defaults", "1-our-defaults"),
    ("Fig. 6 — `R0` across the 10 data sets", "fig-6--r0-across-the-10-data-sets"),
    ("Which of the paper's conclusions hold here?", "which-of-the-papers-conclusions-hold-here"),
    ("snake_case and-hyphen ", "snake_case-and-hyphen"),
])
def test_heading_anchor_is_githubs(heading, anchor):
    assert ledger.heading_anchor(heading) == anchor


def test_notebook_headings_reads_every_level_from_markdown_cells_only():
    nb = {"cells": [{"cell_type": "markdown", "source": ["# One\n", "text # not a heading\n", "###### Six ##\n"]},
                    {"cell_type": "code", "source": "# a comment"},
                    {"cell_type": "markdown", "source": "####### seven is not a heading\n## Two"}]}
    assert ledger.notebook_headings(nb) == ["One", "Six", "Two"]


# --------------------------------------------------------------------------------------------------
# Claims where their evidence is: one small function per claim, taking only its numbers, called


ROOT = Path(__file__).resolve().parents[2]


CLAIM_MODULES = ["replication/study/lab/claims.py", "replication/study/lab/seed_sets.py",
                 "replication/study/table1/claims.py", "replication/study/table1/sqp_claims.py",
                 "replication/study/table1/cell_claims.py", "replication/study/fig5/claims.py",
                 "replication/study/convexity/claims.py"]


MAX_LINES, MAX_PARAMS = 62, 8


CLAIM_MIME = "application/vnd.replication.claim+json"


def oversized(source: str, max_lines: int = MAX_LINES, max_params: int = MAX_PARAMS) -> list:
    """``(name, lines, parameters)`` of every function of ``source`` longer than ``max_lines`` or
    with more than ``max_params`` parameters."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            params = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)
            lines = node.end_lineno - node.lineno + 1
            if lines > max_lines or params > max_params:
                found.append((node.name, lines, params))
    return found


def _function(lines: int, params: int) -> str:
    args = ", ".join(f"a{k}" for k in range(params))
    return f"def f({args}):\n" + "    x = 1\n" * (lines - 2) + "    return x\n"


def test_the_size_rule_sees_a_function_just_past_either_limit():
    assert oversized(_function(MAX_LINES, MAX_PARAMS)) == []
    assert oversized(_function(MAX_LINES + 1, MAX_PARAMS)) == [("f", MAX_LINES + 1, MAX_PARAMS)]
    assert oversized(_function(MAX_LINES, MAX_PARAMS + 1)) == [("f", MAX_LINES, MAX_PARAMS + 1)]
    assert oversized("def g(a, *, b, **kw):\n    pass\n", max_params=2) == [("g", 2, 3)]


@pytest.mark.parametrize("path", CLAIM_MODULES)
def test_no_claim_builder_over_60_lines_or_8_parameters(path):
    assert oversized((ROOT / path).read_text(encoding="utf-8")) == [], path


def records_away_from_their_function(nb: dict) -> list:
    """``(cell, claim)`` of every stored record whose cell does not call a function named for its
    claim (``<claim>(`` or ``<claim>_record(``): a record built elsewhere, in a builder of several
    claims, and only recorded here."""
    away = []
    for index, cell in enumerate(nb["cells"]):
        source = "".join(cell.get("source", ""))
        for out in cell.get("outputs", []):
            rec = out.get("data", {}).get(CLAIM_MIME)
            if rec and not re.search(rf"\b{re.escape(rec['claim'])}(_record)?\(", source):
                away.append((index, rec["claim"]))
    return away


def _notebook_with(source: str, claims: list) -> dict:
    outputs = [{"output_type": "display_data", "data": {CLAIM_MIME: {"claim": c}}} for c in claims]
    return {"cells": [{"cell_type": "code", "source": source, "outputs": outputs}]}


def test_the_cell_rule_sees_a_record_built_by_a_builder():
    assert records_away_from_their_function(_notebook_with(
        "ledger.record(**claims.lab_averaging(study, fresh))", ["lab_averaging"])) == []
    assert records_away_from_their_function(_notebook_with(
        "ledger.record(**either_minimises_record(a, b))", ["either_minimises"])) == []
    assert records_away_from_their_function(_notebook_with(
        "for rec in lab_claims(study, fresh):\n    ledger.record(**rec)", ["lab_averaging", "fig6_accuracy"])) == [
        (0, "lab_averaging"), (0, "fig6_accuracy")]
    assert records_away_from_their_function(_notebook_with(   # a name that only starts like the claim's
        "ledger.record(**lab_averaging_all(study))", ["lab_averaging"])) == [(0, "lab_averaging")]


@pytest.mark.parametrize("name", ["03_table1_monte_carlo", "05_table2_experiment"])
def test_each_record_is_made_in_the_cell_that_calls_its_claims_function(name):
    nb = json.loads((ROOT / "notebooks" / f"{name}.ipynb").read_text(encoding="utf-8"))
    assert records_away_from_their_function(nb) == []
    assert sum(CLAIM_MIME in o.get("data", {}) for c in nb["cells"] for o in c.get("outputs", [])) >= 10
