"""Loaders for real camera / IMU / robot recordings and their published reference rotations.

The recordings live outside the project (they are not ours to redistribute); their folder
is found by :func:`data_root`: an explicit argument, else ``$REPLICATION_REAL_DATA``, else
``../shared/data/real`` next to the project. Each folder's ``README.txt`` gives provenance,
formats and frames.

Conventions
-----------
* An :class:`OrientationStream` holds ``world_from_body`` rotations (a SLAM / mocap
  trajectory's quaternions rotate body vectors into the world) at times in seconds.
  In the paper's notation the body-from-world attitude is ``C_t = Q_t^T``.
* A :class:`GyroStream` holds angular velocity in rad/s, in the body (IMU) frame.
* Every reference rotation is returned as ``camera_from_sensor``, the paper's ``R0``
  (``A_j R0 = R0 B_j`` with ``A`` camera, ``B`` sensor/IMU/hand motions).
* Quaternions in files are unit quaternions; the loaders accept a norm within
  ``QUATERNION_NORM_TOL`` of 1 and normalise.

Malformed files raise ``ValueError`` naming the file, the line and the problem; nothing
is written anywhere by a loader.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from .so3 import check_rotation_matrices, nearest_rotation, quaternion_to_matrix

__all__ = [
    "OrientationStream",
    "GyroStream",
    "DEFAULT_REAL_DATA",
    "data_root",
    "StereoCalibration",
    "load_orbslam3_stereo",
    "real_data_available",
    "load_tum_trajectory",
    "load_euroc_imu",
    "load_euroc_mocap",
    "load_kalibr_camchain",
    "load_euroc_sensor_yaml",
    "load_tabb_poses",
    "load_tabb_camera_poses",
    "load_tabb_solution",
    "load_stream",
    "load_reference",
]

#: Where the shared recordings are when neither an argument nor ``$REPLICATION_REAL_DATA`` says otherwise.
DEFAULT_REAL_DATA = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "real"
#: Accepted deviation of a stored quaternion's norm from 1.
QUATERNION_NORM_TOL = 1e-3


@dataclass(frozen=True)
class OrientationStream:
    """Timestamped orientations: ``R[k]`` is ``world_from_body`` at time ``t[k]`` (s, increasing)."""

    t: np.ndarray
    R: np.ndarray
    source: str = ""

    def __post_init__(self):
        R = check_rotation_matrices(self.R, f"{self.source or 'orientation stream'} R", atol=1e-5)
        _validate_stream(self, "R", R, (3, 3))

    def at(self, times) -> np.ndarray:
        """``world_from_body`` slerp-interpolated at ``times`` (which must lie inside the stream)."""
        return Slerp(self.t, Rotation.from_matrix(self.R))(times).as_matrix()

    def between(self, start: float, stop: float) -> "OrientationStream":
        """The samples with ``start <= t <= stop``."""
        keep = (self.t >= start) & (self.t <= stop)
        return OrientationStream(self.t[keep], self.R[keep], self.source)


@dataclass(frozen=True)
class GyroStream:
    """Angular velocity ``omega[k]`` (rad/s, body frame) at time ``t[k]`` (s, increasing)."""

    t: np.ndarray
    omega: np.ndarray
    source: str = ""

    def __post_init__(self):
        w = np.asarray(self.omega, dtype=float)
        if not np.all(np.isfinite(w)):
            raise ValueError(f"{self.source}: angular velocity contains NaN or inf")
        _validate_stream(self, "omega", w, (3,))


def _validate_stream(stream, name: str, values: np.ndarray, tail: tuple) -> None:
    """Check shapes and timestamps of a frozen stream and store the converted arrays on it."""
    t = np.asarray(stream.t, dtype=float)
    if t.ndim != 1 or values.shape != t.shape + tail:
        raise ValueError(f"{stream.source}: need t of shape (N,) and {name} of shape (N, {', '.join(map(str, tail))}), "
                         f"got {t.shape}, {values.shape}")
    _check_times(t, stream.source)
    object.__setattr__(stream, "t", t)
    object.__setattr__(stream, name, values)


def _check_times(t, source):
    if len(t) < 2:
        raise ValueError(f"{source}: need at least 2 samples, got {len(t)}")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{source}: timestamps contain NaN or inf")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        raise ValueError(f"{source}: timestamps not strictly increasing at sample {bad[0] + 1} "
                         f"({t[bad[0]]!r} then {t[bad[0] + 1]!r})")


def data_root(path=None) -> Path:
    """The folder of the real recordings: ``path``, else ``$REPLICATION_REAL_DATA``, else :data:`DEFAULT_REAL_DATA`.

    Raises
    ------
    FileNotFoundError
        The folder does not exist (the message says where it looked and how to point elsewhere).
    """
    root = Path(path or os.environ.get("REPLICATION_REAL_DATA") or DEFAULT_REAL_DATA)
    if not root.is_dir():
        raise FileNotFoundError(
            f"real-data folder {root} not found; get the recordings with 'python -m replication fetch-data DEST' "
            f"(data/real_data_manifest.csv lists them) and set REPLICATION_REAL_DATA=DEST, or pass the folder's "
            f"path (CI uses ../shared/data/real)"
        )
    return root


def real_data_available(path=None) -> bool:
    """Whether :func:`data_root` finds the folder."""
    try:
        data_root(path)
    except FileNotFoundError:
        return False
    return True


def _read_rows(path, n_columns: int, *, delimiter=None, what: str, drop_repeated: bool = False):
    """Numeric rows of a text file, skipping blank and ``#`` lines; errors name file, line and column.

    ``drop_repeated``: skip a line identical in every value to the previous data line.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    rows, lines = [], []
    with open(path) as fh:
        for lineno, line in enumerate(fh, 1):
            text = line.strip()
            if not text or text.startswith("#"):
                continue
            parts = [p for p in (text.split(delimiter) if delimiter else text.split())]
            if len(parts) != n_columns:
                raise ValueError(f"{path}, line {lineno}: expected {n_columns} columns ({what}), got {len(parts)}")
            try:
                values = [float(p) for p in parts]
            except ValueError:
                col = next(i for i, p in enumerate(parts) if not _is_float(p))
                raise ValueError(f"{path}, line {lineno}, column {col + 1}: not a number: {parts[col]!r}") from None
            bad = [i for i, v in enumerate(values) if not np.isfinite(v)]
            if bad:
                raise ValueError(f"{path}, line {lineno}, column {bad[0] + 1}: NaN or inf")
            if drop_repeated and rows and values == rows[-1]:
                continue
            rows.append(values)
            lines.append(lineno)
    if len(rows) < 2:
        raise ValueError(f"{path}: fewer than 2 data lines ({what})")
    data = np.array(rows)
    step = np.diff(data[:, 0])
    if np.any(step <= 0):
        k = int(np.flatnonzero(step <= 0)[0])
        raise ValueError(f"{path}, line {lines[k + 1]}, column 1: timestamp not after the previous line's "
                         f"({data[k + 1, 0]!r} <= {data[k, 0]!r})")
    return data, np.array(lines)


