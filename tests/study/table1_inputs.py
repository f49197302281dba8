"""Notebook 03's ledger inputs for the tests of Table I's records (``tests/study/
test_table1_claims.py``, ``test_table1_sqp_claims.py``, ``test_table1_cell_claims.py``): small
synthetic measurements that pass every check, each at a set distance from its threshold, the edits
that move one number just inside or just past a check, and the runner that applies both."""
import numpy as np
import pandas as pd
import pytest

from replication.study import paper
from replication.study.table1.claims import SECTION5_SETTINGS, Runs

DEF, IDENT, FAR = SECTION5_SETTINGS  # "defaults", "0-90 deg, identity start", "matched (fresh seeds)"
SQP = ["optimization (analytic)", "optimization (capped)"]
CAPS = {"optimization (capped)": 30}
SCALES = {"as printed": 1.0, "/ 2J": 0.025, "/ 100J": 0.0005}
ORDERS = ["(14) then (15)", "(15) then (14)"]  # the half-step orders of the grid


# ---- synthetic measurements that pass every check
# --------------------------------------------------

def _conv():
    """A convergence table (index (setting, method)) whose numbers pass every check, each at a set
    distance."""
    rows = {}
    two_step = {DEF: (5, 8, 7, 9), IDENT: (11, 12, 11, 13), FAR: (12, 20, 16, 22)}  # below 1 %, settled, its interval
    for label, (below, settled, low, high) in two_step.items():
        rows[(label, "ours_right")] = dict(below_1pct=below, below_1pct_low=below - 1, below_1pct_high=below + 1,
                                           settled=settled, settled_low=low, settled_high=high, error_rises=0.31,
                                           cost_rises=0.5, rises_above_floor=0.0099, diverts_above_floor=0.0049)
        rows[(label, "ours_left")] = dict(rows[(label, "ours_right")])
        for k, name in enumerate(SQP):
            rows[(label, name)] = dict(below_1pct=9 - k, below_1pct_low=8 - k, below_1pct_high=10 - k,
                                       settled=(9 if label == DEF else 11) + 2 * k, settled_low=7, settled_high=14,
                                       error_rises=0.4, cost_rises=0.2, rises_above_floor=0.06,
                                       diverts_above_floor=0.016 if k == 0 else 0.01)
    conv = pd.DataFrame.from_dict(rows, orient="index").astype(float)
    conv.index.names = ["setting", "method"]
    return conv


def _scales():
    rows = {}
    for label in (DEF, IDENT, FAR):
        for k, name in enumerate(SCALES):
            rows[(label, name)] = {"failed": 0.0, "below_1pct": 31 + k, "below_1pct_low": 30 + k,
                                   "below_1pct_high": 33 + k, "settled": 9 + k if label == DEF else 6 + 7 * k,
                                   "settled_low": 5, "settled_high": 25, "mean @15": 0.05, "mean @30": 0.02,
                                   "mean @50": 0.011 + k / 1000}
    scales = pd.DataFrame.from_dict(rows, orient="index").astype(float)
    scales.index.names = ["setting", "eq. (8) times"]
    return scales


def _versus(verdict_early="differs"):
    rows = {}
    for n in (2, 5, 10, 20, 30, 50):
        for k, m in enumerate(["ours_right", "ours_left", *SQP]):
            z = -16.4 - k if n >= 20 else 40.0
            rows[(n, m)] = {"ratio": 0.65 + k / 100 if n >= 20 else 3.0, "z": z, "z uniform": z / 2,
                            "z as printed": 1.25 * z, "verdict": verdict_early if n < 20 else "differs"}
    cmp = pd.DataFrame.from_dict(rows, orient="index")
    cmp.index.names = ["iteration", "method"]
    return cmp


def reference():
    """The paper's Table I with SQP's means at iterations 15 and 30 changed (to see that they are
    the ones printed)."""
    ref = paper.load_table1().copy()
    ref.loc[(15, "optimization"), "mean"], ref.loc[(30, "optimization"), "mean"] = 0.2, 0.05
    return ref


