"""Replication suite for Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment Calibration".

The package face is light: ``import replication.so3`` loads NumPy and SciPy's rotations only;
:func:`calibrate` (and with it the solvers) is imported on first use. The modules, layer by
layer, and where to change what: README's "Layout". Conventions: ``docs/conventions.md``.
"""
__version__ = "0.1.0"

__all__ = ["calibrate", "__version__"]


def __getattr__(name):
    if name == "calibrate":  # the one entry point users need first, loaded on first use
        from .calibration import calibrate

        return calibrate
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
