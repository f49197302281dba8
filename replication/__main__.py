"""Command line: ``python -m replication reproduce`` re-executes every notebook and writes ``results/``."""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
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


def reproduce(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    results = Path(args.results).resolve()
    os.environ["REPLICATION_RESULTS_DIR"] = str(results)
    paths = notebooks(Path(args.notebooks))
    if args.only:
        paths = [p for p in paths if any(key in p.name for key in args.only)]
    times = {}
    with tqdm(paths, unit="notebook", file=sys.stderr) as bar:
        for path in bar:
            bar.set_description(path.stem)
            times[path.name] = execute_notebook(path)
    for name, seconds in times.items():
        print(f"{name}: {seconds:.1f} s")
    print(f"results written to {results}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m replication", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="re-execute every notebook in order and write results/")
    rep.add_argument("--notebooks", default=str(ROOT / "notebooks"), help="folder of NN_*.ipynb")
    rep.add_argument("--results", default=str(ROOT / "results"), help="output folder (tables/, figures/)")
    rep.add_argument("--only", nargs="*", help="run only notebooks whose name contains one of these")
    rep.set_defaults(func=reproduce)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
