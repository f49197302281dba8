"""What the lab records (:class:`LabRecording`), and the files it is stored in: writer and
validating loader. Theory and measured numbers: ``docs/studies.md``, section
``replication.study.lab.recording``."""
from __future__ import annotations

import io
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..._io import PROJECT_ROOT, write_atomic
from ..._jitter import jitter, jitter_setting
from ...core.checks import check_rotation_matrices
from ...rig.datafile import fail as _fail
from ...rig.datafile import read_text
from ...rig.streams import GyroStream, integrate_gyro
from .settings import GRAVITY

__all__ = ["LabRecording", "ACC_COLUMNS", "GYR_COLUMNS", "MAG_COLUMNS", "IMU_COLUMNS", "UNITS", "marker_pixels",
           "static_hold_seconds", "FILES", "write_lab", "load_lab", "default_lab_dir"]


@dataclass
class LabRecording:
    """What the lab records: the rig description and four tables of raw samples.

    Attributes
    ----------
    rig : dict
        ``camera_matrix`` (3 x 3), ``dist_coeffs`` (5), ``image_size`` (w, h) -- the
        *calibrated* intrinsics --, ``wand_points`` (N x 3, metres), ``imu_rate_hz``,
        ``camera_rate_hz`` and ``units``. Schema: ``data/README.md``.
    static_imu, dynamic_imu : pandas.DataFrame
        Columns ``set, pose`` (static only), ``t`` (s), ``acc_x..z`` (m/s^2),
        ``gyr_x..z`` (rad/s), ``mag_x..z`` (micro-tesla), in the sensor frame.
    static_markers, dynamic_markers : pandas.DataFrame
        Columns ``set, pose`` (static only), ``t`` (s), ``u0..u{N-1}``, ``v0..v{N-1}``
        (pixels, distorted image).
    truth : dict
        Simulation only (a real recording has none): ``camera_from_sensor`` (3 x 3).
    """

    rig: dict
    static_imu: pd.DataFrame
    static_markers: pd.DataFrame
    dynamic_imu: pd.DataFrame
    dynamic_markers: pd.DataFrame
    truth: dict = field(default_factory=dict)

    def __post_init__(self):
        if jitter_setting() is None:
            return
        for name in ("static_imu", "static_markers", "dynamic_imu", "dynamic_markers"):
            df = getattr(self, name).copy()
            for col in df.columns:
                if pd.api.types.is_float_dtype(df[col]) and col != "t":  # time stamps are exact ticks
                    df[col] = jitter(df[col].to_numpy())
            setattr(self, name, df)


ACC_COLUMNS, GYR_COLUMNS, MAG_COLUMNS = (["acc_x", "acc_y", "acc_z"], ["gyr_x", "gyr_y", "gyr_z"],
                                         ["mag_x", "mag_y", "mag_z"])
IMU_COLUMNS = ACC_COLUMNS + GYR_COLUMNS + MAG_COLUMNS


def _marker_columns(n):
    return [f"u{i}" for i in range(n)] + [f"v{i}" for i in range(n)]


def marker_pixels(markers: pd.DataFrame, n: int) -> np.ndarray:
    """Columns ``u0..u{n-1}, v0..v{n-1}`` of a marker table as pixels, shape (M, n, 2)."""
    uv = markers[_marker_columns(n)].to_numpy(dtype=float)
    return np.stack([uv[:, :n], uv[:, n:]], axis=-1)


def static_hold_seconds(static_imu: pd.DataFrame, imu_rate_hz: float) -> pd.Series:
    """How long each static orientation was recorded: ``t_last - t_first + 1 / rate``, indexed by
    (set, pose)."""
    t = static_imu.groupby(["set", "pose"])["t"]
    return t.last() - t.first() + 1.0 / imu_rate_hz


#: Units of the recordings (checked by the loader).
UNITS = {"t": "s", "acc": "m/s^2", "gyr": "rad/s", "mag": "uT", "uv": "px", "wand_points": "m"}


# ----------------------------------------------------------------------------- files

