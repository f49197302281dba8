"""The claims ledger: every checkable claim of the paper has a verdict, evidence and uncertainty, and README agrees."""
import re

import pytest

from replication import ledger

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
