"""``python -m replication calibrate``: the command line of
:func:`replication.rig.calibration.calibrate`. Theory and measured numbers: ``docs/reading.md``,
section ``replication.cli.calibrate``."""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
from pathlib import Path

from .._extras import MissingExtra, require
from .._io import os_reason, prepare_output, write_atomic
from ..rig.quality import DEFAULT_METHOD, EXIT_FAIL
from .calibrate_inputs import check_paths, load_all, split_references, time_unit

__all__ = ["CALIBRATE_HELP", "CALIBRATE_EXAMPLES", "add_parser", "run", "EXIT_BAD_INPUT"]

#: Exit code for bad input (argparse's own, too).
EXIT_BAD_INPUT = 2

CALIBRATE_HELP = """\
Estimate R0 = camera_from_sensor (A_j R0 = R0 B_j) from two timestamped streams, or from two static pose sets
(--poses), and judge the answer: the verdict (ok / warning / fail, every reason with its measured number and
threshold) is printed first and stored in the report; a fail exits with code 3 unless --accept.

Formats (recognised by --sensor-kind and the file name):
  camera / orientation sensor:
    *.txt  TUM / ORB-SLAM3 trajectory, lines "t tx ty tz qx qy qz qw" (t in s or ns: --time-unit), world<-body
    *.csv  EuRoC / TUM-VI mocap or ground truth, "t[ns], px, py, pz, qw, qx, qy, qz", world<-body, as
           shipped: EuRoC's 17-column state_groundtruth_estimate0/data.csv too (the first 8 used)
  a time stamp repeated with another pose is refused unless --repeated keep-first|keep-last|mean
  gyro sensor (--sensor-kind gyro):
    *.csv  EuRoC / TUM-VI imu0/data.csv, "t[ns], wx, wy, wz [rad/s], ax, ay, az [m/s^2]"
  a CSV whose stamps are not ns (e.g. seconds "1520530308.181901469"): --camera-time-unit / --sensor-time-unit
  static pose sets (--poses): Tabb & Ahmad Yousef's cali.txt (camera) and robot_cali.txt (robot hand)
  reference (optional; recognised by content, --reference-camera picks the camera):
    Kalibr camchain YAML (<cam>.T_cam_imu), OpenVINS %YAML:1.0 chain (<cam>.T_imu_cam), ORB-SLAM3 settings
    (IMU.T_b_c1), Basalt calib JSON (value0.T_imu_cam), EuRoC sensor.yaml (T_BS), Tabb transformations.txt (Z)
Export the report into your own Kalibr / OpenVINS / Basalt / ORB-SLAM3 file or a ROS 2 command:
  python -m replication export report.json --to kalibr --base camchain.yaml --out camchain-new.yaml
The clock offset is estimated by cross-correlating angular speeds and removed unless --keep-clock; the report
states its sign: the sensor sample stamped t + offset matches the camera sample stamped t.
Outputs: --out, --plot (.png, .pdf or .svg, by its extension) and --track may not be an input file or one another
(after resolving links); an input may be a pipe (read once: --camera <(...)). Refused before any work, exit 2.
Exit codes: 0 ok or warning, 2 bad input or a file-system error (the path and the reason named), 3 verdict fail
(0 with --accept).

Solvers (--method, replication.core.solvers.available()):
{solvers}
"""

#: The epilog of ``calibrate --help``.
CALIBRATE_EXAMPLES = """Examples:
  # an ORB-SLAM3 camera trajectory and a raw EuRoC / TUM-VI gyro, report and figure
  python -m replication calibrate --camera f_cam.txt --sensor imu0/data.csv --sensor-kind gyro \\
      --out report.json --plot report.png
  # two orientation streams (mocap), a reference R0 from a Kalibr camchain
  python -m replication calibrate --camera mocap_cam.csv --sensor mocap_imu.csv --reference camchain.yaml
  # Tabb's static pose sets
  python -m replication calibrate --poses --camera cali.txt --sensor robot_cali.txt --reference transformations.txt
"""

