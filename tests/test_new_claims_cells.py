"""Claims where their evidence is (issue 37, point 3): one small function per claim, taking only its numbers, called
from the notebook cell that measures them; no claim builder over ~60 lines or ~8 parameters."""
import ast
import json
import re
from pathlib import Path

import pytest
from test_claims_records import _confirm, _reference
from test_fig5 import FAIL, _record_inputs
from test_lab_claims import lab_claims_inputs, lab_study

from replication.study.fig5 import claims as fig5_claims
from replication.study.lab import claims as lab_claims
from replication.study.lab.seed_sets import LAB_SETTING, SeedSets, found_setting
from replication.study.table1 import Runs

ROOT = Path(__file__).resolve().parent.parent
CLAIM_MODULES = ["replication/study/lab/claims.py", "replication/study/lab/seed_sets.py",
                 "replication/study/table1/claims.py", "replication/study/table1/sqp_claims.py",
                 "replication/study/table1/cell_claims.py", "replication/study/fig5/claims.py",
                 "replication/study/convexity.py"]
MAX_LINES, MAX_PARAMS = 62, 8
CLAIM_MIME = "application/vnd.replication.claim+json"


def oversized(source: str, max_lines: int = MAX_LINES, max_params: int = MAX_PARAMS) -> list:
    """``(name, lines, parameters)`` of every function of ``source`` longer than ``max_lines`` or with more than
    ``max_params`` parameters."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            a = node.args
            params = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)
            lines = node.end_lineno - node.lineno + 1
            if lines > max_lines or params > max_params:
                found.append((node.name, lines, params))
    return found


def _function(lines: int, params: int) -> str:
    args = ", ".join(f"a{k}" for k in range(params))
    return f"def f({args}):\n" + "    x = 1\n" * (lines - 2) + "    return x\n"


def test_the_size_rule_sees_a_function_just_past_either_limit():
    assert oversized(_function(MAX_LINES, MAX_PARAMS)) == []
    assert oversized(_function(MAX_LINES + 1, MAX_PARAMS)) == [("f", MAX_LINES + 1, MAX_PARAMS)]
    assert oversized(_function(MAX_LINES, MAX_PARAMS + 1)) == [("f", MAX_LINES, MAX_PARAMS + 1)]
    assert oversized("def g(a, *, b, **kw):\n    pass\n", max_params=2) == [("g", 2, 3)]


@pytest.mark.parametrize("path", CLAIM_MODULES)
def test_no_claim_builder_over_60_lines_or_8_parameters(path):
    assert oversized((ROOT / path).read_text(encoding="utf-8")) == [], path


def records_away_from_their_function(nb: dict) -> list:
    """``(cell, claim)`` of every stored record whose cell does not call a function named for its claim (``<claim>(``
    or ``<claim>_record(``): a record built elsewhere, in a builder of several claims, and only recorded here."""
    away = []
    for index, cell in enumerate(nb["cells"]):
        source = "".join(cell.get("source", ""))
        for out in cell.get("outputs", []):
            rec = out.get("data", {}).get(CLAIM_MIME)
            if rec and not re.search(rf"\b{re.escape(rec['claim'])}(_record)?\(", source):
                away.append((index, rec["claim"]))
    return away


def _notebook_with(source: str, claims: list) -> dict:
    outputs = [{"output_type": "display_data", "data": {CLAIM_MIME: {"claim": c}}} for c in claims]
    return {"cells": [{"cell_type": "code", "source": source, "outputs": outputs}]}


def test_the_cell_rule_sees_a_record_built_by_a_builder():
    assert records_away_from_their_function(_notebook_with(
        "ledger.record(**claims.lab_averaging(study, fresh))", ["lab_averaging"])) == []
    assert records_away_from_their_function(_notebook_with(
        "ledger.record(**either_minimises_record(a, b))", ["either_minimises"])) == []
    assert records_away_from_their_function(_notebook_with(
        "for rec in lab_claims(study, fresh):\n    ledger.record(**rec)", ["lab_averaging", "fig6_accuracy"])) == [
        (0, "lab_averaging"), (0, "fig6_accuracy")]
    assert records_away_from_their_function(_notebook_with(   # a name that only starts like the claim's
        "ledger.record(**lab_averaging_all(study))", ["lab_averaging"])) == [(0, "lab_averaging")]


@pytest.mark.parametrize("name", ["03_table1_monte_carlo", "05_table2_experiment"])
def test_each_record_is_made_in_the_cell_that_calls_its_claims_function(name):
    nb = json.loads((ROOT / "notebooks" / f"{name}.ipynb").read_text(encoding="utf-8"))
    assert records_away_from_their_function(nb) == []
    assert sum(CLAIM_MIME in o.get("data", {}) for c in nb["cells"] for o in c.get("outputs", [])) >= 10


def test_the_lab_claims_on_the_first_seeds_need_no_fresh_ones():
    study = lab_study(range(1, 21))
    rec = lab_claims.table2_rms(study, lab_study(range(1, 4))["rms_ours_right"])
    assert rec["setting"] == found_setting(study) == f"{LAB_SETTING}; seeds 1-20 (and the committed draw, seed " \
                                                     "20130501)"
    assert rec["section"] == "Sensitivity to the magnetometer noise" and "(20 seeds)" in rec["evidence"]


def test_seed_sets_label_both_sets_as_the_checks_name_them():
    s = SeedSets(lab_study(range(1, 21)), lab_study(range(21, 41)))
    assert list(s.sets) == ["seeds 1-20", "fresh seeds 21-40"] and s.n == 20
    assert s.setting.endswith("found on seeds 1-20, confirmed on fresh seeds 21-40 (and the committed draw, seed "
                              "20130501)")
    assert s.both("reversed_loses") == "20 of 20 (84-100 %) on the first and 20 of 20 (84-100 %) on the fresh seeds"
    assert s.deg("single_minus_mean").endswith(" deg on the fresh seeds")


def test_a_lab_claim_names_the_fresh_set_where_its_check_fails():
    fresh = lab_study(range(21, 41))
    fresh.loc[fresh.index[-6:], "rms_sensor_frame"] = 0.0   # calibration no longer reduces the RMS in 6 of 20
    with pytest.raises(ValueError, match=r"^claim 'table2_reduction': .*most seeds of fresh seeds 21-40"):
        lab_claims.table2_reduction(lab_study(range(1, 21)), fresh)
    fresh.loc[fresh.index[-6], "rms_sensor_frame"] = 24.0   # 5 of 20: still most
    assert lab_claims.table2_reduction(lab_study(range(1, 21)), fresh)["verdict"] == "holds"


@pytest.mark.parametrize("fresh_seeds, shared", [(range(21, 41), None), (range(20, 40), "20"),
                                                 (range(1, 21), "1, 2, 3, 4, 5 ...")])
def test_the_fresh_seeds_of_a_lab_claim_must_be_disjoint_from_the_first(fresh_seeds, shared):
    study, fresh = lab_study(range(1, 21)), lab_study(fresh_seeds)
    if shared is None:
        assert lab_claims.fig6_accuracy(study, fresh)["verdict"] == "holds only if"
    else:
        with pytest.raises(ValueError, match=rf"^the seed study: the fresh seeds repeat .*\({re.escape(shared)}\); "
                                             "a finding is confirmed only on seeds disjoint"):
            lab_claims.fig6_accuracy(study, fresh)


def test_the_pitch_intervention_is_confirmed_on_disjoint_seeds():
    inputs = lab_claims_inputs()
    kw = dict(pitch_true=-4.09, true_r0_pitch=inputs["frames"].loc["true R0", "pitch mean"])
    first, again = inputs["pitch_cal"]
    assert lab_claims.table2_measures_calibration(inputs["study"], inputs["fresh"], pitch_cal=(first, again), **kw)
    with pytest.raises(ValueError, match="^the pitch-bias intervention: the fresh seeds repeat 120 of"):
        lab_claims.table2_measures_calibration(inputs["study"], inputs["fresh"], pitch_cal=(first, first), **kw)


def test_runs_refuse_a_confirmation_on_the_seeds_it_confirms():
    with pytest.raises(ValueError, match="two different root seeds"):
        Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 1000), reference=_reference())
    runs = Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 21000), reference=_reference())
    with pytest.raises(ValueError, match="confirmed on root seed 21000, one of the seeds they were found on"):
        runs.setting(_confirm())                      # its root seed is 21000
    assert "fresh root seed 21001" in runs.setting({**_confirm(), "seed": 21001})


def test_runs_name_the_seeds_and_the_confirmation_in_the_setting():
    runs = Runs(n_runs=1000, n_slow=300, n_grid=300, seeds=(1000, 11000), reference=_reference())
    setting = runs.setting(_confirm())
    assert setting.startswith("1000 runs each: our defaults") and "fresh root seed 11000" in setting
    assert "finite-difference and capped (300 runs); the counts confirmed on fresh root seed 21000" in setting


@pytest.mark.parametrize("failing_share, settings", [(0.87, "(2 settings)"), (0.8701, "(1 settings)")])
def test_far_start_counts_a_row_as_failing_from_its_share_on(failing_share, settings):
    inp = _record_inputs()   # the far-start rows fail in 87 % and in all of their runs
    stop_keys = list(inp["stop_levels"].index.droplevel(-1).unique())
    growth = inp["found"].drop(index=stop_keys)
    far = fig5_claims.far_start(growth, inp["fresh"], n_runs=150, failing_share=failing_share)
    assert settings in far["text"]


def test_far_start_names_the_fresh_settings_it_was_confirmed_on():
    inp = _record_inputs()
    stop_keys = list(inp["stop_levels"].index.droplevel(-1).unique())
    growth = inp["found"].drop(index=stop_keys)
    assert fig5_claims.far_start(growth, inp["fresh"], n_runs=150)["fresh_settings"] == 1
    assert fig5_claims.far_start(growth, inp["fresh"].drop(index=FAIL[0]), n_runs=150)["fresh_settings"] == 0
