"""Put a calibration into the user's own VIO configuration: Kalibr, OpenVINS, Basalt, ORB-SLAM3, ROS 2.

``python -m replication export REPORT.json --to kalibr|openvins|basalt|orbslam3|ros2 [--base FILE] --out FILE``
(:func:`export_calibration` from Python). With ``--base``, the output is a copy of the user's file in which only the
camera's rotation and the clock offset (in that tool's field and sign) are changed; translation, intrinsics, other
cameras, comments and every other field are kept as written (:mod:`replication.rig.vioformats`). Without it, a minimal
file: its translation is zero and marked as not estimated (a comment, and :class:`TranslationNotEstimatedWarning`).
``ros2`` gives a ``static_transform_publisher`` command (REP-103; quaternion x y z w). Each tool's convention, and
where in its source or documentation it is stated: ``docs/conventions.md`` ("Other tools' files").

The report says how far it can be trusted, and the export keeps saying it: a ``fail`` verdict is refused unless
forced, a ``warning`` verdict is carried over as :class:`ExportWarning`, and so is a clock offset that was measured
against an orientation stream rather than the IMU's gyro.
"""
from __future__ import annotations

import json
import math
import shlex
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._version import __version__
from ..core.checks import check_rotation_matrices
from ..core.solvers import ReplicationWarning
from .datafile import fail, read_text
from .vioformats import VioFile, format_number, read_vio_file

__all__ = ["TARGETS", "Export", "ExportWarning", "TranslationNotEstimatedWarning", "export_calibration",
           "read_report"]

#: What ``--to`` accepts.
TARGETS = ("kalibr", "openvins", "basalt", "orbslam3", "ros2")


class ExportWarning(ReplicationWarning):
    """The exported values carry a doubt the report measured: a ``warning`` (or forced ``fail``) verdict, or a
    clock offset measured against a stream other than the IMU's gyro."""


class TranslationNotEstimatedWarning(ReplicationWarning):
    """A minimal file or a ROS 2 command: the translation written is zero, not an estimate (only the rotation and
    the clock offset are estimated here); measure it, or export into your own file with ``base``."""


@dataclass(frozen=True)
class Export:
    """An exported calibration: ``text`` (the file's content, or the ROS 2 command), the fields ``changed``, and
    ``notes`` (what was kept or not written, and why)."""

    text: str
    to: str
    camera: str
    changed: tuple
    notes: tuple

    def write(self, path) -> None:
        """Write ``text`` to ``path`` atomically (never half-written)."""
        from .._io import write_atomic

        write_atomic(path, self.text)


def read_report(report) -> dict:
    """A calibration report as a dict: a path to its JSON, the dict itself, or a
    :class:`~replication.rig.report.CalibrationResult`; its rotation, offset and verdict checked."""
    path = None
    if hasattr(report, "to_dict"):
        report = report.to_dict()
    elif isinstance(report, (str, Path)):
        path = Path(report)
        try:
            report = json.loads(read_text(path, "a calibration report"))
        except json.JSONDecodeError as err:
            fail(path, f"not valid JSON: {err.msg}", line=err.lineno, column=err.colno)
    where = f"{path}: " if path is not None else "report: "
    if not isinstance(report, dict) or "R0_camera_from_sensor" not in report:
        raise ValueError(f"{where}not a calibration report (no R0_camera_from_sensor; write one with "
                         "'python -m replication calibrate ... --out REPORT.json')")
    try:
        check_rotation_matrices(np.asarray(report["R0_camera_from_sensor"], dtype=float), "R0_camera_from_sensor")
    except (TypeError, ValueError) as err:
        raise ValueError(f"{where}{err}") from None
    d = report.get("time_offset_s")
    if d is not None and (isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d)):
        raise ValueError(f"{where}time_offset_s must be a number of seconds or null, got {d!r}")
    parameters = report.get("parameters") if isinstance(report.get("parameters"), dict) else {}
    bound = parameters.get("max_offset_s", 1.0)
    if d is not None and isinstance(bound, (int, float)) and abs(d) > bound:
        raise ValueError(f"{where}time_offset_s = {d!r} s is beyond the offsets calibrate searched (+-{bound} s): "
                         "milliseconds written as seconds?")
    verdict = report.get("verdict")
    level = verdict.get("level") if isinstance(verdict, dict) else None
    if level not in ("ok", "warning", "fail"):
        raise ValueError(f"{where}verdict must be an object whose level is ok, warning or fail, got {verdict!r}")
    reasons = verdict.get("reasons", [])
    if not isinstance(reasons, list) or not all(isinstance(r, dict) for r in reasons):
        raise ValueError(f"{where}verdict.reasons must be a list of objects (level, message), got {reasons!r}")
    for key in ("inputs", "parameters"):
        if key in report and report[key] is not None and not isinstance(report[key], dict):
            raise ValueError(f"{where}{key} must be an object, got {report[key]!r}")
    return report


def _reasons(report) -> str:
    reasons = report["verdict"].get("reasons") or []
    return "; ".join(f"{r.get('level')}: {r.get('message')}" for r in reasons) or "no reason recorded"


