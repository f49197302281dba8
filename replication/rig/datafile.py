"""Reading text data files, and the one error every loader raises about them.

Every loader of this package (:mod:`replication.rig.realdata`, :mod:`replication.study.lab.recording`,
:mod:`replication.study.paper`) opens its files with :func:`read_text` or :func:`read_lines`
and reports a problem in a file with :func:`fail`, so all of them raise
:class:`DataFileError`: a ``ValueError`` that carries the file, the line and the column
of the problem and prints them on one line, e.g.
``data/t.txt, line 12, column 8 ('qw'): not a number: 'x'``.

A missing file (or a directory where a file is expected) raises :class:`DataFileNotFound`,
which is also a ``FileNotFoundError``, as the loaders raised before.
"""
from __future__ import annotations

import codecs
import errno
from pathlib import Path
from typing import NoReturn

import numpy as np

from .._jitter import jitter

__all__ = ["DataFileError", "DataFileNotFound", "ColumnCountError", "fail", "read_text", "read_text_layout",
           "read_lines", "read_table", "is_number", "unit_quaternion_rotations", "QUATERNION_NORM_TOL"]

#: Accepted deviation of a stored quaternion's norm from 1.
QUATERNION_NORM_TOL = 1e-3


class DataFileError(ValueError):
    """A problem in a data file: where it is and what it is.

    Parameters
    ----------
    path : path-like
        The file.
    message : str
        What is wrong.
    line : int, optional
        1-based line number (a CSV header is line 1).
    column : int or str, optional
        1-based column number, or the column's name.
    column_name : str, optional
        The column's name when ``column`` is its number.

    Attributes
    ----------
    path : pathlib.Path
    message : str
    line : int or None
    column : int, str or None
    column_name : str or None

    Notes
    -----
    ``str()`` is ``"<path>, line <line>, column <column> ('<name>'): <message>"``; the parts
    that are None are left out. A column given by name prints as ``column '<name>'``.
    """

    def __init__(self, path, message: str, line: int | None = None, column: int | str | None = None,
                 column_name: str | None = None):
        self.path = Path(path)
        self.message = str(message)
        self.line = None if line is None else int(line)
        self.column = column if column is None or isinstance(column, str) else int(column)
        self.column_name = column_name
        super().__init__(self._text())

    def _text(self) -> str:
        where = str(self.path)
        if self.line is not None:
            where += f", line {self.line}"
        if isinstance(self.column, str):
            where += f", column {self.column!r}"
        elif self.column is not None:
            where += f", column {self.column}" + (f" ({self.column_name!r})" if self.column_name else "")
        return f"{where}: {self.message}"

    def __str__(self) -> str:
        return self._text()

    def __reduce__(self):
        return type(self), (self.path, self.message, self.line, self.column, self.column_name)


class DataFileNotFound(DataFileError, FileNotFoundError):
    """The data file does not exist, or is a directory: both a :class:`DataFileError` and a ``FileNotFoundError``."""

    def __init__(self, path, message: str, line=None, column=None, column_name=None):
        super().__init__(path, message, line, column, column_name)
        self.errno = errno.ENOENT
        self.filename = str(self.path)


class ColumnCountError(DataFileError):
    """A data line with another number of columns than the format's: a :class:`DataFileError` that also carries the
    numbers, so that a caller can say what the file looks like instead (``calibrate``: an IMU stream given as an
    orientation stream, and the reverse).

    Attributes
    ----------
    expected : int
        The format's number of columns.
    found : int
        The line's.
    """

    def __init__(self, path, message: str, line: int | None = None, column=None, column_name=None,
                 expected: int = 0, found: int = 0):
        super().__init__(path, message, line, column, column_name)
        self.expected, self.found = int(expected), int(found)

    def __reduce__(self):
        return type(self), (self.path, self.message, self.line, self.column, self.column_name, self.expected,
                            self.found)


def fail(path, message: str, line: int | None = None, column: int | str | None = None,
         column_name: str | None = None) -> NoReturn:
    """Raise :class:`DataFileError` for ``path`` (see there for the arguments).

    The error stands alone (``from None``): called in an ``except`` block, it hides the
    exception being handled, whose substance the message is to carry.
    """
    raise DataFileError(path, message, line, column, column_name) from None


def _line_of(data: bytes, index: int) -> int:
    """1-based line of byte ``index`` of ``data`` (universal newlines)."""
    return data[:index].replace(b"\r\n", b"\n").replace(b"\r", b"\n").count(b"\n") + 1


def _universal(text: str) -> str:
    return text.replace("\r\n", "\n").replace("\r", "\n")


def read_text(path, what: str | None = None) -> str:
    """The whole of a UTF-8 text file, newlines translated to ``"\\n"`` (as ``open()`` does).

    A leading UTF-8 byte-order mark is dropped.

    Parameters
    ----------
    path : path-like
    what : str, optional
        What the file is, for the "no such file" message (e.g. ``"the rig description"``).

    Returns
    -------
    str

    Raises
    ------
    DataFileNotFound
        The file does not exist, or ``path`` is a directory.
    DataFileError
        The file cannot be read, or is not UTF-8 text (binary, UTF-16, ...): the message gives
        the byte offset, ``line`` the line, of the first offending byte.
    """
    return read_text_layout(path, what)[0]


