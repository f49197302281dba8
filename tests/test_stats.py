"""Uncertainty helpers of the verdicts (replication.core.stats)."""
import numpy as np
import pytest

from replication.core.stats import bracket, format_ci, mean_se, paired_ratio_ci, share_range, z_score


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
