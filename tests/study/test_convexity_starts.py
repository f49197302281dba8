"""Newton from many starts (``replication.study.convexity.starts``: section 4 of notebook 06): the
non-global minima Newton finds, which end points are strict, their counts with Wilson intervals over
brackets, and the basins' sensitivity to a perturbation."""
import numpy as np
import pandas as pd
import pytest

from replication.core import handeye, so3
from replication.core.solvers import chordal_optimal
from replication.core.solvers.certificate import chordal_newton
from replication.core.stats import wilson_interval
from replication.study import convexity as bl


@pytest.fixture(scope="module")
def runs(noisy):
    return bl.newton_from_starts(noisy.A, noisy.B, so3.random_rotations(np.random.default_rng(2), (3, 40)))


# --- non-global minima
# -----------------------------------------------------------------------------------------------

def test_newton_from_starts_finds_strict_half_turn_twins(runs):
    bad = runs[runs["non-global"]]
    assert 0.2 * len(runs) < len(bad) < 0.8 * len(runs)  # measured 47 % on these problems
    assert bad["strict"].all() and (bad["hessian min / J"] > 0.01).all()
    assert (bad["angle to global (deg)"] > 170).all() and (bad["midpoint sigma2"] < 0.05).all()
    good = runs[~runs["non-global"]]
    assert (good["angle to global (deg)"] < 1e-6).all() and (good["midpoint sigma2"] > 0.99).all()
    assert runs["certified"].all() and (bad["cost"] > 1000 * bad["global cost"]).all()


def test_newton_from_the_global_minimiser_or_its_twin(noisy, runs):
    best = chordal_optimal(noisy.A, noisy.B).R
    at_best = bl.newton_from_starts(noisy.A, noisy.B, best)
    assert not at_best["non-global"].any()
    first = runs[runs["non-global"]].iloc[0]
    K = handeye.kronecker_operator(noisy.A, noisy.B)
    starts = so3.random_rotations(np.random.default_rng(2), (3, 40))[int(first["start"])]
    twin = chordal_newton(K, starts, max_iterations=100)[0]
    again = bl.newton_from_starts(noisy.A, noisy.B, twin)
    assert again.loc[int(first["problem"]), "non-global"] and again.loc[int(first["problem"]), "strict"]


def test_newton_from_starts_refuses_mismatched_starts(noisy):
    with pytest.raises(ValueError, match="starts"):
        bl.newton_from_starts(noisy.A, noisy.B, so3.random_rotations(np.random.default_rng(0), 39))


def test_a_point_that_is_not_stationary_is_not_strict(noisy):
    """STATIONARY_TOL: one Newton iteration from a random start leaves a gradient far above it."""
    starts = so3.random_rotations(np.random.default_rng(5), 40)
    one = bl.newton_from_starts(noisy.A, noisy.B, starts, max_iterations=1)
    assert (one["gradient / J"] > bl.STATIONARY_TOL).mean() > 0.9 and not one["strict"][
        one["gradient / J"] > bl.STATIONARY_TOL].any()


def test_a_stationary_point_that_is_a_maximum_is_not_strict(noisy):
    """The Hessian condition of ``strict``: the maximisers of (8) on SO(3) are stationary, with a
    negative Hessian."""
    K = handeye.kronecker_operator(noisy.A, noisy.B)
    R_max = chordal_newton(-K, so3.random_rotations(np.random.default_rng(7), 40), max_iterations=100)[0]
    at_max = bl.newton_from_starts(noisy.A, noisy.B, R_max, max_iterations=0)  # judged where they are
    assert (at_max["gradient / J"] <= bl.STATIONARY_TOL).all() and (at_max["hessian min / J"] < 0).all()
    assert at_max["non-global"].all() and not at_max["strict"].any()


def test_nonglobal_summary_counts(runs):
    s = bl.nonglobal_summary(runs)
    k = int(runs["non-global"].sum())
    assert s["runs"] == 120 and s["non-global"] == k and s["strict"] == s["half-turn"] == k
    assert s["problems"] == 40 and s["problems with one"] == runs.groupby("problem")["non-global"].any().sum()
    assert s["share low"] <= k / 120 <= s["share high"]
    k_low = int(np.floor(k / 120 / 0.05 + 1e-9) * 0.05 * 120 + 1e-9)
    assert s["strict low"] == pytest.approx(wilson_interval(k_low, k_low)[0])
    view = bl.nonglobal_view(pd.DataFrame({"x": s}).T)
    assert view.loc["x", "strict minima"] == "all" and view.loc["x", "on a non-global minimum (bound)"] == s["share"]


def test_nonglobal_summary_when_not_all_are_strict(runs):
    broken = runs.copy()
    first = broken.index[broken["non-global"]][0]
    broken.loc[first, "strict"] = False
    s = bl.nonglobal_summary(broken)
    assert s["strict"] == s["non-global"] - 1
    assert s["strict low"] == pytest.approx(wilson_interval(s["strict"], s["non-global"])[0])
    view = bl.nonglobal_view(pd.DataFrame({"x": s}).T)
    assert view.loc["x", "strict minima"] == f"{s['strict']} of {s['non-global']}"


def test_basin_sensitivity_zero_and_large_perturbations(noisy):
    starts = so3.random_rotations(np.random.default_rng(6), 40)
    assert bl.basin_sensitivity(noisy.A, noisy.B, starts, scale=0.0, rng=np.random.default_rng(0), repeats=1) == 0
    assert bl.basin_sensitivity(noisy.A, noisy.B, starts, scale=2.0, rng=np.random.default_rng(0), repeats=2) >= 5