def _is_float(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _quaternions(path, q_wxyz, lines):
    norm = np.linalg.norm(q_wxyz, axis=-1)
    bad = np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_NORM_TOL)
    if bad.size:
        raise ValueError(f"{path}, line {lines[bad[0]]}: quaternion norm {norm[bad[0]]:.6g} is not 1 "
                         f"(tolerance {QUATERNION_NORM_TOL:g}); wrong column order or units?")
    return quaternion_to_matrix(q_wxyz / norm[:, None])


def _seconds(t, path, time_unit):
    if time_unit == "auto":
        time_unit = "ns" if np.median(np.abs(t)) > 1e12 else "s"
    if time_unit not in ("s", "ns"):
        raise ValueError(f"time_unit must be 's', 'ns' or 'auto', got {time_unit!r}")
    return t * 1e-9 if time_unit == "ns" else t


def load_tum_trajectory(path, *, time_unit: str = "auto", drop_repeated: bool = False) -> OrientationStream:
    """A TUM / ORB-SLAM3 trajectory: lines ``t tx ty tz qx qy qz qw`` (scalar last).

    Each pose is ``T_world<-body`` (ORB-SLAM3's ``SaveTrajectoryEuRoC`` writes camera-to-world
    ``Twc``; OpenVINS' ground truth writes the IMU body in the world), so the stream holds
    ``world_from_body``. ``time_unit``: ``"s"``, ``"ns"`` or ``"auto"`` (ns when timestamps
    exceed 1e12, as ORB-SLAM3's do). Translations are ignored. ``drop_repeated=True`` skips
    lines that repeat the previous line exactly (one of the shared ORB-SLAM3 runs has such
    lines); otherwise a repeated timestamp is an error.
    """
    data, lines = _read_rows(path, 8, what="t tx ty tz qx qy qz qw", drop_repeated=drop_repeated)
    R = _quaternions(path, data[:, [7, 4, 5, 6]], lines)
    return OrientationStream(_seconds(data[:, 0], path, time_unit), R, str(path))


