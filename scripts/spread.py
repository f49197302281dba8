"""Which stored notebook outputs can another machine's rounding change? Re-execute, compare, report
per number.

Every numbered notebook (or those named) is executed once per *variant* of the machine: its inputs
jittered at the last bits (``REPLICATION_JITTER``, ``replication/_jitter.py``), numpy's SIMD
dispatch limited (``NPY_DISABLE_CPU_FEATURES``: AVX2 or the SSE4.2 baseline on an AVX-512 machine),
OpenBLAS forced to another CPU's kernels (``OPENBLAS_CORETYPE``) with one thread, and a *margin*
variant whose jitter is 1e-13 (100 times the last-bit one). Every output strict nbval compares
(text, HTML, streams, the ledger's records; not images, not cells marked ``NBVAL_IGNORE_OUTPUT``) is
split into its numbers and the text between them, and compared with the stored one, number by
number.

For each stored number the report gives its *spread*: the values it takes over the last-bit variants
(a stored number must not move: spread 0 at its printed precision), and its *margin*: a printed
number does not carry its unrounded value, so its distance to the nearest rounding edge is measured
as the relative input jitter it withstands (unchanged under the 1e-13 variant: a hundred times what
a processor's rounding does to the inputs). Outputs of chaotic quantities go through a guard
(``declared_bound``, ``bracket``, ``share_range`` of ``replication.core.stats``) that checks the
value's distance to its bound's or bracket's edges in its own units; the ``margin`` variant doubles
every guard's margin and logs, instead of raising, each guard that does not hold there, with its
distance. A number that moves in any variant, or a guard that does not hold at twice its margin, is
*fragile*; the exit status is 1 if any is.

Usage (``bash scripts/spread ARGS`` runs it in the project's venv)::

    .venv/bin/python scripts/spread.py                       # every notebook, every variant (about
    45 min, 2 cores) .venv/bin/python scripts/spread.py --notebooks 02 04 --variants avx2 margin
    .venv/bin/python scripts/spread.py --reuse --all          # report again from the executed
    copies, every number

Executed copies are kept in ``.spread/<variant>/`` (``--reuse`` reads them instead of executing);
``--json FILE`` writes the per-number table.
"""
from __future__ import annotations

import argparse
import configparser
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from replication._jitter import GUARD_LOG_ENV, LAST_BIT, MARGIN_ENV, VARIANTS

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / ".spread"
SKIP_MIME = {"image/png", "image/jpeg", "application/vnd.jupyter.widget-view+json"}
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def sanitizers():
    """The regex replacements of ``tests/sanitize.cfg`` (what nbval masks)."""
    cfg = configparser.ConfigParser()
    cfg.read(ROOT / "tests" / "sanitize.cfg")
    return [(re.compile(cfg[s]["regex"]), cfg[s]["replace"]) for s in cfg.sections()]


def compared_texts(nb: dict) -> dict:
    """``{(cell, key): text}``: every output strict nbval compares, sanitised; ``cell`` counts code
    cells from 1."""
    subs = sanitizers()
    out = {}
    cells = [c for c in nb["cells"] if c["cell_type"] == "code"]
    for k, cell in enumerate(cells, 1):
        source = "".join(cell["source"])
        if "NBVAL_IGNORE_OUTPUT" in source or "NBVAL_SKIP" in source:
            continue
        streams, j = {}, 0  # streams merged by name, as nbval does; the other outputs counted apart from them
        for o in cell.get("outputs", []):
            if o["output_type"] == "stream":
                streams[o["name"]] = streams.get(o["name"], "") + "".join(o["text"])
            elif o["output_type"] == "error":
                out[(k, "error")] = f"{o['ename']}: {o['evalue']}"
            elif "data" in o:
                j += 1
                for mime, value in o["data"].items():
                    if mime in SKIP_MIME:
                        continue
                    text = "".join(value) if isinstance(value, list) else json.dumps(value, sort_keys=True)
                    out[(k, f"{j}:{mime}")] = text
        for name, text in streams.items():
            out[(k, f"stream:{name}")] = text
    for key, text in out.items():
        for regex, replace in subs:
            text = regex.sub(replace, text)
        out[key] = text
    return out


def split_numbers(text: str):
    """``(words, numbers)``: the text with each number replaced by ``#`` and runs of blanks by one
    (a table's columns move when one of its numbers widens), and the numbers as printed."""
    return re.sub(r"[ \t]+", " ", NUMBER.sub("#", text)), NUMBER.findall(text)


def execute(notebook: Path, variant: str, *, timeout: int = 2400) -> float:
    """Execute ``notebook`` under ``variant`` into ``.spread/<variant>/``; return the wall time in
    s."""
    dest = CACHE / variant / notebook.name
    dest.parent.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, **VARIANTS[variant], "MPLBACKEND": "Agg",
           "REPLICATION_RESULTS_DIR": tempfile.mkdtemp(prefix=f"spread-{variant}-")}
    guards = guard_log(variant, notebook)
    guards.unlink(missing_ok=True)
    if MARGIN_ENV in VARIANTS[variant]:  # the guards of rounding edges log what does not hold at twice the margin
        env[GUARD_LOG_ENV] = str(guards)
    code = ("import sys, nbformat; from nbclient import NotebookClient\n"
            "nb = nbformat.read(sys.argv[1], as_version=4)\n"
            "NotebookClient(nb, timeout=int(sys.argv[3]), kernel_name='python3', allow_errors=True,\n"
            "               resources={'metadata': {'path': sys.argv[4]}}).execute()\n"
            "nbformat.write(nb, sys.argv[2])\n")
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", code, str(notebook), str(dest), str(timeout), str(notebook.parent)],
                   env=env, check=True, capture_output=True, text=True)
    return time.perf_counter() - start


