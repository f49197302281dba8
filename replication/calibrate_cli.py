"""``python -m replication calibrate``: the command line of :func:`replication.calibration.calibrate`.

Every parameter is checked when the command line is parsed (its name in the message), the output paths before
any work (folders created, a directory or an unwritable place refused), and the report and figure are written
atomically. Exit codes: 0 (verdict ``ok`` or ``warning``), 2 (bad input: nothing computed or nothing written),
:data:`replication.quality.EXIT_FAIL` (verdict ``fail``; 0 with ``--accept``).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

from ._io import write_atomic
from .quality import EXIT_FAIL

__all__ = ["CALIBRATE_HELP", "add_parser", "calibrate_command", "EXIT_BAD_INPUT"]

#: Exit code for bad input (argparse's own, too).
EXIT_BAD_INPUT = 2

CALIBRATE_HELP = """\
Estimate R0 = camera_from_sensor (A_j R0 = R0 B_j) from two timestamped streams, or from two static pose sets
(--poses), and judge the answer: the verdict (ok / warning / fail, every reason with its measured number and
threshold) is printed first and stored in the report; a fail exits with code 3 unless --accept.

Formats (recognised by --sensor-kind and the file name):
  camera / orientation sensor:
    *.txt  TUM / ORB-SLAM3 trajectory, lines "t tx ty tz qx qy qz qw" (t in s or ns: --time-unit), world<-body
    *.csv  EuRoC / TUM-VI mocap or ground truth, "t[ns], px, py, pz, qw, qx, qy, qz", world<-body
  gyro sensor (--sensor-kind gyro):
    *.csv  EuRoC / TUM-VI imu0/data.csv, "t[ns], wx, wy, wz [rad/s], ax, ay, az [m/s^2]"
  static pose sets (--poses): Tabb & Ahmad Yousef's cali.txt (camera) and robot_cali.txt (robot hand)
  reference (optional):
    Kalibr camchain YAML (<cam>.T_cam_imu), EuRoC sensor.yaml (T_BS, cam -> body), Tabb transformations.txt (Z)
The clock offset is estimated by cross-correlating angular speeds and removed unless --keep-clock; the report
states its sign: the sensor sample stamped t + offset matches the camera sample stamped t.
Exit codes: 0 ok or warning, 2 bad input, 3 verdict fail (0 with --accept).
"""


def _number(kind, *, minimum=None, strict=True):
    """An argparse type: a finite ``kind`` above ``minimum`` (``>=`` if not ``strict``)."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a{'n integer' if kind is int else ' number'}: {text!r}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"not finite: {text!r}")
        if minimum is not None and (value <= minimum if strict else value < minimum):
            raise argparse.ArgumentTypeError(f"must be {'>' if strict else '>='} {minimum:g}, got {text}")
        return value
    return parse


