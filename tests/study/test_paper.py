import shutil

import numpy as np
import pytest

from replication.core import checks
from replication.rig.datafile import DataFileError, DataFileNotFound
from replication.study import paper


def test_r0_as_printed_is_nearly_a_rotation():
    R = paper.load_r0()
    assert R.shape == (3, 3)
    assert 1e-4 < np.linalg.norm(R.T @ R - np.eye(3)) < 1e-3
    checks.check_rotation_matrices(paper.r0_camera_from_sensor(), atol=1e-12)


def test_tables_are_complete():
    t1, t2 = paper.load_table1(), paper.load_table2()
    assert len(t1) == 21 and t1.loc[(50, "ours_right"), "mean"] == pytest.approx(0.009)
    assert len(t2) == 12 and t2.loc[("pitch", "sensor_frame"), "rms_deg"] == pytest.approx(68.3401)
    assert paper.load_claims()["sqp_30_iterations"] == 30 and paper.load_claims()["lab_protocol"] == 10


def test_table2_rms_consistency_is_as_documented():
    t2 = paper.load_table2()
    implied = np.hypot(t2["mean_deg"], t2["sd_deg"])
    rel = (implied / t2["rms_deg"] - 1).abs()
    assert rel.loc[("roll", "optimization")] < 0.01 and rel.loc[("pitch", "sensor_frame")] < 0.01
    assert rel.loc[("roll", "ours_left")] > 0.1  # the paper's own roll row does not add up (data/paper/README.md)


@pytest.fixture
def data_copy(tmp_path, monkeypatch):
    shutil.copytree(paper.data_dir() / "paper", tmp_path / "paper")
    monkeypatch.setenv("REPLICATION_DATA_DIR", str(tmp_path))
    return tmp_path / "paper"


def test_malformed_value_is_named(data_copy):
    text = (data_copy / "table1.csv").read_text().replace("2.339", "2.3x9")
    (data_copy / "table1.csv").write_text(text)
    with pytest.raises(ValueError, match=r"table1.csv, line 3, column 'mean': not a number \('2.3x9'\)"):
        paper.load_table1()


def test_missing_row_and_column(data_copy):
    lines = (data_copy / "table2.csv").read_text().splitlines()
    (data_copy / "table2.csv").write_text("\n".join(lines[:-1]) + "\n")
    with pytest.raises(ValueError, match=r"missing \[\('yaw', 'sensor_frame'\)\]"):
        paper.load_table2()
    (data_copy / "r0.csv").write_text("row,col0,col1\n0,1,0\n")
    with pytest.raises(ValueError, match="missing columns"):
        paper.load_r0()


# ---- the claims file: every problem named with file and line
# --------------------------------------------------

def test_malformed_claims_file_names_line_and_column(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,,Sec. II,,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'statement': empty"):
        paper.load_claim_table(path)
    path.write_text("claim,statement,where,paper_value,unit\ntheorem1,s,w,ten,\n")
    with pytest.raises(ValueError, match=r"line 2, column 'paper_value': not a number"):
        paper.load_claim_table(path)


HEADER = ",".join(paper.CLAIM_COLUMNS) + "\n"


@pytest.mark.parametrize("text, message", [
    ("", r"claims.csv, line 1: empty; expected the header"),
    ("claim,statement,where,paper_value\ntheorem1,s,w,\n", r"claims.csv, line 1: columns must be"),
    ("claim,statement,where,unit,paper_value\ntheorem1,s,w,,\n", r"claims.csv, line 1: columns must be"),
    (HEADER + ",s,w,,\n", r"claims.csv, line 2, column 'claim': empty"),
    (HEADER + "   ,s,w,,\n", r"claims.csv, line 2, column 'claim': empty"),
    (HEADER + "theorem1,s,   ,,\n", r"claims.csv, line 2, column 'where': empty"),
    (HEADER + "theorem 1,s,w,,\n", r"claims.csv, line 2, column 'claim': not a claim id"),
    (HEADER + " theorem1,s,w,,\n", r"claims.csv, line 2, column 'claim': not a claim id"),
    (HEADER + "theorem1,s,w,,\nother,s,w,,\ntheorem1,t,w,,\n",
     r"claims.csv, line 4, column 'claim': claim id 'theorem1' repeated \(first on line 2\)"),
    (HEADER + "theorem1,s,w,nan,deg\n", r"claims.csv, line 2, column 'paper_value': not a finite number"),
    (HEADER + "theorem1,s,w,inf,deg\n", r"claims.csv, line 2, column 'paper_value': not a finite number"),
    (HEADER + "theorem1,s,w,ten,deg\n", r"claims.csv, line 2, column 'paper_value': not a number"),
    (HEADER + "theorem1,s,w,1,\n", r"claims.csv, line 2, column 'unit': a unit goes with, and only with"),
    (HEADER + "theorem1,s,w,,deg\n", r"claims.csv, line 2, column 'unit': a unit goes with, and only with"),
    (HEADER + "theorem1,s,w,,,extra\n", r"claims.csv, line 2: expected 5 fields .* got 6"),
    (HEADER + "theorem1,s,w\n", r"claims.csv, line 2: expected 5 fields .* got 3"),
    (HEADER + 'theorem1,"s,w,,\n', r"claims.csv, line 2: not a readable CSV"),
    (HEADER + 'theorem1,"s"x,w,,\n', r"claims.csv, line 2: not a readable CSV"),
    # a statement over two lines, a blank line: the lines counted are the file's
    (HEADER + 'theorem1,"two\nlines",w,,\n\nother,s,w,x,deg\n', r"claims.csv, line 5, column 'paper_value'"),
    (HEADER + 'theorem1,"two\nlines",w,x,deg\n', r"claims.csv, line 2, column 'paper_value'"),  # where it starts
])
def test_malformed_claims_file_is_refused_with_file_and_line(tmp_path, text, message):
    path = tmp_path / "claims.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(DataFileError, match=message):
        paper.load_claim_table(path)


def test_a_well_formed_claims_file_reads_as_text(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text(HEADER + 'theorem1,"two\nlines, a comma",w,,\n\nother,s,w,0.5,deg\n', encoding="utf-8")
    table = paper.load_claim_table(path)
    assert list(table.index) == ["theorem1", "other"]
    assert table.loc["theorem1", "statement"] == "two\nlines, a comma" and table.loc["other", "paper_value"] == "0.5"


def test_a_missing_claims_file_is_named(tmp_path):
    with pytest.raises(DataFileNotFound, match=r"nowhere\.csv: no such file"):
        paper.load_claim_table(tmp_path / "nowhere.csv")