class _HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """``calibrate --help``: the description and epilog as written, the registered solvers listed in
    place of ``{solvers}`` (looked up when the help is shown, so other commands do not import the
    solvers), and each option's default after its help (an option whose default is None says in its
    help what happens without it; a flag is off by default)."""

    def _fill_text(self, text, width, indent):
        if "{solvers}" in text:
            import textwrap

            from ..core.solvers import available

            names = [f"{n} (default)" if n == DEFAULT_METHOD else n for n in available()]
            text = text.replace("{solvers}", textwrap.fill(", ".join(names), width, initial_indent="  ",
                                                           subsequent_indent="  "))
        return super()._fill_text(text, width, indent)

    def _get_help_string(self, action):
        text = action.help or ""
        if not action.option_strings or action.default in (None, argparse.SUPPRESS) or "default" in text:
            return text
        if action.default is False and action.nargs == 0:
            return f"{text} (default: off)"
        return f"{text} (default: %(default)s)"


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
    """The ``calibrate`` sub-command: every option of ``calibrate`` is declared here, in one
    place."""
    cal = sub.add_parser("calibrate", help="calibrate a real rig and judge the answer", description=CALIBRATE_HELP,
                         epilog=CALIBRATE_EXAMPLES, formatter_class=_HelpFormatter)
    cal.add_argument("--camera", required=True, help="camera trajectory (world<-camera), or camera poses (--poses)")
    cal.add_argument("--sensor", required=True, help="sensor trajectory, raw gyro samples, or robot poses (--poses)")
    cal.add_argument("--sensor-kind", choices=["orientation", "gyro"], default="orientation",
                     help="what --sensor holds: orientations (a trajectory, mocap) or raw gyro samples (imu0/data.csv)")
    cal.add_argument("--poses", action="store_true", help="both files are static pose sets (Tabb format)")
    cal.add_argument("--method", default=DEFAULT_METHOD, help="the solver (the list above)")
    cal.add_argument("--interval", type=_number(float, minimum=0), default=1.0,
                     help="seconds between the two poses of a pair")
    cal.add_argument("--stride", type=_number(int, minimum=1, strict=False), default=1,
                     help="keep every stride-th pair (non-overlapping pairs: interval x camera rate)")
    cal.add_argument("--max-offset", type=_number(float, minimum=0), default=0.2,
                     help="largest clock offset searched (s)")
    cal.add_argument("--keep-clock", action="store_true", help="report the clock offset but do not remove it")
    cal.add_argument("--no-gyro-bias", action="store_true",
                     help="a gyro sensor: do not estimate and remove its bias (with R0; with --online, on the "
                          "live rig's first window too); the rates as recorded")
    cal.add_argument("--use", choices=("all", "consistent"), default="all",
                     help="fit R0 on every pair, or on the segments of the recording that agree with each other only "
                          "(a stretch of lost tracking left out; the seconds used are reported)")
    cal.add_argument("--bootstrap", type=_number(int, minimum=0, strict=False), default=200,
                     help="bootstrap replicates (0: none)")
    cal.add_argument("--seed", type=_number(int, minimum=0, strict=False), default=0, help="seed of the bootstrap")
    units = ["auto", "s", "ms", "us", "ns"]
    cal.add_argument("--time-unit", choices=units, default=None,
                     help="time unit of both files when they are TUM trajectories (default: auto: ns above 1e12, "
                          "else s; EuRoC / TUM-VI CSVs are ns)")
    cal.add_argument("--camera-time-unit", choices=units, default=None,
                     help="time unit of the camera file only, a TUM trajectory or a CSV (default: that of "
                          "--time-unit; a CSV's: ns)")
    cal.add_argument("--sensor-time-unit", choices=units, default=None,
                     help="time unit of the sensor file only, a TUM trajectory or a CSV (default: that of "
                          "--time-unit; a CSV's: ns, e.g. s for an IMU CSV whose stamps are seconds)")
    cal.add_argument("--drop-repeated", action="store_true",
                     help="skip lines of a trajectory or CSV that repeat the previous line verbatim")
    cal.add_argument("--repeated", choices=["refuse", "keep-first", "keep-last", "mean"], default="refuse",
                     help="a time stamp repeated with a different pose (or rates): refuse the file, or keep the "
                          "first, the last or the mean of each group (the report counts them)")
    cal.add_argument("--reference", action="append", help="a reference R0 to compare with: a Kalibr camchain, an "
                     "OpenVINS or ORB-SLAM3 %%YAML:1.0 file, Basalt's calib JSON, an EuRoC sensor.yaml or Tabb's "
                     "transformations.txt (recognised by content; default: none). Given twice (two published "
                     "calibrations): the error to each, their disagreement (the reference floor) and which reading "
                     "applies (an error below the floor is agreement, not accuracy)")
    cal.add_argument("--reference-camera", default="cam0",
                     help="camera entry of the reference file (cam0, cam1, ...; Basalt: its index)")
    cal.add_argument("--out", help="write the JSON report here (folders are created; default: no report)")
    cal.add_argument("--plot", help="write the diagnostic figure here: .png, .pdf or .svg by its extension "
                                    "(folders are created; default: no figure)")
    cal.add_argument("--accept", action="store_true", help="exit 0 even when the verdict is fail")
    cal.add_argument("--online", action="store_true",
                     help="also replay the streams through the online estimator (replication.rig.online), as if live")
    cal.add_argument("--track", help="with --online: write its estimate, 95 %% radius, ready and alarms per pair (CSV; "
                          "default: not written)")
    cal.add_argument("--target", type=_number(float, minimum=0), default=0.5,
                     help="with --online: ready once the 95 %% radius is below this (deg)")
    cal.add_argument("--quiet", action="store_true", help="no progress bar")
    cal.set_defaults(func=run)
    return cal


