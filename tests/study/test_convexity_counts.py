"""Counts with their intervals (``replication.study.convexity.counts``): a count with its Wilson
interval, the bracket of a count whose last units depend on rounding, and the Wilson interval over
the bracket's ends."""
import pytest

from replication.core.stats import wilson_interval
from replication.study import convexity as bl

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