def read_text_layout(path, what: str | None = None) -> tuple[str, str, bool]:
    """:func:`read_text`, and how the file wrote its lines: ``(text, newline, bom)``, ``newline`` being
    ``"\\r\\n"`` when every line ends so (else ``"\\n"``) and ``bom`` whether it starts with a UTF-8 byte-order
    mark; for a writer that gives a file back as it found it."""
    path = Path(path)
    if path.is_dir():
        raise DataFileNotFound(path, "is a directory, not a file")
    try:
        data = path.read_bytes()
    except (FileNotFoundError, NotADirectoryError):
        raise DataFileNotFound(path, "no such file" + (f" ({what})" if what else "")) from None
    except OSError as err:
        raise DataFileError(path, f"cannot be read ({err.strerror or err})") from err
    newline = "\r\n" if b"\r\n" in data and data.count(b"\n") == data.count(b"\r\n") else "\n"
    return _decoded(path, data), newline, data.startswith(codecs.BOM_UTF8)


def _decoded(path, data: bytes) -> str:
    bom = len(codecs.BOM_UTF8) if data.startswith(codecs.BOM_UTF8) else 0
    try:
        text = data[bom:].decode("utf-8")
    except UnicodeDecodeError as err:
        at = bom + err.start
        raise DataFileError(path, f"not UTF-8 text ({err.reason} at byte {at}; binary, or UTF-16?)",
                            line=_line_of(data, at)) from None
    nul = data.find(b"\0")
    if nul >= 0:
        raise DataFileError(path, f"not UTF-8 text (a NUL byte at byte {nul}; binary, or UTF-16?)",
                            line=_line_of(data, nul))
    return _universal(text)


def read_lines(path, what: str | None = None) -> list[str]:
    """The lines of a UTF-8 text file, without their newlines (see :func:`read_text`); line ``k`` is item ``k - 1``."""
    text = read_text(path, what)
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def read_table(path, names, *, delimiter=None, what: str | None = None, header: bool = False,
               drop_repeated: bool = False, increasing_first: bool = True):
    """Numeric rows of a text file, skipping blank and ``#`` lines; every error names file, line and column.

    ``names``: the columns (their number is the expected count; a bad value names its column); ``delimiter``:
    ``None`` splits on white space; ``header``: skip the first data line (a header of names); ``drop_repeated``:
    skip a line identical in every value to the previous data line; ``increasing_first``: the first column
    (a time stamp) must increase strictly.
    A line with another number of columns raises :class:`ColumnCountError`, any other problem
    :class:`DataFileError`.

    Returns
    -------
    (data, lines) : ndarray (N, len(names)), ndarray (N,) of 1-based line numbers
    """
    names = tuple(names)
    n_columns = len(names)
    what = what or ", ".join(names)
    rows, lines = [], []
    skip_header = header
    for lineno, line in enumerate(read_lines(path), 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if skip_header:
            skip_header = False
            continue
        parts = text.split(delimiter) if delimiter else text.split()
        if len(parts) != n_columns:
            raise ColumnCountError(path, f"expected {n_columns} columns ({what}), got {len(parts)}", lineno,
                                   expected=n_columns, found=len(parts))
        try:
            values = [float(p) for p in parts]
        except ValueError:
            col = next(i for i, p in enumerate(parts) if not is_number(p))
            fail(path, f"not a number: {parts[col]!r}", line=lineno, column=col + 1, column_name=names[col])
        bad = [i for i, v in enumerate(values) if not np.isfinite(v)]
        if bad:
            fail(path, "NaN or inf", line=lineno, column=bad[0] + 1, column_name=names[bad[0]])
        if drop_repeated and rows and values == rows[-1]:
            continue
        rows.append(values)
        lines.append(lineno)
    if len(rows) < 2:
        fail(path, f"fewer than 2 data lines ({what})")
    data = np.array(rows)
    # the values move at their last bits under REPLICATION_JITTER; time stamps do not: they are the recorder's exact
    # ticks, which every machine parses to the same double and differences exactly alike
    if increasing_first:
        data[:, 1:] = jitter(data[:, 1:])
    else:
        data = jitter(data)
    step = np.diff(data[:, 0])
    if increasing_first and np.any(step <= 0):
        k = int(np.flatnonzero(step <= 0)[0])
        fail(path, f"timestamp not after the previous line's ({data[k + 1, 0]!r} <= {data[k, 0]!r})",
             line=lines[k + 1], column=1, column_name=names[0])
    return data, np.array(lines)


def is_number(text) -> bool:
    """Whether ``float(text)`` succeeds."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def unit_quaternion_rotations(path, q_wxyz, lines, tol: float = QUATERNION_NORM_TOL):
    """Rotation matrices of unit quaternions ``(w, x, y, z)`` read from ``path`` (``lines``: their line numbers).

    A norm off 1 by more than ``tol`` raises :class:`DataFileError` at its line (a wrong column order or
    unit); the others are normalised.
    """
    from ..core.so3 import quaternion_to_matrix

    norm = np.linalg.norm(q_wxyz, axis=-1)
    bad = np.flatnonzero(np.abs(norm - 1.0) > tol)
    if bad.size:
        fail(path, f"quaternion norm {norm[bad[0]]:.6g} is not 1 (tolerance {tol:g}); "
             "wrong column order or units?", line=lines[bad[0]])
    return quaternion_to_matrix(q_wxyz / norm[:, None])