def _source(report) -> str:
    """The sensor stream, on one line (a file name may hold anything: it is written into files and commands)."""
    sensor = (report.get("inputs") or {}).get("sensor") or {}
    sensor = sensor if isinstance(sensor, dict) else {}
    return " ".join(f"{sensor.get('kind', 'a sensor stream')} {sensor.get('source', '')}".split())


# The minimal files: an identity rotation, zero translation and offset, into which the values are then written by
# the same code that edits a user's file.
_NOT_ESTIMATED = ("translation NOT estimated (zeros written): only the rotation and the clock offset come from "
                  "this calibration; measure the translation or export into your own file with --base")


def _minimal(to: str, camera: str, report: dict) -> str:
    head = (f"replication {__version__} export of R0 (camera_from_sensor) estimated from {_source(report)}; "
            f"{_NOT_ESTIMATED}")
    rows = ["[1.0, 0.0, 0.0, 0.0]", "[0.0, 1.0, 0.0, 0.0]", "[0.0, 0.0, 1.0, 0.0]", "[0.0, 0.0, 0.0, 1.0]"]
    if to in ("kalibr", "openvins"):
        key = "T_cam_imu" if to == "kalibr" else "T_imu_cam"
        lines = (["%YAML:1.0"] if to == "openvins" else []) + [f"# {head}", f"{camera}:",
                                                                 "  timeshift_cam_imu: 0.0", f"  {key}:"]
        return "\n".join(lines + [f"    - {r}" for r in rows]) + "\n"
    if to == "orbslam3":
        data = ", ".join(r.strip("[]") for r in rows)
        return (f"%YAML:1.0\n# {head}\nFile.version: \"1.0\"\nIMU.T_b_c1: !!opencv-matrix\n   rows: 4\n   cols: 4\n"
                f"   dt: f\n   data: [{data}]\n")
    if camera != "cam0":
        raise ValueError(f"a minimal Basalt file holds cam0 only; give --base with your calibration for {camera}")
    pose = ", ".join(f'"{k}": {v}' for k, v in zip(("px", "py", "pz", "qx", "qy", "qz", "qw"), [0.0] * 6 + [1.0]))
    return f'{{\n    "value0": {{\n        "T_imu_cam": [{{{pose}}}],\n        "cam_time_offset_ns": 0\n    }}\n}}\n'


def _ros2(R0, report, parent_frame, child_frame) -> str:
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(R0.T).as_quat()  # the child's (camera's) pose in the parent (IMU) frame
    q = -q if q[3] < 0 else q
    args = " ".join(f"--{k} {format_number(v)}" for k, v in zip(("qx", "qy", "qz", "qw"), q))
    return (f"# replication {__version__}: camera pose in the IMU frame (R0 transposed), from {_source(report)}; "
            f"{_NOT_ESTIMATED}\nros2 run tf2_ros static_transform_publisher --x 0.0 --y 0.0 --z 0.0 {args} "
            f"--frame-id {shlex.quote(parent_frame)} --child-frame-id {shlex.quote(child_frame)}\n")


