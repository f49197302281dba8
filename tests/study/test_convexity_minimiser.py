"""Answers against the certified minimiser (``replication.study.convexity.minimiser``): the
certificate under outlier pairs (notebook 06, section 4) and the two-step's fixed point (notebook
01, section 3d)."""

from replication.study import convexity as bl

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
