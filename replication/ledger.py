"""The claims ledger: every checkable statement of the paper, its verdict, the evidence and its uncertainty.

``data/paper/claims.csv`` lists the claims (id, the statement, where the paper makes it, the paper's number
if it gives one). A notebook that checks a claim calls :func:`record` in the cell that computes the evidence;
the record is displayed (a readable line) and stored in the executed notebook as a
``application/vnd.replication.claim+json`` output. :func:`collect` reads the records back from the notebooks
(no re-execution), adds the notebook and cell each came from, and refuses a ledger in which any claim lacks a
verdict, evidence or uncertainty. ``python -m replication reproduce`` writes it to
``results/tables/claims.csv`` and ``.md``; ``python -m replication claims`` prints it and updates the
README's findings table from it.

Verdicts: ``holds``, ``fails``, ``holds only if`` (the condition says what must hold) and
``undecidable from the text`` (the paper does not give what the verdict depends on).
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import pandas as pd

from ._io import write_atomic
from .paper import load_claim_table as load_claims  # the ledger's claims: a public name here

__all__ = ["VERDICTS", "CLAIM_MIME", "ClaimRecord", "load_claims", "record", "collect", "to_markdown",
           "update_readme"]

VERDICTS = ("holds", "fails", "holds only if", "undecidable from the text")
CLAIM_MIME = "application/vnd.replication.claim+json"
ROOT = Path(__file__).resolve().parent.parent
README_START, README_END = "<!-- claims:start -->", "<!-- claims:end -->"


@dataclass(frozen=True)
class ClaimRecord:
    """One verdict on one claim.

    Attributes
    ----------
    claim : str
        An id of ``data/paper/claims.csv``.
    verdict : str
        One of :data:`VERDICTS`.
    evidence : str
        What was computed, with the number(s) the verdict rests on (asserted in the same cell).
    uncertainty : str
        Its uncertainty: a confidence interval or standard error, a count out of a total, or
        ``exact (deterministic)`` for a computation without sampling.
    setting : str
        Where it was measured (simulation settings, solver variant, data set).
    condition : str
        For ``holds only if``: the condition.
    """

    claim: str
    verdict: str
    evidence: str
    uncertainty: str
    setting: str
    condition: str = ""


def record(claim: str, verdict: str, *, evidence: str, uncertainty: str, setting: str, condition: str = "") -> None:
    """Record a verdict in the executed notebook (see the module notes); it is displayed, nothing is returned.

    Raises
    ------
    ValueError
        An unknown claim id, a verdict not in :data:`VERDICTS`, an empty field, or ``holds only if``
        without a condition.
    """
    claims = load_claims()
    if claim not in claims.index:
        raise ValueError(f"unknown claim {claim!r}; known: {', '.join(claims.index)}")
    if verdict not in VERDICTS:
        raise ValueError(f"verdict must be one of {VERDICTS}, got {verdict!r}")
    for name, value in (("evidence", evidence), ("uncertainty", uncertainty), ("setting", setting)):
        if not str(value).strip():
            raise ValueError(f"claim {claim!r}: {name} is empty")
    if (verdict == "holds only if") != bool(condition.strip()):
        raise ValueError(f"claim {claim!r}: a condition goes with, and only with, 'holds only if'")
    rec = ClaimRecord(claim, verdict, evidence, uncertainty, setting, condition)
    verdict_text = f"holds only if {condition}" if condition else verdict
    text = f"[{claim}] {verdict_text}\n  evidence: {evidence}\n  uncertainty: {uncertainty}\n  setting: {setting}"
    try:
        from IPython import get_ipython
        from IPython.display import display
    except ImportError:  # pragma: no cover
        get_ipython = lambda: None  # noqa: E731
    if get_ipython() is not None:
        display({"text/plain": text, CLAIM_MIME: asdict(rec)}, raw=True)
    else:
        print(text)


def collect(notebooks=None, *, claims_path=None, complete: bool = True) -> pd.DataFrame:
    """The ledger from executed notebooks: one row per record, with its notebook and cell.

    Parameters
    ----------
    notebooks : list of paths, optional
        Default: ``notebooks/NN_*.ipynb`` of this project.
    complete : bool
        Raise ``ValueError`` naming every claim without a record.
    """
    paths = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")) if notebooks is None else list(notebooks)
    rows = []
    for path in paths:
        nb = json.loads(Path(path).read_text(encoding="utf-8"))
        for index, cell in enumerate(nb.get("cells", [])):
            for out in cell.get("outputs", []):
                data = out.get("data", {})
                if CLAIM_MIME in data:
                    rows.append({**data[CLAIM_MIME], "notebook": Path(path).stem, "cell": index})
    claims = load_claims(claims_path)
    ledger = pd.DataFrame(rows, columns=["claim", "verdict", "condition", "evidence", "uncertainty", "setting",
                                         "notebook", "cell"])
    unknown = sorted(set(ledger["claim"]) - set(claims.index))
    if unknown:
        raise ValueError(f"records for unknown claims {unknown}")
    if complete:
        missing = [c for c in claims.index if c not in set(ledger["claim"])]
        if missing:
            raise ValueError(f"claims without a verdict and evidence: {missing}")
    ledger = ledger.merge(claims[["statement", "where", "paper_value"]], left_on="claim", right_index=True)
    order = {c: k for k, c in enumerate(claims.index)}
    return ledger.sort_values(["claim", "notebook", "cell"], key=lambda s: s.map(order) if s.name == "claim" else s)\
        .reset_index(drop=True)


def _verdict_text(row) -> str:
    return f"holds only if {row.condition}" if row.verdict == "holds only if" else row.verdict


def to_markdown(ledger: pd.DataFrame) -> str:
    """A compact Markdown table: claim, where, verdict, evidence, uncertainty, source (notebook, cell)."""
    lines = ["| claim | the paper | verdict | evidence | uncertainty | where measured |", "|---|---|---|---|---|---|"]
    for row in ledger.itertuples(index=False):
        cells = [f"`{row.claim}`", f"{row.statement} ({row.where})", _verdict_text(row), row.evidence,
                 row.uncertainty, f"{row.setting}; notebook {row.notebook}, cell {row.cell}"]
        lines.append("| " + " | ".join(c.replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
    return "\n".join(lines) + "\n"


def update_readme(ledger: pd.DataFrame, readme=None, *, check: bool = False) -> bool:
    """Write the ledger table between the README's claims markers; ``check``: only say whether it is current."""
    readme = Path(readme) if readme else ROOT / "README.md"
    text = readme.read_text(encoding="utf-8")
    if README_START not in text or README_END not in text:
        raise ValueError(f"{readme}: markers {README_START} / {README_END} not found")
    head, rest = text.split(README_START, 1)
    _, tail = rest.split(README_END, 1)
    new = f"{head}{README_START}\n{to_markdown(ledger)}{README_END}{tail}"
    if check:
        return new == text
    if new != text:
        write_atomic(readme, new)
    return True