FILES = ("rig.json", "static_imu.csv", "static_markers.csv", "dynamic_imu.csv", "dynamic_markers.csv")

#: Sensor ranges: ADXL330 +-3.6 g (minimum full scale), ITG-3200 +-2000 deg/s, HMC5843 +-4 gauss
#: (400 uT).
ACC_LIMIT = 3.6 * GRAVITY
GYR_LIMIT = np.deg2rad(2000.0)
MAG_LIMIT = 400.0

#: Digits written per column kind (well below each sensor's noise).
_FORMATS = {"t": "%.3f", "acc": "%.4f", "gyr": "%.5f", "mag": "%.3f", "uv": "%.3f"}


def default_lab_dir() -> Path:
    """``data/lab`` of this project."""
    return PROJECT_ROOT / "data" / "lab"


def _json_text(data: dict) -> str:
    """One key per line, arrays on their line (readable, diff-friendly)."""
    return "{\n" + ",\n".join(f"  {json.dumps(k)}: {json.dumps(v)}" for k, v in data.items()) + "\n}\n"


def _csv_text(df: pd.DataFrame) -> str:
    out = pd.DataFrame(index=df.index)
    for col in df.columns:
        if col in ("set", "pose"):
            out[col] = df[col].astype(int).astype(str)
        else:
            kind = "uv" if col[0] in "uv" and col[1:].isdigit() else col.split("_")[0]
            out[col] = [_FORMATS[kind] % x for x in df[col].to_numpy()]
    return out.to_csv(index=False, lineterminator="\n")


