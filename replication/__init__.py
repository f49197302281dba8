"""Replication suite for Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment Calibration".

Modules
-------
so3       rotation validators, SVD projection (eqs. (16)-(17)), noise model, sampling, error metrics
handeye   the rotation-only problem A X = X B of Sec. II: H1/H2/V2H/H2V, the operator K, cost (8)
solvers   the solver registry (solve(), available()): the two-step iteration (eqs. (11)-(19)), SQP,
          classic baselines, the exact minimiser of eq. (8), robust and OpenCV solvers
baselines every registered solver on the same Monte Carlo data (notebook 06)
realdata  loaders of real recordings (TUM, EuRoC/TUM-VI, Kalibr, Tabb) and their reference rotations
calibration  calibrate(): R0 of a real rig from two timestamped streams (also ``replication.calibrate``)
paper     the paper's published numbers (data/paper/), the comparison target only
"""
__version__ = "0.1.0"

from .calibration import calibrate  # noqa: E402  (the one entry point users need first)
