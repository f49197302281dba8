"""Fig. 5: error against sensor noise, the two-step method against SQP (support of ``notebooks/04_noise_sweep.ipynb``).

The paper (Sec. III-A): with the noise on ``Delta R_i`` rising from 1 to 10 deg (1 deg on ``Delta R_c``), the
two-step error grows "much slower than that of the traditional optimization method": it is "more resilient to
the noise". Which SQP, which motions, which start and which noise distribution are not stated, so
:func:`noise_sweep` takes each as a setting, and :func:`resilience` reduces a sweep to what the claim needs,
with uncertainties:

* per level, the two-step error (``R^r``) and SQP's, as means with standard errors;
* SQP runs that do not end at the certified global minimiser of eq. (8) (from a far start SLSQP stops at its
  iteration limit) are counted, not averaged as digits: where such a run stops depends on rounding;
* the ratio two-step / SQP of the mean errors, with a paired bootstrap interval over problems, where SQP reached
  the global minimum in every run of the level;
* the growth ratio ``(two-step error at the top level - at the bottom) / (the same for SQP)``, with a bootstrap
  interval (problems resampled per level, the two methods paired on the same problems): below 1 means the
  two-step error grows more slowly, as the paper claims.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd

from .simulation import noise_bound_for_angle_deg, simulate
from .so3 import angle_between_deg, frobenius_error
from .solvers import SQP_VARIANTS, ReplicationWarning, chordal_optimal, sqp, two_step
from .stats import mean_se

__all__ = ["noise_sweep", "resilience", "AT_MINIMUM_DEG"]

#: An SQP answer within this angle of the certified global minimiser of eq. (8) counts as having reached it.
AT_MINIMUM_DEG = 0.01


def noise_sweep(levels, n_runs: int, seed: int, *, motions=None, init=None, noise_distribution: str = "uniform",
                sqp_variant: str = "analytic", sqp_options=None, iterations: int = 50,
                camera_noise_deg: float = 1.0) -> dict:
    """Final errors of both methods at each sensor-noise level (degrees).

    Level ``k`` draws ``n_runs`` problems with seed ``seed + k``. The two-step method runs the paper's
    ``iterations``; SQP (the named variant of ``SQP_VARIANTS``, updated by ``sqp_options``, e.g.
    ``{"cost": 0.0005}``; at most ``iterations``) is projected onto SO(3) at the end.

    Returns
    -------
    dict
        level -> ``{"two_step": (n,) errors of R^r, "sqp": (n,) errors, "sqp_at_minimum": (n,) bool}``
        (errors ``||R - R0||_F``).
    """
    options = {**SQP_VARIANTS[sqp_variant], **(sqp_options or {})}
    cap = min(int(options.pop("max_iterations", iterations)), iterations)
    out = {}
    for k, level in enumerate(levels):
        sim = simulate(seed + k, n_runs, motion_angle_range_deg=motions, noise_distribution=noise_distribution,
                       noise_camera=noise_bound_for_angle_deg(camera_noise_deg),
                       noise_sensor=noise_bound_for_angle_deg(float(level)))
        with warnings.catch_warnings():  # the fixed protocol and SQP's failures are what is being measured
            warnings.simplefilter("ignore", ReplicationWarning)
            ours = two_step(sim.A, sim.B, iterations=iterations, init=init, history=False)
            opt = sqp(sim.A, sim.B, max_iterations=cap, init=init, **options)
        best = chordal_optimal(sim.A, sim.B)
        out[float(level)] = {
            "two_step": frobenius_error(ours.R_right, sim.R0),
            "sqp": frobenius_error(opt.R, sim.R0),
            "sqp_at_minimum": angle_between_deg(opt.R, best.R) <= AT_MINIMUM_DEG,
        }
    return out


def resilience(sweep: dict, rng: np.random.Generator, *, n_boot: int = 2000) -> tuple[pd.DataFrame, dict]:
    """Per-level statistics and the growth ratio of one :func:`noise_sweep` (see the module notes).

    Returns
    -------
    (per_level, growth)
        ``per_level``: index level; columns ``two_step``, ``two_step_se``, ``sqp_failed`` (runs not at the
        global minimum), ``sqp`` and ``sqp_se`` (NaN where any run failed: their digits depend on rounding),
        ``ratio``, ``ratio_low``, ``ratio_high`` (two-step / SQP, paired bootstrap 95 %; NaN where SQP failed).
        ``growth``: ``{"ratio", "low", "high"}`` between the lowest and the highest level (NaN if SQP failed in
        either), ``{"sqp_failed_share"}`` over all levels, and ``sqp_all_lowest`` / ``sqp_all_highest``: SQP's mean
        error over *all* runs at the lowest and highest level (for bounds only: with failed runs its digits
        depend on rounding).
    """
    levels = sorted(sweep)
    rows = {}
    for level in levels:
        d = sweep[level]
        ours_m, ours_se = mean_se(d["two_step"])
        failed = int((~d["sqp_at_minimum"]).sum())
        row = {"two_step": ours_m, "two_step_se": ours_se, "sqp_failed": failed, "runs": len(d["sqp"])}
        if failed == 0:
            m, se = mean_se(d["sqp"])
            n = len(d["sqp"])
            idx = rng.integers(0, n, size=(int(n_boot), n))
            boot = d["two_step"][idx].mean(axis=1) / d["sqp"][idx].mean(axis=1)
            row.update(sqp=m, sqp_se=se, ratio=ours_m / m, ratio_low=np.percentile(boot, 2.5),
                       ratio_high=np.percentile(boot, 97.5))
        else:
            row.update(sqp=np.nan, sqp_se=np.nan, ratio=np.nan, ratio_low=np.nan, ratio_high=np.nan)
        rows[level] = row
    per_level = pd.DataFrame(rows).T
    per_level.index.name = "sensor noise (deg)"
    lo, hi = sweep[levels[0]], sweep[levels[-1]]
    growth = {"sqp_failed_share": float(per_level["sqp_failed"].sum() / per_level["runs"].sum()),
              "sqp_all_lowest": float(lo["sqp"].mean()), "sqp_all_highest": float(hi["sqp"].mean())}
    if per_level.loc[[levels[0], levels[-1]], "sqp_failed"].sum() == 0:
        i_lo = rng.integers(0, len(lo["sqp"]), size=(int(n_boot), len(lo["sqp"])))
        i_hi = rng.integers(0, len(hi["sqp"]), size=(int(n_boot), len(hi["sqp"])))
        g_ours = hi["two_step"][i_hi].mean(axis=1) - lo["two_step"][i_lo].mean(axis=1)
        g_sqp = hi["sqp"][i_hi].mean(axis=1) - lo["sqp"][i_lo].mean(axis=1)
        ratio = (hi["two_step"].mean() - lo["two_step"].mean()) / (hi["sqp"].mean() - lo["sqp"].mean())
        growth.update(ratio=ratio, low=np.percentile(g_ours / g_sqp, 2.5), high=np.percentile(g_ours / g_sqp, 97.5))
    else:
        growth.update(ratio=np.nan, low=np.nan, high=np.nan)
    return per_level, growth
