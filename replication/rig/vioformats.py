"""Camera-IMU calibration files of the VIO ecosystem: read ``R0`` and the clock offset, change them
in a copy. Theory and measured numbers: ``docs/reading.md``, section
``replication.rig.vioformats``."""
from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..core.checks import check_rotation_matrices
from .datafile import QUATERNION_NORM_TOL, fail, read_text_layout

__all__ = ["FORMATS", "VioFile", "read_vio_file", "looks_like_vio_file", "format_number"]

#: The formats :func:`read_vio_file` recognises, and whether a rotation can be written into them.
FORMATS = {"kalibr": True, "openvins": True, "basalt": True, "orbslam3": True, "euroc": False}
_OPENCV_HEADER = re.compile(r"%YAML[: ]1\.0")
_MATRIX_TAG = "tag:yaml.org,2002:opencv-matrix"


def format_number(x: float) -> str:
    """``x`` to 17 significant digits (round-trips exactly), always with a dot: YAML 1.1 reads
    ``1e-05`` as text."""
    if not math.isfinite(x):
        raise ValueError(f"cannot write a non-finite number ({x}) into a calibration file")
    text = repr(float(x))
    if "e" in text and "." not in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _loader():
    import yaml

    class Loader(yaml.SafeLoader):
        """Safe YAML plus OpenCV's ``!!opencv-matrix`` (a mapping rows, cols, dt, data)."""

    def matrix(loader, node):
        m = loader.construct_mapping(node, deep=True)
        return np.asarray(m["data"], dtype=float).reshape(int(m["rows"]), int(m["cols"]))

    Loader.add_constructor(_MATRIX_TAG, matrix)
    return Loader


def _yaml_text(path, text):
    """The text PyYAML can read: OpenCV's ``%YAML:1.0`` header turned into a comment of the same
    length."""
    if _OPENCV_HEADER.match(text):
        return "#" + text[1:]
    return text


@dataclass
class _Span:
    """A scalar's place in the text."""

    start: int
    end: int


def _compose(path, text, json_text: bool = False):
    """PyYAML's node tree, for the spans. JSON is YAML but for tabs as white space: they become
    spaces (a JSON string holds none unescaped, so every index stays where it was)."""
    import yaml

    try:
        return yaml.compose(text.replace("\t", " ") if json_text else text, Loader=_loader())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        fail(path, f"not valid YAML/JSON: {getattr(err, 'problem', err)}",
             line=None if mark is None else mark.line + 1, column=None if mark is None else mark.column + 1)


def _child(node, key):
    """The value node under ``key`` of a mapping node, or None."""
    import yaml

    if not isinstance(node, yaml.MappingNode):
        return None
    for k, v in node.value:
        if isinstance(k, yaml.ScalarNode) and k.value == key:
            return v
    return None


def _span(node) -> _Span:
    return _Span(node.start_mark.index, node.end_mark.index)


