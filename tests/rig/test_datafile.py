"""Every loader family reports an unreadable or malformed file with one error, DataFileError: the
file, the line and the column of the problem (realdata, lab.recording, paper)."""
import pickle
import re

import numpy as np
import pytest

from conftest import SMALL_LAB
from replication.rig import realdata as rd
from replication.rig.datafile import (
    ColumnCountError,
    DataFileError,
    DataFileNotFound,
    fail,
    read_lines,
    read_table,
    read_text,
)
from replication.study import lab, paper

TUM_LINES = [
    "# t tx ty tz qx qy qz qw",
    "1520530313249735680.0 0 0 0 0 0 0 1",
    "1520530313299737600.0 0 0 0 0.0087265 0 0 0.9999619",
    "1520530313349738752.0 0 0 0 0.0174524 0 0 0.9998477",
]
BINARY = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"
TABLE1 = (paper.data_dir() / "paper" / "table1.csv").read_text()  # the project's lab_dir, read before any monkeypatch


# ----------------------------------------------------------------------------- the error itself

def test_error_prints_file_line_and_column_and_stays_a_value_error(tmp_path):
    err = DataFileError(tmp_path / "t.txt", "not a number: 'x'", line=12, column=3, column_name="qw")
    assert str(err) == f"{tmp_path / 't.txt'}, line 12, column 3 ('qw'): not a number: 'x'"
    assert isinstance(err, ValueError) and not isinstance(err, FileNotFoundError)
    assert (err.path, err.line, err.column, err.message) == (tmp_path / "t.txt", 12, 3, "not a number: 'x'")
    assert str(DataFileError("a.csv", "bad", column="acc_x")) == "a.csv, column 'acc_x': bad"
    assert str(DataFileError("a.csv", "bad", line=2)) == "a.csv, line 2: bad"
    assert str(DataFileError("a.csv", "bad")) == "a.csv: bad"
    again = pickle.loads(pickle.dumps(err))
    assert type(again) is DataFileError and str(again) == str(err) and again.column_name == "qw"


def test_a_wrong_column_count_carries_both_numbers(tmp_path):
    path = tmp_path / "imu.csv"
    path.write_text("# t,w,w,w,a,a,a\n1,0,0,0,0,0,0\n2,0,0,0,0,0,0\n")
    with pytest.raises(ColumnCountError, match=r"imu.csv, line 2: expected 8 columns \(a b\), got 7") as info:
        read_table(path, "abcdefgh", delimiter=",", what="a b")
    err = info.value
    assert isinstance(err, DataFileError) and (err.expected, err.found, err.line) == (8, 7, 2)
    again = pickle.loads(pickle.dumps(err))
    assert type(again) is ColumnCountError and str(again) == str(err) and (again.expected, again.found) == (8, 7)
    assert read_table(path, "abcdefg", delimiter=",")[0].shape == (2, 7)  # one column fewer: read


def test_not_found_is_also_a_file_not_found_error(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"none.txt: no such file \(the rig description\)") as info:
        read_text(tmp_path / "none.txt", "the rig description")
    err = info.value
    assert isinstance(err, DataFileNotFound) and isinstance(err, ValueError)
    assert err.path == tmp_path / "none.txt" and err.filename == str(tmp_path / "none.txt")
    assert str(err) == f"{tmp_path / 'none.txt'}: no such file (the rig description)"
    with pytest.raises(DataFileError, match=r"x.csv, line 4, column 'u3': bad") as info:
        fail("x.csv", "bad", line=4, column="u3")
    assert info.value.__suppress_context__


def test_read_text_translates_newlines_and_drops_a_bom(tmp_path):
    path = tmp_path / "a.txt"
    path.write_bytes(b"\xef\xbb\xbfa\r\nb\rc\n\nd")
    assert read_text(path) == "a\nb\nc\n\nd"
    assert read_lines(path) == ["a", "b", "c", "", "d"]
    path.write_bytes(b"a\n")
    assert read_lines(path) == ["a"]


def test_the_bad_byte_is_located(tmp_path):
    path = tmp_path / "a.txt"
    path.write_bytes(b"1 2\r\n3 4\n5 \xff 6\n")
    with pytest.raises(DataFileError, match=r"a.txt, line 3: not UTF-8 text \(invalid start byte at byte 11") as info:
        read_text(path)
    assert info.value.line == 3 and info.value.column is None


# ----------------------------------------------------------------------------- the loader families

def _tum(path):
    return rd.load_tum_trajectory(path)


def _paper(path):
    return paper.load_table1()


def _lab(path):
    return lab.load_lab(path.parent)


@pytest.fixture
def paper_dir(tmp_path, monkeypatch):
    (tmp_path / "paper").mkdir()
    monkeypatch.setenv("REPLICATION_DATA_DIR", str(tmp_path))
    return tmp_path / "paper"


SMALL = SMALL_LAB


