"""The paper's published numbers (``data/paper/``): the comparison target, never a result.

Every loader validates its file (columns, numbers, no NaN, expected rows) and raises
:class:`~replication.rig.datafile.DataFileError` (a ``ValueError``) naming the file, the line
and column where known, and the problem; a missing file raises
:class:`~replication.rig.datafile.DataFileNotFound` (also a ``FileNotFoundError``).
"""
from __future__ import annotations

import csv
import io
import math
import os
import re
from pathlib import Path

import numpy as np
import pandas as pd

from .._io import PROJECT_ROOT
from ..core.so3 import nearest_rotation
from ..rig.datafile import fail, read_text

__all__ = ["data_dir", "load_r0", "r0_camera_from_sensor", "load_table1", "load_table2", "load_claims",
           "load_claim_table", "CLAIM_COLUMNS", "CLAIM_ID"]

TABLE1_ITERATIONS = (2, 5, 10, 15, 20, 30, 50)
TABLE1_METHODS = ("optimization", "ours_right", "ours_left")
TABLE2_ANGLES = ("roll", "pitch", "yaw")
TABLE2_METHODS = ("optimization", "ours_right", "ours_left", "sensor_frame")


def data_dir() -> Path:
    """``data/`` of this project; ``$REPLICATION_DATA_DIR`` overrides it."""
    env = os.environ.get("REPLICATION_DATA_DIR")
    return Path(env) if env else PROJECT_ROOT / "data"


def _read(name: str, columns: list[str], numeric: list[str]) -> pd.DataFrame:
    """``data_dir()/paper/<name>`` as a table of ``columns``, the ``numeric`` ones as floats.

    Raises
    ------
    DataFileNotFound
        The file is missing (also a ``FileNotFoundError``).
    DataFileError
        Not UTF-8 text, not a CSV, a missing column, or a value of a ``numeric`` column that is
        not a number (line and column named; the header is line 1).
    """
    path = data_dir() / "paper" / name
    text = read_text(path, "paper data file")
    try:
        df = pd.read_csv(io.StringIO(text))
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        fail(path, f"not a readable CSV ({exc})")
    missing = [c for c in columns if c not in df.columns]
    if missing:
        fail(path, f"missing columns {missing}; expected {columns}", line=1)
    for col in numeric:
        values = pd.to_numeric(df[col], errors="coerce")
        bad = values.isna()
        if bad.any():
            row = int(np.flatnonzero(bad)[0]) + 2  # header is line 1
            fail(path, f"not a number ({df[col].iloc[row - 2]!r})", line=row, column=col)
        df[col] = values.astype(float)
    return df[columns]


def load_r0() -> np.ndarray:
    """R0 of the simulation as printed in Sec. III-A (4 decimals, not exactly orthogonal), (3,
    3)."""
    df = _read("r0.csv", ["row", "col0", "col1", "col2"], ["col0", "col1", "col2"])
    if len(df) != 3:
        fail(data_dir() / "paper" / "r0.csv", f"expected 3 rows, got {len(df)}")
    return df[["col0", "col1", "col2"]].to_numpy()


def r0_camera_from_sensor() -> np.ndarray:
    """The printed R0 projected onto SO(3) by eqs. (16)-(17): the simulation's ground truth."""
    return nearest_rotation(load_r0())


def _check_grid(df: pd.DataFrame, name: str, keys: dict) -> pd.DataFrame:
    expected = pd.MultiIndex.from_product(list(keys.values()), names=list(keys))
    got = pd.MultiIndex.from_frame(df[list(keys)])
    if got.has_duplicates or set(got) != set(expected):
        missing = sorted(set(expected) - set(got))
        extra = sorted(set(got) - set(expected))
        fail(data_dir() / "paper" / name, f"expected one row per {tuple(keys)} in {list(keys.values())}; "
             f"missing {missing}, unexpected {extra}, duplicates {got.has_duplicates}")
    return df.set_index(list(keys)).sort_index()


def load_table1() -> pd.DataFrame:
    """Table I: ``||R0_hat - R0||_F`` mean and std, indexed by (iteration, method)."""
    df = _read("table1.csv", ["iteration", "method", "mean", "std"], ["iteration", "mean", "std"])
    df["iteration"] = df["iteration"].astype(int)
    return _check_grid(df, "table1.csv", {"iteration": TABLE1_ITERATIONS, "method": TABLE1_METHODS})