def export_calibration(report, to: str, *, base=None, camera: str = "cam0", parent_frame: str = "imu_link",
                       child_frame: str = "camera_optical_frame", force: bool = False) -> Export:
    """A calibration in another tool's format.

    Parameters
    ----------
    report : path, dict or CalibrationResult
        The calibration (``python -m replication calibrate ... --out REPORT.json``).
    to : {'kalibr', 'openvins', 'basalt', 'orbslam3', 'ros2'}
    base : path, optional
        The user's own file of that tool: the output is a copy with only ``camera``'s rotation and the clock offset
        changed. Its format is recognised from its content and must be ``to``.
    camera : str
        ``cam0``, ``cam1``, ... (Basalt: the index into ``T_imu_cam``; ORB-SLAM3: ``cam0`` = ``T_b_c1``).
    parent_frame, child_frame : str
        ``ros2``: the frame names of the command (the IMU's, the camera's optical frame: REP-103).
    force : bool
        Export a report whose verdict is ``fail`` (with an :class:`ExportWarning`) instead of refusing it.

    Returns
    -------
    Export
        Write it with :meth:`Export.write`.

    Raises
    ------
    ValueError
        A report that is not one, a ``fail`` verdict without ``force``, a base file of another format, a camera the
        base file lacks (:class:`~replication.rig.datafile.DataFileError` for file problems, naming the file).
    """
    if to not in TARGETS:
        raise ValueError(f"to must be one of {', '.join(TARGETS)}, got {to!r}")
    report = read_report(report)
    R0 = np.asarray(report["R0_camera_from_sensor"], dtype=float)
    level = report["verdict"]["level"]
    if level == "fail" and not force:
        raise ValueError(f"the report's verdict is fail ({_reasons(report)}): not exported; force=True (--force) "
                         "writes it anyway")
    if level != "ok":
        warnings.warn(f"the report's verdict is {level}: {_reasons(report)}", ExportWarning, stacklevel=2)
    d = report.get("time_offset_s")
    notes = []
    kind = (((report.get("inputs") or {}).get("sensor") or {}) or {}).get("kind")
    if d is not None and kind not in (None, "GyroStream"):
        warnings.warn(f"the clock offset was measured against {_source(report)}, not the IMU's gyro: it is the "
                      "IMU's only if that stream is stamped by the IMU's clock", ExportWarning, stacklevel=2)
    if to == "ros2":
        if base is not None:
            raise ValueError("ros2 prints a command: there is no base file to edit")
        warnings.warn(f"ros2: {_NOT_ESTIMATED}", TranslationNotEstimatedWarning, stacklevel=2)
        return Export(_ros2(R0, report, parent_frame, child_frame), to, camera, ("rotation (qx qy qz qw)",),
                      ("a static transform carries no clock offset: " + (
                          "none was estimated" if d is None else
                          f"d = {format_number(round(d, 9))} s (t_imu = t_cam + d): add it to the camera messages' "
                          "time stamps"),))
    if base is None:
        file = VioFile(f"<minimal {to} file>", _minimal(to, camera, report))
        warnings.warn(f"{to}: {_NOT_ESTIMATED}", TranslationNotEstimatedWarning, stacklevel=2)
    else:
        file = read_vio_file(base)
        if file.format != to:
            fail(file.path, f"is a {file.format} file, not {to}: give a {to} file as --base or --to {file.format}")
        notes.append(f"kept from {file.path}: everything but the fields changed")
    if d is None:
        notes.append("no clock offset was estimated (static poses): the file's offset is left as it was")
    elif to == "orbslam3":
        notes.append(f"ORB-SLAM3 has no camera-IMU time offset: add d = {format_number(round(d, 9))} s to the image "
                     "time stamps before running it (t_imu = t_cam + d)")
    elif to == "basalt":
        notes.append("Basalt's VIO does not apply cam_time_offset_ns (only its calibration does): for the VIO, add d = "
                     f"{format_number(round(d, 9))} s to the image time stamps")
    elif to == "openvins" and camera != "cam0":
        notes.append(f"OpenVINS reads one time offset, cam0's, for every camera: the offset measured with {camera} "
                     "was written there")
    if file.unread:
        warnings.warn(f"{file.path}: {file.unread}", ExportWarning, stacklevel=2)
    text, changed = file.with_values(camera, R0, d)
    return Export(text, to, camera, tuple(changed), tuple(notes))


EXPORT_HELP = """Write a calibration report's R0 and clock offset into another tool's configuration.

With --base, a copy of your own file in which only the camera's rotation and the clock offset are changed (the
translation, intrinsics, other cameras and comments are kept); without it, a minimal file whose translation is
zero and marked as not estimated. The conventions of each tool, with their sources: docs/conventions.md.

examples:
  python -m replication export report.json --to kalibr --base camchain-imucam.yaml --out camchain-new.yaml
  python -m replication export report.json --to basalt --base calib.json --camera cam1 --out calib-new.json
  python -m replication export report.json --to ros2
"""


def add_parser(sub):
    """The ``export`` sub-command."""
    import argparse

    exp = sub.add_parser("export", help="write a report's R0 and clock offset into Kalibr / OpenVINS / Basalt / "
                         "ORB-SLAM3 files or a ROS 2 command", description=EXPORT_HELP,
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    exp.add_argument("report", help="the calibration report (calibrate --out REPORT.json)")
    exp.add_argument("--to", required=True, choices=TARGETS, help="the tool")
    exp.add_argument("--base", help="your own file of that tool, to copy with only the rotation and offset changed")
    exp.add_argument("--camera", default="cam0", help="the camera entry to change (default: cam0)")
    exp.add_argument("--out", help="the file to write (default: standard output)")
    exp.add_argument("--parent-frame", default="imu_link", help="ros2: the IMU's frame (default: imu_link)")
    exp.add_argument("--child-frame", default="camera_optical_frame",
                     help="ros2: the camera's optical frame (default: camera_optical_frame)")
    exp.add_argument("--force", action="store_true", help="export even when the report's verdict is fail")
    exp.set_defaults(func=export_command)
    return exp


def export_command(args) -> int:
    """Exit 0 (written), 2 (refused: the reason on standard error); warnings reach the terminal through the command
    line's one-line formatter (``replication.__main__``)."""
    import sys

    from .._io import check_clashes, check_input, os_reason, prepare_output, same_file

    try:
        inputs = {"REPORT": args.report, "--base": args.base}
        kinds = {k: check_input(v, k) for k, v in inputs.items() if v is not None}
        if len(kinds) == 2 and "pipe" in kinds.values() and same_file(args.report, args.base):
            raise ValueError(f"--base is the REPORT pipe ({args.base}): a pipe can be read once")
        check_clashes({"--out": args.out}, inputs)
        out = prepare_output(args.out, "--out") if args.out is not None else None
        result = export_calibration(args.report, args.to, base=args.base, camera=args.camera,
                                    parent_frame=args.parent_frame, child_frame=args.child_frame, force=args.force)
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
    print(f"{args.to}: changed {', '.join(result.changed)}" + (f" in {out}" if out else ""), file=sys.stderr)
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    return 0