def load_euroc_mocap(path) -> OrientationStream:
    """EuRoC / TUM-VI ``mocap0/data.csv`` or ground truth: ``t[ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z``.

    ``q_RS`` (scalar first) rotates body (sensor S) vectors into the world R: ``world_from_body``.
    EuRoC's ``state_groundtruth_estimate0/data.csv`` has more columns; pass its first 8 only.
    """
    data, lines = _read_rows(path, 8, delimiter=",", what="t[ns], p_xyz, q_wxyz")
    R = _quaternions(path, data[:, 4:8], lines)
    return OrientationStream(data[:, 0] * 1e-9, R, str(path))


def load_euroc_imu(path, *, max_rate_rad_s: float = 35.0) -> GyroStream:
    """EuRoC / TUM-VI ``imu0/data.csv``: ``t[ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2]``.

    Angular rates above ``max_rate_rad_s`` (2000 deg/s, beyond common MEMS gyro ranges) are
    rejected as a units error (deg/s stored as rad/s).
    """
    data, lines = _read_rows(path, 7, delimiter=",", what="t[ns], w_xyz [rad/s], a_xyz [m/s^2]")
    w = data[:, 1:4]
    bad = np.flatnonzero(np.abs(w).max(axis=1) > max_rate_rad_s)
    if bad.size:
        raise ValueError(f"{path}, line {lines[bad[0]]}: angular rate {np.abs(w[bad[0]]).max():.4g} rad/s exceeds "
                         f"{max_rate_rad_s:g} rad/s; are the rates in deg/s?")
    return GyroStream(data[:, 0] * 1e-9, w, str(path))


def _yaml(path):
    import yaml

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        with open(path) as fh:
            return yaml.safe_load(fh)
    except yaml.YAMLError as err:
        raise ValueError(f"{path}: not valid YAML: {err}") from None


def _rotation_block(path, matrix, what):
    M = np.asarray(matrix, dtype=float)
    if M.shape != (4, 4):
        raise ValueError(f"{path}: {what} must be a 4x4 matrix, got shape {M.shape}")
    return check_rotation_matrices(M[:3, :3], f"{path}: rotation part of {what}", atol=1e-5)


def load_kalibr_camchain(path, camera: str = "cam0") -> np.ndarray:
    """``camera_from_sensor`` from a Kalibr camchain YAML: the rotation of ``<camera>.T_cam_imu``.

    Kalibr's ``T_cam_imu`` maps IMU-frame points into the camera frame, so its rotation is
    ``R_cam<-imu`` = the paper's ``R0`` directly.
    """
    doc = _yaml(path)
    try:
        T = doc[camera]["T_cam_imu"]
    except (KeyError, TypeError):
        raise ValueError(f"{path}: no {camera}.T_cam_imu entry") from None
    return _rotation_block(path, T, f"{camera}.T_cam_imu")


def load_euroc_sensor_yaml(path) -> np.ndarray:
    """``camera_from_sensor`` from an EuRoC ``cam0/sensor.yaml``: the transpose of ``T_BS``'s rotation.

    ``T_BS`` maps sensor (camera) points into the body (= IMU) frame: ``R_BS = R_imu<-cam``,
    so ``R0 = R_cam<-imu = R_BS^T``.
    """
    doc = _yaml(path)
    try:
        T = doc["T_BS"]
        M = np.asarray(T["data"], dtype=float).reshape(int(T["rows"]), int(T["cols"]))
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{path}: no valid T_BS (rows, cols, data) entry") from None
    return _rotation_block(path, M, "T_BS").T


