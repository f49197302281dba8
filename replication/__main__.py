"""Command line.

``python -m replication reproduce`` re-executes every notebook and writes ``results/``.
``python -m replication calibrate --camera FILE --sensor FILE`` calibrates a real rig.
``python -m replication export REPORT.json --to kalibr|openvins|basalt|orbslam3|ros2`` writes it into a tool's file.
``python -m replication fetch-data DEST`` downloads and verifies the real recordings notebook 07 reads.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
import warnings
from pathlib import Path

from ._io import PROJECT_ROOT, write_atomic
from ._version import __version__

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
    """The results folder, before any notebook runs: not the notebooks' folder nor a notebook, and created and
    writable (``ValueError`` naming the path and the reason otherwise)."""
    from ._io import check_clashes, prepare_folder, same_file

    if same_file(results, folder):
        raise ValueError(f"--results {results} is the --notebooks folder: the results would be mixed into the "
                         "notebooks; give another folder")
    check_clashes({"--results": results}, {f"notebook {p.name}": p for p in paths})
    return prepare_folder(results, "--results")


def reproduce(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from .rig.realdata import data_root, real_data_available

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
    from .study.ledger import collect, markdown_from_ledger

    ledger = collect(complete=not args.only)
    (results / "tables").mkdir(parents=True, exist_ok=True)
    write_atomic(results / "tables" / "claims.csv", ledger.to_csv(index=False))
    write_atomic(results / "tables" / "claims.md", markdown_from_ledger(ledger))
    print(f"claims ledger: {ledger['claim'].nunique()} claims, verdicts "
          + ", ".join(f"{v}: {n}" for v, n in ledger.drop_duplicates("claim")["verdict"].value_counts().items()))
    print(f"results written to {results}")
    return 0


def claims_command(args: argparse.Namespace) -> int:
    """Exit 0 (done, or README current), 1 (``--check``: README out of date), 2 (a record, a notebook, the claims
    file or README refused, or more than one of ``--check``, ``--readme``, ``--summary`` given: the message on
    stderr)."""
    from .study.ledger import collect, markdown_from_ledger, summary_from_ledger, update_readme

    given = [flag for flag in ("--check", "--readme", "--summary") if getattr(args, flag[2:])]
    if len(given) > 1:  # each is one action: refused before any work rather than one of them silently ignored
        print(f"error: {' and '.join(given)} cannot be used together: --check compares README's claims table with "
              f"the records, --readme writes it, --summary prints the compact table; give one of them",
              file=sys.stderr)
        return 2
    try:
        ledger = collect()
        if args.check:
            if update_readme(ledger, check=True):
                print("README's claims table matches the records stored in the executed notebooks (that each record "
                      "is what its cell computes is checked by strict nbval: bash scripts/test)")
                return 0
            print("README's claims table is out of date: run 'python -m replication claims --readme'",
                  file=sys.stderr)
            return 1
        if args.readme:
            update_readme(ledger)
            print("README's claims table updated")
            return 0
        if args.summary:
            print(summary_from_ledger(ledger), end="")
            return 0
    except (ValueError, OSError) as err:  # DataFileError is a ValueError; DataFileNotFound both
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(markdown_from_ledger(ledger))
    return 0


def generate_lab_command(args: argparse.Namespace) -> int:
    import time

    from .study.lab import LabSettings, default_lab_dir, simulate_lab, write_lab

    start = time.perf_counter()
    settings = LabSettings() if args.seed is None else LabSettings(seed=args.seed)
    out = write_lab(simulate_lab(settings), args.out or default_lab_dir())
    print(f"lab recordings (seed {settings.seed}) written to {out} in {time.perf_counter() - start:.1f} s")
    return 0


def _one_line_warnings():
    """A ``warnings.showwarning`` for the command line: each warning once (by class and text), on one line of standard
    error as ``warning: <Class>: <message>``, without the file, line and source line Python prints by default."""
    seen = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())
        if (category, text) not in seen:
            seen.add((category, text))
            print(f"warning: {category.__name__}: {text}", file=file or sys.stderr)
    return show


def _run(args: argparse.Namespace) -> int:
    """Run a parsed command with the command line's warnings (:func:`_one_line_warnings`, restored after); an optional
    package that is missing ends it with exit 2 and the extra to install (:mod:`replication._extras`)."""
    from ._extras import OPTIONAL, MissingExtra, missing_message

    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warnings()
        try:
            return args.func(args)
        except ImportError as err:
            if not isinstance(err, MissingExtra) and (err.name or "").split(".")[0] not in OPTIONAL:
                raise
            command = f"python -m replication {args.command}"
            text = err if isinstance(err, MissingExtra) else missing_message(err.name, command)
            print(f"error: {text}", file=sys.stderr)
            return 2


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m replication", description=__doc__)
    parser.add_argument("--version", action="version", version=f"replication {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="re-execute every notebook in order and write results/")
    rep.add_argument("--notebooks", default=str(PROJECT_ROOT / "notebooks"), help="folder of NN_*.ipynb")
    rep.add_argument("--results", default=str(PROJECT_ROOT / "results"), help="output folder (tables/, figures/)")
    rep.add_argument("--only", nargs="*", help="run only notebooks whose name contains one of these")
    rep.set_defaults(func=reproduce)
    from .rig.calibrate_cli import add_parser as add_calibrate_parser

    add_calibrate_parser(sub)
    from .rig.export import add_parser as add_export_parser

    add_export_parser(sub)
    gen = sub.add_parser("generate-lab", help="write the simulated lab recordings (default: data/lab)")
    gen.add_argument("--out", help="output folder (default: data/lab of this project)")
    gen.add_argument("--seed", type=int, help="LabSettings.seed (default: that of the committed data)")
    gen.set_defaults(func=generate_lab_command)
    cla = sub.add_parser("claims", help="the claims ledger from the executed notebooks (data/paper/claims.csv)")
    cla.add_argument("--readme", action="store_true", help="write it into README.md between the claims markers")
    cla.add_argument("--check", action="store_true", help="exit 1 if README.md's table is out of date")
    cla.add_argument("--summary", action="store_true",
                     help="print the compact table (the counts, then claim | the paper says | verdict | measured in)")
    cla.set_defaults(func=claims_command)
    from .rig.fetch import FETCH_HELP, fetch_command

    fet = sub.add_parser("fetch-data", help="download and verify the real recordings (data/real_data_manifest.csv)",
                         description=FETCH_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    fet.add_argument("dest", help="folder to write the recordings to (created if missing)")
    fet.add_argument("--mirror", help="take the files from this local copy (same layout) instead of downloading")
    fet.add_argument("--check", action="store_true", help="only verify the files already in DEST")
    fet.add_argument("--only", nargs="*", help="only these folders of the manifest (e.g. tabb_rwhe_ds1)")
    fet.set_defaults(func=fetch_command)
    args = parser.parse_args(argv)
    return _run(args)


def _main_closing_pipes():
    """``main`` for the command line: a reader that stops early (``| head``) ends the output quietly, exit 141."""
    try:
        code = main()
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # Python would flush into the closed pipe again at exit
        return 128 + 13


if __name__ == "__main__":
    sys.exit(_main_closing_pipes())
