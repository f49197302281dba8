"""Reading text data files, and the one error every loader raises about them. Theory and measured
numbers: ``docs/reading.md``, section ``replication.rig.datafile``."""
from __future__ import annotations

import codecs
import errno
import math
from pathlib import Path
from typing import NoReturn

import numpy as np

from .._jitter import jitter

__all__ = ["DataFileError", "DataFileNotFound", "ColumnCountError", "fail", "read_text", "read_text_layout",
           "read_lines", "read_table", "REPEATED", "is_number", "unit_quaternion_rotations", "QUATERNION_NORM_TOL"]

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
    """The data file does not exist, or is a directory: both a :class:`DataFileError` and a
    ``FileNotFoundError``."""

    def __init__(self, path, message: str, line=None, column=None, column_name=None):
        super().__init__(path, message, line, column, column_name)
        self.errno = errno.ENOENT
        self.filename = str(self.path)


class ColumnCountError(DataFileError):
    """A data line with another number of columns than the format's: a :class:`DataFileError` that
    also carries the numbers, so that a caller can say what the file looks like instead
    (``calibrate``: an IMU stream given as an orientation stream, and the reverse).

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
    """:func:`read_text`, and how the file wrote its lines: ``(text, newline, bom)``, ``newline``
    being ``"\\r\\n"`` when every line ends so (else ``"\\n"``) and ``bom`` whether it starts with a
    UTF-8 byte-order mark; for a writer that gives a file back as it found it."""
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
    """The lines of a UTF-8 text file, without their newlines (see :func:`read_text`); line ``k`` is
    item ``k - 1``."""
    text = read_text(path, what)
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines


#: ``repeated="mean"`` refuses poses of one time stamp further apart than this (deg).
MEAN_MAX_DEG = 90.0
#: What a trajectory may do with a time stamp repeated with another pose
#: (``read_table(repeated=...)``).
REPEATED = ("refuse", "keep-first", "keep-last", "mean")


def read_table(path, names, *, delimiter=None, what: str | None = None, header: bool = False,
               drop_repeated: bool = False, increasing_first: bool = True, optional=(), repeated: str = "refuse",
               quaternion=None, tally: dict | None = None):
    """Numeric rows of a text file, skipping blank and ``#`` lines; every error names file, line and
    column.

    ``names``: the columns (their number is the expected count; a bad value names its column);
    ``optional``: names of further columns a file may carry after them (all its lines alike, the
    first data line decides; they are checked as numbers and not returned); ``delimiter``: ``None``
    splits on white space; ``header``: skip the first data line (a header of names);
    ``drop_repeated``: skip a line identical in every value to the previous data line;
    ``increasing_first``: the first column (a time stamp) must increase strictly.

    ``repeated``: what to do with consecutive lines that share a time stamp but not every value
    (with ``increasing_first``): ``"refuse"`` (the default: a :class:`DataFileError` naming the
    values that read it), ``"keep-first"``, ``"keep-last"`` or ``"mean"`` of each group
    (``quaternion``: the indices of 4 quaternion columns, averaged in one hemisphere and normalised;
    each line's quaternion is checked against :data:`QUATERNION_NORM_TOL` first). ``tally``: a dict
    that receives ``repeated_timestamps`` (the lines merged into an earlier one's time stamp),
    ``repeated_groups``, ``repeated_max_deg`` (the largest angle between two quaternions of one
    group, with ``quaternion``; else None) and ``verbatim_repeats`` (lines dropped by
    ``drop_repeated``). A line with another number of columns raises :class:`ColumnCountError`, any
    other problem :class:`DataFileError`.

    Returns
    -------
    (data, lines) : ndarray (N, len(names)), ndarray (N,) of 1-based line numbers
    """
    if repeated not in REPEATED:
        raise ValueError(f"repeated must be one of {', '.join(map(repr, REPEATED))}, got {repeated!r}")
    names, optional = tuple(names), tuple(optional)
    counts = (len(names), len(names) + len(optional)) if optional else (len(names),)
    n_columns = None
    what = what or ", ".join(names)
    groups, lines = [], []  # groups[k]: the rows that share kept row k's time stamp (one without repeats)
    stamps = []  # each kept row's first field as the file writes it: messages quote it, not its float64
    verbatim = 0
    skip_header = header
    for lineno, line in enumerate(read_lines(path), 1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if skip_header:
            skip_header = False
            continue
        parts = text.split(delimiter) if delimiter else text.split()
        if n_columns is None and len(parts) in counts:
            n_columns = len(parts)
        if len(parts) != (n_columns or counts[0]):
            expected = " or ".join(str(c) for c in counts) if n_columns is None else str(n_columns)
            raise ColumnCountError(path, f"expected {expected} columns ({what}), got {len(parts)}", lineno,
                                   expected=n_columns or counts[0], found=len(parts))
        every = names + optional
        try:
            values = [float(p) for p in parts]
        except ValueError:
            col = next(i for i, p in enumerate(parts) if not is_number(p))
            fail(path, f"not a number: {parts[col]!r}", line=lineno, column=col + 1, column_name=every[col])
        bad = [i for i, v in enumerate(values) if not math.isfinite(v)]
        if bad:
            fail(path, "NaN or inf", line=lineno, column=bad[0] + 1, column_name=every[bad[0]])
        values = values[:len(names)]
        if groups and drop_repeated and _same_pose(values, groups[-1][-1], quaternion):
            verbatim += 1
            continue
        if groups and increasing_first and values[0] == groups[-1][0][0]:
            if repeated == "refuse":
                _refuse_repeat(path, values, groups[-1][0], lineno, names[0], quaternion, (parts[0], stamps[-1]))
            groups[-1].append(values)
            if repeated == "keep-last":
                lines[-1], stamps[-1] = lineno, parts[0]
            continue
        groups.append([values])
        lines.append(lineno)
        stamps.append(parts[0])
    if len(groups) < 2:
        fail(path, f"fewer than 2 data lines ({what})")
    data = np.array([_merged(path, g, repeated, quaternion, line) for g, line in zip(groups, lines)])
    if tally is not None:
        tally.update(_repeat_tally(groups, quaternion, verbatim))
    # the values move at their last bits under REPLICATION_JITTER; time stamps do not: they are the
    # recorder's exact ticks, which every machine parses to the same double and differences exactly
    # alike
    if increasing_first:
        data[:, 1:] = jitter(data[:, 1:])
    else:
        data = jitter(data)
    step = np.diff(data[:, 0])
    if increasing_first and np.any(step <= 0):
        k = int(np.flatnonzero(step <= 0)[0])
        fail(path, f"timestamp not after the previous line's ({_stamps(stamps[k + 1], stamps[k], '<')}): "
             "the lines go back in time (sort them by time, or split the file where the clock restarts)",
             line=lines[k + 1], column=1, column_name=names[0])
    return data, np.array(lines)


def _quaternion_angle_deg(q1, q2) -> float:
    """The angle (deg) between the rotations of two quaternions (any norm, either sign)."""
    q1, q2 = np.asarray(q1, dtype=float), np.asarray(q2, dtype=float)
    c = abs(float(q1 @ q2)) / max(float(np.linalg.norm(q1) * np.linalg.norm(q2)), 1e-300)
    return math.degrees(2.0 * math.acos(min(1.0, c)))


def _same_pose(values, other, quaternion) -> bool:
    """Whether two lines hold the same values, a quaternion and its negative (one rotation) counting
    as equal."""
    if values == other or quaternion is None:
        return values == other
    rest = [i for i in range(len(values)) if i not in quaternion]
    return all(values[i] == other[i] for i in rest) and all(values[i] == -other[i] for i in quaternion)


def _stamps(stamp: str, previous: str, relation: str) -> str:
    """Two time stamps of a message as the file writes them (its own digits: a 19-digit ns stamp
    read as a double moves by up to 128 ns), said equal in float64 where their texts differ."""
    stamp, previous = stamp.strip(), previous.strip()
    if relation == "=" and stamp != previous:
        return f"{stamp} and {previous}, one number once read as float64 (about 16 digits)"
    return f"{stamp} {relation} {previous}"


def _refuse_repeat(path, values, first, lineno, name, quaternion, texts):
    if _same_pose(values, first, quaternion):
        how = "exactly" if values == first else "with its quaternion's sign flipped (one rotation)"
        why = (f"the line repeats the previous one {how}; drop_repeated=True (calibrate --drop-repeated) skips such "
               "lines")
    else:
        away = "" if quaternion is None else (
            f", {_quaternion_angle_deg([values[i] for i in quaternion], [first[i] for i in quaternion]):.3g} deg away")
        why = (f"the time stamp is repeated with a different pose{away}; repeated='keep-first', 'keep-last' or "
               f"'mean' (calibrate --repeated keep-first|keep-last|mean) reads it, keeping one pose per time stamp")
    fail(path, f"timestamp not after the previous line's ({_stamps(*texts, '=')}): {why}",
         line=lineno, column=1, column_name=name)


def _merged(path, group, repeated, quaternion, line):
    """One row for a group of rows sharing a time stamp, by ``repeated``."""
    if len(group) == 1 or repeated == "keep-first":
        return group[0]
    if repeated == "keep-last":
        return group[-1]
    rows = np.array(group)
    if quaternion is not None:
        q = rows[:, list(quaternion)]
        norm = np.linalg.norm(q, axis=1)
        if np.any(np.abs(norm - 1.0) > QUATERNION_NORM_TOL):
            k = int(np.flatnonzero(np.abs(norm - 1.0) > QUATERNION_NORM_TOL)[0])
            fail(path, f"quaternion norm {float(norm[k]):.6g} is not 1 (tolerance {QUATERNION_NORM_TOL:g}) in pose "
                 f"{k + 1} of the {len(group)} sharing this line's time stamp; wrong column order or units?", line=line)
        spread = max(_quaternion_angle_deg(a, b) for a in q for b in q)
        if spread > MEAN_MAX_DEG:  # beyond it the mean of the rotations is no pose of the group (at 180: undefined)
            fail(path, f"the {len(group)} poses sharing this line's time stamp are {spread:.3g} deg apart (more than "
                 f"{MEAN_MAX_DEG:g}): their mean is no pose; repeated='keep-first' or 'keep-last' reads it", line=line)
        q = q * np.where(q @ q[0] < 0, -1.0, 1.0)[:, None]  # one hemisphere
        rows[:, list(quaternion)] = q
    mean = rows.mean(axis=0)
    if quaternion is not None:
        mean[list(quaternion)] /= np.linalg.norm(mean[list(quaternion)])
    return mean.tolist()


def _repeat_tally(groups, quaternion, verbatim) -> dict:
    merged = [g for g in groups if len(g) > 1]
    worst = None
    if quaternion is not None and merged:
        worst = max(_quaternion_angle_deg([a[i] for i in quaternion], [b[i] for i in quaternion])
                    for g in merged for a in g for b in g)
    return {"repeated_timestamps": sum(len(g) - 1 for g in merged), "repeated_groups": len(merged),
            "repeated_max_deg": worst, "verbatim_repeats": verbatim}


def is_number(text) -> bool:
    """Whether ``float(text)`` succeeds."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def unit_quaternion_rotations(path, q_wxyz, lines, tol: float = QUATERNION_NORM_TOL):
    """Rotation matrices of unit quaternions ``(w, x, y, z)`` read from ``path`` (``lines``: their
    line numbers).

    A norm off 1 by more than ``tol`` raises :class:`DataFileError` at its line (a wrong column
    order or unit); the others are normalised.
    """
    from ..core.so3 import matrix_from_quaternion

    norm = np.linalg.norm(q_wxyz, axis=-1)
    bad = np.flatnonzero(np.abs(norm - 1.0) > tol)
    if bad.size:
        fail(path, f"quaternion norm {norm[bad[0]]:.6g} is not 1 (tolerance {tol:g}); "
             "wrong column order or units?", line=lines[bad[0]])
    return matrix_from_quaternion(q_wxyz / norm[:, None])
