"""The command line, ``python -m replication <command>``: one module per command, each with
``add_parser(sub)`` (its options, help and defaults) and ``run(args) -> int`` (its exit code);
:func:`main` builds the top parser from them and runs the command with one-line warnings. Nothing of
the library imports this room; it imports the library.
"""
from __future__ import annotations

import argparse
import os
import sys
import warnings

from .._version import __version__

__all__ = ["DESCRIPTION", "main", "main_closing_pipes"]

#: The top parser's description (``python -m replication --help``).
DESCRIPTION = """Command line.

``python -m replication reproduce`` re-executes every notebook and writes ``results/``.
``python -m replication calibrate --camera FILE --sensor FILE`` calibrates a real rig.
``python -m replication export REPORT.json --to kalibr|openvins|basalt|orbslam3|ros2`` writes it into a tool's file.
``python -m replication fetch-data DEST`` downloads and verifies the real recordings notebook 07 reads.
"""


def _one_line_warnings():
    """A ``warnings.showwarning`` for the command line: each warning once (by class and text), on
    one line of standard error as ``warning: <Class>: <message>``, without the file, line and source
    line Python prints by default."""
    seen = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())
        if (category, text) not in seen:
            seen.add((category, text))
            print(f"warning: {category.__name__}: {text}", file=file or sys.stderr)
    return show


def _run(args: argparse.Namespace) -> int:
    """Run a parsed command with the command line's warnings (:func:`_one_line_warnings`, restored
    after); an optional package that is missing ends it with exit 2 and the extra to install
    (:mod:`replication._extras`)."""
    from .._extras import OPTIONAL, MissingExtra, missing_message

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
    """Parse ``argv`` (default: the process's arguments) and run the command; its exit code."""
    from . import calibrate, claims, export, fetch, lab, reproduce

    parser = argparse.ArgumentParser(prog="python -m replication", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"replication {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    for command in (reproduce, calibrate, export, lab, claims, fetch):  # the order --help lists them in
        command.add_parser(sub)
    args = parser.parse_args(argv)
    return _run(args)


def main_closing_pipes():
    """``main`` for the command line: a reader that stops early (``| head``) ends the output
    quietly, exit 141."""
    try:
        code = main()
        sys.stdout.flush()
        return code
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # Python would flush into the closed pipe again at exit
        return 128 + 13
