"""replication._jitter: last-bit jitter of every generated and loaded input (REPLICATION_JITTER),
off by default."""
import dataclasses

import numpy as np
import pytest

from replication._jitter import DEFAULT_SCALE, ENV, LAST_BIT, VARIANTS, jitter, jitter_setting
from replication.core.so3 import random_rotations
from replication.rig.datafile import read_table
from replication.study.simulation import opencv_protocol, simulate
from replication.testing import rig_streams


def test_off_by_default_and_at_zero_returns_the_same_object(monkeypatch):
    x = np.linspace(0.0, 1.0, 7)
    monkeypatch.delenv(ENV, raising=False)
    assert jitter(x) is x
    monkeypatch.setenv(ENV, "0")
    assert jitter(x) is x and jitter_setting() is None


@pytest.mark.parametrize("text, expected", [("1", (1, DEFAULT_SCALE)), (" 7 ", (7, DEFAULT_SCALE)),
                                            ("2:1e-9", (2, 1e-9)), ("3:1e-3", (3, 1e-3))])
def test_the_setting_is_seed_and_scale(text, expected):
    assert jitter_setting(text) == expected


@pytest.mark.parametrize("text", ["-1", "x", "1:0", "1:-1e-9", "1:1.1e-3", "1.5", "1:abc"])
def test_a_bad_setting_is_refused_naming_the_variable(text):
    with pytest.raises(ValueError, match="REPLICATION_JITTER must be SEED or SEED:SCALE"):
        jitter_setting(text)


def test_relative_change_is_within_the_scale_and_nonzero():
    x = np.random.default_rng(0).normal(size=(50, 3, 3))
    for scale in (1e-15, 1e-11):
        y = jitter(x, (1, scale))
        rel = np.abs(y / x - 1.0)
        assert 0 < rel.max() <= scale + 4.5e-16 and np.count_nonzero(y != x) > x.size // 2


def test_a_stable_function_of_seed_and_content_whatever_the_call_order():
    a, b = np.arange(1.0, 10.0), np.arange(2.0, 11.0)
    first = (jitter(a, (1, 1e-12)), jitter(b, (1, 1e-12)))
    second = (jitter(b, (1, 1e-12)), jitter(a, (1, 1e-12)))
    assert np.array_equal(first[0], second[1]) and np.array_equal(first[1], second[0])
    assert not np.array_equal(jitter(a, (2, 1e-12)), first[0])


@pytest.mark.parametrize("x", [np.arange(5), np.array([True, False]), np.empty(0), 1.5, [1.0, 2.0]])
def test_integers_booleans_empty_and_non_arrays_pass_untouched(x):
    assert jitter(x, (1, 1e-9)) is x


def test_the_entry_points_jitter_their_outputs(monkeypatch, tmp_path):
    path = tmp_path / "t.txt"
    path.write_text("1.0 0.5 0.25\n2.0 0.75 0.125\n")
    monkeypatch.delenv(ENV, raising=False)
    plain = (simulate(3, 2).A, random_rotations(np.random.default_rng(1), 4), read_table(path, "tab")[0],
             opencv_protocol(np.random.default_rng(2)).A, rig_streams(3.0)[1].world_from_body)
    monkeypatch.setenv(ENV, "1:1e-12")
    moved = (simulate(3, 2).A, random_rotations(np.random.default_rng(1), 4), read_table(path, "tab")[0],
             opencv_protocol(np.random.default_rng(2)).A, rig_streams(3.0)[1].world_from_body)
    for p, m in zip(plain, moved):
        d = np.abs(m - p)
        assert 0 < d.max() < 1e-10


def test_the_lab_recording_jitters_its_float_columns_only(monkeypatch, lab_recording):
    from replication.study.lab import load_lab

    monkeypatch.delenv(ENV, raising=False)
    plain = load_lab(lab_recording)
    monkeypatch.setenv(ENV, "1:1e-12")
    moved = load_lab(lab_recording)
    assert moved.static_imu["set"].equals(plain.static_imu["set"])
    d = np.abs(moved.static_imu["gyr_x"].to_numpy() - plain.static_imu["gyr_x"].to_numpy())
    assert 0 < d.max() < 1e-10
    same = dataclasses.replace(plain)  # the same bytes jittered again: the same draw (a function of the content)
    assert np.array_equal(same.dynamic_markers["u0"], moved.dynamic_markers["u0"])
    assert not np.array_equal(same.dynamic_markers["u0"], plain.dynamic_markers["u0"])


def test_the_variants_each_draw_their_own_jitter_and_margin_is_coarser():
    seeds = [jitter_setting(v[ENV])[0] for v in VARIANTS.values()]
    assert len(set(seeds)) == len(seeds)
    assert set(LAST_BIT) == set(VARIANTS) - {"margin"}
    assert all(jitter_setting(VARIANTS[v][ENV])[1] == DEFAULT_SCALE for v in LAST_BIT)
    assert jitter_setting(VARIANTS["margin"][ENV])[1] / DEFAULT_SCALE > 99


def test_a_guard_that_does_not_hold_is_logged_not_raised_when_a_log_is_named(monkeypatch, tmp_path):
    import json

    from replication.core.stats import declared_bound, share_range

    log = tmp_path / "guards.jsonl"
    monkeypatch.setenv("REPLICATION_GUARD_LOG", str(log))
    assert declared_bound(10.05, 10, margin=0.1, what="evaluations") == "at least 10"
    assert share_range(0.66, margin=0.02, what="failed share") == "65-70 %"
    assert declared_bound(10.5, 10, margin=0.1) == "at least 10"  # holds: nothing logged
    records = [json.loads(line) for line in log.read_text().splitlines()]
    assert [r["what"] for r in records] == ["evaluations", "failed share"]
    assert abs(records[0]["distance"] - 0.05) < 1e-12 and abs(records[1]["distance"] - 0.01) < 1e-12
    monkeypatch.delenv("REPLICATION_GUARD_LOG")
    with pytest.raises(ValueError, match="inside its declared bound"):
        declared_bound(10.05, 10, margin=0.1)


def test_time_stamps_are_not_jittered_their_values_are(monkeypatch, tmp_path):
    path = tmp_path / "t.txt"
    path.write_text("1520530308188189400 0.5 0.25\n1520530308193345800 0.75 0.125\n")
    monkeypatch.setenv(ENV, "1:1e-9")
    data, _ = read_table(path, ("t", "a", "b"))
    assert data[0, 0] == 1520530308188189400.0 and data[1, 0] == 1520530308193345800.0
    assert data[0, 1] != 0.5 and abs(data[0, 1] - 0.5) < 1e-9