@pytest.fixture(params=["tum", "paper", "lab rig", "lab csv"])
def family(request, tmp_path, paper_dir, lab_dir):
    """(the file a loader reads, its valid text, a call of the loader)."""
    if request.param == "tum":
        return tmp_path / "traj.txt", "\n".join(TUM_LINES) + "\n", _tum
    if request.param == "paper":
        return paper_dir / "table1.csv", TABLE1, _paper
    name = "rig.json" if request.param == "lab rig" else "static_imu.csv"
    return lab_dir / name, (lab_dir / name).read_text(), _lab


def test_missing_file(family):
    path, _, load = family
    if path.exists():
        path.unlink()
    with pytest.raises(FileNotFoundError, match="no such file") as info:
        load(path)
    err = info.value
    assert isinstance(err, DataFileNotFound) and err.path == path and "no such file" in err.message


def test_directory_instead_of_a_file(family):
    path, _, load = family
    if path.exists():
        path.unlink()
    path.mkdir()
    with pytest.raises(DataFileError, match="is a directory, not a file") as info:
        load(path)
    assert info.value.path == path and info.value.message == "is a directory, not a file"
    assert isinstance(info.value, FileNotFoundError)  # as the loaders raised before


def test_binary_file(family):
    path, _, load = family
    path.write_bytes(BINARY)
    with pytest.raises(DataFileError, match=r"line 1: not UTF-8 text \(invalid start byte at byte 0") as info:
        load(path)
    err = info.value
    assert err.path == path and err.line == 1 and err.message.startswith("not UTF-8 text (invalid start byte at byte 0")


@pytest.mark.parametrize("encoding, problem", [("utf-16", "invalid start byte at byte 0"),
                                               ("utf-16-le", "a NUL byte at byte 1")])
def test_utf16_file(family, encoding, problem):
    path, text, load = family
    path.write_bytes(text.encode(encoding))
    with pytest.raises(DataFileError, match=re.escape(f"not UTF-8 text ({problem}")) as info:
        load(path)
    err = info.value
    assert err.path == path and err.line == 1 and err.message.startswith(f"not UTF-8 text ({problem}")
    assert "UTF-16" in err.message


def test_a_valid_file_loads_with_its_values(family):
    """The loaded values are those of the text (a loader that drops, shifts or mis-scales a column
    fails)."""
    path, text, load = family
    path.write_text(text)
    loaded = load(path)
    if path.name == "traj.txt":  # TUM: nanosecond stamps in seconds, rotations 0, 1, 2 deg about x
        assert loaded.t[0] == pytest.approx(1520530313.24973568, abs=1e-6)
        np.testing.assert_allclose(np.diff(loaded.t), [0.0500019, 0.0500012], atol=1e-6)
        angles = np.degrees(np.arccos(np.clip((np.trace(loaded.R, axis1=1, axis2=2) - 1) / 2, -1, 1)))
        np.testing.assert_allclose(angles, [0.0, 1.0, 2.0], atol=1e-4)  # the quaternions carry 7 digits
        np.testing.assert_allclose(loaded.R[2, 2, 1], 0.0348995, atol=1e-6)  # +2 deg about x: qx > 0, not qw first
    elif path.name == "table1.csv":
        rows = [line.split(",") for line in text.splitlines()[1:] if line]
        assert len(loaded) == len(rows)
        for it, method, mean, _ in rows[:6]:
            assert loaded.loc[(int(it), method), "mean"] == float(mean)
    elif path.name == "rig.json":
        import json

        assert loaded.rig == json.loads(text)
    else:  # static_imu.csv
        header, *lines = text.splitlines()
        expected = np.array([[float(v) for v in line.split(",")] for line in lines])
        assert list(loaded.static_imu.columns) == header.split(",")
        np.testing.assert_array_equal(loaded.static_imu.to_numpy(float), expected)


def test_malformed_value_has_line_and_column(tmp_path, paper_dir, lab_dir):
    path = tmp_path / "traj.txt"
    path.write_text("\n".join(TUM_LINES + ["1520530313399738752.0 0 0 0 0 0 0 1x"]) + "\n")
    with pytest.raises(DataFileError, match=r"line 5, column 8 \('qw'\): not a number: '1x'") as info:
        rd.load_tum_trajectory(path)
    err = info.value
    assert (err.path, err.line, err.column, err.column_name) == (path, 5, 8, "qw")
    assert err.message == "not a number: '1x'"

    table = paper_dir / "table1.csv"
    table.write_text(TABLE1.replace("2.339", "2.3x9"))
    with pytest.raises(DataFileError, match=r"line 3, column 'mean': not a number \('2\.3x9'\)") as info:
        paper.load_table1()
    assert (info.value.path, info.value.line, info.value.column) == (table, 3, "mean")

    imu = lab_dir / "static_imu.csv"
    lines = imu.read_text().splitlines()
    cells = lines[5].split(",")
    cells[lines[0].split(",").index("gyr_y")] = "abc"
    lines[5] = ",".join(cells)
    imu.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataFileError, match=r"line 6, column 'gyr_y': not a number: 'abc'") as info:
        lab.load_lab(lab_dir)
    assert (info.value.path, info.value.line, info.value.column) == (imu, 6, "gyr_y")
    assert info.value.message == "not a number: 'abc'"


