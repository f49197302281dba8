"""The book's generated pages (``bash scripts/docs``): the front page's claims, the full ledger, the
API reference and the calibration report's schema, all Markdown (MyST) written from the records and
files they describe, never copied by hand.

The book's source is assembled in ``docs/_build/source`` by :func:`stage`: the pages of ``docs/`` (a
line ``<!-- book:NAME -->`` in one is replaced by the generated block ``NAME``), ``docs/conf.py``,
``docs/_static/`` and the executed notebooks under ``notebooks/`` (rendered from their stored
outputs, never re-executed). Links to a notebook section use the anchor of its heading
(:func:`~replication.study.ledger.heading_anchor`, as MyST makes it); Sphinx resolves each one or
the build fails.
"""
from __future__ import annotations

import importlib
import inspect
import json
import re
from pathlib import Path

import pandas as pd

from .._io import PROJECT_ROOT, write_atomic
from .ledger import HOLDS_ONLY_IF, VERDICTS, collect, counts_in_words, first_clause, heading_anchor

__all__ = ["MARKER", "TITLES", "VERDICT_MARKS", "claim_anchor", "verdict_badge", "readme_headlines",
           "front_page_claims", "ledger_chapter", "schema_fields", "schema_chapter", "api_chapter", "fill_markers",
           "stage"]

#: Each claim's heading in the ledger chapter: what it is about, in words (its id follows the
#: heading).
TITLES = {
    "eq7_relative": "Eq. (7): relative rotations remove the global frames",
    "theorem1": "Theorem 1: the two-step iteration converges to R0",
    "theorem1_proof": "Theorem 1's proof: decreasing residuals mean convergence",
    "convex_problem": "Problem (8)-(10) is convex",
    "noise_bound_angle": "A noise vector under 0.02 keeps the noise angle under 1 deg",
    "two_step_10_iterations": "About 10 iterations bring the two-step estimate close to R0",
    "cost_to_zero": "The cost (8) falls to 0 in 10 iterations",
    "either_minimises": "Either R^l or R^r minimises the cost (8)",
    "faster_than_sqp": "The two-step method converges faster than SQP",
    "smoother_monotone": "Each iteration brings the estimate closer and the cost lower",
    "sqp_diverts": "SQP may drift from R0 while its cost falls",
    "sqp_30_iterations": "SQP needs more than 30 iterations for 1 % error",
    "sqp_10_evaluations": "SQP evaluates the cost more than 10 times per iteration",
    "runtime_ratio": "The two-step method is over 40 times faster than SQP",
    "table1_final": "Table I: the two-step error from iteration 20 on",
    "table1_early": "Table I: the two-step error at iterations 2, 5 and 10",
    "table1_sqp": "Table I: SQP's error at iterations 2-50",
    "converge_15_vs_30": "15 iterations for the two-step method, 30 for SQP",
    "fig5_resilience": "Fig. 5: the two-step method is more resilient to noise",
    "lab_protocol": "The lab protocol: 10 data sets of held orientations",
    "lab_averaging": "Averaging each orientation, rather than all samples, raises the SNR",
    "fig6_consistency": "Fig. 6: the 10 lab estimates of R0 agree",
    "fig6_accuracy": "Fig. 6: consistency shows robustness and reproducibility",
    "table2_reduction": "Table II: calibration reduces the orientation difference",
    "table2_correlation": "Table II: camera and converted sensor correlate at 0.999",
    "table2_methods_agree": "Table II: SQP converts as accurately",
    "table2_measures_calibration": "Table II: a smaller difference means a better calibration",
    "table2_rms": "Table II: calibrated RMS differences of 0.63-0.99 deg",
    "fig7_projection": "Fig. 7: the projected sensor traces follow the camera's",
    "online_recalibration": "The method meets the requirements of online re-calibration",
}

