"""The common end of ``calibrate`` (``rig/solve_and_judge.py``): ``solve_pairs`` takes the pairs and
its named groups (``Resampling``, ``Provenance``), frozen."""
import inspect

import numpy as np
import pytest

from conftest import noisy_problem


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

    R0, A, B = noisy_problem()
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
