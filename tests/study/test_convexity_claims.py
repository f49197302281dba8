"""The ``convex_problem`` record (``replication.study.convexity.claims``): a valid record, and its
guards at their boundaries."""
import pandas as pd
import pytest

from replication.study import convexity as bl
from replication.study.ledger import check_record

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
