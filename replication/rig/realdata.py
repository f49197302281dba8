"""Loaders for real camera / IMU / robot recordings and their published reference rotations. Theory
and measured numbers: ``docs/reading.md``, section ``replication.rig.realdata``."""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._io import PROJECT_ROOT
from .._jitter import jitter
from ..core.checks import check_rotation_matrices
from ..core.so3 import nearest_rotation
from .datafile import fail, is_number, read_lines, read_table, read_text, unit_quaternion_rotations
from .streams import GyroStream, OrientationStream  # re-exported: defined in replication.rig.streams

__all__ = [
    "DEFAULT_REAL_DATA",
    "data_root",
    "StereoCalibration",
    "load_orbslam3_stereo",
    "real_data_available",
    "load_tum_trajectory",
    "load_euroc_imu",
    "load_euroc_mocap",
    "load_tabb_poses",
    "load_tabb_camera_poses",
    "load_tabb_solution",
    "load_stream",
    "load_reference",
]

#: Where the shared recordings are when neither an argument nor ``$REPLICATION_REAL_DATA`` says
#: otherwise.
DEFAULT_REAL_DATA = PROJECT_ROOT.parent / "shared" / "data" / "real"


def data_root(path=None) -> Path:
    """The folder of the real recordings: ``path``, else ``$REPLICATION_REAL_DATA``, else
    :data:`DEFAULT_REAL_DATA`.

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


#: Seconds per unit of the time stamps a loader accepts (``time_unit``).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}


def _seconds(t, path, time_unit):
    if time_unit == "auto":
        time_unit = "ns" if np.median(np.abs(t)) > 1e12 else "s"
    if time_unit not in TIME_UNITS:
        raise ValueError(f"time_unit must be one of {sorted(TIME_UNITS)} or 'auto', got {time_unit!r}")
    return t * TIME_UNITS[time_unit]


TUM_COLUMNS = ("t", "tx", "ty", "tz", "qx", "qy", "qz", "qw")
EUROC_POSE_COLUMNS = ("t[ns]", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z")
#: The 9 further columns of EuRoC's ``state_groundtruth_estimate0/data.csv`` (17 in all): velocity,
#: gyro bias, accelerometer bias (``v_RS_R``, ``b_w_RS_S``, ``b_a_RS_S``); read as numbers, not
#: used.
EUROC_GROUNDTRUTH_EXTRA = ("v_x", "v_y", "v_z", "b_w_x", "b_w_y", "b_w_z", "b_a_x", "b_a_y", "b_a_z")
EUROC_IMU_COLUMNS = ("t[ns]", "w_x", "w_y", "w_z", "a_x", "a_y", "a_z")


def load_tum_trajectory(path, *, time_unit: str = "auto", drop_repeated: bool = False, repeated: str = "refuse",
                        tally: dict | None = None) -> OrientationStream:
    """A TUM / ORB-SLAM3 trajectory: lines ``t tx ty tz qx qy qz qw`` (scalar last).

    Each pose is ``T_world<-body`` (ORB-SLAM3's ``SaveTrajectoryEuRoC`` writes camera-to-world
    ``Twc``; OpenVINS' ground truth writes the IMU body in the world), so the stream holds
    ``world_from_body``. ``time_unit``: ``"s"``, ``"ms"``, ``"us"``, ``"ns"`` or ``"auto"`` (ns when
    timestamps exceed 1e12, as ORB-SLAM3's do). Translations are ignored. ``drop_repeated=True``
    skips lines that repeat the previous line exactly (one of the shared ORB-SLAM3 runs has such
    lines). A time stamp repeated with a *different* pose is refused unless ``repeated`` says which
    pose to keep: ``"keep-first"``, ``"keep-last"`` or ``"mean"`` (the refusal names them);
    ``tally``, a dict, receives how many lines were merged and the largest angle between two poses
    of one time stamp (:func:`~replication.rig.datafile.read_table`).

    Raises
    ------
    DataFileError
        A missing or unreadable file, or the first malformed line (line and column named).
    """
    data, lines = read_table(path, TUM_COLUMNS, what=" ".join(TUM_COLUMNS), drop_repeated=drop_repeated,
                             repeated=repeated, quaternion=(7, 4, 5, 6), tally=tally)
    R = unit_quaternion_rotations(path, data[:, [7, 4, 5, 6]], lines)
    return OrientationStream(_seconds(data[:, 0], path, time_unit), R, str(path))


def _csv_seconds(path, t, lines, time_unit):
    """A EuRoC / TUM-VI CSV's time stamps in seconds: nanoseconds by format (``time_unit="ns"`` or
    ``"auto"``), else the unit given. A stamp with a fraction is no count of nanoseconds: read as
    ns it is refused, naming the unit option that reads it."""
    if time_unit in ("auto", "ns"):
        frac = np.flatnonzero(t != np.round(t))
        if frac.size:
            stamp = read_lines(path)[lines[frac[0]] - 1].split(",")[0].strip()  # as the file writes it
            fail(path, f"the time stamp {stamp} has a fraction: not nanoseconds, the unit of EuRoC / TUM-VI CSV files; "
                 "in seconds (or ms, us)? time_unit='s' (calibrate --camera-time-unit / --sensor-time-unit s) "
                 "reads it", line=lines[frac[0]], column=1)
        time_unit = "ns"
    return _seconds(t, path, time_unit)


def load_euroc_mocap(path, *, time_unit: str = "ns", drop_repeated: bool = False, repeated: str = "refuse",
                     tally: dict | None = None) -> OrientationStream:
    """EuRoC / TUM-VI ``mocap0/data.csv`` or ground truth, as shipped: ``t[ns], p_x, p_y, p_z, q_w,
    q_x, q_y, q_z``.

    8 columns (``mocap0/data.csv``; TUM-VI's ground truth) or the 17 of EuRoC's
    ``state_groundtruth_estimate0/data.csv`` (header ``#timestamp, p_RS_R_x [m], p_RS_R_y [m],
    p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y, v_RS_R_z,
    b_w_RS_S_x [rad s^-1], b_w_RS_S_y, b_w_RS_S_z, b_a_RS_S_x [m s^-2], b_a_RS_S_y, b_a_RS_S_z``):
    the first 8 are used, the velocity and the two biases are checked as numbers and left out; every
    line of a file has the same count. ``q_RS`` (scalar first) rotates body (sensor S) vectors into
    the world R: ``world_from_body``. ``time_unit``: the stamps' unit, nanoseconds by format
    (``"s"``, ``"ms"``, ``"us"`` for files written otherwise; a stamp with a fraction read as ns
    is refused). ``drop_repeated``, ``repeated`` and ``tally``: as :func:`load_tum_trajectory`'s.
    """
    data, lines = read_table(path, EUROC_POSE_COLUMNS, delimiter=",", what="t[ns], p_xyz, q_wxyz[, v_xyz, b_w_xyz, "
                             "b_a_xyz]", optional=EUROC_GROUNDTRUTH_EXTRA, drop_repeated=drop_repeated,
                             repeated=repeated, quaternion=(4, 5, 6, 7), tally=tally)
    R = unit_quaternion_rotations(path, data[:, 4:8], lines)
    return OrientationStream(_csv_seconds(path, data[:, 0], lines, time_unit), R, str(path))


def load_euroc_imu(path, *, max_rate_rad_s: float = 35.0, time_unit: str = "ns", drop_repeated: bool = False,
                   repeated: str = "refuse", tally: dict | None = None) -> GyroStream:
    """EuRoC / TUM-VI ``imu0/data.csv``: ``t[ns], w_x, w_y, w_z [rad/s], a_x, a_y, a_z [m/s^2]``.

    Angular rates above ``max_rate_rad_s`` (2000 deg/s, beyond common MEMS gyro ranges) are rejected
    as a units error (deg/s stored as rad/s). ``time_unit``: as :func:`load_euroc_mocap`'s.
    ``drop_repeated``, ``repeated`` and ``tally``: as :func:`load_tum_trajectory`'s (``"mean"``
    averages the rates).
    """
    data, lines = read_table(path, EUROC_IMU_COLUMNS, delimiter=",", what="t[ns], w_xyz [rad/s], a_xyz [m/s^2]",
                             drop_repeated=drop_repeated, repeated=repeated, tally=tally)
    w = data[:, 1:4]
    bad = np.flatnonzero(np.abs(w).max(axis=1) > max_rate_rad_s)
    if bad.size:
        fail(path, f"angular rate {float(np.abs(w[bad[0]]).max()):.4g} rad/s exceeds {max_rate_rad_s:g} rad/s; "
             "are the rates in deg/s?", line=lines[bad[0]])
    return GyroStream(_csv_seconds(path, data[:, 0], lines, time_unit), w, str(path))


def _rotation(path, M, what, atol):
    """``check_rotation_matrices`` whose error is a :class:`~replication.rig.datafile.DataFileError`
    for ``path``."""
    try:
        return check_rotation_matrices(M, what, atol=atol)
    except ValueError as err:
        fail(path, str(err))


def _rotation_block(path, matrix, what):
    try:
        M = np.asarray(matrix, dtype=float)
    except (TypeError, ValueError):
        fail(path, f"{what} is not a numeric matrix")
    if M.shape != (4, 4):
        fail(path, f"{what} must be a 4x4 matrix, got shape {M.shape}")
    return _rotation(path, M[:3, :3], f"rotation part of {what}", atol=1e-5)


def _tabb_count(path, tokens):
    try:
        return int(tokens[0])
    except (IndexError, ValueError):
        fail(path, "expected the number of poses", line=1, column=1)


def load_tabb_poses(path) -> np.ndarray:
    """Tabb & Ahmad Yousef ``robot_cali.txt``: N, then N row-major 4x4 base->hand transforms.

    Returns the rotations ``hand_from_base`` (body-from-world attitudes of the hand), shape (N, 3,
    3). The file prints 6 digits, so each rotation is checked to 1e-4 and projected onto SO(3).
    """
    tokens = read_text(path).split()
    n = _tabb_count(path, tokens)
    values = tokens[1:]
    if len(values) != 16 * n:
        fail(path, f"header says {n} poses (need {16 * n} numbers), found {len(values)} numbers")
    try:
        T = np.array([float(v) for v in values]).reshape(n, 4, 4)
    except ValueError:
        bad = next(v for v in values if not is_number(v))
        fail(path, f"a pose entry is not a number: {bad!r}")
    return jitter(nearest_rotation(_rotation(path, T[:, :3, :3], "hand_from_base rotations", atol=1e-4)))


def load_tabb_camera_poses(path) -> np.ndarray:
    """Tabb & Ahmad Yousef ``cali.txt``: per line ``image K(9) R(9, row-major) t(3) dist(8)``.

    ``R`` maps chessboard (target) points into the camera: ``camera_from_target``, the
    camera's body-from-world attitude. The file prints 6 digits, so rows are orthonormal only
    to about 1e-6; each rotation is projected onto SO(3). Returns shape (N, 3, 3).
    """
    lines = read_lines(path)
    n = _tabb_count(path, lines[0].split() if lines else [])
    mats = []
    for lineno, line in enumerate(lines[1:], 2):
        parts = line.split()
        if not parts:
            continue
        if len(parts) != 30:
            fail(path, f"expected 30 fields (image, K, R, t, distortion), got {len(parts)}", line=lineno)
        bad = [i for i in range(10, 19) if not is_number(parts[i])]
        if bad:
            fail(path, f"rotation entries (fields 11-19) are not numbers: {parts[bad[0]]!r}", line=lineno,
                 column=bad[0] + 1)
        mats.append(np.array([float(v) for v in parts[10:19]]).reshape(3, 3))
    if len(mats) != n:
        fail(path, f"header says {n} poses, found {len(mats)}")
    R = np.array(mats)
    _rotation(path, R, "camera_from_target rotations", atol=1e-4)
    return jitter(nearest_rotation(R))


def load_tabb_solution(path) -> np.ndarray:
    """Tabb's published solution ``transformations.txt``: the rotation of ``Z = T_cam<-hand``
    (``R0``)."""
    lines = [ln.split() for ln in read_lines(path)]
    try:
        start = next(i for i, ln in enumerate(lines) if ln and ln[0] == "Z")
        M = np.array([[float(v) for v in lines[start + 1 + r]] for r in range(4)])
    except (StopIteration, ValueError, IndexError):
        fail(path, "no 4x4 matrix after a line starting with 'Z'")
    return _rotation_block(path, M, "Z")


def load_stream(path, kind: str = "orientation", *, time_unit: str = "auto", drop_repeated: bool = False,
                repeated: str = "refuse", tally: dict | None = None):
    """Load a stream by kind and file type.

    ``kind="gyro"``: an EuRoC/TUM-VI ``imu0/data.csv`` (:func:`load_euroc_imu`).
    ``kind="orientation"``: a ``.csv`` is read as EuRoC/TUM-VI mocap or ground truth, 8 or 17
    columns (:func:`load_euroc_mocap`), anything else as a TUM trajectory
    (:func:`load_tum_trajectory`). ``time_unit`` goes to every loader: EuRoC CSVs are in
    nanoseconds by their format (``"auto"``), a CSV written in another unit is read with it.
    ``drop_repeated``, ``repeated`` and ``tally`` go to the loader (:func:`load_tum_trajectory`).
    """
    if kind not in ("gyro", "orientation"):
        raise ValueError(f"kind must be 'gyro' or 'orientation', got {kind!r}")
    if time_unit != "auto" and time_unit not in TIME_UNITS:
        raise ValueError(f"time_unit must be one of {sorted(TIME_UNITS)} or 'auto', got {time_unit!r}")
    euroc = kind == "gyro" or Path(path).suffix.lower() == ".csv"
    common = dict(time_unit=time_unit, drop_repeated=drop_repeated, repeated=repeated, tally=tally)
    if kind == "gyro":
        return load_euroc_imu(path, **common)
    return load_euroc_mocap(path, **common) if euroc else load_tum_trajectory(path, **common)


def load_reference(path, camera: str = "cam0") -> np.ndarray:
    """A reference ``camera_from_sensor`` from a calibration file, its kind recognised from the
    content.

    Kalibr camchains (``<camera>.T_cam_imu``), OpenVINS ``%YAML:1.0`` imu-camera chains
    (``T_imu_cam`` or ``T_cam_imu``), ORB-SLAM3 visual-inertial settings (``IMU.T_b_c1``), Basalt's
    calibration JSON (``value0.T_imu_cam``), EuRoC camera ``sensor.yaml`` files (``T_BS``): see
    :mod:`replication.rig.vioformats`; anything else is read as Tabb's ``transformations.txt`` (a
    ``Z`` matrix).
    """
    from .vioformats import looks_like_vio_file, read_vio_file

    path = Path(path)
    text = read_text(path, "a reference calibration")
    if looks_like_vio_file(path, text):
        return jitter(read_vio_file(path, text).camera_from_sensor(camera))
    return jitter(load_tabb_solution(path))


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
        """``R1`` of ``cv2.stereoRectify``: the rotation from the raw left camera to the rectified
        one.

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
    """Read an ORB-SLAM3 stereo settings file (OpenCV ``FileStorage`` YAML, ``Camera.type:
    "PinHole"``).

    Raises
    ------
    DataFileNotFound
        Missing file (also a ``FileNotFoundError``).
    DataFileError
        A missing or malformed entry (named), a camera type other than PinHole, or a
        ``Stereo.T_c1_c2`` whose rotation is not a rotation.
    """
    import cv2

    path = Path(path)
    read_text(path)  # missing, a directory, not UTF-8 text: the same errors as every loader
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error as err:
        fail(path, f"not an OpenCV FileStorage YAML file ({str(err).strip().splitlines()[-1]})")
    if not fs.isOpened():
        fail(path, "not an OpenCV FileStorage YAML file")
    try:
        def number(key):
            node = fs.getNode(key)
            if node.empty() or not node.isReal() and not node.isInt():
                fail(path, f"entry {key!r} missing or not a number")
            return float(node.real())

        kind = fs.getNode("Camera.type")
        if not kind.empty() and kind.string() != "PinHole":
            fail(path, f"Camera.type is {kind.string()!r}; only 'PinHole' is supported")
        cams = []
        for c in ("Camera1", "Camera2"):
            K = np.array([[number(f"{c}.fx"), 0.0, number(f"{c}.cx")], [0.0, number(f"{c}.fy"), number(f"{c}.cy")],
                          [0.0, 0.0, 1.0]])
            cams.append((K, np.array([number(f"{c}.{k}") for k in ("k1", "k2", "p1", "p2")])))
        size = (int(number("Camera.width")), int(number("Camera.height")))
        T = fs.getNode("Stereo.T_c1_c2").mat()
        if T is None or np.shape(T) != (4, 4):
            fail(path, "entry 'Stereo.T_c1_c2' missing or not a 4x4 matrix")
    finally:
        fs.release()
    T = np.asarray(T, dtype=float)
    R = _rotation(path, T[:3, :3], "Stereo.T_c1_c2 rotation", atol=1e-5)
    return StereoCalibration(cams[0][0], cams[0][1], cams[1][0], cams[1][1], size, R, T[:3, 3], str(path))
