"""The two-step records of notebook 03 (``replication.study.table1.claims``:
``two_step_10_iterations``, ``cost_to_zero``, ``faster_than_sqp``, ``smoother_monotone``, and
``Runs``, the run counts and seeds every record of the notebook names), built in the notebook's
order from the synthetic measurements of ``tests/study/table1_inputs.py``: the claim ids and
verdicts, the numbers in the evidence, every record valid for the ledger and in a heading of the
notebook, and each check raising just past its threshold, not just before it. SQP's records:
test_table1_sqp_claims.py; Table I's cells: test_table1_cell_claims.py; the functions the records
rest on: test_table1.py."""
import json
from pathlib import Path

import numpy as np
import pytest
from table1_inputs import (
    DEF,
    FAR,
    IDENT,
    SQP,
    check_just_inside_and_past,
    confirm,
    confirm_at,
    conv_at,
    reference,
    runs_of,
    scaled_settled,
    table1_inputs,
)

from conftest import _valid
from replication.study import ledger
from replication.study.table1.claims import (
    SECTIONS,
    Runs,
    cost_to_zero,
    faster_than_sqp,
    smoother_monotone,
    two_step_10_iterations,
)

TWO_STEP_IDS = ["two_step_10_iterations", "cost_to_zero", "faster_than_sqp", "smoother_monotone"]
NOTEBOOK = Path(__file__).resolve().parents[2] / "notebooks" / "03_table1_monte_carlo.ipynb"


def two_step_claims(settings, conv, cost_ratio, min_cost, scales, scale_names, *, sqp_names, caps, confirm,
                    fresh_minimum, **run_counts):
    """Notebook 03's two-step records (section 5), one call per claim with its numbers, in the
    ledger's order."""
    runs = runs_of(run_counts)
    return [two_step_10_iterations(settings, conv, runs, confirm, caps=caps),
            cost_to_zero(cost_ratio, min_cost, fresh_minimum, runs, confirm),
            faster_than_sqp(conv, scales, runs, confirm, sqp_names=sqp_names, caps=caps, scale_names=scale_names),
            smoother_monotone(conv, runs, confirm)]


def test_two_step_claims_ids_verdicts_and_numbers():
    first, _ = table1_inputs()
    records = two_step_claims(**first)
    assert [r["claim"] for r in records] == TWO_STEP_IDS
    assert [r["verdict"] for r in records] == ["holds only if", "holds only if", "undecidable from the text",
                                                "holds only if"]
    _valid(records)
    ten, cost, faster, smooth = records
    assert f"mean error at iteration 10: {0.0123 / np.sqrt(3):.1%} of ||R0||" in ten["condition"]
    assert f"the paper's own {0.051 / np.sqrt(3):.1%} (Table I)" in ten["condition"]
    assert "under 1 % only from iteration 11-12" in ten["condition"]
    assert ten["evidence"].startswith(f"mean R^r error at iteration 10: {DEF} 0.0123, {IDENT} 0.0456, {FAR} 0.0789; "
                                      "first iteration under 1 % (0.0173): defaults 5 [4, 6]; 0-90 deg, identity "
                                      "11 [10, 12]; matched 12 [11, 13]; smaller motions")
    assert ten["uncertainty"] == "95 % bootstrap intervals over runs (in brackets)"
    assert ten["setting"].startswith("1000 runs each: our defaults") and "identity on root seed 1000; the matched " \
        "setting (0-90 deg, start 150 deg from R0) on fresh root seed 11000; SQP variants analytic and per-pair cost " \
        "(1000 runs), finite-difference and capped (300 runs); the counts confirmed on fresh root seed 21000 (the " \
        "two identity-start settings: two-step 1000 runs, SQP as printed and / 2J 300; the matched setting: SQP as " \
        "printed and / 100J, 300 runs)" in ten["setting"]
    assert "certified minimum, 0.1234 on average (defaults), and the two-step iterates level off 5%-9% above it" \
        in cost["condition"] and "the cost at iteration 10 is still 3.21 [3.11, 3.31] (identity start) to 7.89 " \
        "[7.79, 7.99] (start 150 deg from R0) times that minimum, on new problems (root seed 43000, identity start) " \
        "2.16 [2.00, 2.32]: a ratio of means with a heavy tail" in cost["condition"]
    assert "again on 1000 new problems of root seed 43000" in cost["setting"]
    assert cost["evidence"].startswith("two-step cost at iteration 10: 2.5e-04 of its value at iteration 1")
    assert f"{DEF} 1.06x / 1.050x; {IDENT} 3.21x / 1.070x" in cost["evidence"]
    assert cost["uncertainty"].startswith("SE 0.0012 of the mean minimum")
    assert "two-step method (8) beats every SQP configuration tried (variants: analytic 9 [7, 14], capped 11 [7, 14]"\
        in faster["evidence"]
    assert "eq. (8) scaled as printed 9 [5, 25], / 2J 10 [5, 25], / 100J 11 [5, 25])" in faster["evidence"]
    assert "settles at 12 [11, 13] (identity start) and 20 [16, 22] (far start)" in faster["evidence"]
    assert f"error rises at some iteration: {DEF} 31% [28, 34], {IDENT} 31% [28, 34], {FAR} 31% [28, 34]; whose " \
        f"cost rises: {DEF} 50% [47, 53]" in smooth["evidence"]
    assert "at most 1.0% [0.5, 1.8] (SQP, analytic: 6% [5, 8] at our defaults). On fresh root seed 21000: error " \
        f"rises {DEF} 32% [29, 35], {IDENT} 32% [29, 35]; cost rises {DEF} 45% [42, 48]" in smooth["evidence"]
    assert smooth["evidence"].endswith("above twice its final value at most 1.0% [0.5, 1.8] (SQP as printed, 300 "
                                       "runs: 74% [69, 79] at our defaults)")
    assert smooth["uncertainty"] == "95 % Wilson intervals over runs (in brackets)"


