"""``python -m replication reproduce``: re-execute every numbered notebook in order and write
``results/`` (the tables, the figures and the claims ledger); a notebook that needs the real
recordings is skipped, saying why, when they are absent."""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from .._io import PROJECT_ROOT, write_atomic

__all__ = ["KERNELSPEC", "notebooks", "execute_notebook", "needs_real_data", "add_parser", "run"]

KERNELSPEC = {"name": "python3", "display_name": "Python 3 (ipykernel)", "language": "python"}


def notebooks(folder: Path) -> list[Path]:
    """The numbered notebooks of ``folder`` in order (``01_*.ipynb``, ``02_*.ipynb``, ...)."""
    found = sorted(p for p in folder.glob("[0-9][0-9]_*.ipynb"))
    if not found:
        raise SystemExit(f"no numbered notebooks (NN_name.ipynb) in {folder}")
    return found


def execute_notebook(path: Path, *, timeout: int = 1200) -> float:
    """Execute ``path`` in place with a normalised kernelspec; return the wall time in s."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    nb.metadata["kernelspec"] = dict(KERNELSPEC)
    client = NotebookClient(
        nb, timeout=timeout, kernel_name="python3", record_timing=False,
        resources={"metadata": {"path": str(path.parent)}},
    )
    start = time.perf_counter()
    client.execute()
    elapsed = time.perf_counter() - start
    nb.metadata["kernelspec"] = dict(KERNELSPEC)
    nb.metadata["language_info"] = {"name": "python"}
    nbformat.write(nb, path)
    return elapsed


def needs_real_data(path: Path) -> bool:
    """Whether a notebook declares ``metadata.replication.requires_real_data``."""
    import nbformat

    meta = nbformat.read(path, as_version=4).metadata.get("replication", {})
    return bool(meta.get("requires_real_data", False))


def _check_results(results, folder, paths) -> Path:
    """The results folder, before any notebook runs: not the notebooks' folder nor a notebook, and
    created and writable (``ValueError`` naming the path and the reason otherwise)."""
    from .._io import check_clashes, prepare_folder, same_file

    if same_file(results, folder):
        raise ValueError(f"--results {results} is the --notebooks folder: the results would be mixed into the "
                         "notebooks; give another folder")
    check_clashes({"--results": results}, {f"notebook {p.name}": p for p in paths})
    return prepare_folder(results, "--results")


def run(args: argparse.Namespace) -> int:
    """Exit 0 (every notebook run, the ledger written), 2 (the results folder refused: the reason on
    stderr)."""
    from tqdm import tqdm

    from ..rig.realdata import data_root, real_data_available

    paths = notebooks(Path(args.notebooks))
    try:
        results = _check_results(args.results, args.notebooks, paths)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    os.environ["REPLICATION_RESULTS_DIR"] = str(results)
    if args.only:
        paths = [p for p in paths if any(key in p.name for key in args.only)]
    if not real_data_available():
        skipped = [p for p in paths if needs_real_data(p)]
        for p in skipped:
            try:
                data_root()
            except FileNotFoundError as err:
                print(f"skipping {p.name}: {err}")
        paths = [p for p in paths if p not in skipped]
    times = {}
    with tqdm(paths, unit="notebook", file=sys.stderr) as bar:
        for path in bar:
            bar.set_description(path.stem)
            times[path.name] = execute_notebook(path)
    for name, seconds in times.items():
        print(f"{name}: {seconds:.1f} s")
    from ..study.ledger import collect, markdown_from_ledger

    ledger = collect(complete=not args.only)
    (results / "tables").mkdir(parents=True, exist_ok=True)
    write_atomic(results / "tables" / "claims.csv", ledger.to_csv(index=False))
    write_atomic(results / "tables" / "claims.md", markdown_from_ledger(ledger))
    print(f"claims ledger: {ledger['claim'].nunique()} claims, verdicts "
          + ", ".join(f"{v}: {n}" for v, n in ledger.drop_duplicates("claim")["verdict"].value_counts().items()))
    print(f"results written to {results}")
    return 0


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``reproduce`` sub-command."""
    rep = sub.add_parser("reproduce", help="re-execute every notebook in order and write results/")
    rep.add_argument("--notebooks", default=str(PROJECT_ROOT / "notebooks"), help="folder of NN_*.ipynb")
    rep.add_argument("--results", default=str(PROJECT_ROOT / "results"), help="output folder (tables/, figures/)")
    rep.add_argument("--only", nargs="*", help="run only notebooks whose name contains one of these")
    rep.set_defaults(func=run)
    return rep