#: Each verdict's mark and CSS class (``docs/_static/book.css`` colours them): told apart at a
#: glance and in print.
VERDICT_MARKS = {"holds": ("✔", "holds"), HOLDS_ONLY_IF: ("◐", "only-if"), "fails": ("✘", "fails"),
                 "undecidable from the text": ("?", "undecidable")}

#: A line of a page of ``docs/`` that :func:`stage` replaces by a generated block (its name in the
#: group).
MARKER = re.compile(r"^<!-- book:([a-z_]+) -->$", re.MULTILINE)


def _md(text) -> str:
    """Text that Markdown shows as written, in a table cell too (``|``, emphasis and brackets
    escaped; code in backticks kept)."""
    return re.sub(r"([\\*_\[\]<>|])", r"\\\1", str(text).replace("\n", " "))


def _where(row) -> str:
    return (f"[notebook {row.notebook[:2]}, § {_md(row.section)}](notebooks/{row.notebook}.ipynb#{row.anchor})")


def _title(claim: str) -> str:
    if claim not in TITLES:
        raise ValueError(f"the claim {claim!r} has no title in replication.study.book.TITLES (its heading in the "
                         "ledger chapter): add one")
    return TITLES[claim]


def claim_anchor(claim: str) -> str:
    """The anchor of the claim's section in the ledger chapter (its heading's, as MyST makes it)."""
    return heading_anchor(_title(claim))


def verdict_badge(verdict: str) -> str:
    """The verdict with its mark, in a span of its class (inline HTML: MyST passes it through)."""
    if verdict not in VERDICT_MARKS:
        raise ValueError(f"no mark for the verdict {verdict!r} (known: {', '.join(VERDICTS)})")
    mark, css = VERDICT_MARKS[verdict]
    return f'<span class="verdict verdict-{css}">{mark} {verdict}</span>'


def readme_headlines(readme: str, ledger: pd.DataFrame) -> str:
    """README's headlines (the bullets after "The headlines:", up to the next heading), each claim
    id in them linked to its record in the ledger chapter: the front page says what README says,
    never a copy kept by hand.

    Raises
    ------
    ValueError
        README has no such list.
    """
    match = re.search(r"The headlines:\n\n((?:\* .*\n(?:  .*\n)*)+)", readme)
    if match is None:
        raise ValueError("README.md has no list of headlines after 'The headlines:' (the front page shows it)")
    claims = set(ledger["claim"])

    def link(m):
        return f"[`{m.group(1)}`](ledger.md#{claim_anchor(m.group(1))})" if m.group(1) in claims else m.group(0)

    return re.sub(r"`(\w+)`", link, match.group(1))


def _brief(text: str) -> tuple[str, bool]:
    """The text's first clause, whole (:func:`~replication.study.ledger.first_clause` without a word
    limit), and whether more follows it."""
    clause = first_clause(text, max_words=10**6)
    return (clause[:-2], True) if clause.endswith(" …") else (clause, False)


def front_page_claims(ledger: pd.DataFrame) -> str:
    """The counts, then one row per claim: what the paper claims (linked to its full record in the
    ledger chapter), the verdict with its mark (:func:`verdict_badge`), the condition in full
    (``holds only if``: never cut) or the evidence's first clause (a link to the rest where there is
    more), and the notebook section where it is measured."""
    lines = [f"**{counts_in_words(ledger)}.**", "",
             "| the paper claims | verdict | the condition it holds under, or the evidence | measured in |",
             "|---|---|---|---|"]
    for row in ledger.itertuples(index=False):
        anchor = claim_anchor(row.claim)
        if row.verdict == HOLDS_ONLY_IF:
            line = f"only if {_md(row.condition)}"
        else:
            clause, more = _brief(str(row.evidence))
            line = _md(clause) + (f" [(more)](ledger.md#{anchor})" if more else "")
        lines.append(f"| [{_md(row.statement)}](ledger.md#{anchor}) | {verdict_badge(row.verdict)} | {line} | "
                     f"{_where(row)} |")
    return "\n".join(lines) + "\n"