def write_lab(recording: LabRecording, directory) -> Path:
    """Write ``recording`` to ``directory`` (created if missing); returns the folder."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    write_atomic(directory / "rig.json", _json_text(recording.rig))
    for name in FILES[1:]:
        write_atomic(directory / name, _csv_text(getattr(recording, name[:-4])))
    if recording.truth:
        truth = {k: np.asarray(v).round(12).tolist() for k, v in recording.truth.items()}
        truth["note"] = "simulation only: the true camera_from_sensor rotation (v_camera = R0 v_sensor)"
        write_atomic(directory / "truth.json", _json_text(truth))
    return directory


# ----------------------------------------------------------------------------- loading

def _load_rig(path: Path) -> dict:
    text = read_text(path, "the rig description")
    try:
        rig = json.loads(text)
    except json.JSONDecodeError as exc:
        _fail(path, f"not valid JSON ({exc.msg})", line=exc.lineno, column=exc.colno)
    if not isinstance(rig, dict):
        _fail(path, f"must hold a JSON object, got {type(rig).__name__}")
    required = ("camera_matrix", "dist_coeffs", "image_size", "wand_points", "imu_rate_hz", "camera_rate_hz", "units")
    missing = [k for k in required if k not in rig]
    if missing:
        _fail(path, f"missing key(s) {missing}")

    def array(key, shape=None):
        try:
            a = np.asarray(rig[key], dtype=float)
        except (TypeError, ValueError):
            _fail(path, f"key {key!r} is not numeric")
        if shape is not None and a.shape != shape:
            _fail(path, f"key {key!r} must have shape {shape}, got {a.shape}")
        if not np.all(np.isfinite(a)):
            _fail(path, f"key {key!r} contains NaN or inf")
        return a

    K = array("camera_matrix", (3, 3))
    if K[0, 0] <= 0 or K[1, 1] <= 0 or not np.allclose(K[2], [0, 0, 1]) or K[1, 0] != 0:
        _fail(path, "key 'camera_matrix' is not [[fx, s, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0")
    dist = array("dist_coeffs")
    if dist.ndim != 1 or dist.size not in (4, 5, 8, 12, 14):
        _fail(path, f"key 'dist_coeffs' must list 4, 5, 8, 12 or 14 OpenCV coefficients, got shape {dist.shape}")
    size = array("image_size", (2,))
    if np.any(size <= 0):
        _fail(path, f"key 'image_size' must be positive (width, height), got {size.tolist()}")
    X = array("wand_points")
    if X.ndim != 2 or X.shape[1] != 3 or X.shape[0] < 6:
        _fail(path, f"key 'wand_points' must be (N, 3) with N >= 6 markers, got shape {X.shape}")
    sv = np.linalg.svd(X - X.mean(axis=0), compute_uv=False)
    if sv[2] < 1e-3 * sv[0]:
        _fail(path, "key 'wand_points': the markers are coplanar (the PnP set-up needs a 3-D wand)")
    if np.max(np.abs(X)) > 10:
        _fail(path, f"key 'wand_points': coordinates up to {np.max(np.abs(X)):.4g}; expected metres, not mm")
    for key in ("imu_rate_hz", "camera_rate_hz"):
        if array(key, ()) <= 0:
            _fail(path, f"key {key!r} must be positive")
    if rig["units"] != UNITS:
        _fail(path, f"key 'units' must be {UNITS} (convert the recordings), got {rig['units']}")
    return rig


def _load_table(path: Path, columns: list, *, grouped: bool) -> pd.DataFrame:
    """Read a CSV, checking columns, numbers, NaN and strictly increasing ``t`` (per set)."""
    text = read_text(path)
    try:
        df = pd.read_csv(io.StringIO(text), skip_blank_lines=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        _fail(path, f"not a readable CSV ({exc})")
    missing = [c for c in columns if c not in df.columns]
    if missing:
        _fail(path, f"missing column(s) {missing}; expected {columns}", line=1)
    df = df[columns]
    if len(df) < 2:
        _fail(path, "fewer than 2 data lines")
    for col in columns:
        if not pd.api.types.is_numeric_dtype(df[col]):
            numbers = pd.to_numeric(df[col], errors="coerce")
            bad = np.flatnonzero(numbers.isna() & df[col].notna())
            if bad.size:
                _fail(path, f"not a number: {df[col].iloc[bad[0]]!r}", line=int(bad[0]) + 2, column=col)
            df[col] = numbers
    values = df.to_numpy(dtype=float)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        _fail(path, "NaN, empty or inf", line=int(bad[0, 0]) + 2, column=columns[bad[0, 1]])
    if grouped:
        for col in ("set", "pose"):
            v = df[col].to_numpy()
            frac = np.flatnonzero((v != np.round(v)) | (v < 0))
            if frac.size:
                _fail(path, f"must be a non-negative integer, got {v[frac[0]]:.6g}", line=int(frac[0]) + 2, column=col)
        df = df.astype({"set": int, "pose": int})
    t = df["t"].to_numpy()
    same = np.ones(len(df) - 1, dtype=bool) if not grouped else (df["set"].to_numpy()[1:] == df["set"].to_numpy()[:-1])
    back = np.flatnonzero(same & (np.diff(t) <= 0))
    if back.size:
        k = int(back[0]) + 1
        _fail(path, f"timestamp {t[k]:.6g} is not after the previous line's {t[k - 1]:.6g}", line=k + 2, column="t")
    if grouped:
        s, p = df["set"].to_numpy(), df["pose"].to_numpy()
        step = np.flatnonzero(same & (np.diff(p) < 0))
        if step.size:
            k = int(step[0]) + 1
            _fail(path, f"pose {p[k]} follows pose {p[k - 1]} in set {s[k]}; rows must be ordered by set, pose, t",
                  line=k + 2, column="pose")
        order = np.flatnonzero(np.diff(s) < 0)
        if order.size:
            k = int(order[0]) + 1
            _fail(path, f"set {s[k]} follows set {s[k - 1]}; rows must be ordered by set", line=k + 2, column="set")
    return df


def _check_range(path, df, cols, limit, unit_hint):
    values = np.abs(df[cols].to_numpy())
    bad = np.argwhere(values > limit)
    if bad.size:
        i, j = bad[0]
        _fail(path, f"{df[cols[j]].iloc[i]:.6g} is outside the sensor's range +-{limit:.4g}; {unit_hint}",
              line=int(i) + 2, column=cols[j])


def _check_imu(path, df):
    _check_range(path, df, ACC_COLUMNS, ACC_LIMIT, "expected m/s^2")
    _check_range(path, df, GYR_COLUMNS, GYR_LIMIT, "expected rad/s, not deg/s")
    _check_range(path, df, MAG_COLUMNS, MAG_LIMIT, "expected micro-tesla")
    g = np.median(np.linalg.norm(df[ACC_COLUMNS].to_numpy(), axis=1))
    if not 0.5 * GRAVITY < g < 1.5 * GRAVITY:
        _fail(path, f"median accelerometer norm {g:.4g}; expected about {GRAVITY} m/s^2 (data in g?)",
              column="acc_x")
    b = np.median(np.linalg.norm(df[MAG_COLUMNS].to_numpy(), axis=1))
    if not 10.0 < b < 100.0:
        _fail(path, f"median magnetometer norm {b:.4g}; expected Earth's field, 25-65 micro-tesla (data in gauss?)",
              column="mag_x")


def _check_gyro_units(path, df, window_s=2.0, limit_deg=20.0):
    """Gyro units by physics, on a continuous recording: the integrated gyroscope
    (:func:`replication.rig.streams.integrate_gyro`) must carry the accelerometer's
    direction at the start of each ``window_s`` onto the one at its end (up to
    ``limit_deg``, room for bias and linear acceleration). deg/s data turn it 57 times
    too far. (A static recording cannot show its gyro units: it does not rotate.)"""
    t = df["t"].to_numpy()
    Q = integrate_gyro(GyroStream(t, df[GYR_COLUMNS].to_numpy(), str(path))).R
    acc = df[ACC_COLUMNS].to_numpy()
    acc = acc / np.linalg.norm(acc, axis=-1, keepdims=True)
    edges = np.searchsorted(t, np.arange(t[0], t[-1], window_s))    # first sample of each window
    start, end = edges[:-1], edges[1:]
    if not len(start):
        return
    # (Q_s^T Q_e)^T a_s: a_s seen from body_end
    predicted = np.einsum("wji,wj->wi", np.swapaxes(Q[start], -1, -2) @ Q[end], acc[start])
    err = np.degrees(np.arccos(np.clip(np.sum(predicted * acc[end], axis=-1), -1, 1)))
    if np.median(err) > limit_deg:
        _fail(path, f"integrating the gyroscope over {window_s:g} s windows misses the accelerometer's tilt "
              f"by {np.median(err):.3g} deg (median); expected rad/s (data in deg/s?)", column="gyr_x")


def _check_time_unit(path, df, rate_hz):
    """The time column must step by the rig's sample period (within a factor of 2 in the median): a
    column in ms or us steps 1000 or 1e6 times too far, and every duration computed from it is off
    by that factor."""
    step = np.median(np.diff(df["t"].to_numpy()))
    ratio = step * rate_hz
    if not 0.5 < ratio < 2.0:
        units = {1e3: "ms", 1e6: "us", 1e9: "ns"}
        guess = next((f"; the times look like {u}, not s" for f, u in units.items() if 0.5 < ratio / f < 2.0), "")
        _fail(path, f"time stamps step by {step:.6g} (median) where the rig's {rate_hz:g} Hz needs "
              f"{1.0 / rate_hz:.6g} s{guess}", column="t")


def _check_pixels(path, df, rig):
    n = len(rig["wand_points"])
    w, h = rig["image_size"]
    for cols, limit in ((_marker_columns(n)[:n], w), (_marker_columns(n)[n:], h)):
        values = df[cols].to_numpy()
        bad = np.argwhere((values < 0) | (values > limit))
        if bad.size:
            i, j = bad[0]
            _fail(path, f"pixel {values[i, j]:.6g} is outside the image (0..{limit})", line=int(i) + 2, column=cols[j])


#: Tolerance of the truth's rotation test (it is written rounded to 12 decimals).
TRUTH_ATOL = 1e-5


def _load_truth(path: Path) -> np.ndarray:
    """``camera_from_sensor`` of ``truth.json``: a rotation, else an error at the line and column of
    its value."""
    text = read_text(path)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        _fail(path, f"not valid JSON ({exc.msg})", line=exc.lineno, column=exc.colno)
    try:
        R = np.asarray(data["camera_from_sensor"], dtype=float)
    except (KeyError, TypeError, ValueError):
        _fail(path, "no numeric key 'camera_from_sensor'")
    try:
        if R.shape != (3, 3):
            raise ValueError(f"key 'camera_from_sensor' must be a 3 x 3 rotation matrix, got shape {R.shape}")
        return check_rotation_matrices(R, "key 'camera_from_sensor'", atol=TRUTH_ATOL)
    except ValueError as err:
        found = re.search(r'"camera_from_sensor"\s*:\s*', text)
        at = found.end() if found else 0
        _fail(path, str(err), line=text.count("\n", 0, at) + 1, column=at - (text.rfind("\n", 0, at) + 1) + 1)


def load_lab(directory=None, *, min_static_seconds: float = 5.0, min_poses: int = 3) -> LabRecording:
    """Load and validate a lab recording folder (schema: ``data/README.md``).

    Parameters
    ----------
    directory : path-like, optional
        The folder; default ``data/lab`` of this project.
    min_static_seconds : float
        Shortest accepted static window per orientation (the paper: at least 5 s).
    min_poses : int
        Fewest static orientations per data set (3: two motions with distinct axes).

    Returns
    -------
    LabRecording
        ``truth`` is filled only if ``truth.json`` is present.

    Raises
    ------
    DataFileNotFound
        A file is missing (also a ``FileNotFoundError``).
    DataFileError
        The first problem found (a ``ValueError``), naming file, line and column where known.
    """
    directory = default_lab_dir() if directory is None else Path(directory)
    rig = _load_rig(directory / "rig.json")
    n = len(rig["wand_points"])
    marker_cols = _marker_columns(n)
    tables = {}
    for name in FILES[1:]:
        grouped = name.startswith("static")
        cols = (["set", "pose"] if grouped else []) + ["t"] + (IMU_COLUMNS if "imu" in name else marker_cols)
        path = directory / name
        df = _load_table(path, cols, grouped=grouped)
        _check_time_unit(path, df, rig["imu_rate_hz" if "imu" in name else "camera_rate_hz"])
        if "imu" in name:
            _check_imu(path, df)
            if not grouped:
                _check_gyro_units(path, df)
        else:
            _check_pixels(path, df, rig)
        tables[name[:-4]] = df

    imu, markers = tables["static_imu"], tables["static_markers"]
    poses_imu = set(map(tuple, imu[["set", "pose"]].drop_duplicates().to_numpy()))
    poses_cam = set(map(tuple, markers[["set", "pose"]].drop_duplicates().to_numpy()))
    if poses_imu != poses_cam:
        only = sorted(poses_imu ^ poses_cam)[0]
        where = "static_imu.csv" if only in poses_imu else "static_markers.csv"
        _fail(directory / "static_markers.csv", f"(set, pose) {tuple(map(int, only))} appears only in {where}; "
              "both files must hold the same static orientations")
    span = static_hold_seconds(imu, rig["imu_rate_hz"])
    short = span[span < min_static_seconds]
    if len(short):
        (k, p), sec = short.index[0], short.iloc[0]
        _fail(directory / "static_imu.csv", f"set {k}, pose {p} is held for {sec:.3g} s, "
              f"less than min_static_seconds = {min_static_seconds} s")
    counts = imu.groupby("set")["pose"].nunique()
    few = counts[counts < min_poses]
    if len(few):
        _fail(directory / "static_imu.csv", f"set {few.index[0]} has {few.iloc[0]} static orientations, "
              f"fewer than min_poses = {min_poses}")

    truth = {}
    path = directory / "truth.json"
    if path.is_file():
        truth = {"camera_from_sensor": _load_truth(path)}
    return LabRecording(rig, tables["static_imu"], tables["static_markers"], tables["dynamic_imu"],
                        tables["dynamic_markers"], truth=truth)
