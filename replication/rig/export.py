"""Put a calibration into the user's own VIO configuration: Kalibr, OpenVINS, Basalt, ORB-SLAM3, ROS
2. Theory and measured numbers: ``docs/reading.md``, section ``replication.rig.export``."""
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
from .datafile import DataFileError, fail, read_text
from .vioformats import VioFile, format_number, read_vio_file

__all__ = ["TARGETS", "NEEDS_BASE", "Export", "ExportWarning", "TranslationNotEstimatedWarning", "export_calibration",
           "read_report"]

#: What ``--to`` accepts.
TARGETS = ("kalibr", "openvins", "basalt", "orbslam3", "ros2")


class ExportWarning(ReplicationWarning):
    """The exported values carry a doubt the report measured: a ``warning`` (or forced ``fail``)
    verdict, or a clock offset measured against a stream other than the IMU's gyro."""


class TranslationNotEstimatedWarning(ReplicationWarning):
    """A ROS 2 command: the translation written is zero, not an estimate (only the rotation and the
    clock offset are estimated here); put your measured translation in its ``--x --y --z``."""


@dataclass(frozen=True)
class Export:
    """An exported calibration: ``text`` (the file's content, or the ROS 2 command), the fields
    ``changed`` and ``added`` (a key the base file lacked), and ``notes`` (what was kept or not
    written, and why)."""

    text: str
    to: str
    camera: str
    changed: tuple
    notes: tuple
    added: tuple = ()

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
    """The sensor stream, on one line, its file by name only (a file name may hold anything: it is
    written into commands; a folder is the user's own business)."""
    sensor = (report.get("inputs") or {}).get("sensor") or {}
    sensor = sensor if isinstance(sensor, dict) else {}
    source = sensor.get("source") or ""
    name = Path(str(source).replace("\\", "/")).name if source else ""
    return " ".join(f"{sensor.get('kind', 'a sensor stream')} {name}".split())


_NOT_ESTIMATED = ("translation NOT estimated (zeros written): only the rotation and the clock offset come from "
                  "this calibration; put your measured translation in --x --y --z")

#: What each tool's loader requires that a calibration of R0 does not give: a file is written only
#: into a base that has them (the sources: docs/conventions.md, "Other tools' files").
NEEDS_BASE = {
    "kalibr": ("Kalibr", "camera_model, intrinsics, distortion_model, distortion_coeffs, resolution and rostopic for "
                         "each camera (ConfigReader.py)"),
    "openvins": ("OpenVINS", "distortion_model, distortion_coeffs, intrinsics and resolution for each camera "
                             "(VioManagerOptions.h)"),
    "basalt": ("Basalt", "value0.intrinsics, resolution, calib_accel_bias, calib_gyro_bias, imu_update_rate, "
                         "accel_noise_std, gyro_noise_std, accel_bias_std, gyro_bias_std and vignette (its calibration "
                         "serialisation)"),
    "orbslam3": ("ORB-SLAM3", "Camera.type, the camera's intrinsics and distortion (Camera1.fx ...), Camera.width, "
                              "Camera.height, Camera.fps, the IMU's noises and Frequency (IMU.NoiseGyro ...), "
                              "ORBextractor.* and Viewer.* (Settings.cc)"),
}
_ARTICLE = {"kalibr": "a Kalibr", "openvins": "an OpenVINS", "basalt": "a Basalt", "orbslam3": "an ORB-SLAM3",
            "euroc": "an EuRoC sensor.yaml"}


def _ros2(R0, report, parent_frame, child_frame) -> str:
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(R0.T).as_quat()  # the child's (camera's) pose in the parent (IMU) frame
    q = -q if q[3] < 0 else q
    args = " ".join(f"--{k} {format_number(v)}" for k, v in zip(("qx", "qy", "qz", "qw"), q))
    return (f"# replication {__version__}: camera pose in the IMU frame (R0 transposed), from {_source(report)}; "
            f"{_NOT_ESTIMATED}\nros2 run tf2_ros static_transform_publisher --x 0.0 --y 0.0 --z 0.0 {args} "
            f"--frame-id {shlex.quote(parent_frame)} --child-frame-id {shlex.quote(child_frame)}\n")


