"""One solver shape: the registered doors show what they take; the registry's flags; solve_pairs' arguments."""
import inspect

import numpy as np
import pytest

from replication.core import solvers
from replication.core.motions import Motions
from replication.core.so3 import random_rotations
from replication.core.solvers import _registry, available, register, solve
from replication.core.solvers.certificate import relaxed_rotation

#: The registered solvers exported as functions of their own name (the others are reached through ``solve``).
EXPORTED_DOORS = ["park_martin", "horaud_dornaika", "andreff", "tsai_lenz", "robust"]


def _problem(seed=0, J=8):
    rng = np.random.default_rng(seed)
    R0 = random_rotations(rng, ())
    A = random_rotations(rng, J)
    return R0, A, np.swapaxes(R0, -1, -2) @ A @ R0


@pytest.mark.parametrize("name", EXPORTED_DOORS)
def test_a_registered_door_shows_the_doors_signature_not_the_cores(name):
    door = getattr(solvers, name)
    params = inspect.signature(door).parameters
    assert list(params)[:4] == ["A", "B", "full_output", "warn_axis_spread_deg"]
    assert "motions" not in params
    assert params["B"].default is None and params["full_output"].default is False
    core_options = list(inspect.signature(_registry.solver_info(name).core).parameters)[1:]
    assert list(params)[4:] == core_options  # the core's own options, keyword-only, with their defaults
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in list(params.values())[2:])


def test_the_signature_binds_what_the_door_accepts_and_refuses_what_it_does_not():
    R0, A, B = _problem()
    sig = inspect.signature(solvers.robust)
    sig.bind(A, B, threshold_deg=3.0, seed=1, full_output=True)  # what a caller may write
    with pytest.raises(TypeError):
        sig.bind(A, B, threshold=3.0)  # a misspelt option: the signature says no, as the call does
    with pytest.raises(TypeError):
        solvers.robust(A, B, threshold=3.0)
    np.testing.assert_array_equal(solvers.robust(A, B, threshold_deg=3.0), solve("robust", A, B, threshold_deg=3.0))


def test_a_newly_registered_door_shows_its_options(monkeypatch):
    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))

    def core(motions, gain=2.0, *, steps: int = 3):
        return np.broadcast_to(np.eye(3), motions.batch_shape + (3, 3)).copy()

    door = register("shape_test_solver", reference="test")(core)
    params = inspect.signature(door).parameters
    assert list(params) == ["A", "B", "full_output", "warn_axis_spread_deg", "gain", "steps"]
    assert params["gain"].kind is inspect.Parameter.KEYWORD_ONLY and params["gain"].default == 2.0
    assert door.__doc__ == core.__doc__ and door.core is core
    assert "shape_test_solver" in available()


def test_relaxed_start_is_a_flag_of_the_solvers_that_read_the_relaxed_solution():
    flagged = {name for name in available() if _registry.solver_info(name).relaxed_start}
    assert flagged == {"andreff", "chordal_optimal"}
    assert not hasattr(_registry, "RELAXED_START")  # one place says it: the solver's registration


@pytest.mark.parametrize("relaxed_start", [False, True])
def test_solve_decomposes_sym_k_once_for_a_relaxed_start_solver(monkeypatch, relaxed_start):
    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    name = f"relaxed_{relaxed_start}"
    register(name, reference="test", relaxed_start=relaxed_start)(lambda motions: relaxed_rotation(motions.K))
    m = Motions(*_problem(1)[1:])
    solve(name, m)
    # with the flag, the checks' eigenvalues are those of the one decomposition with vectors (the same array)
    assert (m.sym_eigvals is m.sym_eigh[0]) is relaxed_start


# --- solve_pairs' arguments: the data, how to solve and judge, how to resample, what the report carries


def _noisy_pairs(seed=2, J=30, noise_deg=0.2):
    from replication.core.so3 import exp_map

    rng = np.random.default_rng(seed)
    R0, A, B = _problem(seed, J)
    B = B @ exp_map(np.radians(noise_deg) * rng.standard_normal((J, 3)))
    return R0, A, B


