"""Other answers against the certified minimiser of (8): the certificate under outlier pairs and
Newton from the relaxed start alone (notebook 06, section 4), and the two-step estimates after a
number of iterations (notebook 01, section 3d)."""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from ...core.handeye import handeye_cost
from ...core.so3 import angle_between_deg
from ...core.solvers import WEAK_GAP_FACTOR, ReplicationWarning, chordal_optimal, two_step
from ..baselines import corrupt_pairs
from ..simulation import simulate
from .starts import NONGLOBAL_TOL

__all__ = ["OUTLIER_CONFIGS", "outlier_certificate_study", "fixed_point_against_minimiser"]

#: The certificate study under outlier pairs: ``(J, outlier fraction)`` per row.
OUTLIER_CONFIGS = ((3, 0.2), (3, 0.4), (5, 0.2), (5, 0.4), (10, 0.3), (20, 0.4))


def outlier_certificate_study(seed: int, n_runs: int, configs=OUTLIER_CONFIGS) -> pd.DataFrame:
    """The certificate under outlier pairs, and Newton from the relaxed start alone, per ``(J,
    fraction)``.

    Problems ``simulate(seed + 900 + J, n_runs, n_motions=J)``, the fraction of corrupted pairs
    drawn by ``default_rng(seed + J)`` (:func:`corrupt_pairs`). The solvers' warnings (outlier
    problems are poorly determined) are counted per problem, not shown.

    Returns
    -------
    pandas.DataFrame
        Index ``(J, outlier fraction)``; columns ``problems``, ``reported poorly determined``,
        ``certified global``, ``needed the relaxation``, ``relaxation tight (certified by it)``,
        ``Newton alone on a non-global minimum``, ``of them strict`` (strict local minima: gradient
        zero, Hessian positive definite), ``their excess cost (max, %)``, ``their angle to the
        global minimiser (min deg)`` (``inf`` where there are none).
    """
    rows = {}
    for J, fraction in configs:
        sim = simulate(seed + 900 + J, n_runs, n_motions=J)
        B, _ = corrupt_pairs(sim.B, fraction, np.random.default_rng(seed + J))
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always", ReplicationWarning)
            full = chordal_optimal(sim.A, B)
            newton = chordal_optimal(sim.A, B, certify=False)  # Newton from the relaxed start alone
        obs = full.observability
        stuck = newton.cost > full.cost + NONGLOBAL_TOL * J
        rows[(J, fraction)] = {
            "problems": n_runs,
            "reported poorly determined": int(np.sum(obs.symmetric_gap < WEAK_GAP_FACTOR * obs.inconsistency)),
            "certified global": int(full.global_optimum.sum()),
            "needed the relaxation": int(full.sdp_used.sum()),
            "relaxation tight (certified by it)": int((full.certificate == "sdp").sum()),
            "Newton alone on a non-global minimum": int(stuck.sum()),
            "of them strict": int(newton.local_minimum[stuck].sum()),
            "their excess cost (max, %)": float(100 * np.max((newton.cost - full.cost)[stuck] / full.cost[stuck],
                                                             initial=0.0)),
            "their angle to the global minimiser (min deg)": float(np.min(angle_between_deg(newton.R, full.R)[stuck],
                                                                          initial=np.inf)),
        }
    table = pd.DataFrame(rows).T
    table.index.names = ["J", "outlier fraction"]
    return table


def fixed_point_against_minimiser(A, B, R0, *, iterations: int = 50) -> pd.DataFrame:
    """The two-step estimates after ``iterations`` against the certified minimiser of (8), one row
    per problem.

    Columns ``excess cost R^r``, ``excess cost R^l`` (eq. (8) at the estimate minus the certified
    minimum), ``angle R^r``, ``angle R^l``, ``angle minimiser`` (degrees to ``R0``), ``certified``.
    """
    res = two_step(A, B, iterations=iterations)
    best = chordal_optimal(A, B)
    return pd.DataFrame({
        "excess cost R^r": handeye_cost(res.R, A, B) - best.cost,
        "excess cost R^l": handeye_cost(res.history.R_left, A, B) - best.cost,
        "angle R^r": angle_between_deg(res.R, R0), "angle R^l": angle_between_deg(res.history.R_left, R0),
        "angle minimiser": angle_between_deg(best.R, R0), "certified": best.global_optimum,
    })
