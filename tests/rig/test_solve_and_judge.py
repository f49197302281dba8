"""The common end of ``calibrate`` (``rig/solve_and_judge.py``): ``solve_pairs`` takes the pairs and
its named groups (``Resampling``, ``Provenance``), frozen."""
import inspect

import numpy as np
import pytest

from conftest import noisy_problem
from replication.rig.solve_and_judge import reference_reading


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


EPS = 1e-9


@pytest.mark.parametrize("errors, floor, reading", [
    ((0.169, 0.234), 0.343, "agreement, not accuracy: both errors (0.169, 0.234 deg)"),  # EuRoC MH01, measured
    ((0.3, 0.3), 0.3, "agreement, not accuracy"),                      # at the floor: within it
    ((0.3 + EPS, 0.1), 0.3, "closer to reference 2: its error (0.100 deg) is within"),  # one just above
    ((0.1, 0.3 + EPS), 0.3, "closer to reference 1"),
    ((0.3 + EPS, 0.3 + EPS), 0.3, "a difference beyond the floor: both errors"),
])
def test_the_reading_of_two_references_at_the_floor(errors, floor, reading):
    text = reference_reading(errors, floor)
    assert text.startswith(reading)
    assert f"the references' own disagreement {floor:.3f} deg (the reference floor)" in text


@pytest.mark.parametrize("errors, floor, radius, reading", [
    ((0.0, 10.0), 10.0, 0.1, "closer to reference 1: its error (0.000 deg) is the smaller, by more than R0's"),
    ((0.5, 9.5), 10.0, 0.1, "closer to reference 1"),                   # was "agreement, not accuracy"
    ((0.05, 0.05), 0.0, 0.1, "agreement within R0's radius"),           # the same reference twice: was "beyond"
    ((0.1, 0.1), 0.0, 0.1, "agreement within R0's radius"),             # at the radius: within it
    ((0.1 + EPS, 0.1 + EPS), 0.0, 0.1, "a difference beyond the floor"),
    ((0.169, 0.234), 0.343, 0.09, "agreement, not accuracy"),           # EuRoC: 0.065 apart, within the radius
    ((0.169, 0.234), 0.343, 0.064, "closer to reference 1"),            # ... and just beyond a smaller radius
    ((0.2, 0.4), 0.3, 0.5, "agreement within R0's radius"),
    ((0.2, 0.55), 0.35, 0.5, "not resolved: the errors (0.200, 0.550 deg) differ by no more than"),
])
def test_the_reading_weighs_the_difference_of_the_errors_against_r0s_radius(errors, floor, radius, reading):
    assert reference_reading(errors, floor, radius).startswith(reading)