def add_parser(sub) -> argparse.ArgumentParser:
    cal = sub.add_parser("calibrate", help="calibrate a real rig and judge the answer",
                         description=CALIBRATE_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    cal.add_argument("--camera", required=True, help="camera trajectory (world<-camera), or camera poses (--poses)")
    cal.add_argument("--sensor", required=True, help="sensor trajectory, raw gyro samples, or robot poses (--poses)")
    cal.add_argument("--sensor-kind", choices=["orientation", "gyro"], default="orientation")
    cal.add_argument("--poses", action="store_true", help="both files are static pose sets (Tabb format)")
    cal.add_argument("--method", default="chordal_optimal", help="a solver from replication.solvers.available()")
    cal.add_argument("--interval", type=_number(float, minimum=0), default=1.0,
                     help="seconds between the two poses of a pair")
    cal.add_argument("--stride", type=_number(int, minimum=1, strict=False), default=1,
                     help="keep every stride-th pair (non-overlapping pairs: interval x camera rate)")
    cal.add_argument("--max-offset", type=_number(float, minimum=0), default=0.2,
                     help="largest clock offset searched (s)")
    cal.add_argument("--keep-clock", action="store_true", help="report the clock offset but do not remove it")
    cal.add_argument("--bootstrap", type=_number(int, minimum=0, strict=False), default=200,
                     help="bootstrap replicates (0: none)")
    cal.add_argument("--seed", type=_number(int, minimum=0, strict=False), default=0, help="seed of the bootstrap")
    units = ["auto", "s", "ms", "us", "ns"]
    cal.add_argument("--time-unit", choices=units, default=None,
                     help="time unit of both files when they are TUM trajectories (auto: ns above 1e12, else s)")
    cal.add_argument("--camera-time-unit", choices=units, default=None, help="time unit of the camera file only")
    cal.add_argument("--sensor-time-unit", choices=units, default=None, help="time unit of the sensor file only")
    cal.add_argument("--drop-repeated", action="store_true",
                     help="skip lines of a TUM trajectory that repeat the previous line verbatim")
    cal.add_argument("--reference", help="a reference R0 to compare with (Kalibr / EuRoC / Tabb file)")
    cal.add_argument("--reference-camera", default="cam0", help="camera entry of a Kalibr camchain")
    cal.add_argument("--out", help="write the JSON report here (folders are created)")
    cal.add_argument("--plot", help="write the diagnostic figure (PNG) here (folders are created)")
    cal.add_argument("--accept", action="store_true", help="exit 0 even when the verdict is fail")
    cal.add_argument("--online", action="store_true",
                     help="also replay the streams through the online estimator (replication.online), as if live")
    cal.add_argument("--track", help="with --online: write its estimate, 95 %% radius, ready and alarms per pair (CSV)")
    cal.add_argument("--target", type=_number(float, minimum=0), default=0.5,
                     help="with --online: ready once the 95 %% radius is below this (deg)")
    cal.add_argument("--quiet", action="store_true", help="no progress bar")
    cal.set_defaults(func=calibrate_command)
    return cal


def _check_output(path) -> Path:
    """Create the folders of ``path`` and check that it can be written, before any work."""
    text = str(path)
    if not text.strip():
        raise ValueError("an output path is empty")
    if text.endswith(("/", os.sep)):
        raise ValueError(f"{text}: names a folder; give a file name")
    path = Path(path).resolve()
    if path.is_dir():
        raise ValueError(f"{path}: is a directory; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        probe = path.with_name(path.name + ".part")
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as err:
        raise ValueError(f"{path}: cannot write here ({err.strerror})") from None
    return path


def _file_entry(path) -> dict:
    from .fetch import sha256_of

    path = Path(path).resolve()
    return {"path": str(path), "bytes": path.stat().st_size, "sha256": sha256_of(path)}


def _load(args):
    from . import realdata

    if args.poses:
        return realdata.load_tabb_camera_poses(args.camera), realdata.load_tabb_poses(args.sensor)
    camera = realdata.load_stream(args.camera, "orientation", time_unit=_unit(args, "camera"),
                                  drop_repeated=args.drop_repeated)
    sensor = realdata.load_stream(args.sensor, args.sensor_kind, time_unit=_unit(args, "sensor"),
                                  drop_repeated=args.drop_repeated)
    return camera, sensor


def _unit(args, side: str) -> str:
    """The time unit for one file: its own option, else ``--time-unit`` where it applies (TUM files), else auto."""
    own = getattr(args, f"{side}_time_unit")
    if own is not None:
        return own
    path = args.camera if side == "camera" else args.sensor
    csv = side == "sensor" and args.sensor_kind == "gyro" or str(path).lower().endswith(".csv")
    return "auto" if args.time_unit is None or csv else args.time_unit


def _online(args, camera, sensor, reference, result):
    """Replay the streams through the online estimator with the batch options (interval, stride, clock offset
    search and whether to apply it); print what it found; return the result with the online summary and track."""
    import dataclasses

    from .live import replay
    from .online import OnlineCalibrator

    rows = replay(camera, sensor, OnlineCalibrator(target_deg=args.target), interval=args.interval,
                  max_offset=args.max_offset, correct_offset=not args.keep_clock, stride=args.stride,
                  reference=reference)
    summary = rows.attrs["summary"]
    offset = summary["clock_offset_s"]
    head = (f"online: {len(rows)} pairs at {args.interval:g} s"
            + (f", clock offset {1e3 * offset:+.1f} ms" if offset is not None else "")
            + f"; verdict {summary['verdict']['level'].upper()}")
    if not len(rows):
        print(f"{head}; no pairs were formed" + (f" ({summary['note']})" if summary["note"] else
                                                   " (the streams overlap too little for one pair)"))
    elif summary["ready_at_s"] is not None:
        print(f"{head}; ready ({100 * summary['radius_level']:g} % radius < {args.target:g} deg) when the pair ending "
              f"at {summary['ready_pair_end_s']:.1f} s was formed, {summary['ready_at_s']:.1f} s after the camera's "
              f"first sample; final radius {summary['radius_deg']:.3g} deg")
    else:
        print(f"{head}; never ready: " + "; ".join(summary["not_ready"]))
    for line in summary["verdict"]["reasons"]:
        if line["level"] == "fail":
            print(f"  online fail: {line['message']}")
    print("  events: " + ("none" if not summary["events"] else ", ".join(
        f"{ev['kind']} at {ev['t_s']:.1f} s" for ev in summary["events"])))
    print(f"  the online radius covers {summary['radius_covers']}")
    diagnostics = {**result.diagnostics, "online_track": rows}
    return dataclasses.replace(result, online=summary, diagnostics=diagnostics), rows


def calibrate_command(args: argparse.Namespace) -> int:
    from .calibration import calibrate, calibrate_poses
    from .realdata import load_reference
    from .solvers import solver_info

    try:
        solver_info(args.method)
        if args.track is not None and not args.online:
            raise ValueError("--track needs --online")
        if args.online and args.poses:
            raise ValueError("--online needs streams, not static pose sets (--poses)")
        out = _check_output(args.out) if args.out is not None else None
        plot = _check_output(args.plot) if args.plot is not None else None
        track = _check_output(args.track) if args.track is not None else None
        camera, sensor = _load(args)
        reference = load_reference(args.reference, args.reference_camera) if args.reference else None
        common = dict(method=args.method, n_bootstrap=args.bootstrap, seed=args.seed, reference=reference,
                      progress=not args.quiet and sys.stderr.isatty())
        if args.poses:
            result = calibrate_poses(camera, sensor, **common)
        else:
            result = calibrate(camera, sensor, interval=args.interval, stride=args.stride,
                               max_offset=args.max_offset, correct_offset=not args.keep_clock, **common)
    except (ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    print(result.summary())
    if args.online:
        result, rows = _online(args, camera, sensor, reference, result)
        if track is not None:
            write_atomic(track, rows.to_csv(index=False))
            print(f"online track written to {track}")
    if out is not None:
        files = {"camera": _file_entry(args.camera), "sensor": _file_entry(args.sensor)}
        if args.reference:
            files["reference"] = {**_file_entry(args.reference), "camera_entry": args.reference_camera}
        report = {"command": ["python", "-m", "replication", *sys.argv[1:]] if sys.argv else [],
                  "cwd": os.getcwd(), "files": files,
                  "cli": {"sensor_kind": "poses" if args.poses else args.sensor_kind,
                          "time_units": {"camera": _unit(args, "camera"), "sensor": _unit(args, "sensor")},
                          "drop_repeated": args.drop_repeated, "accept": args.accept},
                  **result.to_dict()}
        write_atomic(out, json.dumps(report, indent=2, allow_nan=False) + "\n")  # never a half-written report
        print(f"report written to {out}")
    if plot is not None:
        result.plot(plot)
        print(f"figure written to {plot}")
    if result.verdict.level == "fail" and not args.accept:
        print(f"verdict FAIL: exit code {EXIT_FAIL} (--accept to exit 0)", file=sys.stderr)
        return EXIT_FAIL
    return 0