def _tabb_count(path, tokens):
    try:
        n = int(tokens[0])
    except (IndexError, ValueError):
        raise ValueError(f"{path}, line 1: expected the number of poses") from None
    return n


def load_tabb_poses(path) -> np.ndarray:
    """Tabb & Ahmad Yousef ``robot_cali.txt``: N, then N row-major 4x4 base->hand transforms.

    Returns the rotations ``hand_from_base`` (body-from-world attitudes of the hand), shape (N, 3, 3).
    The file prints 6 digits, so each rotation is checked to 1e-4 and projected onto SO(3).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    tokens = path.read_text().split()
    n = _tabb_count(path, tokens)
    values = tokens[1:]
    if len(values) != 16 * n:
        raise ValueError(f"{path}: header says {n} poses (need {16 * n} numbers), found {len(values)} numbers")
    try:
        T = np.array([float(v) for v in values]).reshape(n, 4, 4)
    except ValueError:
        raise ValueError(f"{path}: a pose entry is not a number") from None
    return nearest_rotation(check_rotation_matrices(T[:, :3, :3], f"{path}: hand_from_base rotations", atol=1e-4))


def load_tabb_camera_poses(path) -> np.ndarray:
    """Tabb & Ahmad Yousef ``cali.txt``: per line ``image K(9) R(9, row-major) t(3) dist(8)``.

    ``R`` maps chessboard (target) points into the camera: ``camera_from_target``, the
    camera's body-from-world attitude. The file prints 6 digits, so rows are orthonormal only
    to about 1e-6; each rotation is projected onto SO(3). Returns shape (N, 3, 3).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    lines = path.read_text().splitlines()
    n = _tabb_count(path, lines[0].split() if lines else [])
    mats = []
    for lineno, line in enumerate(lines[1:], 2):
        parts = line.split()
        if not parts:
            continue
        if len(parts) != 30:
            raise ValueError(f"{path}, line {lineno}: expected 30 fields (image, K, R, t, distortion), got {len(parts)}")
        try:
            mats.append(np.array([float(v) for v in parts[10:19]]).reshape(3, 3))
        except ValueError:
            raise ValueError(f"{path}, line {lineno}: rotation entries (fields 11-19) are not numbers") from None
    if len(mats) != n:
        raise ValueError(f"{path}: header says {n} poses, found {len(mats)}")
    R = np.array(mats)
    check_rotation_matrices(R, f"{path}: camera_from_target rotations", atol=1e-4)
    return nearest_rotation(R)


