"""Every registered solver on the same Monte Carlo data (``notebooks/06_baselines.ipynb``).

The study varies one setting of :class:`replication.study.simulation.SimulationSettings`
at a time around the paper's simulation (J = 20, ``||v|| < 0.02``, the paper's
``R0``, Haar-random motions) and records, per solver, the error of the
estimate against the true ``R0`` in degrees and the time it took.

Every solver runs with its defaults: the two-step solvers run to their limit
(``iterations="auto"``), so small motions, which slow the iteration down, are not
mistaken for inaccuracy. The warnings a solver issues are recorded, not shown.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
import pandas as pd

from ..core.checks import check_rotation_matrices
from ..core.handeye import handeye_cost
from ..core.so3 import angle_between_deg, random_rotations
from ..core.solvers import ReplicationWarning, available, solve
from ..core.stats import paired_ratio_ci
from .simulation import noise_bound_for_angle_deg, simulate

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


def compare(A, B, R0, *, methods=None, options=None, ratio_to: str | None = None,
            rng: np.random.Generator | None = None, pairs_for: dict | None = None,
            ignore_warnings: tuple = ()) -> pd.DataFrame:
    """Run solvers on the same problems; one row per solver.

    The one study loop over solvers: notebook 06 runs it on Monte Carlo batches, notebook 07
    (:mod:`replication.study.real_study`) on one real recording at a time.

    Parameters
    ----------
    A, B : ndarray, shape (N, J, 3, 3) or (J, 3, 3)
        Camera / sensor relative rotations of ``N`` problems (or of one).
    R0 : array_like, shape (N, 3, 3) or (3, 3)
        True (or reference) ``camera_from_sensor``.
    methods : list of str, optional
        Default: :func:`replication.core.solvers.available`.
    options : dict, optional
        ``{method: {option: value}}`` passed to :func:`replication.core.solvers.solve`.
    ratio_to : str, optional
        A method in ``methods``: adds ``ratio`` (each method's mean error over its mean error, on
        the problems both solved) with a paired bootstrap 95 % interval ``ratio_low``,
        ``ratio_high`` (needs ``rng``).
    rng : numpy.random.Generator, optional
        For the bootstrap.
    pairs_for : dict, optional
        ``{name prefix: (A, B)}``: other pairs for the methods whose name starts with the prefix
        (e.g. the ``opencv_`` solvers, which rebuild a pose chain from consecutive pairs and form
        all its pairs).
    ignore_warnings : tuple of Warning classes
        Warnings left out of the ``warnings`` column (e.g.
        :class:`~replication.core.solvers.ObservabilityWarning`, which concerns the data set, not
        the solver).

    Returns
    -------
    pandas.DataFrame
        Index ``method``; columns ``mean_deg``, ``sd_deg`` (its standard deviation over the
        problems; NaN for one), ``n_solved`` (the problems these statistics are over),
        ``median_deg``, ``p95_deg``, ``max_deg`` (angle to ``R0``), ``mean_cost`` (eq. (8)),
        ``failures`` (problems where OpenCV returned no rotation; they are left out of the error
        statistics), ``warnings`` (the classes of the warnings the call issued, e.g.
        ``LocalMinimumWarning``; empty if none), ``seconds`` (wall time of the call), ``per_s``
        (calibrations per second), ``n_pairs`` (pairs per problem given to the method).
    """
    methods = available() if methods is None else list(methods)
    options = dict(options or {})
    rows, errors = [], {}
    for name in methods:
        opts = dict(options.get(name, {}))
        if name.startswith("opencv_"):
            opts.setdefault("on_failure", "nan")  # count OpenCV's non-rotations instead of stopping
        a, b = next((p for prefix, p in (pairs_for or {}).items() if name.startswith(prefix)), (A, B))
        start = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ReplicationWarning)
            R = solve(name, a, b, **opts)  # each call validates and builds K itself: fair timings
        seconds = time.perf_counter() - start
        issued = sorted({w.category.__name__ for w in caught if issubclass(w.category, ReplicationWarning)
                         and not issubclass(w.category, tuple(ignore_warnings))})
        a, b, R = (np.asarray(x)[None] if np.ndim(a) == 3 else np.asarray(x) for x in (a, b, R))  # one problem
        failed = ~np.isfinite(R).all(axis=(-2, -1))
        ok = ~failed
        err = angle_between_deg(R[ok], np.broadcast_to(R0, R.shape)[ok])
        errors[name] = np.full(ok.shape, np.nan)
        errors[name][ok] = err
        rows.append({
            "method": name,
            "mean_deg": err.mean(),
            "sd_deg": err.std(ddof=1) if len(err) > 1 else np.nan,
            "n_solved": len(err),
            "median_deg": np.median(err),
            "p95_deg": np.percentile(err, 95),
            "max_deg": err.max(),
            "mean_cost": handeye_cost(R[ok], a[ok], b[ok]).mean(),
            "failures": int(failed.sum()),
            "warnings": ", ".join(issued),
            "seconds": seconds,
            "per_s": len(R) / seconds,
            "n_pairs": a.shape[-3],
        })
    table = pd.DataFrame(rows).set_index("method")
    if ratio_to is not None:
        if ratio_to not in errors or rng is None:
            raise ValueError("ratio_to must be one of the methods compared, and rng must be given")
        for name, err in errors.items():
            both = np.isfinite(err) & np.isfinite(errors[ratio_to])
            table.loc[name, ["ratio", "ratio_low", "ratio_high"]] = paired_ratio_ci(
                err[both], errors[ratio_to][both], rng)
    return table


def sweep(parameter: str, values, *, n_runs: int, seed: int, methods=None, options=None,
          outlier_fraction: float = 0.0, ratio_to: str | None = None) -> pd.DataFrame:
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
    ratio_to : str, optional
        See :func:`compare`; the bootstrap of value ``k`` is seeded by ``[seed + k, 2]``.

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
        df = compare(sim.A, B, sim.R0, methods=methods, options=options, ratio_to=ratio_to,
                     rng=np.random.default_rng([seed + k, 2])).reset_index()
        df.insert(0, "value", value)
        df.insert(0, "parameter", parameter)
        frames.append(df)
    return pd.concat(frames, ignore_index=True)
