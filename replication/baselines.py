"""Every registered solver on the same Monte Carlo data (``notebooks/06_baselines.ipynb``).

The study varies one setting of :class:`replication.simulation.SimulationSettings`
at a time around the paper's simulation (J = 20, ``||v|| < 0.02``, the paper's
``R0``, Haar-random motions) and records, per solver, the error of the
estimate against the true ``R0`` in degrees and the time it took.

The two-step solvers are run until they reach their fixed point: the number of
iterations comes from the motions' observability
(:func:`replication.solvers.two_step_iterations`), so small
motions, which slow the iteration down, are not mistaken for inaccuracy.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
import pandas as pd

from .handeye import handeye_cost
from .simulation import noise_bound_for_angle_deg, simulate
from .so3 import angle_between_deg, check_rotation_matrices, random_rotations
from .solvers import ConvergenceWarning, available, solve, two_step_fixed_point, two_step_iterations

__all__ = ["corrupt_pairs", "compare", "sweep", "SWEEPS"]

#: The settings a sweep can vary, and how a value maps to simulation overrides.
SWEEPS = {
    "noise_deg": lambda v: {"noise_camera": noise_bound_for_angle_deg(v),
                            "noise_sensor": noise_bound_for_angle_deg(v)},
    "n_motions": lambda v: {"n_motions": int(v)},
    "motion_amplitude_deg": lambda v: {"motion_angle_range_deg": (0.0, float(v))},
    "outlier_fraction": lambda v: {},
}


def corrupt_pairs(B, fraction: float, rng: np.random.Generator):
    """Replace a random ``fraction`` of the sensor rotations by unrelated (Haar-random) rotations.

    Models outlier pairs: camera and sensor rotations that do not describe the
    same motion (mismatched time stamps, a wrong PnP solution).

    Parameters
    ----------
    B : array_like, shape (..., J, 3, 3)
    fraction : float in [0, 1)
        Probability that a pair is corrupted (independently per pair).
    rng : numpy.random.Generator

    Returns
    -------
    (B_corrupted, outlier) : ndarray (..., J, 3, 3), bool ndarray (..., J)
    """
    if not 0.0 <= fraction < 1.0:
        raise ValueError(f"fraction must be in [0, 1), got {fraction!r}")
    B = check_rotation_matrices(B, "B").copy()
    outlier = rng.random(B.shape[:-2]) < fraction
    B[outlier] = random_rotations(rng, int(outlier.sum()))
    return B, outlier


def compare(A, B, R0, *, methods=None, options=None) -> pd.DataFrame:
    """Run solvers on the same problems; one row per solver.

    Parameters
    ----------
    A, B : ndarray, shape (N, J, 3, 3)
        Camera / sensor relative rotations of ``N`` problems.
    R0 : array_like, shape (N, 3, 3) or (3, 3)
        True ``camera_from_sensor``.
    methods : list of str, optional
        Default: :func:`replication.solvers.available`.
    options : dict, optional
        ``{method: {option: value}}`` passed to :func:`replication.solvers.solve`.
        The two-step solvers default to
        :func:`replication.solvers.two_step_iterations`.

    Returns
    -------
    pandas.DataFrame
        Index ``method``; columns ``mean_deg``, ``median_deg``, ``p95_deg``,
        ``max_deg`` (angle to ``R0``), ``mean_cost`` (eq. (8)), ``failures``
        (problems where OpenCV returned no rotation; they are left out of the
        error statistics), ``unconverged`` (two-step problems more than 1e-3 deg
        from the fixed point after the iterations given), ``seconds`` (wall time of the call), ``per_s``
        (calibrations per second).
    """
    methods = available() if methods is None else list(methods)
    options = dict(options or {})
    n_it = two_step_iterations(A, B)
    rows = []
    for name in methods:
        opts = dict(options.get(name, {}))
        if name.startswith("two_step"):
            opts.setdefault("iterations", n_it)
        if name.startswith("opencv_"):
            opts.setdefault("on_failure", "nan")  # count OpenCV's non-rotations instead of stopping
        start = time.perf_counter()
        with warnings.catch_warnings():
            # counted below instead: problems where the two-step method is still off its fixed point
            warnings.simplefilter("ignore", ConvergenceWarning)
            R = solve(name, A, B, **opts)
        seconds = time.perf_counter() - start
        unconverged = 0
        if name.startswith("two_step"):
            fixed = two_step_fixed_point(A, B)[0 if name.endswith("right") else 1]
            unconverged = int(np.sum(angle_between_deg(R, fixed) > 1e-3))
        failed = ~np.isfinite(R).all(axis=(-2, -1))
        ok = ~failed
        err = angle_between_deg(R[ok], np.broadcast_to(R0, R.shape)[ok])
        rows.append({
            "method": name,
            "mean_deg": err.mean(),
            "median_deg": np.median(err),
            "p95_deg": np.percentile(err, 95),
            "max_deg": err.max(),
            "mean_cost": handeye_cost(R[ok], A[ok], B[ok]).mean(),
            "failures": int(failed.sum()),
            "unconverged": unconverged,
            "seconds": seconds,
            "per_s": len(R) / seconds,
        })
    return pd.DataFrame(rows).set_index("method")


def sweep(parameter: str, values, *, n_runs: int, seed: int, methods=None, options=None,
          outlier_fraction: float = 0.0) -> pd.DataFrame:
    """:func:`compare` at each value of one setting; a long table.

    Parameters
    ----------
    parameter : str
        A key of :data:`SWEEPS`: ``"noise_deg"`` (bound on the noise angle on both
        sides), ``"n_motions"`` (J), ``"motion_amplitude_deg"`` (motion angles
        uniform in ``[0, value]``), ``"outlier_fraction"``.
    values : sequence
    n_runs : int
        Problems per value.
    seed : int
        Value ``k`` uses seed ``seed + k`` for the simulation (and the outliers).
    methods, options
        See :func:`compare`.
    outlier_fraction : float
        Fraction of corrupted pairs when ``parameter`` is not ``"outlier_fraction"``.

    Returns
    -------
    pandas.DataFrame
        Columns ``parameter``, ``value``, ``method`` and those of :func:`compare`.
    """
    if parameter not in SWEEPS:
        raise ValueError(f"unknown sweep parameter {parameter!r}; choose from {', '.join(SWEEPS)}")
    frames = []
    for k, value in enumerate(values):
        sim = simulate(seed + k, n_runs, **SWEEPS[parameter](value))
        fraction = float(value) if parameter == "outlier_fraction" else outlier_fraction
        B = sim.B
        if fraction > 0:
            B, _ = corrupt_pairs(B, fraction, np.random.default_rng([seed + k, 1]))
        df = compare(sim.A, B, sim.R0, methods=methods, options=options).reset_index()
        df.insert(0, "value", value)
        df.insert(0, "parameter", parameter)
        frames.append(df)
    return pd.concat(frames, ignore_index=True)
