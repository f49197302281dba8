"""``chordal_optimal`` (``core/solvers/optimal.py``): the same answer type as
``solve(full_output=True)``."""
import numpy as np

from conftest import noisy_problem
from replication.core import solvers
from replication.core.solvers import solve


def test_chordal_optimal_returns_the_same_type_as_solve_full_output():
    from replication.core.solvers import Solution, chordal_optimal

    R0, A, B = noisy_problem(5, J=12)
    best = chordal_optimal(A, B)
    sol = solve("chordal_optimal", A, B, full_output=True)
    assert type(best) is Solution and type(sol) is Solution
    assert best.method == sol.method == "chordal_optimal"
    np.testing.assert_array_equal(best.R, sol.R)  # the same computation: bitwise
    np.testing.assert_array_equal(best.lower_bound, sol.lower_bound)
    assert best.certificate == sol.certificate == "lagrangian" and bool(best.global_optimum)
    assert best.local_minimum and best.iterations >= 1 and best.gradient_norm < 1e-8
    assert sol.iterations is None and sol.local_minimum is None  # solve does not say how a Newton run ended
    assert not hasattr(solvers, "ChordalResult")


def test_an_uncertified_newton_run_says_so():
    from replication.core.solvers import chordal_optimal

    R0, A, B = noisy_problem(7, J=12)
    bare = chordal_optimal(A, B, certify=False)
    assert bare.certificate == "none" and bare.sdp_used and not bare.global_optimum
    assert np.isnan(bare.lower_bound) and np.isnan(bare.duality_gap)
