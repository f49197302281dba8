"""``python -m replication fetch-data``: the command line of :func:`replication.rig.fetch.fetch` and
:func:`~replication.rig.fetch.verify`."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._io import os_reason
from ..rig import fetch as rig_fetch  # called through the module: a stand-in set on it is what runs

__all__ = ["FETCH_HELP", "add_parser", "run"]

FETCH_HELP = """\
Download the real recordings that notebook 07 and the real-data tests read, from their public origins
(GitHub repositories at pinned commits; see data/real_data_manifest.csv for each file's repository, commit,
path, size, SHA-256, licence and citation: in the project's clone, or shipped inside the installed package as
replication/_shipped/data/real_data_manifest.csv), verify every checksum, and write them to DEST. Then run with
REPLICATION_REAL_DATA=DEST. Files already in DEST with the right checksum are kept.
Without a network the fetch stops at the first server it cannot reach, with one message naming that URL and the
reason; --mirror FOLDER takes the files from a local copy instead.
Exit status: 0 all files verified, 1 some missing or not matching, or no network, 2 bad arguments or manifest, or
DEST cannot be created or written (a file in the way, no permission, a full disk: the path and the reason named).
"""


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``fetch-data`` sub-command."""
    fet = sub.add_parser("fetch-data", help="download and verify the real recordings (data/real_data_manifest.csv)",
                         description=FETCH_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    fet.add_argument("dest", help="folder to write the recordings to (created if missing)")
    fet.add_argument("--mirror", help="take the files from this local copy (same layout) instead of downloading")
    fet.add_argument("--check", action="store_true", help="only verify the files already in DEST")
    fet.add_argument("--only", nargs="*", help="only these folders of the manifest (e.g. tabb_rwhe_ds1)")
    fet.set_defaults(func=run)
    return fet


def run(args: argparse.Namespace) -> int:
    """``python -m replication fetch-data``: exit 0 if every file is present and verified, else 1
    (no network included), 2 for bad arguments or an unwritable DEST."""
    try:
        entries = rig_fetch.load_manifest()
        if args.only:
            entries = [e for e in entries if e.folder in args.only]
            if not entries:
                raise ValueError(f"--only {args.only}: no such folder in the manifest")
        if args.check:
            report = rig_fetch.verify(args.dest, entries)
            for rel, status in report.items():
                print(f"{status:8s} {rel}" if status in ("ok", "missing") else f"BAD      {rel}: {status}")
        else:
            report = rig_fetch.fetch(args.dest, mirror=args.mirror, entries=entries)
    except ValueError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    except rig_fetch.NoNetwork as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    except OSError as err:  # FileNotFoundError, NotADirectoryError, PermissionError, ...
        where = f"{err.filename}: " if err.filename and str(err.filename) not in str(err.strerror or "") else ""
        print(f"error: {where}{os_reason(err) if where else err}", file=sys.stderr)
        return 2
    bad = [rel for rel, status in report.items() if status != "ok"]
    if bad:
        print(f"{len(bad)} of {len(report)} files missing or not matching the manifest", file=sys.stderr)
        return 1
    print(f"all {len(report)} files verified in {Path(args.dest).resolve()}; "
          f"set REPLICATION_REAL_DATA={Path(args.dest).resolve()}")
    return 0
