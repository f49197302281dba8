"""The inputs of ``python -m replication calibrate``: every path checked before any work
(:func:`check_paths`), each input read once (a pipe into a temporary copy, every file hashed) and
loaded (:func:`load_all`), a CSV of the other kind named as such, each file's time unit
(:func:`time_unit`)."""
from __future__ import annotations

import contextlib
import dataclasses
import os
import tempfile
from pathlib import Path

from .._io import check_clashes, check_input, figure_format, os_reason, same_file

__all__ = ["INPUTS", "OUTPUTS", "split_references", "check_paths", "load_all", "time_unit"]


#: The inputs and outputs of ``calibrate``: (option, attribute).
INPUTS = (("--camera", "camera"), ("--sensor", "sensor"), ("--reference", "reference"), ("--reference2", "reference2"))
#: How an input is named in messages (the second --reference has no option of its own).
_SHOWN = {"--reference2": "--reference (the second)"}


def split_references(args) -> None:
    """``--reference`` given at most twice: ``args.reference`` the first (or None),
    ``args.reference2`` the second."""
    given = args.reference if isinstance(args.reference, list) else [args.reference] if args.reference else []
    if len(given) > 2:
        raise ValueError(f"--reference given {len(given)} times: at most two (two published calibrations)")
    args.reference, args.reference2 = (given + [None, None])[:2]
OUTPUTS = (("--out", "out"), ("--plot", "plot"), ("--track", "track"))


def check_paths(args) -> dict:
    """Every path before any work; ``{option: "file" | "pipe"}`` of the inputs given.

    Inputs exist and are regular files or pipes (a pipe is given once); no output is an input or
    another output; the figure's extension is a known format; each output's folder is created and
    writable.
    """
    inputs = {option: getattr(args, attr) for option, attr in INPUTS}
    kinds = {option: check_input(path, _SHOWN.get(option, option)) for option, path in inputs.items()
             if path is not None}
    pipes = [option for option, kind in kinds.items() if kind == "pipe"]
    for i, option in enumerate(pipes):
        for other in pipes[:i]:
            if same_file(inputs[option], inputs[other]):
                raise ValueError(f"{_SHOWN.get(option, option)} is the same pipe as {_SHOWN.get(other, other)} "
                                 f"({inputs[option]}): a pipe can be read once")
    check_clashes({option: getattr(args, attr) for option, attr in OUTPUTS}, inputs)
    if args.plot is not None:
        try:
            figure_format(args.plot)
        except ValueError as err:
            raise ValueError(f"--plot {err}") from None
    return kinds


@contextlib.contextmanager
def _read_inputs(args, kinds: dict):
    """Read every input once: ``(paths to load from, report entries, {copy: shown name})``.

    A regular file is loaded from its path and hashed now; a pipe is read whole into a temporary
    copy (its name's extension kept: the loaders recognise formats by it) that the loaders read, and
    its entry records the pipe, the bytes and the SHA-256 of what was read, no path to read again.
    """
    from ..rig.fetch import sha256_of

    paths, files, copies = {}, {}, {}
    with tempfile.TemporaryDirectory(prefix="replication-inputs-") as tmp:
        for option, kind in kinds.items():
            given = getattr(args, option[2:])
            try:
                if kind == "pipe":
                    with open(given, "rb") as f:
                        data = f.read()
                    entry = {"bytes": len(data), "sha256": sha256_of(data)}
                else:  # hashed in blocks, not held in memory
                    entry = {"bytes": os.path.getsize(given), "sha256": sha256_of(given)}
            except OSError as err:
                raise ValueError(f"{_SHOWN.get(option, option)} {given}: cannot be read ({os_reason(err)})") from None
            if kind == "pipe":
                copy = Path(tmp) / (option[2:] + Path(given).suffix)
                copy.write_bytes(data)
                paths[option], copies[str(copy)] = copy, f"{given} (a pipe, read once)"
                files[option[2:]] = {"pipe": True, "given": str(given), **entry}
            else:
                paths[option] = given
                files[option[2:]] = {"path": str(Path(given).resolve()), **entry}
        yield paths, files, copies


