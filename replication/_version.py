"""The package version, in one place (read by the package face and the calibration report)."""
__version__ = "0.1.0"