def guard_log(variant: str, notebook: Path) -> Path:
    return CACHE / variant / (notebook.stem + ".guards.jsonl")


def guard_rows(notebook: Path, variants) -> list[dict]:
    """The guards of rounding edges (``declared_bound``, ``bracket``, ``share_range``) that did not
    hold under the doubled margin: each value's distance to its edge, in its own units, against the
    margin."""
    rows = []
    for v in variants:
        path = guard_log(v, notebook)
        if path.is_file():
            for line in path.read_text(encoding="utf-8").splitlines():
                r = json.loads(line)
                rows.append({"cell": None, "output": "guard", "index": None, "stored": r["bound"], "fragile": True,
                             "values": {v: r["value"]},
                             "what": f"{r['what']} {r['value']:.6g} is {r['distance']:.4g} from an edge of "
                                     f"{r['bound']}, less than {r['margin']:g} (twice its margin)"})
    return rows


def compare(stored: dict, runs: dict) -> list[dict]:
    """One row per stored number (and per text that differs): its value in every variant."""
    rows = []
    for key, text in stored.items():
        words, numbers = split_numbers(text)
        seen = {}
        for variant, texts in runs.items():
            other = texts.get(key)
            if other is None:
                seen[variant] = None
                continue
            w, n = split_numbers(other)
            seen[variant] = n if (w == words and len(n) == len(numbers)) else None
        broken = [v for v, n in seen.items() if n is None]
        if broken:
            first = next((runs[v].get(key) for v in broken if runs[v].get(key) is not None), None)
            diff = "missing" if first is None else next(
                (f"{a.strip()!r} -> {b.strip()!r}" for a, b in zip(text.splitlines(), first.splitlines())
                 if split_numbers(a)[0] != split_numbers(b)[0]), "a line more or less")
            rows.append({"cell": key[0], "output": key[1], "index": None, "stored": text[:200],
                         "values": {v: None for v in broken}, "fragile": True,
                         "what": f"text differs (not only numbers) in {', '.join(broken)}: {diff[:300]}"})
        for i, value in enumerate(numbers):
            values = {v: n[i] for v, n in seen.items() if n is not None}
            moved = sorted(v for v, x in values.items() if x != value)
            rows.append({"cell": key[0], "output": key[1], "index": i, "stored": value, "values": values,
                         "fragile": bool(moved),
                         "spread": sorted({value, *(values[v] for v in values if v in LAST_BIT)}),
                         "margin": "below 1e-13" if "margin" in moved else
                                   (">= 1e-13" if "margin" in values else "not measured"),
                         "what": ("moves in " + ", ".join(moved)) if moved else "stable"})
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--notebooks", nargs="*", help="two-digit prefixes (default: every numbered notebook)")
    parser.add_argument("--variants", nargs="*", choices=sorted(VARIANTS), default=sorted(VARIANTS))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--reuse", action="store_true", help="compare the executed copies in .spread/ again")
    parser.add_argument("--all", action="store_true", help="print every number, not only the fragile ones")
    parser.add_argument("--json", type=Path, help="write the per-number table here")
    args = parser.parse_args(argv)
    notebooks = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))
    if args.notebooks:
        notebooks = [p for p in notebooks if p.name[:2] in set(args.notebooks)]
    jobs = [(nb, v) for nb in notebooks for v in args.variants]
    if not args.reuse:
        with ThreadPoolExecutor(args.workers) as pool:
            for (nb, v), seconds in zip(jobs, pool.map(lambda job: execute(*job), jobs)):
                print(f"executed {nb.name} under {v} in {seconds:.0f} s", flush=True)
    table, fragile = {}, 0
    for nb in notebooks:
        stored = compared_texts(json.loads(nb.read_text(encoding="utf-8")))
        runs = {v: compared_texts(json.loads((CACHE / v / nb.name).read_text(encoding="utf-8")))
                for v in args.variants if (CACHE / v / nb.name).is_file()}
        rows = compare(stored, runs) + guard_rows(nb, args.variants)
        table[nb.name] = rows
        bad = [r for r in rows if r["fragile"]]
        fragile += len(bad)
        numbers = sum(r["index"] is not None for r in rows)
        print(f"{nb.name}: {numbers} stored numbers in {len(stored)} outputs, {len(bad)} fragile "
              f"(variants: {', '.join(runs)})")
        for r in rows if args.all else bad:
            shown = {v: x for v, x in r["values"].items() if x != r["stored"]} if r["fragile"] else {}
            print(f"  cell {r['cell']} [{r['output']}] #{r['index']}: {r['stored']!s:.80} -> {r['what']} {shown}")
    if args.json:
        args.json.write_text(json.dumps(table, indent=1), encoding="utf-8")
    print(f"{fragile} fragile outputs" if fragile else "every stored number is stable in every variant")
    return 1 if fragile else 0


if __name__ == "__main__":
    sys.exit(main())
