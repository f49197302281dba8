"""The claims ledger: every checkable statement of the paper, its verdict, the evidence and its
uncertainty. Theory and measured numbers: ``docs/studies.md``, section
``replication.study.ledger``."""
from __future__ import annotations

import difflib
import json
import re
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import pandas as pd

from .._io import PROJECT_ROOT, write_atomic
from ..rig.datafile import DataFileError, fail, read_text
from .paper import data_dir, load_claim_table

__all__ = ["VERDICTS", "HOLDS_ONLY_IF", "CLAIM_MIME", "ClaimRecord", "check_record", "record", "check_evidence",
           "heading_anchor", "notebook_headings", "collect", "markdown_from_ledger", "verdict_counts",
           "counts_in_words", "first_clause", "summary_from_ledger", "update_readme"]

#: The verdict that needs a condition.
HOLDS_ONLY_IF = "holds only if"
#: The only verdicts a record may give.
VERDICTS = ("holds", "fails", HOLDS_ONLY_IF, "undecidable from the text")
CLAIM_MIME = "application/vnd.replication.claim+json"
README_START, README_END = "<!-- claims:start -->", "<!-- claims:end -->"
#: Optional inline markers of README's first screen, between which :func:`update_readme` writes the
#: counts.
COUNTS = re.compile(r"<!-- counts:start -->.*?<!-- counts:end -->")


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
        Its uncertainty: a confidence interval or standard error (a count out of a total with its
        interval), a bound (from the paper's rounding, say so: a bound is not an interval), or
        ``exact (deterministic)`` for a computation without sampling.
    setting : str
        The setting it was measured in (simulation settings, solver variant, data set; for a count
        over seeds, the seeds it was found on and the fresh seeds it was confirmed on).
    section : str
        The heading (its text, without the ``#``) of the notebook section where the evidence is
        measured.
    condition : str
        For ``holds only if``: the condition.
    """

    claim: str
    verdict: str
    evidence: str
    uncertainty: str
    setting: str
    section: str
    condition: str = ""


#: The fields of a stored record, in order.
RECORD_FIELDS = tuple(f.name for f in fields(ClaimRecord))


def _claims_file(claims_path=None) -> Path:
    return Path(claims_path) if claims_path else data_dir() / "paper" / "claims.csv"


def _unknown_claim(claim, known, claims_path) -> str:
    close = difflib.get_close_matches(str(claim), list(known), n=5, cutoff=0.6)
    hint = (f"close known ids: {', '.join(close)}" if close
            else f"no known id is close; known: {', '.join(known)}")
    return f"unknown claim {claim!r} (not an id of {_claims_file(claims_path)}); {hint}"


def check_record(claim, verdict, evidence, uncertainty, setting, section, condition="", *, claims=None,
                 claims_path=None) -> ClaimRecord:
    """The record if it keeps the rules of the module notes, else ``ValueError`` naming the claim
    and the problem.

    ``claims``: the claims table (:func:`~replication.study.paper.load_claim_table`), read from
    ``claims_path`` (default ``data/paper/claims.csv``) when not given.
    """
    values = dict(claim=claim, verdict=verdict, evidence=evidence, uncertainty=uncertainty, setting=setting,
                  section=section, condition=condition)
    for name, value in values.items():
        if not isinstance(value, str):
            raise ValueError(f"claim {claim!r}: {name} must be text, got {type(value).__name__} {value!r}")
    claims = load_claim_table(claims_path) if claims is None else claims
    if claim not in claims.index:
        raise ValueError(_unknown_claim(claim, claims.index, claims_path))
    if verdict not in VERDICTS:
        raise ValueError(f"claim {claim!r}: verdict must be one of {VERDICTS}, got {verdict!r}")
    for name in ("evidence", "uncertainty", "setting", "section"):
        if not values[name].strip():
            raise ValueError(f"claim {claim!r}: {name} is blank (empty or white space only)")
    if (verdict == HOLDS_ONLY_IF) != bool(condition.strip()):
        raise ValueError(f"claim {claim!r}: a condition goes with, and only with, {HOLDS_ONLY_IF!r} "
                         f"(verdict {verdict!r}, condition {condition!r})")
    return ClaimRecord(**values)


def record(claim: str, verdict: str, *, evidence: str, uncertainty: str, setting: str, section: str,
           condition: str = "") -> None:
    """Record a verdict in the executed notebook (see the module notes); it is displayed, nothing is
    returned.

    Raises
    ------
    ValueError
        A record that breaks a rule of :func:`check_record`: an unknown claim id (the close known
        ids named), a verdict not in :data:`VERDICTS`, a field that is not text, blank evidence,
        uncertainty, setting or section, ``holds only if`` without a condition or a condition with
        another verdict. (A second record of the same claim is found by :func:`collect`.)
    """
    rec = check_record(claim, verdict, evidence, uncertainty, setting, section, condition)
    verdict_text = f"{HOLDS_ONLY_IF} {condition}" if verdict == HOLDS_ONLY_IF else verdict
    text = (f"[{claim}] {verdict_text}\n  evidence: {evidence}\n  uncertainty: {uncertainty}\n  setting: {setting}"
            f"\n  measured in: {section}")
    try:
        from IPython import get_ipython
        from IPython.display import display
    except ImportError:  # pragma: no cover
        get_ipython = lambda: None  # noqa: E731
    if get_ipython() is not None:
        display({"text/plain": text, CLAIM_MIME: asdict(rec)}, raw=True)
    else:
        print(text)


def check_evidence(holds, claim: str, condition: str) -> None:
    """Nothing if ``holds``; else ``ValueError`` naming the claim and the ``condition`` its verdict
    rests on.

    The sanity checks of the functions that build a notebook's records (e.g.
    :func:`replication.study.table1.two_step_10_iterations`): the measured numbers must bear the
    verdict, or no record is made. ``condition`` says what should hold, with the measured values.
    """
    if not holds:
        raise ValueError(f"claim {claim!r}: the evidence does not bear the verdict: expected {condition}")


def heading_anchor(heading: str) -> str:
    """The anchor of a Markdown heading, as GitHub and MyST make it: lower case, every character
    that is not a letter, digit, ``_``, ``-`` or space dropped, spaces as ``-``.

    >>> heading_anchor("Fig. 6 — `R0` across the 10 data sets")
    'fig-6--r0-across-the-10-data-sets'
    """
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def notebook_headings(nb: dict) -> list[str]:
    """The text of every Markdown heading of a notebook (``#`` to ``######``, the marks stripped),
    in order."""
    found = []
    for cell in nb["cells"]:
        if isinstance(cell, dict) and cell.get("cell_type") == "markdown":
            source = cell.get("source", "")
            for line in ("".join(source) if isinstance(source, list) else str(source)).splitlines():
                m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
                if m:
                    found.append(m.group(1))
    return found


def _read_notebook(path: Path) -> dict:
    """A notebook's JSON; ``DataFileError`` naming the file (and line and column of a JSON
    error)."""
    text = read_text(path, "a notebook")
    try:
        nb = json.loads(text)
    except json.JSONDecodeError as err:
        fail(path, f"not a notebook: not valid JSON ({err.msg}; a truncated file?)", line=err.lineno,
             column=err.colno)
    if not isinstance(nb, dict) or not isinstance(nb.get("cells"), list):
        fail(path, "not a notebook: no list of 'cells'")
    return nb


def _stored_records(path: Path, nb: dict):
    """``(cell index, stored record)`` of every claim output of a notebook, in order."""
    for index, cell in enumerate(nb["cells"]):
        outputs = cell.get("outputs", []) if isinstance(cell, dict) else None
        if not isinstance(outputs, list):
            fail(path, f"cell {index}: not a notebook cell (a cell object with a list of 'outputs')")
        for out in outputs:
            data = out.get("data", {}) if isinstance(out, dict) else None
            if not isinstance(data, dict):
                fail(path, f"cell {index}: an output that is not an object with a 'data' object")
            if CLAIM_MIME in data:
                yield index, data[CLAIM_MIME]


def collect(notebooks=None, *, claims_path=None, complete: bool = True) -> pd.DataFrame:
    """The ledger from executed notebooks: one row per record, with its notebook and cell.

    Parameters
    ----------
    notebooks : list of paths, optional
        Default: ``notebooks/NN_*.ipynb`` of this project.
    claims_path : path, optional
        Default: ``data/paper/claims.csv``.
    complete : bool
        Raise ``ValueError`` naming every claim without a record.

    Raises
    ------
    DataFileError
        (a ``ValueError``) naming the notebook: not valid JSON (line and column), not a notebook, a
        stored record that is not an object of the :class:`ClaimRecord` fields, one that breaks a
        rule of :func:`check_record` (with its cell), or a second record of a claim (both notebooks
        and cells); or naming the claims file and line
        (:func:`~replication.study.paper.load_claim_table`).
    ValueError
        ``complete`` and a claim without a record.
    """
    paths = sorted((PROJECT_ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb")) if notebooks is None else list(notebooks)
    claims = load_claim_table(claims_path)
    rows, first = [], {}
    for path in map(Path, paths):
        nb = _read_notebook(path)
        headings = notebook_headings(nb)
        for index, stored in _stored_records(path, nb):
            if not isinstance(stored, dict) or set(stored) != set(RECORD_FIELDS):
                got = sorted(stored) if isinstance(stored, dict) else type(stored).__name__
                fail(path, f"cell {index}: a stored claim record must have the fields {list(RECORD_FIELDS)}, "
                     f"got {got}")
            try:
                rec = check_record(**stored, claims=claims, claims_path=claims_path)
            except ValueError as err:
                raise DataFileError(path, f"cell {index}: {err}") from None
            if rec.claim in first:
                other_path, other_index, other = first[rec.claim]
                how = "repeats" if other == rec else "contradicts" if other.verdict != rec.verdict else "differs from"
                fail(path, f"cell {index}: a second record of claim {rec.claim!r} ({rec.verdict!r}) {how} the one in "
                     f"{other_path.name}, cell {other_index} ({other.verdict!r}): one record per claim")
            if rec.section not in headings:
                close = difflib.get_close_matches(rec.section, headings, n=3, cutoff=0.5)
                fail(path, f"cell {index}: claim {rec.claim!r}: the section {rec.section!r} is not a heading of this "
                     f"notebook" + (f"; close headings: {close}" if close else f"; its headings: {headings}"))
            first[rec.claim] = (path, index, rec)
            rows.append({**asdict(rec), "notebook": path.stem, "cell": index, "anchor": heading_anchor(rec.section)})
    ledger = pd.DataFrame(rows, columns=["claim", "verdict", "condition", "evidence", "uncertainty", "setting",
                                         "section", "notebook", "cell", "anchor"])
    if complete:
        missing = [c for c in claims.index if c not in set(ledger["claim"])]
        if missing:
            raise ValueError(f"claims without a verdict and evidence: {missing}")
    ledger = ledger.merge(claims[["statement", "where", "paper_value"]], left_on="claim", right_index=True)
    order = {c: k for k, c in enumerate(claims.index)}
    return ledger.sort_values(["claim", "notebook", "cell"], key=lambda s: s.map(order) if s.name == "claim" else s)\
        .reset_index(drop=True)


def _verdict_text(row) -> str:
    return f"{HOLDS_ONLY_IF} {row.condition}" if row.verdict == HOLDS_ONLY_IF else row.verdict


def markdown_from_ledger(ledger: pd.DataFrame) -> str:
    """A compact Markdown table: claim, where, verdict, evidence, uncertainty, where measured (the
    setting and a link to the notebook section)."""
    lines = ["| claim | the paper | verdict | evidence | uncertainty | where measured |", "|---|---|---|---|---|---|"]
    for row in ledger.itertuples(index=False):
        cells = [f"`{row.claim}`", f"{row.statement} ({row.where})", _verdict_text(row), row.evidence,
                 row.uncertainty,
                 f"{row.setting}; [notebook {row.notebook[:2]}, § {row.section}](notebooks/{row.notebook}.ipynb"
                 f"#{row.anchor})"]
        lines.append("| " + " | ".join(c.replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
    return "\n".join(lines) + "\n"


#: How the counts name each verdict (a number of claims before it).
_PLURAL = {"holds": "hold", HOLDS_ONLY_IF: "hold only if", "fails": "fail",
           "undecidable from the text": "undecidable from the text"}


def verdict_counts(ledger: pd.DataFrame) -> dict:
    """The number of claims per verdict, every verdict of :data:`VERDICTS` in its order (zeros
    included)."""
    found = ledger.drop_duplicates("claim")["verdict"].value_counts()
    return {v: int(found.get(v, 0)) for v in VERDICTS}


def counts_in_words(ledger: pd.DataFrame) -> str:
    """One line: the number of claims and how many have each verdict, e.g. ``28 claims: 4 hold, 7
    hold only if, 6 fail, 11 undecidable from the text``."""
    counts = verdict_counts(ledger)
    return f"{sum(counts.values())} claims: " + ", ".join(f"{counts[v]} {_PLURAL[v]}" for v in _PLURAL)


def first_clause(text: str, max_words: int = 30) -> str:
    """The text up to its first ``"; "`` (or ``". "`` before a capital: not ``eq. (8)``) outside
    brackets, at most ``max_words`` words; ``…`` marks a cut.

    >>> first_clause("error < 1e-12 (3a; 3b) by eq. (8); start 170 deg off: the reflection")
    'error < 1e-12 (3a; 3b) by eq. (8) …'
    >>> first_clause("it holds. The rest")
    'it holds …'
    >>> first_clause("one two three", max_words=2)
    'one two …'
    """
    depth, end = 0, len(text)
    for k, char in enumerate(text):
        depth += char in "([{"
        depth -= char in ")]}" and depth > 0
        if depth == 0 and (text.startswith("; ", k) or text.startswith(". ", k) and text[k + 2:k + 3].isupper()):
            end = k
            break
    words = text[:end].split()
    cut = end < len(text.rstrip(" .;")) or len(words) > max_words
    return " ".join(words[:max_words]) + (" …" if cut else "")


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def summary_from_ledger(ledger: pd.DataFrame) -> str:
    """The compact ledger (README, ``claims --summary``): the counts (:func:`counts_in_words`), then
    one row per claim: its id, what the paper says, the verdict (the condition is in the full
    ledger) and a link to the notebook section where it is measured."""
    lines = [f"**{counts_in_words(ledger)}.**", "", "| claim | the paper says | verdict | measured in |",
             "|---|---|---|---|"]
    for row in ledger.itertuples(index=False):
        link = f"[{row.notebook[:2]}, § {row.section}](notebooks/{row.notebook}.ipynb#{row.anchor})"
        lines.append("| " + " | ".join(_cell(c) for c in (f"`{row.claim}`", row.statement, row.verdict, link))
                     + " |")
    return "\n".join(lines) + "\n"


def _readme_parts(readme: Path, text: str) -> tuple[str, str]:
    """The README's text before its start marker and from its end marker on; ``DataFileError``
    naming the file, and the marker, if a marker is missing or repeated or the end comes before the
    start."""
    found = {}
    for marker in (README_START, README_END):
        at = [text.count("\n", 0, m.start()) + 1 for m in re.finditer(re.escape(marker), text)]
        if len(at) > 1:
            fail(readme, f"the claims marker {marker} appears {len(at)} times (lines {at}); it must appear once",
                 line=at[1])
        found[marker] = at[0] if at else None
    missing = [m for m, line in found.items() if line is None]
    if missing:
        fail(readme, f"no claims marker {' and no '.join(missing)}: the claims table goes between "
             f"{README_START} and a later {README_END}")
    if text.index(README_END) < text.index(README_START):
        fail(readme, f"the claims marker {README_END} (line {found[README_END]}) comes before "
             f"{README_START} (line {found[README_START]}); it must come after", line=found[README_END])
    head, rest = text.split(README_START, 1)
    _, tail = rest.split(README_END, 1)
    return head, tail


def update_readme(ledger: pd.DataFrame, readme=None, *, check: bool = False) -> bool:
    """Write the compact ledger (:func:`summary_from_ledger`) between the README's claims markers,
    and the counts (:func:`counts_in_words`) between each pair of inline counts markers
    (:data:`COUNTS`) on one line; ``check``: only say whether it is current.

    Raises
    ------
    DataFileNotFound
        No README (also a ``FileNotFoundError``).
    DataFileError
        A claims marker (:data:`README_START`, :data:`README_END`) missing or repeated, or the end
        marker not after the start marker.
    """
    readme = Path(readme) if readme else PROJECT_ROOT / "README.md"
    text = read_text(readme, "the README with the claims table")
    head, tail = _readme_parts(readme, text)
    new = f"{head}{README_START}\n{summary_from_ledger(ledger)}{README_END}{tail}"
    counts = f"<!-- counts:start -->{counts_in_words(ledger)}<!-- counts:end -->"
    new = COUNTS.sub(lambda _: counts, new)
    if check:
        return new == text
    if new != text:
        write_atomic(readme, new)
    return True