class VioFile:
    """One calibration file, its format recognised from its content.

    Use :func:`read_vio_file`. ``camera_from_sensor(camera)`` and ``time_offset_s(camera)`` read it;
    ``with_values(camera, R0, d)`` returns the text of a copy with only those values changed.
    """

    def __init__(self, path, text: str, newline: str = "\n", bom: bool = False):
        self.path = Path(path) if not isinstance(path, Path) else path
        self.text, self.newline, self.bom = text, newline, bom
        self.opencv = bool(_OPENCV_HEADER.match(text))
        self.json = text.lstrip().startswith("{")
        yaml_text = _yaml_text(path, text)
        self._root = _compose(path, yaml_text, self.json)
        self._shared = _checked_tree(self.path, self._root)
        if self.json:
            try:
                self.doc = json.loads(text)
            except json.JSONDecodeError as err:
                fail(path, f"not valid JSON: {err.msg}", line=err.lineno, column=err.colno)
        else:
            import yaml

            try:
                self.doc = yaml.load(yaml_text, Loader=_loader())  # noqa: S506 (a SafeLoader subclass)
            except (yaml.YAMLError, KeyError, TypeError, ValueError) as err:
                fail(path, f"not a readable calibration file: {err}")
        self.unread = None  # why the tool would not read the entry this file is edited in, if it would not
        self.unwritable = None  # why a rotation cannot be written into it, if it cannot
        self.format = self._recognise()

    # -- recognising
    # -------------------------------------------------------------------------------------------
    def _recognise(self) -> str:
        doc = self.doc
        if not isinstance(doc, dict):
            fail(self.path, "not a calibration file: its top level is not a mapping")
        if self.json:
            if isinstance(doc.get("value0"), dict) and "T_imu_cam" in doc["value0"]:
                return "basalt"
            fail(self.path, "a JSON file without value0.T_imu_cam: not a Basalt calibration")
        if "IMU.T_b_c1" in doc or "Tbc" in doc:
            self._orbslam3_key = self._orbslam3_entry()
            return "orbslam3"
        if "T_BS" in doc:
            if doc.get("sensor_type") != "camera":
                fail(self.path, f"an EuRoC sensor.yaml of sensor_type {doc.get('sensor_type')!r}, not 'camera': its "
                                "T_BS is not a camera-IMU extrinsic")
            return "euroc"
        cams = [str(k) for k, v in doc.items() if isinstance(v, dict) and ("T_cam_imu" in v or "T_imu_cam" in v)]
        if cams:  # Kalibr writes T_cam_imu only, and no %YAML header
            if self.opencv or any("T_imu_cam" in doc[k] for k in doc if str(k) in cams):
                if not self.opencv:
                    self.unread = ("no %YAML:1.0 header: OpenVINS reads its files with cv::FileStorage, which "
                                   "needs it")
                return "openvins"
            return "kalibr"
        if any(str(k).startswith(("Camera.", "Camera1.", "ORBextractor.")) for k in doc):
            fail(self.path, "ORB-SLAM3 settings without IMU.T_b_c1: a vision-only configuration (ORB-SLAM3's "
                            "Monocular-Inertial / Stereo-Inertial settings carry the camera-IMU extrinsic)")
        fail(self.path, "no camera-IMU extrinsic found: expected <camera>.T_cam_imu or T_imu_cam (Kalibr, OpenVINS), "
                        "IMU.T_b_c1 (ORB-SLAM3), T_BS (EuRoC) or value0.T_imu_cam (Basalt JSON)")

    def _orbslam3_entry(self) -> str:
        """The key ORB-SLAM3 reads the extrinsic from: ``IMU.T_b_c1`` with ``File.version: "1.0"``
        (a string), else its legacy ``Tbc`` (``System.cc``)."""
        version = _child(self._root, "File.version")
        versioned = version is not None and version.value == "1.0" and version.style in ('"', "'")
        if versioned:
            if "IMU.T_b_c1" not in self.doc:
                fail(self.path, 'File.version "1.0" without IMU.T_b_c1: ORB-SLAM3 reads the extrinsic from '
                                "IMU.T_b_c1 in these files, not from the legacy Tbc")
            return "IMU.T_b_c1"
        if "Tbc" in self.doc:
            return "Tbc"
        self.unread = ('no File.version: "1.0" (a quoted string): ORB-SLAM3 then reads the legacy keys (Tbc), not '
                       "IMU.T_b_c1")
        return "IMU.T_b_c1"

    def cameras(self) -> list[str]:
        """The camera names this file holds (``cam0``, ``cam1``, ...)."""
        if self.format in ("kalibr", "openvins"):
            return [str(k) for k, v in self.doc.items()
                    if isinstance(v, dict) and ("T_cam_imu" in v or "T_imu_cam" in v)]
        if self.format == "basalt":
            return [f"cam{i}" for i in range(len(self.doc["value0"]["T_imu_cam"]))]
        return ["cam0"]

    def _check_camera(self, camera):
        if camera not in self.cameras():
            only = {"orbslam3": " (ORB-SLAM3's extrinsic is camera 1's: use cam0)"}.get(self.format, "")
            fail(self.path, f"no camera {camera!r} in this {self.format} file; it has "
                            f"{', '.join(self.cameras())}{only}")

    # -- the rotation
    # --------------------------------------------------------------------------------------------
    def _matrix_nodes(self, camera):
        """``(key, transposed, nine scalar nodes in row-major order, the translation's three)`` of
        the camera's extrinsic."""
        import yaml

        self._check_camera(camera)
        if self.format == "basalt":
            raise AssertionError("Basalt stores a quaternion")
        if self.format in ("kalibr", "openvins"):
            cam = _child(self._root, camera)
            if _child(cam, "<<") is not None:
                fail(self.path, f"{camera} uses a YAML merge key (<<): write its entries out in full")
            # OpenVINS reads T_imu_cam and falls back to T_cam_imu; Kalibr reads T_cam_imu
            keys = ("T_imu_cam", "T_cam_imu") if self.format == "openvins" else ("T_cam_imu",)
            key = next(k for k in keys if _child(cam, k) is not None)
            node, transposed, name = _child(cam, key), key == "T_imu_cam", f"{camera}.{key}"
        else:
            key = self._orbslam3_key if self.format == "orbslam3" else "T_BS"
            node, transposed, name = _child(self._root, key), True, key
        nine, rows, three = [], [], []
        if isinstance(node, yaml.MappingNode):  # !!opencv-matrix or EuRoC's rows / cols / data
            data, shape = _child(node, "data"), [_child(node, k) for k in ("rows", "cols")]
            scalars = data.value if isinstance(data, yaml.SequenceNode) else []
            if [getattr(n, "value", None) for n in shape] == ["4", "4"] and len(scalars) == 16:
                nine, rows = [scalars[r * 4 + c] for r in range(3) for c in range(3)], [data]
                three = [scalars[r * 4 + 3] for r in range(3)]
            kind = _child(node, "dt")
            if kind is not None and kind.value not in ("f", "d"):
                self.unwritable = f"{name} has dt: {kind.value} (not f or d): a rotation cannot be written into it"
        elif isinstance(node, yaml.SequenceNode) and len(node.value) == 4 and all(
                isinstance(row, yaml.SequenceNode) and len(row.value) == 4 for row in node.value):
            nine, rows = [node.value[r].value[c] for r in range(3) for c in range(3)], node.value
            three = [node.value[r].value[3] for r in range(3)]
        if len(nine) != 9 or not all(isinstance(x, yaml.ScalarNode) for x in nine + three):
            fail(self.path, f"{name} is not a 4x4 matrix (4 lists of 4 numbers, or rows: 4, cols: 4 and 16 data)")
        self._not_shared([node, *rows], nine + three, name)
        return key, transposed, nine, three

    def _quaternion_nodes(self, camera):
        self._check_camera(camera)
        index = int(camera[3:])
        entry = self._root_value0("T_imu_cam").value[index]
        nodes = [_child(entry, k) for k in ("qx", "qy", "qz", "qw")]
        if any(n is None for n in nodes):
            fail(self.path, f"value0.T_imu_cam[{index}] has no qx, qy, qz, qw")
        self._not_shared([entry], nodes, f"value0.T_imu_cam[{index}]")
        return nodes

    def _not_shared(self, containers, scalars, what):
        """Refuse to edit an entry that a YAML alias (``*name``) also stands for elsewhere: one edit
        would change both."""
        if any(id(n) in self._shared for n in [*containers, *scalars] if n is not None):
            fail(self.path, f"{what} is shared with another entry through a YAML anchor and alias (&, *): changing it "
                            "would change both; write it out in full")

    def _root_value0(self, key):
        node = _child(_child(self._root, "value0"), key)
        if node is None:
            fail(self.path, f"no value0.{key}")
        return node

    def camera_from_sensor(self, camera: str = "cam0") -> np.ndarray:
        """``R0`` (``camera_from_sensor``) as this file states it for ``camera``, checked to be a
        rotation."""
        self._check_camera(camera)
        if self.format == "basalt":
            from scipy.spatial.transform import Rotation

            try:
                q = np.array([float(n.value) for n in self._quaternion_nodes(camera)])
            except ValueError:
                fail(self.path, f"value0.T_imu_cam[{camera[3:]}] has a quaternion entry that is not a number")
            if not np.all(np.isfinite(q)) or abs(np.linalg.norm(q) - 1) > QUATERNION_NORM_TOL:
                fail(self.path, f"value0.T_imu_cam[{camera[3:]}] quaternion has norm {np.linalg.norm(q):.9g}, not "
                                f"within {QUATERNION_NORM_TOL:g} of 1")
            return Rotation.from_quat(q / np.linalg.norm(q)).as_matrix().T  # T_imu_cam's rotation: imu_from_camera
        key, transposed, nine, _ = self._matrix_nodes(camera)
        try:
            M = np.array([float(n.value) for n in nine]).reshape(3, 3)
        except ValueError:
            fail(self.path, f"{key} has an entry that is not a number")
        try:
            named = f"{camera}.{key}" if self.format in ("kalibr", "openvins") else key
            M = check_rotation_matrices(M, f"rotation part of {named}", atol=1e-5)
        except ValueError as err:
            fail(self.path, str(err))
        return M.T if transposed else M

    # -- the clock offset
    # -----------------------------------------------------------------------------------------
    def _offset_node(self, camera):
        self._check_camera(camera)
        if self.format in ("kalibr", "openvins"):
            return _child(_child(self._root, self._offset_camera(camera)), "timeshift_cam_imu"), 1.0
        if self.format == "basalt":
            return _child(_child(self._root, "value0"), "cam_time_offset_ns"), 1e-9
        return None, None

    def _offset_camera(self, camera):
        """The camera whose entry holds the offset: OpenVINS reads one, cam0's, for every camera."""
        return "cam0" if self.format == "openvins" and "cam0" in self.cameras() else camera

    def time_offset_s(self, camera: str = "cam0") -> float | None:
        """``d`` (``t_imu = t_cam + d``, seconds) as this file states it; None if the file has no
        such field."""
        node, scale = self._offset_node(camera)
        if node is None:
            return None
        try:
            return float(node.value) * scale
        except ValueError:
            fail(self.path, f"the time offset {node.value!r} is not a number", line=node.start_mark.line + 1)

    # -- the rig: positions
    # ---------------------------------------------------------------------------------------
    def _translation(self, camera):
        """``(stored as T_imu_cam, the three numbers as stored, their nodes)``: the camera's
        position in the IMU frame (``T_imu_cam``, Basalt) or the IMU's in the camera frame
        (``T_cam_imu``)."""
        if self.format == "basalt":
            entry = self._root_value0("T_imu_cam").value[int(camera[3:])]
            nodes, transposed = [_child(entry, k) for k in ("px", "py", "pz")], True
            if any(n is None for n in nodes):
                fail(self.path, f"value0.T_imu_cam[{camera[3:]}] has no px, py, pz")
        else:
            key, transposed, _, nodes = self._matrix_nodes(camera)
        try:
            return transposed, np.array([float(n.value) for n in nodes]), nodes
        except ValueError:
            fail(self.path, f"{camera}'s translation has an entry that is not a number")

    def camera_position(self, camera: str = "cam0") -> np.ndarray:
        """Where ``camera`` is in the IMU frame (metres), from its translation as this file states
        it."""
        transposed, t, _ = self._translation(camera)
        return t if transposed else -self.camera_from_sensor(camera).T @ t

    # -- writing
    # ----------------------------------------------------------------------------------------------
    def with_values(self, camera: str, R0, time_offset_s: float | None, whole_rig: bool = True):
        """The text of a copy with ``camera``'s rotation set to ``R0`` and, if given and the format
        has a field for it, the clock offset set to ``time_offset_s``; the names of the fields
        changed, and of those added.

        ``whole_rig``: the other cameras turn with ``camera`` (each ``R_i`` becomes ``R_i C`` with
        the correction ``C = R_old^T R0``), their positions in the IMU frame with them, and Kalibr's
        other per-camera clock offsets move by the same amount, so that every camera-camera
        transform (Kalibr's ``T_cn_cnm1`` too) stays as it was. The edited camera's translation is
        kept as stored."""
        if not FORMATS[self.format]:
            fail(self.path, f"{self.format} files are read as references only, not written")
        self._check_camera(camera)
        R0 = check_rotation_matrices(np.asarray(R0, dtype=float), "R0")
        others = [c for c in self.cameras() if c != camera] if whole_rig else []
        C = self.camera_from_sensor(camera).T @ R0 if others else np.eye(3)
        edits, changed, added = [], [], []
        for cam in [camera, *others]:
            rotation = R0 if cam == camera else self.camera_from_sensor(cam) @ C
            edits += self._rotation_edits(cam, rotation, changed)
        if others:
            edits += self._position_edits(camera, others, C, changed)
        if time_offset_s is not None and self.format != "orbslam3":
            edits += self._offset_edits(camera, others, time_offset_s, changed, added)
        text = self.text
        for span, value in sorted(edits, key=lambda e: e[0].start, reverse=True):
            text = text[:span.start] + value + text[span.end:]
        if self.newline != "\n":
            text = text.replace("\n", self.newline)
        return ("\ufeff" if self.bom else "") + text, changed, added

    def _rotation_edits(self, camera, R, changed):
        if self.format == "basalt":
            from scipy.spatial.transform import Rotation

            nodes = self._quaternion_nodes(camera)
            old = np.array([float(n.value) for n in nodes])
            q = Rotation.from_matrix(R.T).as_quat()
            q = -q if np.dot(q, old) < 0 else q  # the hemisphere of the file's own quaternion
            changed.append(f"value0.T_imu_cam[{camera[3:]}].qx..qw")
            return [(_span(n), format_number(v)) for n, v in zip(nodes, q)]
        key, transposed, nine, _ = self._matrix_nodes(camera)
        if self.unwritable:
            fail(self.path, self.unwritable)
        changed.append(f"{camera}.{key} rotation" if self.format in ("kalibr", "openvins") else f"{key} rotation")
        return [(_span(n), format_number(v)) for n, v in zip(nine, (R.T if transposed else R).ravel())]

    def _position_edits(self, camera, others, C, changed):
        """The other cameras' translations such that each one's transform to ``camera`` is kept:
        positions in the IMU frame ``p_i -> p_c' + C^T (p_i - p_c)``. Stored as ``T_cam_imu`` next
        to a ``T_cam_imu`` anchor they are unchanged (``t_i`` is the IMU's position in camera
        ``i``): left as written."""
        anchor_imu_cam, _, _ = self._translation(camera)
        p_c = self.camera_position(camera)
        p_c_new = p_c if anchor_imu_cam else C.T @ p_c  # the anchor keeps its stored numbers
        edits = []
        for cam in others:
            imu_cam, _, nodes = self._translation(cam)
            if not imu_cam and not anchor_imu_cam:
                continue
            p_new = p_c_new + C.T @ (self.camera_position(cam) - p_c)
            value = p_new if imu_cam else -(self.camera_from_sensor(cam) @ C) @ p_new
            edits += [(_span(n), format_number(v)) for n, v in zip(nodes, value)]
            changed.append(f"value0.T_imu_cam[{cam[3:]}].px..pz" if self.format == "basalt"
                           else f"{cam}.{'T_imu_cam' if imu_cam else 'T_cam_imu'} translation")
        return edits

    def _offset_edits(self, camera, others, time_offset_s, changed, added):
        where = self._offset_camera(camera)
        node, scale = self._offset_node(camera)
        ns = int(round(time_offset_s * 1e9))  # to the nanosecond, Basalt's unit: finer is noise
        value = str(ns) if self.format == "basalt" else format_number(ns * 1e-9)
        name = "value0.cam_time_offset_ns" if self.format == "basalt" else f"{where}.timeshift_cam_imu"
        if node is not None:
            self._not_shared([], [node], "the time offset")
            edits, old = [(_span(node), value)], self.time_offset_s(camera)
            changed.append(name)
        elif self.format == "basalt":
            fail(self.path, "no value0.cam_time_offset_ns to set")
        else:
            edits, old = [self._insertion(where, f"timeshift_cam_imu: {value}")], 0.0
            added.append(name)
        if self.format == "kalibr" and node is not None:  # one offset per camera: the others move with it (by how
            for cam in others:                                 # much is unknown where the camera had none: kept)
                other, _ = self._offset_node(cam)
                if other is not None:
                    self._not_shared([], [other], "the time offset")
                    edits.append((_span(other), format_number(self.time_offset_s(cam) + ns * 1e-9 - old)))
                    changed.append(f"{cam}.timeshift_cam_imu")
        return edits

    def _insertion(self, camera, line):
        """An edit that adds ``line`` as the camera mapping's first key, at its indentation (block
        style only)."""
        cam = _child(self._root, camera)
        if cam.flow_style:
            fail(self.path, f"{camera} is written in flow style: add timeshift_cam_imu by hand")
        first = cam.value[0][0].start_mark
        start = first.index - first.column
        return _Span(start, start), " " * first.column + line + "\n"


