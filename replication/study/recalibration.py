"""The paper's online re-calibration claim (Sec. III-A), checked in
``notebooks/02_theorem1_convergence.ipynb``.

The paper: the sensor node is taped to the camera and moves a little against it on uneven ground, so
"online re-calibration must be performed during the experiments, which significantly requires the
efficiency and simplicity of the calibration algorithm. The proposed method have shown its strength
meet the requirements for such applications." It states no requirement (rate, latency, accuracy, how
a re-mount is noticed) and shows no online run. What can be measured is what its protocol does with
the motions such a robot sees between re-calibrations, which are small: :func:`small_motion_study`
runs the two-step method at the paper's 50 iterations and to its limit over motion ranges;
:func:`online_recalibration_record` builds the record. Notebook 08 studies an online estimator built
for the task (warm starts, its own radius, ``ready``, change detection).
"""
from __future__ import annotations

import warnings

import pandas as pd

from ..core.so3 import angle_between_deg
from ..core.solvers import ReplicationWarning, two_step
from ..core.stats import mean_se
from .ledger import check_evidence
from .simulation import simulate

__all__ = ["small_motion_study", "online_recalibration_record"]


def small_motion_study(seed: int, n_runs: int, ranges: dict, *, iterations: int = 50) -> pd.DataFrame:
    """The two-step error (``R^r``, deg) at ``iterations`` and at its limit, per motion range, the
    paper's noise.

    Range ``k`` (in the order of ``ranges``: label -> ``motion_angle_range_deg``) draws
    ``simulate(seed + k, n_runs, ...)``. Returns one row per range: ``at <iterations>`` and
    ``limit`` (mean angle to ``R0``), each with ``_se``, and ``ratio`` (their quotient).
    """
    rows = {}
    for k, (label, motions) in enumerate(ranges.items()):
        sim = simulate(seed + k, n_runs, motion_angle_range_deg=motions)
        with warnings.catch_warnings():  # the fixed protocol on purpose; small motions determine R0 poorly
            warnings.simplefilter("ignore", ReplicationWarning)
            short = two_step(sim.A, sim.B, iterations=iterations, history=False)
            limit = two_step(sim.A, sim.B, history=False)
        a, b = (angle_between_deg(r.R, sim.R0) for r in (short, limit))
        (ma, sa), (mb, sb) = mean_se(a), mean_se(b)
        rows[label] = {f"at {iterations}": ma, f"at {iterations}_se": sa, "limit": mb, "limit_se": sb,
                       "ratio": ma / mb}
    out = pd.DataFrame(rows).T
    out.index.name = "motions"
    return out


def online_recalibration_record(found: pd.DataFrame, fresh: pd.DataFrame, *, section: str, setting: str,
                                iterations: int = 50, short_factor: float = 2.0) -> dict:
    """The record of ``online_recalibration``: ``undecidable from the text``.

    ``found`` / ``fresh``: :func:`small_motion_study` on two seed sets, ranges from the smallest
    motions to the largest. Checked first (``ValueError`` naming the claim otherwise), on both: with
    the smallest motions the estimate at ``iterations`` is more than ``short_factor`` times as far
    from ``R0`` as the limit (the protocol stops short), with the largest within 10 % of it.
    """
    claim, at = "online_recalibration", f"at {iterations}"
    for label, f in (("found", found), ("fresh", fresh)):
        check_evidence(f["ratio"].iloc[0] > short_factor and abs(f["ratio"].iloc[-1] - 1) < 0.1, claim,
                       f"with the smallest motions the paper's {iterations} iterations leave the estimate more than "
                       f"{short_factor:g} times as far from R0 as the limit, with the largest within 10 % ({label}: "
                       f"{f['ratio'].iloc[0]:.2f}, {f['ratio'].iloc[-1]:.3f})")

    def row(f, label):
        r = f.loc[label]
        return (f"{r[at]:.2f} ± {r[at + '_se']:.2f} deg at {iterations} iterations against {r['limit']:.2f} ± "
                f"{r['limit_se']:.2f} at its limit")
    short = [m for m in found.index if found.loc[m, "ratio"] > short_factor and fresh.loc[m, "ratio"] > short_factor]
    return dict(
        claim=claim, verdict="undecidable from the text",
        evidence="the paper states no requirement (update rate, latency, accuracy, how a re-mount is noticed) and "
                 "shows no online run. Cheap it is: a calibration evaluates no cost and runs two 9x9 "
                 "matrix-vector products per iteration (sections above). But a robot re-calibrating during its "
                 "run sees small relative motions, and there the paper's fixed 50 iterations stop short: "
                 + "; ".join(f"motions {m}: {row(found, m)} (fresh: {row(fresh, m)})" for m in found.index)
                 + f". With motions {', '.join(short)} the protocol's estimate is several times farther from R0 "
                 "than the method's own limit, so what it meets depends on the motions and on iterating to "
                 "convergence, neither addressed; nor does the batch method say when the data determine R0 or "
                 "when the mount has moved, which online use needs (notebook 08 builds and measures both for an "
                 "online estimator)",
        uncertainty="mean ± SE of the angle to R0 over the problems of each range; the run time is machine-dependent "
                    "and not asserted",
        setting=setting, section=section)
