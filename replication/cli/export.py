"""``python -m replication export``: the command line of
:func:`replication.rig.export.export_calibration`.

The report is checked and read before anything is written (a pipe once); the output goes to
``--out`` atomically, or to standard output; what was changed, added and noted is said on standard
error. Exit codes: 0 written, 2 refused (the reason named).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._io import check_clashes, check_input, os_reason, prepare_output, same_file
from ..rig import export as rig_export  # called through the module: a stand-in set on it is what runs

__all__ = ["EXPORT_HELP", "add_parser", "run"]


EXPORT_HELP = """Write a calibration report's R0 and clock offset into another tool's configuration.

--base is your own file of that tool (Kalibr camchain-imucam, OpenVINS kalibr_imucam_chain, Basalt calibration
JSON, ORB-SLAM3 settings): the output is a copy in which only the rotations and the clock offset are changed (the
translation, intrinsics, comments are kept). A file with several cameras stays a rig: the other cameras turn with
the one calibrated (--camera), so every camera-camera transform is unchanged; --one-camera changes that camera only,
with a warning saying how far the stereo calibration moves. Each tool's loader needs intrinsics that a calibration
of R0 does not give, so without --base a file is refused (naming what the base must hold); --to ros2 prints a
static_transform_publisher command instead. Each tool's frame direction, field, unit and sign, with the line of its
source: docs/conventions.md, "Other tools' files" (in the project's clone, or shipped inside the installed package
as replication/_shipped/docs/conventions.md); in short: python -m pydoc replication.rig.vioformats.

examples:
  python -m replication export report.json --to kalibr --base camchain-imucam.yaml --out camchain-new.yaml
  python -m replication export report.json --to basalt --base calib.json --camera cam1 --out calib-new.json
  python -m replication export report.json --to ros2
"""


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``export`` sub-command."""
    exp = sub.add_parser("export", help="write a report's R0 and clock offset into Kalibr / OpenVINS / Basalt / "
                         "ORB-SLAM3 files or a ROS 2 command", description=EXPORT_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    exp.add_argument("report", help="the calibration report (calibrate --out REPORT.json)")
    exp.add_argument("--to", required=True, choices=rig_export.TARGETS, help="the tool")
    exp.add_argument("--base", help="your own file of that tool, to copy with only the rotations and offset changed "
                     "(required but for ros2)")
    exp.add_argument("--camera", default="cam0", help="the camera the report calibrated (default: cam0)")
    exp.add_argument("--one-camera", action="store_true", help="change --camera only, not the rest of the rig "
                     "(moves every camera-camera rotation by the correction: a warning says how far)")
    exp.add_argument("--out", help="the file to write (default: standard output)")
    exp.add_argument("--parent-frame", default="imu_link", help="ros2: the IMU's frame (default: imu_link)")
    exp.add_argument("--child-frame", default="camera_optical_frame",
                     help="ros2: the camera's optical frame (default: camera_optical_frame)")
    exp.add_argument("--force", action="store_true", help="export even when the report's verdict is fail")
    exp.set_defaults(func=run)
    return exp


def run(args: argparse.Namespace) -> int:
    """Exit 0 (written), 2 (refused: the reason on standard error); warnings reach the terminal
    through the command line's one-line formatter (:mod:`replication.cli`)."""
    try:
        inputs = {"REPORT": args.report, "--base": args.base}
        kinds = {k: check_input(v, k) for k, v in inputs.items() if v is not None}
        if len(kinds) == 2 and "pipe" in kinds.values() and same_file(args.report, args.base):
            raise ValueError(f"--base is the REPORT pipe ({args.base}): a pipe can be read once")
        check_clashes({"--out": args.out}, inputs)
        out = prepare_output(args.out, "--out") if args.out is not None else None
        result = rig_export.export_calibration(args.report, args.to, base=args.base, camera=args.camera,
                                    parent_frame=args.parent_frame, child_frame=args.child_frame, force=args.force,
                                    whole_rig=not getattr(args, "one_camera", False))
    except ValueError as err:  # DataFileError is a ValueError
        print(f"error: {err}", file=sys.stderr)
        return 2
    if out is None:
        sys.stdout.write(result.text)
    else:
        try:
            result.write(out)
        except OSError as err:
            print(f"error: --out {out}: cannot write ({os_reason(err)}); nothing was written there", file=sys.stderr)
            return 2
    what = f"changed {', '.join(result.changed)}" + (f"; added {', '.join(result.added)}" if result.added else "")
    print(f"{args.to}: {what}" + (f" in {Path(out).name}" if out else ""), file=sys.stderr)
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    return 0
