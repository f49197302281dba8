"""Uncertainty helpers of the verdicts (replication.core.stats)."""
import numpy as np
import pytest

from replication.core.stats import (
    bracket,
    declared_bound,
    format_ci,
    mean_se,
    paired_ratio_ci,
    radius_deg,
    share_range,
    z_score,
)


def test_mean_se_and_z():
    m, se = mean_se([1.0, 2.0, 3.0, 4.0])
    assert m == 2.5 and np.isclose(se, np.std([1, 2, 3, 4], ddof=1) / 2)
    assert np.isclose(z_score(1.0, 0.3, 0.5, 0.4), 1.0)
    with pytest.raises(ValueError, match="at least 2"):
        mean_se([1.0])


def test_paired_ratio_interval_covers_the_truth_and_is_paired():
    rng = np.random.default_rng(0)
    b = rng.uniform(1.0, 3.0, 500)
    a = 1.5 * b * rng.uniform(0.95, 1.05, 500)  # strongly paired: the interval is narrow
    r, lo, hi = paired_ratio_ci(a, b, np.random.default_rng(1))
    assert lo < 1.5 < hi and hi - lo < 0.02 and lo < r < hi
    with pytest.raises(ValueError, match="Generator"):
        paired_ratio_ci(a, b, 1)
    with pytest.raises(ValueError, match="paired"):
        paired_ratio_ci(a, b[:-1], rng)


def test_share_range_brackets():
    assert share_range(0.0) == "none" and share_range(1.0) == "all"
    assert share_range(0.837) == "80-85 %" and share_range(0.85) == "85-90 %" and share_range(0.999) == "95-100 %"
    assert share_range(0.02) == "0-5 %"
    with pytest.raises(ValueError, match="share"):
        share_range(1.2)
    assert format_ci(0.1234, 0.5678) == "[0.12, 0.57]"


def test_bracket():
    assert bracket(13.86, 1) == "13-14" and bracket(13.0, 1) == "13-14" and bracket(414, 50) == "400-450"
    assert bracket(0.3, 0.1) == "0.3-0.4"
    with pytest.raises(ValueError, match="positive width"):
        bracket(1.0, 0)


@pytest.mark.parametrize("value, ok", [(13.5, True), (13.1, True), (13.0999, False), (13.9, True), (13.9001, False)])
def test_bracket_guards_its_edges_by_the_margin(value, ok):
    if ok:
        assert bracket(value, 1, margin=0.1) == "13-14"
    else:
        with pytest.raises(ValueError, match="within 0.1 of an edge of its bracket 13-14"):
            bracket(value, 1, margin=0.1)


@pytest.mark.parametrize("k, ok", [(242, True), (243, True), (241, False), (253, True), (254, False)])
def test_share_range_keeps_the_runs_a_machine_moves_from_the_edges(k, ok):
    # 300 runs, 2 runs of margin: 80-85 % holds counts 240-254; a count within 2 runs of 240 or 255
    # is refused
    if ok:
        assert share_range(k / 300, margin=2 / 300) == "80-85 %"
    else:
        with pytest.raises(ValueError, match="another machine's rounding can move it across"):
            share_range(k / 300, margin=2 / 300)


def test_a_share_of_one_run_is_guarded_against_becoming_none():
    with pytest.raises(ValueError, match="of an edge"):
        share_range(1 / 300, margin=2 / 300)


@pytest.mark.parametrize("value, low, high, ok", [(10.2, 10, None, True), (10.19, 10, None, False),
                                                  (0.3, None, 0.5, True), (0.31, None, 0.5, False),
                                                  (620, 600, 700, True), (681, 600, 700, False)])
def test_declared_bound_at_its_margin(value, low, high, ok):
    if ok:
        assert declared_bound(value, low, high, margin=0.2 if high != 700 else 20) in {
            "at least 10", "at most 0.5", "600-700"}
    else:
        with pytest.raises(ValueError, match="inside its declared bound"):
            declared_bound(value, low, high, margin=0.2 if high != 700 else 20)


def test_declared_bound_text_is_the_constants_not_the_value():
    assert declared_bound(610, 600, 700, margin=5) == declared_bound(690, 600, 700, margin=5) == "600-700"
    with pytest.raises(ValueError, match="declare low, high or both"):
        declared_bound(1.0, margin=0.1)


@pytest.mark.parametrize("scale, ok", [("1", True), ("2", False)])
def test_the_margin_scale_doubles_every_guard(monkeypatch, scale, ok):
    monkeypatch.setenv("REPLICATION_MARGIN_SCALE", scale)
    calls = [lambda: declared_bound(10.3, 10, margin=0.2), lambda: bracket(13.3, 1, margin=0.2),
             lambda: share_range(0.8033, margin=0.002)]
    for call in calls:
        if ok:
            call()
        else:
            with pytest.raises(ValueError):
                call()


@pytest.mark.parametrize("text", ["0.5", "x", "-2"])
def test_a_margin_scale_below_one_is_refused(monkeypatch, text):
    monkeypatch.setenv("REPLICATION_MARGIN_SCALE", text)
    with pytest.raises(ValueError, match="REPLICATION_MARGIN_SCALE must be a number >= 1"):
        declared_bound(1.0, 0, margin=0.1)


def test_radius_matches_the_gaussian_quantile():
    cov = np.diag([1.0, 1.0, 1.0]) * np.radians(0.1) ** 2
    # |w| / 0.1 deg is chi with 3 degrees of freedom: its 95 % quantile is 2.7955
    assert radius_deg(cov) == pytest.approx(0.1 * 2.7955, rel=0.01)
    # nu = 1: the worst case
    assert radius_deg(np.diag([1.0, 0.0, 0.0]) * np.radians(0.1) ** 2) == pytest.approx(0.1 * 1.96, rel=0.02)
