"""The audit's study functions (``replication.study.convexity``: section 4 of notebook 06 and
section 3d of notebook 01): the Hessian of eq. (8) in vec(R), the derivatives on SO(3) computed from
it, the non-global minima Newton finds, their counts with Wilson intervals, and the guards of the
``convex_problem`` record."""
import numpy as np
import pandas as pd
import pytest

from replication.core import handeye, so3
from replication.core.solvers import chordal_optimal
from replication.core.solvers.certificate import chordal_newton
from replication.core.stats import wilson_interval
from replication.study import convexity as bl
from replication.study.ledger import check_record
from replication.study.simulation import simulate


@pytest.fixture(scope="module")
def noisy():
    return simulate(11, 40)


@pytest.fixture(scope="module")
def clean():
    return simulate(11, 40, noise_camera=0.0, noise_sensor=0.0)


@pytest.fixture(scope="module")
def runs(noisy):
    return bl.newton_from_starts(noisy.A, noisy.B, so3.random_rotations(np.random.default_rng(2), (3, 40)))


# --- counts
# --------------------------------------------------------------------------------------------------

def test_count_text_gives_the_wilson_interval():
    low, high = wilson_interval(51, 1800)
    assert bl.count_text(51, 1800) == f"51 of 1800 (2.8 %, 95 % Wilson interval [{100 * low:.1f}, {100 * high:.1f}] %)"
    assert bl.count_text(200, 200).startswith("200 of 200 (100.0 %, 95 % Wilson interval [98.1, 100.0] %")


@pytest.mark.parametrize("k, text, ends", [(448, "40-45 %", (400, 450)), (452, "45-50 %", (450, 500)),
                                           (453, "45-50 %", (450, 500)), (498, "45-50 %", (450, 500))])
def test_bracket_interval_is_the_wilson_interval_at_the_bracket_ends(k, text, ends):
    got, low, high = bl.bracket_interval(k, 1000)
    assert got == text
    assert low == pytest.approx(wilson_interval(ends[0], 1000)[0]) and high == pytest.approx(
        wilson_interval(ends[1], 1000)[1])


@pytest.mark.parametrize("k", [449, 450, 451, 499])
def test_a_count_within_two_runs_of_a_bracket_edge_is_refused(k):
    # which basin a start falls into moves with the machine's rounding by a run or two: the bracket
    # would flip
    with pytest.raises(ValueError, match="a share of starts .* of an edge of its bracket"):
        bl.bracket_interval(k, 1000)


def test_bracket_interval_does_not_move_inside_its_bracket():
    assert bl.bracket_interval(442, 1000, 0.1) == bl.bracket_interval(492, 1000, 0.1)
    assert bl.bracket_interval(0, 1000)[1:] == wilson_interval(0, 1000)
    assert bl.bracket_interval(1000, 1000)[0] == "all"


# --- the Hessian of (8) in vec(R)
# ----------------------------------------------------------------------------------

def test_cost_hessian_vec_is_the_quadratic_form_of_eq8_for_any_matrix(noisy):
    H = bl.cost_hessian_vec(noisy.A, noisy.B)
    X = np.random.default_rng(0).normal(size=(40, 3, 3))  # not rotations: f is a quadratic on all 3x3 matrices
    x = handeye.vec(X)
    f = handeye.handeye_cost(X, noisy.A, noisy.B)
    np.testing.assert_allclose(0.5 * np.einsum("na,nab,nb->n", x, H, x), f, rtol=1e-12)
    np.testing.assert_allclose(H, np.swapaxes(H, -1, -2), atol=1e-12)


def test_cost_hessian_vec_is_psd_and_singular_exactly_noise_free(noisy, clean):
    ev = np.linalg.eigvalsh(bl.cost_hessian_vec(noisy.A, noisy.B))
    assert ev[:, 0].min() > 1e-4 * 20  # measured 0.0004 J and more with the paper's noise
    H0 = bl.cost_hessian_vec(clean.A, clean.B)
    assert np.abs(np.einsum("nab,nb->na", H0, handeye.vec(clean.R0))).max() < 1e-12  # vec(R0) is a null vector
    conv = bl.cost_convexity(clean.A, clean.B)
    assert conv["PSD"] == conv["problems"] == 40 and abs(conv["smallest / J (min)"]) < 1e-12


