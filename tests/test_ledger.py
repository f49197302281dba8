"""The claims ledger: every checkable claim of the paper has a verdict, evidence and uncertainty, and README agrees."""
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from replication import ledger
from replication.datafile import DataFileError, DataFileNotFound

CLAIMS = ledger.load_claims()


@pytest.fixture(scope="module")
def collected():
    return ledger.collect()


def test_every_claim_has_a_verdict_evidence_and_uncertainty(collected):
    assert set(collected["claim"]) == set(CLAIMS.index)
    assert collected["verdict"].isin(ledger.VERDICTS).all()
    for col in ("evidence", "uncertainty", "setting"):
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
    extra.write_text(ledger.ROOT.joinpath("data", "paper", "claims.csv").read_text()
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
        ledger.record(**{"evidence": "e 1", "uncertainty": "u", "setting": "s", **kwargs})


def test_malformed_claims_file_names_line_and_column(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,,Sec. II,,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'statement': empty"):
        ledger.load_claims(path)
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,s,w,ten,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'paper_value': not a number"):
        ledger.load_claims(path)


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
        ledger.load_claims(path)
    with pytest.raises(DataFileError, match=message):  # and the ledger, which reads it
        ledger.collect([], claims_path=path)


def test_a_well_formed_claims_file_reads_as_text(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + 'theorem1,"two\nlines, a comma",w,,\n\nother,s,w,0.5,deg\n', encoding="utf-8")
    table = ledger.load_claims(path)
    assert list(table.index) == ["theorem1", "other"]
    assert table.loc["theorem1", "statement"] == "two\nlines, a comma" and table.loc["other", "paper_value"] == "0.5"


def test_a_missing_claims_file_is_named(tmp_path):
    with pytest.raises(DataFileNotFound, match=r"nowhere\.csv: no such file"):
        ledger.load_claims(tmp_path / "nowhere.csv")
