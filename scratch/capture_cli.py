"""Capture the command line's outputs (stdout, stderr, exit code) for a fixed list of argv, in process, COLUMNS=120.

python scratch/capture_cli.py OUTDIR  (before the move: main from replication.__main__; after: replication.cli)
"""
import contextlib
import io
import json
import os
import sys
from pathlib import Path

os.environ["COLUMNS"] = "120"
try:
    from replication.cli import main
except ImportError:
    from replication.__main__ import main

CASES = {
    "top_help": ["--help"], "version": ["--version"], "no_command": [], "bogus": ["bogus"],
    "reproduce_help": ["reproduce", "--help"], "calibrate_help": ["calibrate", "--help"],
    "export_help": ["export", "--help"], "generate-lab_help": ["generate-lab", "--help"],
    "claims_help": ["claims", "--help"], "fetch-data_help": ["fetch-data", "--help"],
    "calibrate_missing": ["calibrate"],
    "calibrate_bad_interval": ["calibrate", "--camera", "x", "--sensor", "y", "--interval", "-1"],
    "calibrate_bad_stride": ["calibrate", "--camera", "x", "--sensor", "y", "--stride", "nan"],
    "calibrate_no_file": ["calibrate", "--camera", "/nonexistent/c.txt", "--sensor", "/nonexistent/s.txt"],
    "calibrate_track": ["calibrate", "--camera", "a", "--sensor", "b", "--track", "t.csv"],
    "calibrate_method": ["calibrate", "--camera", "a", "--sensor", "b", "--method", "nope"],
    "export_missing_to": ["export", "r.json"],
    "export_no_file": ["export", "/nonexistent/r.json", "--to", "kalibr"],
    "fetch_missing_dest": ["fetch-data"],
    "claims_two": ["claims", "--check", "--readme"],
    "reproduce_no_notebooks": ["reproduce", "--notebooks", "/nonexistent"],
}

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
for name, argv in CASES.items():
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            code = main(argv)
        except SystemExit as err:
            code = err.code
    (out / f"{name}.json").write_text(json.dumps({"argv": argv, "code": code, "stdout": stdout.getvalue(),
                                                  "stderr": stderr.getvalue()}, indent=1) + "\n")
print(f"{len(CASES)} cases written to {out}")