def ledger_chapter(ledger: pd.DataFrame) -> str:
    """Every record in full, one section per claim (its title the heading, :data:`TITLES`, then its
    id): the paper's statement and where it makes it, the paper's number, the verdict and its
    condition, the evidence, its uncertainty, the setting and the notebook section where it is
    measured."""
    parts = [f"**{counts_in_words(ledger)}.**\n"]
    for row in ledger.itertuples(index=False):
        verdict = verdict_badge(row.verdict) + (f": {_md(row.condition)}" if row.verdict == HOLDS_ONLY_IF else "")
        paper_value = "" if pd.isna(row.paper_value) or str(row.paper_value) == "" else \
            f" The paper's number: {_md(row.paper_value)}."
        parts.append(f"## {_title(row.claim)}\n\n`{row.claim}`\n\n"
                     f"**The paper** ({_md(row.where)}): {_md(row.statement)}.{paper_value}\n\n"
                     f"**Verdict:** {verdict}\n\n"
                     f"**Evidence:** {_md(row.evidence)}\n\n"
                     f"**Uncertainty:** {_md(row.uncertainty)}\n\n"
                     f"**Setting:** {_md(row.setting)}\n\n"
                     f"**Measured in:** {_where(row)}\n")
    return "\n".join(parts)


def _type(node: dict) -> str:
    if "$ref" in node:
        return node["$ref"].rsplit("/", 1)[-1]
    if "enum" in node:
        return "one of " + ", ".join(json.dumps(v) for v in node["enum"])
    if "const" in node:
        return f"always {json.dumps(node['const'])}"
    if "oneOf" in node and "type" not in node:
        return " or ".join(_type(n) for n in node["oneOf"])
    kind = node.get("type", "any")
    if kind == "array" and "items" in node:
        return f"array of {_type(node['items'])}"
    return " or ".join(kind) if isinstance(kind, list) else kind


def schema_fields(schema: dict) -> list[tuple[str, str, str]]:
    """``(field, type, description)`` of every field of the report's JSON schema, its definitions
    first (``#name``), nested fields as ``parent.child`` and array items as ``parent[].child``.

    Raises
    ------
    ValueError
        Naming every field (and definition) without a description.
    """
    rows, missing = [], []

    def walk(node, path):
        if not isinstance(node, dict):
            return
        for option in node.get("oneOf", []):
            walk(option, path)
        if isinstance(node.get("items"), dict):
            walk(node["items"], path + "[]")
        for name, child in node.get("properties", {}).items():
            field = f"{path}.{name}" if path else name
            if not str(child.get("description", "")).strip():
                missing.append(field)
            rows.append((field, _type(child), str(child.get("description", ""))))
            walk(child, field)

    for name, node in schema.get("definitions", {}).items():
        if not str(node.get("description", "")).strip():
            missing.append(f"#{name}")
        rows.append((f"#{name}", _type(node), str(node.get("description", ""))))
        walk(node, f"#{name}")
    walk({"properties": schema.get("properties", {})}, "")
    if missing:
        raise ValueError(f"the report schema has {len(missing)} field(s) without a description: {', '.join(missing)}")
    return rows


def schema_chapter(schema: dict) -> str:
    """A table of every field of the report's schema (:func:`schema_fields`): name, type,
    description."""
    lines = ["| field | type | description |", "|---|---|---|"]
    for field, kind, description in schema_fields(schema):
        lines.append(f"| `{field}` | {_md(kind)} | {_md(description)} |")
    return "\n".join(lines) + "\n"