def test_cost_convexity_counts_against_its_tolerance(noisy):
    """``PSD`` counts problems whose smallest eigenvalue / J is at least ``-tol``: just below and
    just above."""
    smallest = bl.cost_convexity(noisy.A, noisy.B)["smallest / J (min)"]
    assert bl.cost_convexity(noisy.A, noisy.B, tol=-(smallest - 1e-9))["PSD"] == 40
    assert bl.cost_convexity(noisy.A, noisy.B, tol=-(smallest + 1e-9))["PSD"] == 39
    with pytest.raises(ValueError, match="same shape"):
        bl.cost_hessian_vec(noisy.A, noisy.B[:, :4])


# --- derivatives on SO(3), independent of the solver's
# ---------------------------------------------------------------

def test_derivatives_on_so3_match_finite_differences(noisy):
    R = so3.random_rotations(np.random.default_rng(3), 40)
    cost, grad, hess = bl.cost_derivatives_on_so3(noisy.A, noisy.B, R)
    np.testing.assert_allclose(cost, handeye.handeye_cost(R, noisy.A, noisy.B), rtol=1e-12)
    f = lambda w: handeye.handeye_cost(R @ so3.matrix_from_rotation_vector(w), noisy.A, noisy.B)  # noqa: E731
    eps, E = 1e-4, np.eye(3)
    g_fd = np.stack([(f(eps * E[k]) - f(-eps * E[k])) / (2 * eps) for k in range(3)], -1)
    np.testing.assert_allclose(grad, g_fd, atol=1e-5)  # measured 4e-7
    def second(k, m):
        return (f(eps * (E[k] + E[m])) - f(eps * (E[k] - E[m])) - f(eps * (E[m] - E[k]))
                + f(-eps * (E[k] + E[m]))) / (4 * eps ** 2)

    h_fd = np.stack([np.stack([second(k, m) for m in range(3)], -1) for k in range(3)], -2)
    np.testing.assert_allclose(hess, h_fd, atol=1e-4)  # measured 4e-6 on entries up to 140


def test_derivatives_on_so3_agree_with_the_solver_at_its_end_points(noisy):
    starts = so3.random_rotations(np.random.default_rng(4), 40)
    res = chordal_optimal(noisy.A, noisy.B, init=starts, certify=False, max_iterations=100)
    _, grad, hess = bl.cost_derivatives_on_so3(noisy.A, noisy.B, res.R)
    np.testing.assert_allclose(np.linalg.eigvalsh(hess)[:, 0] / 20, res.hessian_min_eigenvalue, atol=1e-10)
    np.testing.assert_allclose(np.linalg.norm(grad, axis=-1) / 20, res.gradient_norm, atol=1e-10)


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


def test_noise_free_twins_are_exact_half_turns_at_the_predicted_cost(clean):
    """Noise-free, a twin is R0 Rot(n, 180 deg), whose cost is 8 sum_j (1 - (n^T B_j n)^2)."""
    starts = so3.random_rotations(np.random.default_rng(2), 40)
    R = chordal_newton(handeye.kronecker_operator(clean.A, clean.B), starts, max_iterations=100)[0]
    cost = handeye.handeye_cost(R, clean.A, clean.B)
    twin = cost > 1.0
    assert twin.sum() >= 10
    w = so3.rotation_vector_from_matrix(np.swapaxes(clean.R0, -1, -2) @ R)[twin]
    np.testing.assert_allclose(np.linalg.norm(w, axis=-1), np.pi, atol=1e-6)
    n = w / np.linalg.norm(w, axis=-1, keepdims=True)
    nbn = np.einsum("pa,pjab,pb->pj", n, clean.B[twin], n)
    np.testing.assert_allclose(cost[twin], 8 * np.sum(1 - nbn ** 2, axis=-1), rtol=1e-8)


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


# --- outliers, the fixed point
# ---------------------------------------------------------------------------------------

def test_outlier_certificate_study_is_certified_and_counts_strict_minima():
    table = bl.outlier_certificate_study(123, 60, configs=((3, 0.4),))
    row = table.loc[(3, 0.4)]
    assert row["problems"] == 60 and row["certified global"] == 60
    assert row["of them strict"] == row["Newton alone on a non-global minimum"]
    assert row["relaxation tight (certified by it)"] == row["needed the relaxation"]


def test_fixed_point_costs_more_than_the_certified_minimiser(noisy):
    t = bl.fixed_point_against_minimiser(noisy.A, noisy.B, noisy.R0)
    assert t["certified"].all() and (t["excess cost R^r"] > 1e-6).all() and (t["excess cost R^l"] > 1e-6).all()
    assert t["angle minimiser"].mean() < t["angle R^l"].mean()


