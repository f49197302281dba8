"""scripts/spread.py: which stored notebook outputs another machine's rounding changes (its
comparison logic)."""
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("spread", ROOT / "scripts" / "spread.py")
spread = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(spread)


def cell(source, *outputs):
    return {"cell_type": "code", "source": [source], "outputs": list(outputs)}


def stream(text, name="stdout"):
    return {"output_type": "stream", "name": name, "text": [text]}


def result(text, png=None):
    data = {"text/plain": [text]}
    if png:
        data["image/png"] = png
    return {"output_type": "execute_result", "data": data}


def nb(*cells):
    return {"cells": [{"cell_type": "markdown", "source": ["# t"]}, *cells]}


def test_streams_are_merged_images_and_ignored_cells_left_out():
    texts = spread.compared_texts(nb(cell("print(1)", stream("a 1"), stream("\n"), result("x 2", png="AAAA")),
                                     cell("# NBVAL_IGNORE_OUTPUT\nt()", stream("12.3 ms"))))
    assert texts == {(1, "stream:stdout"): "a 1\n", (1, "1:text/plain"): "x 2"}


def test_memory_addresses_are_sanitised_as_nbval_does():
    texts = spread.compared_texts(nb(cell("f", result("<f at 0x7f3a2b1c4d50>"))))
    assert texts[(1, "1:text/plain")] == "<f at 0xADDRESS>"


def test_a_number_that_moves_is_fragile_and_named_with_its_variant():
    stored = {(1, "1:text/plain"): "share 80-85 % [75, 88]"}
    runs = {"jitter": {(1, "1:text/plain"): "share 80-85 % [75, 88]"},
            "avx2": {(1, "1:text/plain"): "share 80-85 % [76, 88]"}}
    rows = spread.compare(stored, runs)
    moved = [r for r in rows if r["fragile"]]
    assert [r["stored"] for r in moved] == ["75"] and "avx2" in moved[0]["what"]
    assert moved[0]["spread"] == ["75", "76"]
    assert sum(not r["fragile"] for r in rows) == 3


def test_a_column_realigned_by_a_wider_number_is_not_a_text_difference():
    stored = {(1, "1:text/plain"): "a    9.5\nbb   1.0"}
    runs = {"jitter": {(1, "1:text/plain"): "a   10.5\nbb   1.0"}}
    rows = spread.compare(stored, runs)
    assert [r["stored"] for r in rows if r["fragile"]] == ["9.5"]


@pytest.mark.parametrize("other, found", [("every run stopped", "text differs"), (None, "missing")])
def test_other_words_or_a_missing_output_are_fragile(other, found):
    stored = {(2, "stream:stdout"): "all runs stopped"}
    runs = {"avx2": {} if other is None else {(2, "stream:stdout"): other}}
    rows = spread.compare(stored, runs)
    assert rows[0]["fragile"] and found in rows[0]["what"]


def test_the_margin_variant_measures_the_distance_to_the_edge():
    stored = {(1, "1:text/plain"): "0.27 and 3"}
    runs = {"jitter": {(1, "1:text/plain"): "0.27 and 3"}, "margin": {(1, "1:text/plain"): "0.28 and 3"}}
    rows = {r["stored"]: r for r in spread.compare(stored, runs)}
    assert rows["0.27"]["margin"] == "below 1e-13" and rows["0.27"]["fragile"]
    assert rows["3"]["margin"] == ">= 1e-13" and not rows["3"]["fragile"]


def test_guards_that_fail_at_twice_their_margin_are_fragile_with_their_distance(monkeypatch, tmp_path):
    monkeypatch.setattr(spread, "CACHE", tmp_path)
    (tmp_path / "margin").mkdir()
    (tmp_path / "margin" / "03_t.guards.jsonl").write_text(
        '{"what": "a share of runs", "value": 0.66, "bound": "65-70 %", "margin": 0.0133, "distance": 0.01}\n')
    rows = spread.guard_rows(Path("notebooks/03_t.ipynb"), ["jitter", "margin"])
    assert len(rows) == 1 and rows[0]["fragile"]
    assert "0.66 is 0.01 from an edge of 65-70 %, less than 0.0133" in rows[0]["what"]
