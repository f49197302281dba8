"""scripts/mutation_report.py: what a resumed mutation run tests (``--pending-names``)."""
import importlib.util
import json
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("mutation_report", ROOT / "scripts" / "mutation_report.py")
report = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(report)


def _project(tmp_path, monkeypatch, codes_by_module):
    """A project whose modules ``replication.rig.<name>`` have the given mutmut results (None: no
    meta file yet); each meta written after its source."""
    monkeypatch.setattr(report, "ROOT", tmp_path)
    monkeypatch.setattr(report, "TARGETS", [f"replication.rig.{n}.*" for n in codes_by_module]
                        + ["replication.rig.a.x_kept__mutmut_*"] * ("a" in codes_by_module))
    for name, codes in codes_by_module.items():
        source = tmp_path / "replication" / "rig" / f"{name}.py"
        source.parent.mkdir(parents=True, exist_ok=True)
        source.write_text("def f():\n    return 1\n")
        os.utime(source, (1_000_000, 1_000_000))
        if codes is not None:
            meta = tmp_path / "mutants" / "replication" / "rig" / f"{name}.py.meta"
            meta.parent.mkdir(parents=True, exist_ok=True)
            meta.write_text(json.dumps({"exit_code_by_key": codes}))
            os.utime(meta, (2_000_000, 2_000_000))
    return tmp_path


def test_a_stopped_run_resumes_with_the_mutants_that_have_no_result(tmp_path, monkeypatch):
    a = "replication.rig.a."
    _project(tmp_path, monkeypatch, {"a": {f"{a}x_f__mutmut_1": 1, f"{a}x_f__mutmut_2": None,
                                           f"{a}x_kept__mutmut_1": None}})
    assert report.pending_names() == ["replication.rig.a.x_f__mutmut_2", "replication.rig.a.x_kept__mutmut_1"]


def test_a_module_without_results_or_changed_since_runs_as_a_whole(tmp_path, monkeypatch):
    root = _project(tmp_path, monkeypatch, {"new": None, "done": {"replication.rig.done.x_f__mutmut_1": 0},
                                            "edited": {"replication.rig.edited.x_f__mutmut_1": 1}})
    edited = root / "replication" / "rig" / "edited.py"
    os.utime(edited, (2_000_001, 2_000_001))  # a second after its last result
    assert report.pending_names() == ["replication.rig.new.*", "replication.rig.edited.*"]
    os.utime(edited, (1_999_999, 1_999_999))  # a second before it
    assert report.pending_names() == ["replication.rig.new.*"]


def test_every_result_in_means_nothing_is_pending(tmp_path, monkeypatch):
    _project(tmp_path, monkeypatch, {"done": {"replication.rig.done.x_f__mutmut_1": 33}})
    assert report.pending_names() == []


_conftest_spec = importlib.util.spec_from_file_location("root_conftest", ROOT / "conftest.py")
root_conftest = importlib.util.module_from_spec(_conftest_spec)
_conftest_spec.loader.exec_module(root_conftest)


def test_a_mutant_meets_the_test_files_named_for_its_module_under_unit():
    mutant = "replication.rig.online.x\u01c1OnlineCalibrator\u01c1_decide__mutmut_23"
    files = root_conftest.unit_test_files(ROOT, mutant)
    names = {f.name for f in files}
    assert {"test_online.py", "test_online_drift.py", "test_online_guard.py"} <= names
    assert all(f.parent == ROOT / "tests" / "rig" for f in files) and "test_quality.py" not in names
    registry = root_conftest.unit_test_files(ROOT, "replication.core.solvers._registry.x_check_answer__mutmut_1")
    assert {f for f in registry if f.exists()} == {ROOT / "tests" / "core" / "test_solvers_registry.py"}
    ledger = root_conftest.unit_test_files(ROOT, "replication.study.ledger.x_first_clause__mutmut_3")
    assert ROOT / "tests" / "study" / "test_ledger.py" in ledger
    assert ROOT / "tests" / "study" / "test_book.py" in ledger  # book.py imports the ledger: a door
    offset = root_conftest.unit_test_files(ROOT, "replication.rig.offset_search.x__search__mutmut_1")
    assert {f.name for f in offset if f.exists()} == {"test_offset_search.py", "test_association.py"}  # its door
    for not_a_mutant in ("", "stats", "fail", "list_all_tests"):
        assert root_conftest.unit_test_files(ROOT, not_a_mutant) is None


def test_survivors_of_a_unit_only_run_are_marked_and_the_scores_called_lower_bounds(tmp_path, monkeypatch, capsys):
    a = "replication.rig.a."
    root = _project(tmp_path, monkeypatch, {"a": {f"{a}x_f__mutmut_1": 1, f"{a}x_f__mutmut_2": 0,
                                                  f"{a}x_f__mutmut_3": 33}})
    assert report.main() == 0
    out = capsys.readouterr().out
    assert "lower bound" not in out and "[unit tests only]" not in out
    (root / "mutants" / report.UNIT_ONLY).write_text("replication.rig.a.x_f__mutmut_2\nreplication.rig.a.x_f__*\n")
    assert report.main() == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("replication.rig.a "))
    assert row.split()[1:6] == ["3", "1", "0", "0", "2"]  # total, killed, survived, equivalent, unit only
    assert "2 mutants were run against their unit's test files only" in out and "lower bound" in out
    assert "x_f__mutmut_2 [unit tests only]" in out


def test_survivors_re_run_all_but_those_declared_equivalent(tmp_path, monkeypatch):
    a = "replication.rig.a."
    root = _project(tmp_path, monkeypatch, {"a": {f"{a}x_f__mutmut_{i}": code
                                                  for i, code in enumerate((1, 0, 0, 33, None, 36), start=1)}})
    (root / "docs").mkdir()
    (root / "docs" / "mutation_survivors.md").write_text(f"| {a}x_f__mutmut_3 | a.py:2 | x | y |\n")
    assert report.rerun_names() == [f"{a}x_f__mutmut_{i}" for i in (2, 4, 5, 6)]


def test_a_mutant_re_run_against_every_test_after_unit_is_no_longer_unit_only():
    key = "replication.rig.a.x_f__mutmut_2"
    assert report.unit_only(key, ["replication.rig.a.*"], [])
    assert not report.unit_only(key, ["replication.rig.a.*"], [key])
    assert report.unit_only(key, ["replication.rig.a.*"], ["replication.rig.a.x_f__mutmut_1"])
    assert not report.unit_only(key, ["replication.rig.b.*"], [])
