"""The paper's published numbers (``data/paper/``): the comparison target, never a result.

Every loader validates its file (columns, numbers, no NaN, expected rows) and raises
:class:`~replication.datafile.DataFileError` (a ``ValueError``) naming the file, the line
and column where known, and the problem; a missing file raises
:class:`~replication.datafile.DataFileNotFound` (also a ``FileNotFoundError``).
"""
from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pandas as pd

from .datafile import fail, read_text
from .so3 import nearest_rotation

__all__ = ["data_dir", "load_r0", "r0_camera_from_sensor", "load_table1", "load_table2", "load_claims",
           "load_claim_table"]

TABLE1_ITERATIONS = (2, 5, 10, 15, 20, 30, 50)
TABLE1_METHODS = ("optimization", "ours_right", "ours_left")
TABLE2_ANGLES = ("roll", "pitch", "yaw")
TABLE2_METHODS = ("optimization", "ours_right", "ours_left", "sensor_frame")


def data_dir() -> Path:
    """``data/`` of this project; ``$REPLICATION_DATA_DIR`` overrides it."""
    env = os.environ.get("REPLICATION_DATA_DIR")
    return Path(env) if env else Path(__file__).resolve().parent.parent / "data"


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
    """R0 of the simulation as printed in Sec. III-A (4 decimals, not exactly orthogonal), (3, 3)."""
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
    """The paper's numbers in its checkable claims, indexed by claim id (claims without a number left out).

    The full table of claims (statements, where the paper makes them) is :func:`load_claim_table`.
    """
    df = load_claim_table()
    values = df.loc[df["paper_value"] != "", "paper_value"].astype(float)
    values.index.name = "claim"
    return values


def load_claim_table(path=None) -> pd.DataFrame:
    """The checkable claims of ``data/paper/claims.csv``, indexed by ``claim``: ``statement``, ``where``,
    ``paper_value``, ``unit`` (the ledger's rows, :mod:`replication.ledger`)."""
    path = Path(path) if path else data_dir() / "paper" / "claims.csv"
    df = pd.read_csv(io.StringIO(read_text(path, "the claims file")), dtype=str, keep_default_na=False)
    expected = ["claim", "statement", "where", "paper_value", "unit"]
    if list(df.columns) != expected:
        fail(path, f"columns must be {expected}, got {list(df.columns)}", line=1)
    for line, row in enumerate(df.itertuples(index=False), start=2):
        for col in ("claim", "statement", "where"):
            if not getattr(row, col).strip():
                fail(path, "empty", line=line, column=col)
        if row.paper_value.strip():
            try:
                float(row.paper_value)
            except ValueError:
                fail(path, f"not a number ({row.paper_value!r})", line=line, column="paper_value")
    if df["claim"].duplicated().any():
        fail(path, f"claim ids repeated: {sorted(df.loc[df['claim'].duplicated(), 'claim'])}")
    return df.set_index("claim")