def export_calibration(report, to: str, *, base=None, camera: str = "cam0", parent_frame: str = "imu_link",
                       child_frame: str = "camera_optical_frame", force: bool = False,
                       whole_rig: bool = True) -> Export:
    """A calibration in another tool's format.

    Parameters
    ----------
    report : path, dict or CalibrationResult
        The calibration (``python -m replication calibrate ... --out REPORT.json``).
    to : {'kalibr', 'openvins', 'basalt', 'orbslam3', 'ros2'}
    base : path
        The user's own file of that tool (required but for ``ros2``: each tool's loader needs
        intrinsics and more that a calibration of ``R0`` does not give, :data:`NEEDS_BASE`): the
        output is a copy in which only the rotations and the clock offset are changed. Its format is
        recognised from its content and must be ``to``.
    camera : str
        ``cam0``, ``cam1``, ... (Basalt: the index into ``T_imu_cam``; ORB-SLAM3: ``cam0`` =
        ``T_b_c1``): the camera the report calibrated.
    parent_frame, child_frame : str
        ``ros2``: the frame names of the command (the IMU's, the camera's optical frame: REP-103).
    force : bool
        Export a report whose verdict is ``fail`` (with an :class:`ExportWarning`) instead of
        refusing it.
    whole_rig : bool
        The file's other cameras turn with ``camera`` (by the same correction of the IMU frame), so
        every camera-camera transform stays as the file has it; False changes ``camera`` only, with
        an :class:`ExportWarning` saying how far each camera-camera rotation moves.

    Returns
    -------
    Export
        Write it with :meth:`Export.write`.

    Raises
    ------
    ValueError
        A report that is not one, a ``fail`` verdict without ``force``, no ``base`` (naming what the
        tool's loader needs from it), a base file of another format, a camera the base file lacks
        (:class:`~replication.rig.datafile.DataFileError` for file problems, naming the file).
    """
    if to not in TARGETS:
        raise ValueError(f"to must be one of {', '.join(TARGETS)}, got {to!r}")
    report = read_report(report)
    R0 = np.asarray(report["R0_camera_from_sensor"], dtype=float)
    level = report["verdict"]["level"]
    if level == "fail" and not force:
        raise ValueError(f"the report's verdict is fail ({_reasons(report)}): not exported; force=True (--force) "
                         "writes it anyway")
    if to not in ("ros2",) and base is None:
        tool, fields = NEEDS_BASE[to]
        raise ValueError(f"--to {to} needs --base: {tool} loads no file without {fields}, which this calibration does "
                         f"not estimate; give your own {tool} file as --base (only the rotation and the clock offset "
                         "are changed in it), or --to ros2 for the rotation alone")
    if level != "ok":
        warnings.warn(f"the report's verdict is {level}: {_reasons(report)}", ExportWarning, stacklevel=2)
    d, notes = report.get("time_offset_s"), []
    kind = (((report.get("inputs") or {}).get("sensor") or {}) or {}).get("kind")
    if kind == "static poses":  # no clock: a number there (reports before schema 1.x wrote 0.0) was not measured
        if d is not None:
            notes.append(f"the report's time_offset_s ({format_number(d)} s) comes from static poses, which have no "
                         "clock: it is not a measurement and is not exported")
        d = None
    if d is not None and kind not in (None, "GyroStream"):
        warnings.warn(f"the clock offset was measured against {_source(report)}, not the IMU's gyro: it is the "
                      "IMU's only if that stream is stamped by the IMU's clock", ExportWarning, stacklevel=2)
    if to == "ros2":
        if base is not None:
            raise ValueError("ros2 prints a command: there is no base file to edit")
        warnings.warn(f"ros2: {_NOT_ESTIMATED}", TranslationNotEstimatedWarning, stacklevel=2)
        return Export(_ros2(R0, report, parent_frame, child_frame), to, camera, ("rotation (qx qy qz qw)",),
                      tuple(notes) + ("a static transform carries no clock offset: " + (
                          "none was estimated" if d is None else
                          f"d = {format_number(round(d, 9))} s (t_imu = t_cam + d): add it to the camera messages' "
                          "time stamps"),))
    file = read_vio_file(base)
    if file.format != to:
        fail(file.path, f"is {_ARTICLE[file.format]} file, not {_ARTICLE[to].split()[1]}: give "
                        f"{_ARTICLE[to]} file as --base, or --to {file.format}")
    notes.append(f"kept from {file.path.name}: everything but the fields changed")
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
        warnings.warn(f"{file.path.name}: {file.unread}", ExportWarning, stacklevel=2)
    try:
        text, changed, added = file.with_values(camera, R0, d, whole_rig=whole_rig)
    except DataFileError as err:
        if not whole_rig:
            raise
        file.with_values(camera, R0, d, whole_rig=False)  # the camera's own problem: raised as it is
        others = [c for c in file.cameras() if c != camera]
        raise DataFileError(err.path, f"{err.message} (the rig's other cameras, {', '.join(others)}, turn with "
                                      f"{camera}; --one-camera edits {camera} only)", err.line, err.column) from None
    kept = [c for c in file.cameras() if c != camera and file.time_offset_s(c) is not None] if to == "kalibr" else []
    if whole_rig and added and kept:
        notes.append(f"{camera} had no timeshift_cam_imu (added): {', '.join(kept)}'s offsets are left as they were, "
                     "having no old value of it to move them by")
    written = text[1:] if file.bom else text
    notes += _rig_notes(file, VioFile(file.path, written.replace(file.newline, "\n")), camera, whole_rig)
    return Export(text, to, camera, tuple(changed), tuple(notes), tuple(added))


