"""``python -m replication claims``: the claims ledger collected from the executed notebooks,
printed, checked against README's table or written into it (:mod:`replication.study.ledger`)."""
from __future__ import annotations

import argparse
import sys

__all__ = ["add_parser", "run"]


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``claims`` sub-command."""
    cla = sub.add_parser("claims", help="the claims ledger from the executed notebooks (data/paper/claims.csv)")
    cla.add_argument("--readme", action="store_true", help="write it into README.md between the claims markers")
    cla.add_argument("--check", action="store_true", help="exit 1 if README.md's table is out of date")
    cla.add_argument("--summary", action="store_true",
                     help="print the compact table (the counts, then claim | the paper says | verdict | measured in)")
    cla.set_defaults(func=run)
    return cla


def run(args: argparse.Namespace) -> int:
    """Exit 0 (done, or README current), 1 (``--check``: README out of date), 2 (a record, a
    notebook, the claims file or README refused, or more than one of ``--check``, ``--readme``,
    ``--summary`` given: the message on stderr)."""
    from ..study.ledger import collect, markdown_from_ledger, summary_from_ledger, update_readme

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
