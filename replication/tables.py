"""Table I machinery: per-iteration errors of each method, the table, and the comparison with the paper."""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import paper
from .simulation import SimulatedProblems
from .so3 import frobenius_error
from .solvers import sqp, two_step

__all__ = ["iterate_errors", "table1", "versus_paper"]


def iterate_errors(problems: SimulatedProblems, *, iterations: int = 50, init=None,
                   with_sqp: bool = True) -> dict:
    """``||R_hat_n - R0||_F`` at every iteration ``n`` of each method, as in Table I.

    Parameters
    ----------
    problems : SimulatedProblems
    iterations : int
        Iterations of the two-step method and SQP's ``max_iterations``.
    init : None or array_like, shape (3, 3) or (n_runs, 3, 3)
        Start of both methods (``None``: identity).
    with_sqp : bool
        Include SQP (``"optimization"``); its *raw* iterates are scored, like the paper's column,
        whose iteration-2 mean (3.488) exceeds the largest distance between two rotations.

    Returns
    -------
    dict
        ``{"optimization"?, "ours_right", "ours_left"}`` -> ndarray of shape (n_runs, iterations).
    """
    R0 = problems.R0[:, None]
    ours = two_step(problems.A, problems.B, iterations=iterations, init=init)
    errors = {}
    if with_sqp:
        opt = sqp(problems.A, problems.B, max_iterations=iterations, init=init)
        errors["optimization"] = frobenius_error(opt.iterates, R0)
    errors["ours_right"] = frobenius_error(ours.right, R0)
    errors["ours_left"] = frobenius_error(ours.left, R0)
    return errors


def table1(errors: dict, iterations=paper.TABLE1_ITERATIONS) -> pd.DataFrame:
    """Mean and std over runs of each method's error at the given (1-based) iterations.

    Columns are ``(method, "mean" | "std")``, the index is the iteration.
    """
    cols = {}
    for method, err in errors.items():
        at = np.asarray(err)[:, [n - 1 for n in iterations]]
        cols[(method, "mean")] = at.mean(axis=0)
        cols[(method, "std")] = at.std(axis=0)
    return pd.DataFrame(cols, index=pd.Index(list(iterations), name="iteration"))


#: A mean error above this is reported as "infeasible": between rotations ``||R - R0||_F <= 2 sqrt 2``, so
#: only infeasible SQP iterates exceed it, and their values (10^5 and more) depend on rounding.
DIVERGED = 10.0


def versus_paper(ours: pd.DataFrame, *, rel_tol: float = 0.25, abs_tol: float = 0.005) -> pd.DataFrame:
    """Our Table I beside the paper's, cell by cell, with a verdict.

    A cell "agrees" when ``|ours_mean - paper_mean| <= max(abs_tol, rel_tol * paper_mean)``.
    A mean above :data:`DIVERGED` is printed as "infeasible" with no difference: such
    values come from SQP iterates far off SO(3) (early iterations, diverging runs),
    and those of diverging runs change with the machine's rounding.
    ``ours`` is the output of :func:`table1` with the paper's iterations and methods.
    """
    reference = paper.load_table1()
    rows = []
    for n in paper.TABLE1_ITERATIONS:
        for method in paper.TABLE1_METHODS:
            p_mean, p_std = reference.loc[(n, method), ["mean", "std"]]
            o_mean, o_std = ours.loc[n, (method, "mean")], ours.loc[n, (method, "std")]
            tol = max(abs_tol, rel_tol * p_mean)
            diverged = not o_mean <= DIVERGED
            rows.append({"iteration": n, "method": method,
                         "ours": f"infeasible (mean > {DIVERGED:g})" if diverged else f"{o_mean:.3f} ± {o_std:.3f}",
                         "paper": f"{p_mean:.3f} ± {p_std:.3f}",
                         "difference": np.nan if diverged else round(o_mean - p_mean, 3),
                         "verdict": "agrees" if abs(o_mean - p_mean) <= tol else "differs"})
    return pd.DataFrame(rows).set_index(["iteration", "method"])