def confirm():
    """:func:`fresh_seed_counts`'s output whose shares pass every check, each at a set distance."""
    rows = {}
    for label in (DEF, IDENT):
        rows[(label, "ours_right")] = dict(error_rises=0.32, cost_rises=0.45, rises_above_floor=0.0098,
                                           diverts_above_floor=0.0048)
        rows[(label, "optimization (analytic)")] = dict(error_rises=0.9, cost_rises=0.8, rises_above_floor=0.74,
                                                        diverts_above_floor=0.016 if label == DEF else 0.012)
    conv = pd.DataFrame.from_dict(rows, orient="index")
    conv.index.names = ["setting", "method"]
    div = pd.DataFrame({"diverts, error > 0.05": [0.023, 0.0, 0.0, 0.033, 0.0, 0.0],
                        "... and on a rotation": [0.0, 0.0, 0.0, 0.003, 0.0, 0.0],
                        "... read on projected iterates": [0.93, 0.1, 0.0, 0.95, 0.1, 0.0]},
                       index=pd.MultiIndex.from_product([[DEF, IDENT], ["SQP, eq. (8) as printed",
                                                                         "SQP, eq. (8) / 2J", "two-step R^r"]]))
    scales = pd.DataFrame.from_dict({("matched", "as printed"): dict(failed=0.84, below_1pct=np.nan,
                                                                     below_1pct_low=np.nan, below_1pct_high=np.nan),
                                     ("matched", "/ 100J"): dict(failed=0.0, below_1pct=36, below_1pct_low=35,
                                                                 below_1pct_high=37)}, orient="index")
    scales.index.names = ["setting", "eq. (8) times"]
    return dict(seed=21000, n_runs=1000, n_sqp=300, conv=conv, div=div, scales=scales)


def table1_inputs():
    """``(first, second)``: the keyword arguments of the two-step records (``first``) and of SQP's
    and Table I's cells' records (``second``), the measurements of :func:`_conv` etc. and the run
    counts :func:`runs_of` reads."""
    at10 = {DEF: 0.0123, IDENT: 0.0456, FAR: 0.0789}
    settings = {label: (None, {"ours_right": np.full((4, 50), v)}, None) for label, v in at10.items()}
    cost_ratio = {label: {"@10 / @1": 2.5e-4, "@10 / minimum": (r10, r10 - 0.1, r10 + 0.1),
                          "@50 / minimum": (r50, r50 - 0.01, r50 + 0.01)}
                  for label, r10, r50 in ((DEF, 1.06, 1.05), (IDENT, 3.21, 1.07), (FAR, 7.89, 1.09))}
    scales = _scales()
    sens_index = pd.MultiIndex.from_tuples([("0-90 deg", "R0 turned 150 deg", n, o) for n in ("a", "b", "c")
                                            for o in ORDERS] + [("Haar", "identity", "a", ORDERS[0])],
                                           names=["motions", "start", "noise", "half-steps"])
    closer_index = pd.MultiIndex.from_tuples([("0-90 deg", "R0 turned 150 deg", "a", o, n) for o in ORDERS
                                              for n in (2, 5, 10, 15, 20, 30, 50)],
                                             names=["motions", "start", "noise", "half-steps", "iteration"])
    matched = pd.DataFrame({("ours_right", "mean"): [2.1234]}, index=pd.Index([2], name="iteration"))
    fails = pd.DataFrame({"optimization (analytic)": [0.82]}, index=["matched setting (fresh seeds)"])
    div = pd.DataFrame({"diverts, error > 0.05": [0.013, 0.0, 0.0, 0.03, 0.0, 0.0],
                        "... and on a rotation": [0.0, 0.0, 0.0, 0.003, 0.0, 0.0],
                        "... read on projected iterates": [0.94, 0.1, 0.0, 0.96, 0.1, 0.0]},
                       index=pd.MultiIndex.from_product([[DEF, IDENT], ["SQP, eq. (8) as printed",
                                                                         "SQP, eq. (8) / 2J", "two-step R^r"]]))
    common = dict(scale_names=SCALES, sqp_names=SQP, caps=CAPS, n_runs=1000, n_slow=300, reference=reference(),
                  seeds=(1000, 11000), confirm=confirm())
    first = dict(settings=settings, conv=_conv(), cost_ratio=cost_ratio, min_cost=(0.1234, 0.0012), scales=scales,
                 fresh_minimum={"seed": 43000, IDENT: {"@10 / minimum": (2.16, 2.0, 2.32), "n": 1000}}, **common)
    second = dict(conv=_conv(), div=div, fails=fails, scales=scales, far_scaled=scales.loc[(FAR, "/ 100J")],
                  cmp_default=_versus(), cmp_matched=_versus(), matched=matched,
                  sens=pd.DataFrame({"R^r @50": [0.0081, 0.0081, 0.0102, 0.0102, 0.0131, 0.0131, 0.02],
                                     "early cells agreeing": [2, 5, 1, 1, 0, 0, 0]}, index=sens_index),
                  left_closer=pd.Series([True] * 7 + [False] * 7, index=closer_index),
                  fresh=pd.DataFrame({"early cells agreeing": [1, 5], "R^l closer": [9, 0], "early cells": [9, 8]},
                                     index=pd.MultiIndex.from_tuples([("0-90 deg", "R0 turned 150 deg", o)
                                                                      for o in ORDERS],
                                                                     names=["motions", "start", "half-steps"])),
                  cap_shares={"found": {50: 0.8433, 100: 0.68, "n": 300}, "fresh": {50: 0.8433, 100: 0.7033, "n": 300},
                              "seeds": (41000, 42000)},
                  **common)
    return first, second