def _named(stream, copies: dict, given):
    """``stream`` with its source the name given on the command line where it was loaded from a
    pipe's copy."""
    if str(stream.source) in copies:
        return dataclasses.replace(stream, source=str(given))
    return stream


def _load(args, paths):
    from ..rig import realdata

    if args.poses:
        return realdata.load_tabb_camera_poses(paths["--camera"]), realdata.load_tabb_poses(paths["--sensor"])
    args.repeats = {"camera": {}, "sensor": {}}  # the loaders' tallies, for the report
    camera = _stream(paths["--camera"], "--camera", "orientation", time_unit=time_unit(args, "camera"),
                     drop_repeated=args.drop_repeated, repeated=args.repeated, tally=args.repeats["camera"])
    sensor = _stream(paths["--sensor"], "--sensor", args.sensor_kind, time_unit=time_unit(args, "sensor"),
                     drop_repeated=args.drop_repeated, repeated=args.repeated, tally=args.repeats["sensor"])
    for side, tally in args.repeats.items():
        if tally.get("repeated_timestamps"):
            worst = tally["repeated_max_deg"]
            print(f"--{side}: {tally['repeated_timestamps']} lines repeat an earlier line's time stamp "
                  f"({tally['repeated_groups']} time stamps" + (f", poses up to {worst:.3g} deg apart" if worst
                                                               is not None else "") + f"): --repeated {args.repeated}")
    return camera, sensor


def _stream(path, option: str, kind: str, **options):
    """:func:`~replication.rig.realdata.load_stream`; a CSV whose lines have the other kind's number
    of columns (7: an IMU stream read as orientations; 8: orientations read as a gyro) is said to
    look like that kind, naming the option to give."""
    from ..rig.datafile import ColumnCountError
    from ..rig.realdata import EUROC_IMU_COLUMNS, EUROC_POSE_COLUMNS, load_stream

    try:
        return load_stream(path, kind, **options)
    except ColumnCountError as err:
        csv = Path(path).suffix.lower() == ".csv"
        if kind == "orientation" and csv and err.found == len(EUROC_IMU_COLUMNS):
            looks = "a gyro / IMU stream (t, wx, wy, wz, ax, ay, az: EuRoC / TUM-VI imu0/data.csv)"
            hint = ("give --sensor-kind gyro" if option == "--sensor" else
                    "--camera takes the camera's orientations; a gyro goes to --sensor with --sensor-kind gyro")
        elif kind == "gyro" and err.found in (len(EUROC_POSE_COLUMNS), 17):
            looks = "an orientation stream (t, px, py, pz, qw, qx, qy, qz: EuRoC / TUM-VI mocap or ground truth)"
            hint = "leave out --sensor-kind gyro (orientation, the default, reads it)"
        else:
            raise
        raise ColumnCountError(err.path, f"{err.message}: the file looks like {looks}; {hint}", err.line,
                               expected=err.expected, found=err.found) from None


def time_unit(args, side: str) -> str:
    """The time unit for one file: its own option (a TUM trajectory or a CSV), else ``--time-unit``
    where it applies (TUM files), else auto."""
    own = getattr(args, f"{side}_time_unit")
    if own is not None:
        return own
    path = args.camera if side == "camera" else args.sensor
    csv = side == "sensor" and args.sensor_kind == "gyro" or str(path).lower().endswith(".csv")
    return "auto" if args.time_unit is None or csv else args.time_unit


def load_all(args, kinds):
    """Read the inputs once and load them: ``(camera, sensor, reference, report entries)``; errors
    about a pipe's copy name the pipe as given."""
    from ..rig.realdata import load_reference

    with _read_inputs(args, kinds) as (paths, files, copies):
        try:
            camera, sensor = _load(args, paths)
            reference = load_reference(paths["--reference"], args.reference_camera) if args.reference else None
            if args.reference2:
                import numpy as np

                reference = np.stack([reference, load_reference(paths["--reference2"], args.reference_camera)])
        except (ValueError, OSError) as err:
            text = str(err)
            for copy, shown in copies.items():
                text = text.replace(copy, shown)
            raise ValueError(text) from None
        if not args.poses:
            camera, sensor = _named(camera, copies, args.camera), _named(sensor, copies, args.sensor)
    return camera, sensor, reference, files