def _checked_tree(path, root) -> set:
    """``id`` of every node reached more than once (through an alias) from ``root``; a mapping with
    a key twice is refused, naming its line (readers differ on which one counts: PyYAML and Kalibr
    take the last)."""
    import yaml

    seen, shared, stack = set(), set(), [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            shared.add(id(node))
            continue
        seen.add(id(node))
        if isinstance(node, yaml.MappingNode):
            keys = {}
            for k, _ in node.value:
                if isinstance(k, yaml.ScalarNode) and k.value != "<<":
                    if k.value in keys:
                        line = k.start_mark.line + 1
                        fail(path, f"the key {k.value!r} appears twice in one mapping (lines {keys[k.value]} and "
                                   f"{line}): readers disagree on which counts", line=line)
                    keys[k.value] = k.start_mark.line + 1
        value = getattr(node, "value", None)
        if isinstance(value, list):
            for item in value:
                stack.extend(item if isinstance(item, tuple) else (item,))
    return shared


def looks_like_vio_file(path, text: str) -> bool:
    """Whether ``text`` (the content of ``path``) is to be read as YAML or JSON: a ``.yaml``,
    ``.yml`` or ``.json`` name, an OpenCV ``%YAML`` header, or a JSON object."""
    stripped = text.lstrip()
    if Path(path).suffix.lower() in (".yaml", ".yml", ".json") or stripped.startswith(("%YAML", "{")):
        return True
    first = next((ln for ln in text.split("\n") if ln.strip() and not ln.lstrip().startswith("#")), "")
    return bool(re.match(r"""\s*[\w."'-]+\s*:(\s|$)""", first))  # a YAML key; Tabb's file starts "X"


def read_vio_file(path, text: str | None = None) -> VioFile:
    """Read a calibration file of any format in :data:`FORMATS` (recognised by content, not by
    name).

    ``text``: the file's content when already read (a pipe can be read once)."""
    if text is not None:
        return VioFile(path, text)
    return VioFile(path, *read_text_layout(path, "a calibration file"))