def test_solve_pairs_takes_the_pairs_and_six_named_groups():
    from replication.rig.solve_and_judge import solve_pairs

    params = inspect.signature(solve_pairs).parameters
    assert list(params) == ["A", "B", "method", "options", "reference", "evidence", "resampling", "provenance"]
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY and p.default is inspect.Parameter.empty
               for p in list(params.values())[2:])  # nothing forgotten silently: every group is said


def test_the_groups_are_frozen():
    import dataclasses

    from replication.rig.solve_and_judge import Provenance, Resampling

    with pytest.raises(dataclasses.FrozenInstanceError):
        Resampling(n_bootstrap=10, seed=0).seed = 1
    with pytest.raises(dataclasses.FrozenInstanceError):
        Provenance().interval = 1.0
    p = Provenance()  # the defaults say "no clock, no interval" (a pose set), never a made-up number
    assert np.isnan(p.interval) and np.isnan(p.time_offset[0]) and p.time_offset[2] is False
    assert p.parameters == {} and p.parameters is not Provenance().parameters  # no dict shared between calls


def test_solve_pairs_reports_its_provenance_and_resamples_as_told():
    from replication.rig.solve_and_judge import Provenance, Resampling, solve_pairs

    R0, A, B = _noisy_pairs()
    times = np.arange(len(A)) * 0.5
    kw = dict(method="chordal_optimal", options={}, reference=R0, evidence={})
    provenance = Provenance(interval=0.5, time_offset=(0.01, 0.9, True), parameters={"method": "chordal_optimal"},
                            pair_times=times, extra_diagnostics={"mine": 1})
    res = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=3, block=3), provenance=provenance, **kw)
    assert res.interval_s == 0.5 and res.time_offset_s == 0.01 and res.time_offset_applied is True
    assert res.parameters == {"method": "chordal_optimal"} and res.diagnostics["mine"] == 1
    assert res.diagnostics["pair_times"] is times
    assert res.bootstrap_resamples == "pairs in moving blocks of 3" and np.isfinite(res.bootstrap_ci95_deg)
    again = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=3, block=3), provenance=provenance, **kw)
    assert again.bootstrap_ci95_deg == res.bootstrap_ci95_deg  # the seed decides the replicates
    other = solve_pairs(A, B, resampling=Resampling(n_bootstrap=40, seed=4, block=3), provenance=provenance, **kw)
    assert other.bootstrap_ci95_deg != res.bootstrap_ci95_deg
    none = solve_pairs(A, B, resampling=Resampling(n_bootstrap=0, seed=3), provenance=Provenance(), **kw)
    assert none.bootstrap_resamples == "none" and np.isnan(none.bootstrap_ci95_deg) and np.isnan(none.interval_s)


# --- one answer type: solve(full_output=True) and chordal_optimal return a Solution


def test_chordal_optimal_returns_the_same_type_as_solve_full_output():
    from replication.core.solvers import Solution, chordal_optimal

    R0, A, B = _noisy_pairs(5, J=12)
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


@pytest.mark.parametrize("method", ["park_martin", "sqp", "two_step_left"])
def test_every_full_output_says_how_its_lower_bound_was_certified(method):
    from replication.core.motions import motion_observability

    R0, A, B = _noisy_pairs(6, J=12)
    sol = solve(method, A, B, full_output=True, **({"init": R0} if method == "sqp" else {}))
    assert sol.method == method and sol.certificate == "lagrangian" and not sol.sdp_used
    expected = motion_observability(A, B)  # computed when read, the same numbers
    assert sol.observability.spectral_ratio == expected.spectral_ratio
    np.testing.assert_array_equal(sol.observability.kron_singular_values, expected.kron_singular_values)
    assert sol.duality_gap >= 0 and sol.cost >= sol.lower_bound


def test_an_uncertified_newton_run_says_so():
    from replication.core.solvers import chordal_optimal

    R0, A, B = _noisy_pairs(7, J=12)
    bare = chordal_optimal(A, B, certify=False)
    assert bare.certificate == "none" and bare.sdp_used and not bare.global_optimum
    assert np.isnan(bare.lower_bound) and np.isnan(bare.duality_gap)