# --- the convex_problem record and its guards
# ----------------------------------------------------------------------

def _record_inputs():
    s = {"runs": 1000, "non-global": 470, "share": "40-50 %", "share low": 0.37, "share high": 0.53, "problems": 1000,
         "problems with one": 470, "fewest starts on one": 0, "strict": 470, "strict low": 0.99, "half-turn": 470,
         "half-turn low": 0.99, "hessian min / J": 0.048, "gradient max / J": 2e-10, "angle min (deg)": 178.4,
         "midpoint sigma2 max": 0.014, "cost min": 53.0, "global cost max": 0.027, "all certified": True}
    m = {**s, "runs": 4800, "non-global": 2270, "share": "45-50 %", "problems": 200, "problems with one": 200,
         "fewest starts on one": 3, "strict": 2270, "half-turn": 2270}
    one = pd.DataFrame({(seeds, noise): s for seeds in ("found", "fresh") for noise in ("noise", "noise-free")}).T
    many = pd.DataFrame({seeds: m for seeds in ("found", "fresh")}).T
    conv = pd.DataFrame({"a": {"problems": 1000, "PSD": 1000, "smallest / J (min)": 3e-4, "smallest / J (max)": 9e-4,
                               "largest / J (max)": 6.0},
                         "b": {"problems": 1000, "PSD": 1000, "smallest / J (min)": 1e-16, "smallest / J (max)": 1e-16,
                               "largest / J (max)": 6.0}}).T
    out = pd.DataFrame({(3, 0.2): {"problems": 300, "certified global": 300, "Newton alone on a non-global minimum": 15,
                                   "of them strict": 15, "their excess cost (max, %)": 44.0,
                                   "their angle to the global minimiser (min deg)": 109.0}}).T
    return conv, one, many, {"found": out, "fresh": out.copy()}


def _record(conv, one, many, outliers):
    return bl.convex_problem_record(conv, one, many, outliers, n_starts=24, sensitivity=(1e-12, 6, 1000),
                                    section="4. x", setting="y")


def test_convex_problem_record_is_a_valid_record():
    rec = _record(*_record_inputs())
    check_record(**rec)
    assert rec["verdict"] == "fails"
    assert "40-50 % of 1000 problems in each set" in rec["evidence"] and "15 of 300" in rec["evidence"]
    assert "Wilson" in rec["uncertainty"] and "bound" in rec["uncertainty"]


@pytest.mark.parametrize("column, value, ok", [("non-global", 260, True), ("non-global", 240, False),
                                               ("non-global", 740, True), ("non-global", 760, False)])
def test_convex_problem_record_guards_the_share(column, value, ok):
    conv, one, many, out = _record_inputs()
    one.loc[("fresh", "noise"), [column, "strict", "half-turn"]] = value
    if ok:
        _record(conv, one, many, out)
    else:
        with pytest.raises(ValueError, match="25-75 %"):
            _record(conv, one, many, out)


@pytest.mark.parametrize("fewest, ok", [(1, False), (2, True)])
def test_convex_problem_record_guards_the_margin_of_several_starts(fewest, ok):
    conv, one, many, out = _record_inputs()
    many.loc["fresh", "fewest starts on one"] = fewest
    if ok:
        _record(conv, one, many, out)
    else:
        with pytest.raises(ValueError, match="at least 2 starts"):
            _record(conv, one, many, out)


def test_convex_problem_record_guards_strictness_psd_and_fresh_outliers():
    conv, one, many, out = _record_inputs()
    one.loc[("found", "noise"), "strict"] = 469
    with pytest.raises(ValueError, match="strict local minimum"):
        _record(conv, one, many, out)
    conv, one, many, out = _record_inputs()
    conv.loc["a", "PSD"] = 999
    with pytest.raises(ValueError, match="PSD"):
        _record(conv, one, many, out)
    conv, one, many, out = _record_inputs()
    out["fresh"] = out["fresh"].assign(**{"Newton alone on a non-global minimum": 0, "of them strict": 0})
    with pytest.raises(ValueError, match="outliers"):
        _record(conv, one, many, out)
    conv, one, many, out = _record_inputs()
    with pytest.raises(ValueError, match="found and on the fresh"):
        _record(conv, one.loc[["found"]], many, out)