def load_tabb_solution(path) -> np.ndarray:
    """Tabb's published solution ``transformations.txt``: the rotation of ``Z = T_cam<-hand`` (``R0``)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    lines = [ln.split() for ln in path.read_text().splitlines()]
    try:
        start = next(i for i, ln in enumerate(lines) if ln and ln[0] == "Z")
        M = np.array([[float(v) for v in lines[start + 1 + r]] for r in range(4)])
    except (StopIteration, ValueError, IndexError):
        raise ValueError(f"{path}: no 4x4 matrix after a line starting with 'Z'") from None
    return _rotation_block(path, M, "Z")


def load_stream(path, kind: str = "orientation"):
    """Load a stream by kind and file type.

    ``kind="gyro"``: an EuRoC/TUM-VI ``imu0/data.csv`` (:func:`load_euroc_imu`).
    ``kind="orientation"``: a ``.csv`` is read as EuRoC/TUM-VI mocap or ground truth
    (:func:`load_euroc_mocap`), anything else as a TUM trajectory (:func:`load_tum_trajectory`).
    """
    if kind == "gyro":
        return load_euroc_imu(path)
    if kind != "orientation":
        raise ValueError(f"kind must be 'gyro' or 'orientation', got {kind!r}")
    return load_euroc_mocap(path) if Path(path).suffix.lower() == ".csv" else load_tum_trajectory(path)


def load_reference(path, camera: str = "cam0") -> np.ndarray:
    """A reference ``camera_from_sensor`` from a Kalibr camchain, an EuRoC ``sensor.yaml`` or Tabb's solution.

    The kind is recognised from the content: ``<camera>.T_cam_imu`` (Kalibr), ``T_BS`` (EuRoC),
    a ``Z`` matrix (Tabb's ``transformations.txt``).
    """
    path = Path(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        doc = _yaml(path)
        if isinstance(doc, dict) and "T_BS" in doc:
            return load_euroc_sensor_yaml(path)
        return load_kalibr_camchain(path, camera)
    return load_tabb_solution(path)


@dataclass(frozen=True)
class StereoCalibration:
    """A stereo rig's calibration as ORB-SLAM3 reads it (``Examples/Stereo/*.yaml``, pinhole model).

    Attributes
    ----------
    K1, K2 : ndarray (3, 3)
        Camera matrices of the left (1) and right (2) camera.
    dist1, dist2 : ndarray (4,)
        Radial-tangential distortion ``k1, k2, p1, p2``.
    size : (int, int)
        Image width and height.
    R_c1_c2, t_c1_c2 : ndarray (3, 3), (3,)
        ``Stereo.T_c1_c2``: camera 2 in camera 1 (``x_c1 = R x_c2 + t``).
    source : str
    """

    K1: np.ndarray
    dist1: np.ndarray
    K2: np.ndarray
    dist2: np.ndarray
    size: tuple
    R_c1_c2: np.ndarray
    t_c1_c2: np.ndarray
    source: str

    def rectification_rotation(self) -> np.ndarray:
        """``R1`` of ``cv2.stereoRectify``: the rotation from the raw left camera to the rectified one.

        ORB-SLAM3 (v1.0) rectifies a pinhole stereo pair itself and reports the *rectified* left
        camera, so a stereo trajectory's camera is ``R1`` times the raw ``cam0``:
        ``camera_from_sensor`` becomes ``R1 R0``.
        """
        import cv2

        R_c2_c1 = self.R_c1_c2.T  # cv2.stereoRectify takes x_c2 = R x_c1 + T
        R1 = cv2.stereoRectify(self.K1, self.dist1, self.K2, self.dist2, self.size, R_c2_c1,
                               -R_c2_c1 @ self.t_c1_c2)[0]
        return np.asarray(R1, dtype=float)


def load_orbslam3_stereo(path) -> StereoCalibration:
    """Read an ORB-SLAM3 stereo settings file (OpenCV ``FileStorage`` YAML, ``Camera.type: "PinHole"``).

    Raises
    ------
    FileNotFoundError, ValueError
        Missing file, a missing or malformed entry (named), a camera type other than PinHole, or a
        ``Stereo.T_c1_c2`` whose rotation is not a rotation.
    """
    import cv2

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file" + (" (it is a directory)" if path.is_dir() else ""))
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error as err:
        raise ValueError(f"{path}: not an OpenCV FileStorage YAML file ({str(err).strip().splitlines()[-1]})") from None
    if not fs.isOpened():
        raise ValueError(f"{path}: not an OpenCV FileStorage YAML file")
    try:
        def number(key):
            node = fs.getNode(key)
            if node.empty() or not node.isReal() and not node.isInt():
                raise ValueError(f"{path}: entry {key!r} missing or not a number")
            return float(node.real())

        kind = fs.getNode("Camera.type")
        if not kind.empty() and kind.string() != "PinHole":
            raise ValueError(f"{path}: Camera.type is {kind.string()!r}; only 'PinHole' is supported")
        cams = []
        for c in ("Camera1", "Camera2"):
            K = np.array([[number(f"{c}.fx"), 0.0, number(f"{c}.cx")], [0.0, number(f"{c}.fy"), number(f"{c}.cy")],
                          [0.0, 0.0, 1.0]])
            cams.append((K, np.array([number(f"{c}.{k}") for k in ("k1", "k2", "p1", "p2")])))
        size = (int(number("Camera.width")), int(number("Camera.height")))
        T = fs.getNode("Stereo.T_c1_c2").mat()
        if T is None or np.shape(T) != (4, 4):
            raise ValueError(f"{path}: entry 'Stereo.T_c1_c2' missing or not a 4x4 matrix")
    finally:
        fs.release()
    T = np.asarray(T, dtype=float)
    R = check_rotation_matrices(T[:3, :3], f"{path}: Stereo.T_c1_c2 rotation", atol=1e-5)
    return StereoCalibration(cams[0][0], cams[0][1], cams[1][0], cams[1][1], size, R, T[:3, 3], str(path))
