"""A simulated version of the paper's lab experiment (Sec. III-B, Fig. 6-7, Table II).

The paper's recordings (a BSN node on a robot's top camera, a 9-marker calibration wand)
are not public. This package simulates that lab from first principles, so that the full
chain of the experiment runs from raw data. One module per job:

============  ==========================================================================
settings      :class:`LabSettings` (every setting, its default and the reason for it),
              the error sources (:data:`SOURCES`, :data:`PARTS`), Table II's solvers
simulate      :func:`simulate_lab`: camera + wand (``cv2.projectPoints``), IMU with
              datasheet-sized errors, the static protocol and the dynamic trial
recording     :class:`LabRecording`, its columns and units; :func:`write_lab` /
              :func:`load_lab` (the files of ``data/lab/``, validated on load)
chain         the processing chain: PnP, ``ecompass`` / Madgwick, motions (eqs. (3)-(4)),
              one solve per data set, the dynamic trial (:func:`run_lab`)
fastchain     the seed studies' faster equivalents of chain steps: :func:`refine_camera_orientations`
              (PnP on many frames at once), :func:`ecompass_attitudes`, :func:`madgwick_marg`
study         :func:`summarize`, :func:`ablation`, :func:`sensitivity`, :func:`seed_study`,
              :func:`seed_spread`, :func:`seed_findings` (counts with Wilson intervals, means
              with standard errors), :func:`count_text`, :func:`sqp_shares`, :func:`seed_range`,
              :func:`pitch_bias_intervention`, :func:`intervention_finding` (one part switched off, many seeds)
seed_sets     :class:`SeedSets`: the seed study on the seeds of its findings and on fresh ones, in the
              ledger's words
claims        one function per claim of the lab (``lab_averaging``, ...): each checks its numbers and returns
              its ledger record, called from the notebook cell that measures them
============  ==========================================================================

Table II's statistics and its comparison with the paper live beside Table I's in
:mod:`replication.study.table2`. Frames and conventions: ``docs/conventions.md``.
"""
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

#: Names of the modules that need OpenCV, ``ahrs`` or the solvers, loaded on first use so that reading or writing a
#: recording (:mod:`.recording`) imports none of them.
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