def _online(args, camera, sensor, reference, result):
    """Replay the streams through the online estimator with the batch options (interval, stride,
    clock offset search and whether to apply it); print what it found; return the result with the
    online summary and track."""

    from ..rig.live import replay
    from ..rig.online import OnlineCalibrator

    rows = replay(camera, sensor, OnlineCalibrator(target_deg=args.target), interval=args.interval,
                  max_offset=args.max_offset, correct_offset=not args.keep_clock, stride=args.stride,
                  reference=reference, gyro_bias=not args.no_gyro_bias)
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
        f"{ev['kind']} at {ev['t_s']:.1f} s" + (f" ({ev['rate_deg_s']:.2g} deg/s)" if ev.get("rate_deg_s") else "")
        for ev in summary["events"])))
    print(f"  the online radius covers {summary['radius_covers']}")
    diagnostics = {**result.diagnostics, "online_track": rows}
    return dataclasses.replace(result, online=summary, diagnostics=diagnostics), rows


def _error(text) -> int:
    print(f"error: {text}", file=sys.stderr)
    return EXIT_BAD_INPUT


def _write(path, data, what: str) -> bool:
    """Write an output atomically; False (the path and the reason said on standard error) if the
    file system refuses."""
    try:
        write_atomic(path, data)
    except OSError as err:
        _error(f"{what} {path}: cannot write ({os_reason(err)}); nothing was written there")
        return False
    return True


def run(args: argparse.Namespace) -> int:
    from ..core.solvers import solver_info
    from ..rig.calibration import OverlapError, calibrate
    from ..rig.poses import calibrate_poses
    from ..rig.solve_and_judge import first_reference

    try:
        solver_info(args.method)
        if args.track is not None and not args.online:
            raise ValueError("--track needs --online")
        if args.online and args.poses:
            raise ValueError("--online needs streams, not static pose sets (--poses)")
        if args.online:
            require("pandas", "calibrate --online")
        split_references(args)
        kinds = check_paths(args)
        out = prepare_output(args.out, "--out") if args.out is not None else None
        plot = prepare_output(args.plot, "--plot") if args.plot is not None else None
        track = prepare_output(args.track, "--track") if args.track is not None else None
        camera, sensor, reference, files = load_all(args, kinds)
        common = dict(method=args.method, n_bootstrap=args.bootstrap, seed=args.seed, reference=reference,
                      progress=not args.quiet and sys.stderr.isatty())
        if args.poses:
            result = calibrate_poses(camera, sensor, **common)
        else:
            result = calibrate(camera, sensor, interval=args.interval, stride=args.stride,
                               max_offset=args.max_offset, correct_offset=not args.keep_clock, use=args.use,
                               gyro_bias=not args.no_gyro_bias, **common)
    except OverlapError as err:
        return _error(err.named("--max-offset"))
    except (ValueError, OSError, MissingExtra) as err:
        return _error(err)
    print(result.summary())
    if args.online:
        result, rows = _online(args, camera, sensor, first_reference(reference), result)
        if track is not None:
            if not _write(track, rows.to_csv(index=False), "--track"):
                return EXIT_BAD_INPUT
            print(f"online track written to {track}")
    if out is not None:
        for key in ("reference", "reference2"):
            if getattr(args, key):
                files[key] = {**files[key], "camera_entry": args.reference_camera}
        report = {"command": ["python", "-m", "replication", *sys.argv[1:]] if sys.argv else [],
                  "cwd": os.getcwd(), "files": files,
                  "cli": {"sensor_kind": "poses" if args.poses else args.sensor_kind,
                          "time_units": {"camera": time_unit(args, "camera"), "sensor": time_unit(args, "sensor")},
                          "drop_repeated": args.drop_repeated, "repeated": args.repeated,
                          "repeats": getattr(args, "repeats", None), "accept": args.accept},
                  **result.to_dict()}
        if not _write(out, json.dumps(report, indent=2, allow_nan=False) + "\n", "--out"):  # never half-written
            return EXIT_BAD_INPUT
        print(f"report written to {out}")
    if plot is not None:
        try:
            result.plot(plot, name=f"{Path(args.camera).stem} + {Path(args.sensor).stem}",  # the recording
                        reference_name=" and ".join(Path(r).name for r in (args.reference, args.reference2) if r)
                        or None)
        except OSError as err:
            return _error(f"--plot {plot}: cannot write ({os_reason(err)}); nothing was written there")
        print(f"figure written to {plot}")
    if result.verdict.level == "fail" and not args.accept:
        print(f"verdict FAIL: exit code {EXIT_FAIL} (--accept to exit 0)", file=sys.stderr)
        return EXIT_FAIL
    return 0
