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
