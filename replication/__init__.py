"""Replication suite for Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment
Calibration".

Three rooms (the book's "Layout", ``docs/layout.md``): :mod:`replication.core` (rotations, the
hand-eye operator, the solvers), :mod:`replication.rig` (calibrating a real rig: streams, loaders,
``calibrate``, its verdict, report and online estimator) and :mod:`replication.study` (the paper's
replication, one support module per notebook). The public names below are the package's API; each is
loaded on first use, so ``import replication`` stays light. Conventions: ``docs/conventions.md``.

>>> from replication import calibrate, solve
>>> callable(calibrate) and callable(solve)
True
"""
import importlib

from ._version import __version__

#: Public name -> the module that defines it (loaded on first use).
_PUBLIC = {
    # calibrating a rig
    "calibrate": "rig.calibration", "calibrate_poses": "rig.poses", "CalibrationResult": "rig.report",
    "Verdict": "rig.quality", "OrientationStream": "rig.streams", "GyroStream": "rig.streams",
    "load_stream": "rig.realdata", "load_reference": "rig.realdata",
    "OnlineCalibrator": "rig.online", "LiveRig": "rig.live", "replay": "rig.live",
    # solving A X = X B
    "solve": "core.solvers", "available": "core.solvers", "solver_info": "core.solvers", "register": "core.solvers",
    "ReplicationWarning": "core.solvers",
}

__all__ = [*_PUBLIC, "__version__"]


def __getattr__(name):
    if name in _PUBLIC:
        return getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_PUBLIC))