# (claim, change of the passing inputs just inside the check, the same just outside)
BOUNDARIES = {
    "R^r under 1 % by iteration 5 at the defaults": (
        "two_step_10_iterations", conv_at((DEF, "ours_right"), "below_1pct", 5),
        conv_at((DEF, "ours_right"), "below_1pct", 6)),
    "R^r under 1 % only after iteration 10 with 0-90 deg motions": (
        "two_step_10_iterations", conv_at((IDENT, "ours_right"), "below_1pct", 11),
        conv_at((IDENT, "ours_right"), "below_1pct", 10)),
    "two-step settles before every SQP variant at the defaults": (
        "faster_than_sqp", conv_at((DEF, SQP[0]), "settled", 9), conv_at((DEF, SQP[0]), "settled", 8)),
    "two-step settles before SQP at every scale at the defaults": (
        "faster_than_sqp", scaled_settled(DEF, [9, 10, 11]), scaled_settled(DEF, [8, 10, 11])),
    "some SQP variant settles first from the identity": (
        "faster_than_sqp", conv_at((IDENT, SQP[0]), "settled", 11), conv_at((IDENT, SQP[0]), "settled", 12)),
    "SQP at some scale settles later from the identity": (
        "faster_than_sqp", scaled_settled(IDENT, [6, 8, 13]), scaled_settled(IDENT, [6, 8, 12])),
    "two-step error rises above the floor in under 1 %": (
        "smoother_monotone", conv_at((FAR, "ours_right"), "rises_above_floor", 0.0099),
        conv_at((FAR, "ours_right"), "rises_above_floor", 0.01)),
    "two-step error rises in over 30 %": (
        "smoother_monotone", conv_at((IDENT, "ours_right"), "error_rises", 0.3001),
        conv_at((IDENT, "ours_right"), "error_rises", 0.3)),
    "fresh: two-step error rises above the floor in under 1 %": (
        "smoother_monotone", confirm_at("conv", (IDENT, "ours_right"), "rises_above_floor", 0.0099),
        confirm_at("conv", (IDENT, "ours_right"), "rises_above_floor", 0.01)),
    "fresh: two-step error rises in over 30 %": (
        "smoother_monotone", confirm_at("conv", (DEF, "ours_right"), "error_rises", 0.3001),
        confirm_at("conv", (DEF, "ours_right"), "error_rises", 0.3)),
}


@pytest.mark.parametrize("name", BOUNDARIES)
def test_each_two_step_check_raises_just_past_its_threshold(name):
    check_just_inside_and_past(BOUNDARIES, name, lambda first, second: two_step_claims(**first))


def test_a_missing_setting_is_named():
    first, _ = table1_inputs()
    first["conv"] = first["conv"].drop(index=IDENT, level="setting")
    with pytest.raises(ValueError, match=r"no setting \['0-90 deg, identity start'\]"):
        two_step_claims(**first)


def test_each_record_names_a_heading_of_notebook_03():
    headings = ledger.notebook_headings(json.loads(NOTEBOOK.read_text()))
    assert set(SECTIONS.values()) <= set(headings)
    first, _ = table1_inputs()
    for rec in two_step_claims(**first):
        assert rec["section"] == SECTIONS[rec["claim"]]
    assert SECTIONS["table1_sqp"] == SECTIONS["sqp_30_iterations"] == "SQP and the scale of its objective"
    assert SECTIONS["table1_early"] == SECTIONS["table1_final"] == "2. Sensitivity to the unstated settings"


def test_runs_refuse_a_confirmation_on_the_seeds_it_confirms():
    with pytest.raises(ValueError, match="two different root seeds"):
        Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 1000), reference=reference())
    runs = Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 21000), reference=reference())
    with pytest.raises(ValueError, match="confirmed on root seed 21000, one of the seeds they were found on"):
        runs.setting(confirm())                      # its root seed is 21000
    assert "fresh root seed 21001" in runs.setting({**confirm(), "seed": 21001})


def test_runs_name_the_seeds_and_the_confirmation_in_the_setting():
    runs = Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 11000), reference=reference())
    setting = runs.setting(confirm())
    assert setting.startswith("1000 runs each: our defaults") and "fresh root seed 11000" in setting
    assert "finite-difference and capped (300 runs); the counts confirmed on fresh root seed 21000" in setting