def _rig_notes(before, after, camera, whole_rig) -> list:
    """What happened to the file's other cameras, checked on the text written: with the whole rig,
    every camera-camera rotation and translation is as it was (else an error: the export is not
    written); with one camera only, an :class:`ExportWarning` says how far each camera-camera
    rotation moved."""
    from ..core.so3 import angle_between_deg

    others = [c for c in before.cameras() if c != camera]
    if not others:
        return []
    turn = angle_between_deg(before.camera_from_sensor(camera), after.camera_from_sensor(camera))
    if not whole_rig:
        kept = " with their T_cn_cnm1" if any(isinstance(before.doc.get(c), dict) and "T_cn_cnm1" in before.doc[c]
                                               for c in others) else ""
        warnings.warn(f"one camera only: {camera} is changed and {', '.join(others)} kept as written{kept}, so the "
                      f"rotation between {camera} and each of them moves by {turn:.4g} deg (the file's stereo "
                      "calibration no longer holds); leave out --one-camera to keep the rig whole",
                      ExportWarning, stacklevel=3)
        return []
    moved = []
    for cam in others:
        pair = [(f.camera_from_sensor(cam) @ f.camera_from_sensor(camera).T,
                 f.camera_from_sensor(camera) @ (f.camera_position(cam) - f.camera_position(camera)))
                for f in (before, after)]
        if angle_between_deg(pair[0][0], pair[1][0]) > 1e-9 or np.abs(pair[0][1] - pair[1][1]).max() > 1e-12:
            raise RuntimeError(f"the export would change the {camera}-{cam} transform: not written (a bug; please "
                               "report it with the files)")
        shift = 1e3 * np.linalg.norm(after.camera_position(cam) - before.camera_position(cam))
        moved.append(f"{cam}" + (f" (its position in the IMU frame moved {shift:.3g} mm with it)" if shift else ""))
    return [f"the rig kept whole: {', '.join(moved)} turned with {camera} by the same {turn:.4g} deg, so every "
            "camera-camera transform is as the file had it (--one-camera changes only the camera named)"]