def load_table2() -> pd.DataFrame:
    """Table II: RMS, mean, SD (deg) and correlation, indexed by (angle, method)."""
    cols = ["angle", "method", "rms_deg", "mean_deg", "sd_deg", "correlation"]
    df = _read("table2.csv", cols, cols[2:])
    return _check_grid(df, "table2.csv", {"angle": TABLE2_ANGLES, "method": TABLE2_METHODS})


def load_claims() -> pd.Series:
    """The paper's numbers in its checkable claims, indexed by claim id (claims without a number
    left out).

    The full table of claims (statements, where the paper makes them) is :func:`load_claim_table`.
    """
    df = load_claim_table()
    values = df.loc[df["paper_value"].str.strip() != "", "paper_value"].astype(float)
    values.index.name = "claim"
    return values


#: The columns of ``data/paper/claims.csv``, in order.
CLAIM_COLUMNS = ("claim", "statement", "where", "paper_value", "unit")
#: A claim id: a letter, then letters, digits and underscores (no spaces: ids are matched exactly).
CLAIM_ID = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def load_claim_table(path=None) -> pd.DataFrame:
    """The checkable claims of ``data/paper/claims.csv``, indexed by ``claim``: ``statement``,
    ``where``, ``paper_value``, ``unit`` (the ledger's rows, :mod:`replication.study.ledger`), all
    text.

    Raises
    ------
    DataFileNotFound
        The file is missing.
    DataFileError
        Naming the file and the line (a record's first line; the header is line 1) and, where it is
        one field, the column: not a CSV (an unclosed quote, text after a closing quote), a header
        other than :data:`CLAIM_COLUMNS`, a record with another number of fields, an empty
        ``claim``, ``statement`` or ``where``, a claim id that is not :data:`CLAIM_ID`, a claim id
        given twice, a ``paper_value`` that is not a finite number, or a ``unit`` without a
        ``paper_value`` (or the reverse).
    """
    path = Path(path) if path else data_dir() / "paper" / "claims.csv"
    reader = csv.reader(io.StringIO(read_text(path, "the claims file"), newline=""), strict=True)
    records, end = [], 0  # (first line, fields) of every non-blank record
    try:
        for fields in reader:
            start, end = end + 1, reader.line_num
            if fields:
                records.append((start, fields))
    except csv.Error as err:
        fail(path, f"not a readable CSV from this line on ({err}; a quote not closed?)", line=end + 1)
    if not records:
        fail(path, f"empty; expected the header {','.join(CLAIM_COLUMNS)}", line=1)
    header_line, header = records[0]
    if tuple(header) != CLAIM_COLUMNS:
        fail(path, f"columns must be {list(CLAIM_COLUMNS)}, got {header}", line=header_line)
    seen = {}
    for line, fields in records[1:]:
        if len(fields) != len(CLAIM_COLUMNS):
            fail(path, f"expected {len(CLAIM_COLUMNS)} fields ({','.join(CLAIM_COLUMNS)}), got {len(fields)}",
                 line=line)
        row = dict(zip(CLAIM_COLUMNS, fields))
        for col in ("claim", "statement", "where"):
            if not row[col].strip():
                fail(path, "empty", line=line, column=col)
        claim = row["claim"]
        if not CLAIM_ID.fullmatch(claim):
            fail(path, f"not a claim id (a letter, then letters, digits, underscores): {claim!r}", line=line,
                 column="claim")
        if claim in seen:
            fail(path, f"claim id {claim!r} repeated (first on line {seen[claim]})", line=line, column="claim")
        seen[claim] = line
        value = row["paper_value"]
        if value.strip():
            try:
                number = float(value)
            except ValueError:
                fail(path, f"not a number ({value!r})", line=line, column="paper_value")
            if not math.isfinite(number):
                fail(path, f"not a finite number ({value!r})", line=line, column="paper_value")
        if bool(value.strip()) != bool(row["unit"].strip()):
            fail(path, "a unit goes with, and only with, a paper_value", line=line, column="unit")
    table = pd.DataFrame([fields for _, fields in records[1:]], columns=list(CLAIM_COLUMNS), dtype=str)
    return table.set_index("claim")
