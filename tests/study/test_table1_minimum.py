"""SQP's failures at two iteration caps and the two-step iterates against the certified minimum
(``replication.study.table1.minimum``, notebook 03)."""
import numpy as np
import pytest

from replication.study import ledger
from replication.study.simulation import MATCHED_MOTIONS_DEG, matched_start, simulate

# ---- SQP's failures at two caps, the two-step iterates against the certified minimum
# -------------------

def test_sqp_cap_shares_reads_one_run_at_each_cap():
    from replication.study.table1 import sqp_cap_shares

    s = simulate(41000, 12, motion_angle_range_deg=MATCHED_MOTIONS_DEG)
    shares = sqp_cap_shares(s, init=matched_start(), caps=(100, 50))
    assert set(shares) == {50, 100, "n"} and shares["n"] == 12
    assert 0 <= shares[100] <= 1 and 0 <= shares[50] <= 1
    with pytest.raises(ValueError, match="caps must be positive"):
        sqp_cap_shares(s, caps=(0, 50))


@pytest.mark.parametrize("p100, ok", [(62 / 300, None), (0.6 + 2 / 300, True), (0.6 + 1.9 / 300, False),
                                      (0.75 - 2 / 300, True), (0.75 - 1.9 / 300, False)])
def test_cap_shares_text_keeps_its_declared_bound_two_runs_inside(p100, ok):
    from replication.study.table1 import cap_shares_text

    shares = {50: 0.8433, 100: p100, "n": 300}
    if ok is None:
        with pytest.raises(ValueError, match="not at least .* inside its declared bound"):
            cap_shares_text(shares)
    elif ok:
        assert cap_shares_text(shares) == "80-90 % [75, 93] of 300 at 50 iterations, 60-75 % [54, 80] at 100"
    else:
        with pytest.raises(ValueError, match="failure share at 100 iterations"):
            cap_shares_text(shares)


def test_minimiser_cheaper_counts_only_beyond_rounding():
    from replication.study.table1 import COST_RTOL, minimiser_cheaper

    right, left = np.array([[2.0, 1.0], [2.0, 1.0], [2.0, 1.0]]), np.array([1.0, 1.0, 0.5])
    minimum = np.array([1.0 - 2 * COST_RTOL, 1.0 - 0.5 * COST_RTOL, 0.9])
    assert minimiser_cheaper(right, left, minimum).tolist() == [True, False, False]


def test_minimum_study_and_the_either_minimises_record():
    from replication.study.table1 import either_minimises_record, minimum_study

    fresh = {"defaults": minimum_study(43000, 30, np.random.default_rng(0))}
    assert fresh["defaults"]["cheaper"] == fresh["defaults"]["certified"] == 30
    ratio, low, high = fresh["defaults"]["@10 / minimum"]
    assert 1 < low <= ratio <= high
    rec = either_minimises_record({"defaults": (1000, 1000, 1000)}, fresh, section="s", setting="t")
    assert rec["verdict"] == "fails" and "1000 of 1000 [99.6, 100.0] %" in rec["evidence"]
    assert "on fresh problems defaults (fresh) 30 of 30" in rec["evidence"]
    ledger.check_record(**rec)  # its claim is in data/paper/claims.csv
    for found in ({"defaults": (999, 1000, 1000)}, {"defaults": (1000, 999, 1000)}):
        with pytest.raises(ValueError, match="claim 'either_minimises'.*costs less than both R\\^r and R\\^l"):
            either_minimises_record(found, fresh, section="s", setting="t")
