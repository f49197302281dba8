"""Replication suite for Z.-Q. Zhang, "Cameras and Inertial/Magnetic Sensor Units Alignment Calibration".

Modules
-------
so3       rotation validators, SVD projection (eqs. (16)-(17)), noise model, sampling, error metrics
handeye   the rotation-only problem A X = X B of Sec. II: H1/H2/V2H/H2V, the operator K, cost (8)
solvers   the two-step iteration (eqs. (11)-(19)) and the solver registry: solve(), available()
paper     the paper's published numbers (data/paper/), the comparison target only
"""
__version__ = "0.1.0"
