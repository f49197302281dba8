"""The claims ledger's rules that mutation testing found unguarded (scripts/mutation): what :func:`record` displays,
how :func:`collect` reads records back (which notebook and cell, the claims file's order), the Markdown table and the
README update."""
import json
import sys
from dataclasses import asdict

import pytest

from replication.study import ledger

CLAIMS_CSV = ("claim,statement,where,paper_value,unit\n"
              "zeta,the last id alphabetically comes first,Sec. 1,,\n"
              "alpha,a | pipe in the statement,Eq. (2),0.5,deg\n"
              "mid,a third claim,Table 1,,\n")


def _record(claim, verdict="holds", condition="", evidence="e 1.0", uncertainty="u", setting="s", section="S"):
    return asdict(ledger.ClaimRecord(claim, verdict, evidence, uncertainty, setting, section, condition))


def _notebook(path, cells):
    """A notebook whose cells carry these outputs (a list of output lists; None: a cell without outputs)."""
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
    a = _notebook(tmp_path / "01_a.ipynb", [
        None,
        [{"output_type": "stream", "text": "no data"}, _out(_record("alpha", evidence="from a, cell 1"))],
        [{"output_type": "execute_result", "data": {"text/plain": "2"}}],
        [_out(_record("zeta", evidence="z in a"))],
    ])
    b = _notebook(tmp_path / "02_b.ipynb", [
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
    with pytest.raises(ValueError, match=rf"^claim 'theorem1': {field} is blank \(empty or white space only\)$"):
        ledger.record("theorem1", "holds", **kwargs)


def test_record_messages_name_the_known_claims_and_verdicts():
    with pytest.raises(ValueError, match=r"unknown claim 'nope' \(not an id of .*claims\.csv\); no known id is close; "
                                         r"known: eq7_relative, theorem1, "):
        ledger.record("nope", "holds", evidence="e", uncertainty="u", setting="s", section="S")
    with pytest.raises(ValueError, match=r"verdict must be one of \('holds', 'fails', .*got 'maybe'"):
        ledger.record("theorem1", "maybe", evidence="e", uncertainty="u", setting="s", section="S")


def test_collect_reads_every_record_with_its_notebook_and_cell_in_the_claims_order(two_notebooks, claims_path):
    got = ledger.collect(two_notebooks, claims_path=claims_path)
    assert list(got.columns) == ["claim", "verdict", "condition", "evidence", "uncertainty", "setting", "section",
                                 "notebook", "cell", "anchor", "statement", "where", "paper_value"]
    assert list(got.index) == [0, 1, 2]
    # claims in the claims file's order (zeta, alpha, mid: not alphabetical), not in the notebooks' order
    assert list(got["claim"]) == ["zeta", "alpha", "mid"]
    assert list(got["notebook"]) == ["01_a", "01_a", "02_b"]
    assert list(got["cell"]) == [3, 1, 1]
    assert list(got["evidence"]) == ["z in a", "from a, cell 1", "m"]
    assert list(got["condition"]) == ["", "", "J >= 3"]
    assert got.loc[1, "statement"] == "a | pipe in the statement" and got.loc[1, "paper_value"] == "0.5"


def test_collect_refuses_unknown_and_missing_claims(tmp_path, two_notebooks, claims_path):
    extra = _notebook(tmp_path / "04_x.ipynb", [[_out(_record("ghost"))], [_out(_record("boo"))]])
    with pytest.raises(ValueError, match=r"04_x\.ipynb.*cell 0: unknown claim 'ghost'"):
        ledger.collect(two_notebooks + [extra], claims_path=claims_path)
    partial = [two_notebooks[1]]  # mid has no record there
    with pytest.raises(ValueError, match=r"^claims without a verdict and evidence: \['mid'\]$"):
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
    nb = _notebook(tmp_path / "01_a.ipynb", [[_out(_record("alpha", section="T"))]])
    with pytest.raises(ValueError, match=r"01_a\.ipynb: cell 0: claim 'alpha': the section 'T' is not a heading of "
                                         r"this notebook; its headings: \['S'\]"):
        ledger.collect([nb], claims_path=claims_path, complete=False)
    near = _notebook(tmp_path / "02_b.ipynb", [[_out(_record("alpha", section="S."))]])
    with pytest.raises(ValueError, match=r"the section 'S\.' is not a heading of this notebook; close headings: "
                                         r"\['S'\]"):
        ledger.collect([near], claims_path=claims_path, complete=False)


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