def api_chapter(public: dict) -> str:
    """An autodoc entry (numpy docstrings) for every public name of the package
    (``replication._PUBLIC``: name -> the module that defines it), grouped by room."""
    groups = {"rig": ("Calibrating a rig", []), "core": ("Solving A X = X B", [])}
    for name, module in public.items():
        obj = getattr(importlib.import_module(f"replication.{module}"), name)
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            directive = "autoexception"
        elif inspect.isclass(obj):
            directive = "autoclass"
        else:
            directive = "autofunction"
        options = "   :members:\n" if directive == "autoclass" else ""
        # autodoc writes reStructuredText: an eval-rst block parses it as such (a MyST directive
        # would not)
        groups[module.split(".")[0]][1].append(f"```{{eval-rst}}\n.. {directive}:: replication.{module}.{name}\n"
                                               f"{options}```\n")
    return "\n".join(f"## {title}\n\n" + "\n".join(entries) for title, entries in groups.values())


def fill_markers(text: str, blocks: dict, path) -> str:
    """``text`` with each marker line (:data:`MARKER`) replaced by its block; ``ValueError`` naming
    the page, the line and the name for a marker that names no block."""
    for match in MARKER.finditer(text):
        if match.group(1) not in blocks:
            line = text.count("\n", 0, match.start()) + 1
            raise ValueError(f"{path}, line {line}: no generated block {match.group(1)!r} "
                             f"(known: {', '.join(sorted(blocks))})")
    return MARKER.sub(lambda m: blocks[m.group(1)].rstrip("\n"), text)


def _write_if_changed(path: Path, data: bytes | str) -> None:
    data = data.encode("utf-8") if isinstance(data, str) else data
    if not path.exists() or path.read_bytes() != data:
        write_atomic(path, data)


def stage(source=None, *, public: dict, root=None, ledger=None) -> Path:
    """Assemble the book's source in ``source`` (default ``docs/_build/source``) and return it.

    ``public``: the package's public names (``replication._PUBLIC``, passed in: the study room does
    not import the package face) for :func:`api_chapter`; ``ledger``: default
    :func:`~replication.study.ledger.collect` of ``root``'s notebooks.

    Files are written only when they change, so that Sphinx rebuilds only what changed. Pages of
    ``docs/`` whose marker names no block, a report schema field without a description and a ledger
    that :func:`~replication.study.ledger.collect` refuses raise ``ValueError``.
    """
    root = Path(root) if root else PROJECT_ROOT
    source = Path(source) if source else root / "docs" / "_build" / "source"
    ledger = collect(sorted((root / "notebooks").glob("[0-9][0-9]_*.ipynb")),
                     claims_path=root / "data" / "paper" / "claims.csv") if ledger is None else ledger
    schema = json.loads((root / "docs" / "calibration_report.schema.json").read_text(encoding="utf-8"))
    readme = (root / "README.md").read_text(encoding="utf-8")
    blocks = {"claims": front_page_claims(ledger), "ledger": ledger_chapter(ledger),
              "headlines": readme_headlines(readme, ledger),
              "schema": schema_chapter(schema), "api": api_chapter(public)}
    (source / "notebooks").mkdir(parents=True, exist_ok=True)
    wanted = {"conf.py"}
    _write_if_changed(source / "conf.py", (root / "docs" / "conf.py").read_text(encoding="utf-8"))
    for page in sorted((root / "docs").glob("*.md")):
        wanted.add(page.name)
        _write_if_changed(source / page.name, fill_markers(page.read_text(encoding="utf-8"), blocks, page))
    (source / "_static").mkdir(exist_ok=True)
    for static in sorted((root / "docs" / "_static").glob("*")):
        wanted.add(f"_static/{static.name}")
        _write_if_changed(source / "_static" / static.name, static.read_bytes())
    for notebook in sorted((root / "notebooks").glob("[0-9][0-9]_*.ipynb")):
        wanted.add(f"notebooks/{notebook.name}")
        _write_if_changed(source / "notebooks" / notebook.name, notebook.read_bytes())
    for stale in [*source.glob("*.md"), *(source / "notebooks").glob("*.ipynb"), *(source / "_static").glob("*")]:
        if stale.relative_to(source).as_posix() not in wanted:
            stale.unlink()
    return source