def test_other_realdata_loaders_raise_it_too(tmp_path):
    yaml_file = tmp_path / "c.yaml"
    yaml_file.write_text("cam0:\n  T_cam_imu: [[1, 0,\n  - 2\n")
    with pytest.raises(DataFileError, match="not valid YAML") as info:
        rd.load_reference(yaml_file)
    assert info.value.path == yaml_file and info.value.line is not None and "not valid YAML" in info.value.message
    with pytest.raises(DataFileNotFound, match="none.yaml: no such file"):
        rd.load_orbslam3_stereo(tmp_path / "none.yaml")
    (tmp_path / "dir.yaml").mkdir()
    with pytest.raises(DataFileNotFound, match="is a directory, not a file"):
        rd.load_orbslam3_stereo(tmp_path / "dir.yaml")
    robot = tmp_path / "robot.txt"
    robot.write_text("x\n")
    with pytest.raises(DataFileError, match="number of poses") as info:
        rd.load_tabb_poses(robot)
    assert (info.value.line, info.value.column) == (1, 1) and "number of poses" in info.value.message


def test_read_table_is_the_loaders_parser_with_a_header_and_quaternion_check(tmp_path):
    """A new format's loader needs only the toolkit: header, file/line/column errors, quaternion
    norms."""
    from replication.rig.datafile import read_table, unit_quaternion_rotations

    path = tmp_path / "poses.csv"
    path.write_text("t_ns,qw,qx,qy,qz\n1,1,0,0,0\n2,0,1,0,0\n3,0.5,x,0.5,0.5\n")
    names = ("t_ns", "qw", "qx", "qy", "qz")
    with pytest.raises(DataFileError, match=r"line 4, column 3 \('qx'\): not a number: 'x'") as err:
        read_table(path, names, delimiter=",", header=True)
    assert (err.value.line, err.value.column, err.value.column_name) == (4, 3, "qx")
    path.write_text("t_ns,qw,qx,qy,qz\n1,1,0,0,0\n2,0,1,0,0\n3,0.5,0.5,0.5,0.6\n")
    data, lines = read_table(path, names, delimiter=",", header=True)
    assert data.shape == (3, 5) and list(lines) == [2, 3, 4]
    with pytest.raises(DataFileError, match="quaternion norm") as err:
        unit_quaternion_rotations(path, data[:, 1:], lines)
    assert err.value.line == 4
    np.testing.assert_allclose(unit_quaternion_rotations(path, data[:2, 1:], lines[:2])[1], np.diag([1.0, -1, -1]))


IMU_HEAD = "#timestamp [ns],wx,wy,wz,ax,ay,az"


@pytest.mark.parametrize("second, message", [
    ("1520530321404060469", "(1520530321404060469 < 1520530321404065469)"),       # back in time
    ("1520530321404065469", "(1520530321404065469 = 1520530321404065469)"),       # the same text
    ("1520530321404065500", "(1520530321404065500 and 1520530321404065469, one number once read as float64"),
])
def test_time_stamps_in_messages_are_the_files_own_text(tmp_path, second, message):
    """A 19-digit ns stamp moves by up to 128 ns as a double (...469 reads as ...536): a message
    quotes the file's digits, and two texts that read as one double are said to be that, not
    equal."""
    path = tmp_path / "imu.csv"
    path.write_text("\n".join([IMU_HEAD, "1520530321404065469,0,0,0,0,0,9.8", f"{second},0,0,0,0,0,9.8"]) + "\n")
    with pytest.raises(DataFileError, match=r"imu.csv, line 3, column 1 \('t\[ns\]'\): timestamp not after the "
                                            rf"previous line's {re.escape(message)}") as err:
        rd.load_euroc_imu(path)
    assert "065536" not in str(err.value)
    path.write_text("\n".join([IMU_HEAD, "1520530321404065469,0,0,0,0,0,9.8", "1520530321404065725,0,0,0,0,0,9.8"])
                    + "\n")  # the next double (256 ns on): read
    assert len(rd.load_euroc_imu(path).t) == 2


def test_a_fractional_csv_stamp_is_quoted_as_written(tmp_path):
    path = tmp_path / "imu.csv"
    path.write_text("\n".join([IMU_HEAD, "1520530308.181901469,0,0,0,0,0,9.8", "1520530308.186917469,0,0,0,0,0,9.8"]))
    with pytest.raises(DataFileError, match=r"line 2, column 1: the time stamp 1520530308.181901469 has a fraction"):
        rd.load_euroc_imu(path)


def test_unknown_policy_is_refused():
    with pytest.raises(ValueError, match=r"repeated must be one of 'refuse', 'keep-first'.*got 'first'"):
        read_table("any.txt", ("t", "x"), repeated="first")