def runs_of(inputs: dict, n_grid: int = 300) -> Runs:
    """The :class:`Runs` that ``inputs`` (one of :func:`table1_inputs`'s dicts) name."""
    return Runs(n_runs=inputs["n_runs"], n_slow=inputs["n_slow"], n_grid=n_grid, seeds=inputs["seeds"],
                reference=inputs["reference"])


# ---- edits of the passing inputs: ``change(first, second)`` moves one number
# --------------------------------------------------

def _set(frame, index, column, value):
    frame = frame.copy()
    frame.loc[index, column] = value
    return frame


def conv_at(index, column, value):
    """Set ``conv.loc[index, column]`` in both functions' inputs (``index``: a row, or a list of
    rows)."""
    rows = index if isinstance(index, list) else [index]

    def change(first, second):
        for inputs in (first, second):
            for row in rows:
                inputs["conv"] = _set(inputs["conv"], row, column, value)
    return change


def scaled_settled(label, values):
    """Set where SQP settles at each cost scale of ``label`` (the two-step records' ``scales``)."""
    def change(first, second):
        scales = first["scales"].copy()
        for name, v in zip(SCALES, values):
            scales.loc[(label, name), "settled"] = v
        first.update(scales=scales)
    return change


def second_at(key, index, column, value):
    """Set ``second[key].loc[index, column]``."""
    return lambda first, second: second.update({key: _set(second[key], index, column, value)})


def confirm_at(key, index, column, value):
    """Set ``confirm[key].loc[index, column]`` (the fresh seeds' counts) in both functions'
    inputs."""
    def change(first, second):
        for inputs in (first, second):
            inputs["confirm"] = {**inputs["confirm"], key: _set(inputs["confirm"][key], index, column, value)}
    return change


def far_scaled_at(column, value):
    def change(first, second):
        second["far_scaled"] = second["far_scaled"].copy()
        second["far_scaled"][column] = value
    return change


def reference_at(index, value):
    """Set the paper's Table I mean at ``index``."""
    def change(first, second):
        second["reference"] = _set(second["reference"], index, "mean", value)
    return change


def closer_at(position, value):
    def change(first, second):
        closer = second["left_closer"].copy()
        closer.iloc[position] = value
        second["left_closer"] = closer
    return change


def check_just_inside_and_past(boundaries, name, records):
    """``records(first, second)`` (a unit's records from :func:`table1_inputs`'s dicts) pass with
    ``boundaries[name]``'s inside edit and raise, naming the claim, with its outside one
    (``boundaries[name] = (claim, inside, outside)``)."""
    claim, inside, outside = boundaries[name]
    first, second = table1_inputs()
    inside(first, second)
    assert records(first, second)
    first, second = table1_inputs()
    outside(first, second)
    with pytest.raises(ValueError, match=f"claim '{claim}': the evidence does not bear the verdict: expected "):
        records(first, second)
