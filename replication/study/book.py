"""The book's generated pages (``bash scripts/docs``): the front page's claims, the full ledger, the API reference
and the calibration report's schema, all Markdown (MyST) written from the records and files they describe, never
copied by hand.

The book's source is assembled in ``docs/_build/source`` by :func:`stage`: the pages of ``docs/`` (a line
``<!-- book:NAME -->`` in one is replaced by the generated block ``NAME``), ``docs/conf.py``, ``docs/_static/``
and the executed notebooks under ``notebooks/`` (rendered from their stored outputs, never re-executed). Links to a
notebook section use the anchor of its heading (:func:`~replication.study.ledger.heading_anchor`, as MyST makes
it); Sphinx resolves each one or the build fails.
"""
from __future__ import annotations

import importlib
import inspect
import json
import re
from pathlib import Path

import pandas as pd

from .._io import PROJECT_ROOT, write_atomic
from .ledger import HOLDS_ONLY_IF, collect, counts_in_words, first_clause

__all__ = ["MARKER", "front_page_claims", "ledger_chapter", "schema_fields", "schema_chapter", "api_chapter",
           "fill_markers", "stage"]

#: A line of a page of ``docs/`` that :func:`stage` replaces by a generated block (its name in the group).
MARKER = re.compile(r"^<!-- book:([a-z_]+) -->$", re.MULTILINE)


def _md(text) -> str:
    """Text that Markdown shows as written, in a table cell too (``|``, emphasis and brackets escaped; code in
    backticks kept)."""
    return re.sub(r"([\\*_\[\]<>|])", r"\\\1", str(text).replace("\n", " "))


def _where(row) -> str:
    return (f"[notebook {row.notebook[:2]}, § {_md(row.section)}](notebooks/{row.notebook}.ipynb#{row.anchor})")


def front_page_claims(ledger: pd.DataFrame) -> str:
    """The counts, then one row per claim: what the paper claims (linked to its full record in the ledger chapter),
    the verdict, in one line the condition's first clause (``holds only if``) or the evidence's
    (:func:`~replication.study.ledger.first_clause`), and the notebook section where it is measured."""
    lines = [f"**{counts_in_words(ledger)}.**", "",
             "| the paper claims | verdict | in one line: the condition, or the evidence | measured in |",
             "|---|---|---|---|"]
    for row in ledger.itertuples(index=False):
        line = (f"only if {first_clause(row.condition, max_words=22)}" if row.verdict == HOLDS_ONLY_IF
                else first_clause(row.evidence, max_words=22))
        lines.append(f"| [{_md(row.statement)}](ledger.md#{row.claim}) | **{row.verdict}** | {_md(line)} | "
                     f"{_where(row)} |")
    return "\n".join(lines) + "\n"


def ledger_chapter(ledger: pd.DataFrame) -> str:
    """Every record in full, one section per claim (its id the heading): the paper's statement and where it makes
    it, the paper's number, the verdict and its condition, the evidence, its uncertainty, the setting and the
    notebook section where it is measured."""
    parts = [f"**{counts_in_words(ledger)}.**\n"]
    for row in ledger.itertuples(index=False):
        verdict = f"{HOLDS_ONLY_IF}: {_md(row.condition)}" if row.verdict == HOLDS_ONLY_IF else row.verdict
        paper_value = "" if pd.isna(row.paper_value) or str(row.paper_value) == "" else \
            f" The paper's number: {_md(row.paper_value)}."
        parts.append(f"## {row.claim}\n\n"
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
    """``(field, type, description)`` of every field of the report's JSON schema, its definitions first
    (``#name``), nested fields as ``parent.child`` and array items as ``parent[].child``.

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
    """A table of every field of the report's schema (:func:`schema_fields`): name, type, description."""
    lines = ["| field | type | description |", "|---|---|---|"]
    for field, kind, description in schema_fields(schema):
        lines.append(f"| `{field}` | {_md(kind)} | {_md(description)} |")
    return "\n".join(lines) + "\n"


def api_chapter(public: dict) -> str:
    """An autodoc entry (numpy docstrings) for every public name of the package (``replication._PUBLIC``: name ->
    the module that defines it), grouped by room."""
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
        # autodoc writes reStructuredText: an eval-rst block parses it as such (a MyST directive would not)
        groups[module.split(".")[0]][1].append(f"```{{eval-rst}}\n.. {directive}:: replication.{module}.{name}\n"
                                               f"{options}```\n")
    return "\n".join(f"## {title}\n\n" + "\n".join(entries) for title, entries in groups.values())


def fill_markers(text: str, blocks: dict, path) -> str:
    """``text`` with each marker line (:data:`MARKER`) replaced by its block; ``ValueError`` naming the page, the
    line and the name for a marker that names no block."""
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

    ``public``: the package's public names (``replication._PUBLIC``, passed in: the study room does not import the
    package face) for :func:`api_chapter`; ``ledger``: default :func:`~replication.study.ledger.collect` of
    ``root``'s notebooks.

    Files are written only when they change, so that Sphinx rebuilds only what changed. Pages of ``docs/`` whose
    marker names no block, a report schema field without a description and a ledger that
    :func:`~replication.study.ledger.collect` refuses raise ``ValueError``.
    """
    root = Path(root) if root else PROJECT_ROOT
    source = Path(source) if source else root / "docs" / "_build" / "source"
    ledger = collect(sorted((root / "notebooks").glob("[0-9][0-9]_*.ipynb")),
                     claims_path=root / "data" / "paper" / "claims.csv") if ledger is None else ledger
    schema = json.loads((root / "docs" / "calibration_report.schema.json").read_text(encoding="utf-8"))
    blocks = {"claims": front_page_claims(ledger), "ledger": ledger_chapter(ledger),
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
