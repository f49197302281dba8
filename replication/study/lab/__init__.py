"""A simulated version of the paper's lab experiment (Sec. III-B, Fig. 6-7, Table II). Theory and
measured numbers: ``docs/studies.md``, section ``replication.study.lab.__init__``."""
import importlib

from .recording import (
    ACC_COLUMNS,
    FILES,
    GYR_COLUMNS,
    IMU_COLUMNS,
    MAG_COLUMNS,
    UNITS,
    LabRecording,
    default_lab_dir,
    load_lab,
    marker_pixels,
    static_hold_seconds,
    write_lab,
)
from .settings import GRAVITY, NOMINAL_CAMERA_FROM_SENSOR, PARTS, SOURCES, TABLE2_SOLVERS, WAND_POINTS, LabSettings

#: Names of the modules that need OpenCV, ``ahrs`` or the solvers, loaded on first use so that
#: reading or writing a recording (:mod:`.recording`) imports none of them.
_LAZY = {
    "simulate_lab": "simulate",
    "camera_orientations": "chain", "static_sensor_orientations": "chain", "dynamic_sensor_orientations": "chain",
    "static_motions": "chain", "LabResult": "chain", "run_lab": "chain", "camera_poses": "chain",
    "refine_camera_orientations": "fastchain", "ecompass_attitudes": "fastchain", "madgwick_marg": "fastchain",
    "summarize": "study", "ablation": "study", "sensitivity": "study", "seed_study": "study", "seed_spread": "study",
    "seed_findings": "study", "count_text": "study", "sqp_shares": "study", "check_sqp_shares": "study",
    "seed_range": "study", "pitch_bias_intervention": "study", "intervention_finding": "study", "RESOLVE_DEG": "study",
    "SeedSets": "seed_sets",
}

__all__ = [
    "GRAVITY", "WAND_POINTS", "NOMINAL_CAMERA_FROM_SENSOR", "SOURCES", "PARTS", "TABLE2_SOLVERS", "LabSettings",
    "LabRecording", "ACC_COLUMNS", "GYR_COLUMNS", "MAG_COLUMNS", "IMU_COLUMNS", "UNITS", "marker_pixels",
    "static_hold_seconds", "FILES", "write_lab", "load_lab", "default_lab_dir", *_LAZY,
]


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
