"""Files written and read by the command line: atomic writes, figure formats, and the checks made
before any work.

Every output of this package is written whole or not at all (:func:`write_atomic`), under a
temporary name that never replaces an existing file. Before a command does any work it checks its
paths: every output against every input and every other output (:func:`check_clashes`: the same file
after resolving links, or a hard link), each input (:func:`check_input`: a regular file or a pipe,
readable), each output (:func:`prepare_output`, :func:`prepare_folder`: folders created, writable).
Their problems are ``ValueError`` s whose message names the option, the path and the operating
system's reason.
"""
from __future__ import annotations

import os
import secrets
import stat
from pathlib import Path

__all__ = ["PROJECT_ROOT", "write_atomic", "png_bytes", "figure_bytes", "figure_format", "FIGURE_FORMATS", "os_reason",
           "same_file", "check_clashes", "check_not_standard_stream", "check_input", "prepare_output", "prepare_folder"]

#: The project folder (the one holding ``replication/``, ``data/`` and ``notebooks/``): every
#: default path starts here.
PROJECT_ROOT = Path(__file__).resolve().parent.parent

#: Figure formats :func:`figure_bytes` writes, by file extension (matplotlib's
#: ``savefig(format=...)``).
FIGURE_FORMATS = ("png", "pdf", "svg")
#: Metadata left out of each format (a creation date or a software version would make the bytes
#: vary).
_NO_METADATA = {"png": {"Software": None}, "pdf": {"Creator": None, "Producer": None, "CreationDate": None},
                "svg": {"Creator": None, "Date": None}}


def os_reason(err: OSError) -> str:
    """The operating system's reason for ``err`` ("Permission denied", "No space left on device",
    ...)."""
    return err.strerror or str(err)


def _temporary_sibling(path: Path):
    """Create an empty file next to ``path`` under a fresh name (never an existing file); ``(name,
    fd)``."""
    for _ in range(100):
        tmp = path.with_name(f"{path.name}.{secrets.token_hex(4)}.part")
        try:
            return tmp, os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
    raise FileExistsError(f"{path}: no free temporary name next to it")


def write_atomic(path, data: bytes | str) -> None:
    """Write ``data`` (``str`` as UTF-8) to ``path`` through a temporary file and an atomic rename.

    A reader never sees a half-written file, and an interrupted write leaves the old file (or none)
    in place. The temporary file has a fresh name (``<name>.<random>.part``, created exclusively):
    it never overwrites another file. Raises ``OSError`` (the folder is not writable, the disk is
    full, ...) with nothing left behind.
    """
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    tmp, fd = _temporary_sibling(path)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    finally:
        try:
            tmp.unlink()
        except FileNotFoundError:
            pass


def figure_format(path) -> str:
    """The figure format named by ``path``'s extension (``png``, ``pdf``, ``svg``, any case); a
    ``ValueError`` naming the supported ones otherwise."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        raise ValueError(f"{path}: unknown figure format {('.' + suffix) if suffix else '(no extension)'}; "
                         f"supported: {', '.join('.' + f for f in FIGURE_FORMATS)}")
    return suffix


def figure_bytes(fig, fmt: str = "png", dpi=None) -> bytes:
    """A matplotlib figure in ``fmt`` (:data:`FIGURE_FORMATS`), cropped to its content, without a
    software tag or creation date."""
    import io

    if fmt not in FIGURE_FORMATS:
        raise ValueError(f"unknown figure format {fmt!r}; supported: {', '.join(FIGURE_FORMATS)}")
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt, bbox_inches="tight", metadata=_NO_METADATA[fmt],
                **({} if dpi is None else {"dpi": dpi}))
    return buffer.getvalue()


def png_bytes(fig, dpi=None) -> bytes:
    """A matplotlib figure as PNG bytes, cropped to its content, without the (version-dependent)
    software tag."""
    return figure_bytes(fig, "png", dpi)


# --------------------------------------------------------------------------- checks before any work

def same_file(a, b) -> bool:
    """Whether two paths name one file: equal after resolving links (``os.path.realpath``), or,
    where both exist, the same inode (``os.path.samefile``: hard links)."""
    try:
        if os.path.realpath(a) == os.path.realpath(b):
            return True
    except (OSError, ValueError):
        pass
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def check_clashes(outputs: dict, inputs: dict) -> None:
    """Refuse an output that is one of the inputs or another output (``{option: path}``; ``None``
    paths skipped).

    Raises ``ValueError``: ``"--out is the --camera input file: cam.txt"``, ``"--plot and --out are
    the same file: r.json"``.
    """
    outs = [(k, v) for k, v in outputs.items() if v is not None]
    ins = [(k, v) for k, v in inputs.items() if v is not None]

    def shown(path, other):
        if str(path) == str(other):
            return str(path)
        real = os.path.realpath(path)
        if real == os.path.realpath(other):
            return f"{path} (resolves to {real}, as {other} does)"
        return f"{path} (a hard link to {other})"

    for name, path in outs:
        for other, source in ins:
            if same_file(path, source):
                raise ValueError(f"{name} is the {other} input file: {shown(path, source)}; writing it would "
                                 f"destroy the input")
    for i, (name, path) in enumerate(outs):
        for other, earlier in outs[:i]:
            if same_file(path, earlier):
                raise ValueError(f"{name} and {other} are the same file: {shown(path, earlier)}; one would "
                                 f"overwrite the other")


def check_not_standard_stream(path, what: str) -> None:
    """Refuse an output that is this process's standard output or error (``/dev/stdout`` redirected
    to a file): replacing it would drop what the command prints."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return
    for fd, name in ((1, "standard output"), (2, "standard error")):
        try:
            other = os.fstat(fd)
        except OSError:
            continue
        if (st.st_dev, st.st_ino) == (other.st_dev, other.st_ino):
            raise ValueError(f"{what} {path}: is this command's {name}; give a file name")


def check_input(path, what: str) -> str:
    """Check an input before any work: ``"file"`` (a regular, readable file) or ``"pipe"`` (a FIFO:
    read it once).

    Raises ``ValueError`` naming ``what`` (the option), the path and the reason: missing, a
    directory, another special file (a device or a socket), unreadable.
    """
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        raise ValueError(f"{what} {path}: no such file") from None
    except OSError as err:
        raise ValueError(f"{what} {path}: cannot be read ({os_reason(err)})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{what} {path}: is a directory, not a file")
    if stat.S_ISFIFO(st.st_mode):
        return "pipe"
    if not stat.S_ISREG(st.st_mode):
        kind = ("a character device" if stat.S_ISCHR(st.st_mode) else "a block device" if stat.S_ISBLK(st.st_mode)
                else "a socket" if stat.S_ISSOCK(st.st_mode) else "a special file")
        raise ValueError(f"{what} {path}: is {kind}, not a regular file or a pipe")
    try:
        with open(path, "rb"):
            pass
    except OSError as err:
        raise ValueError(f"{what} {path}: cannot be read ({os_reason(err)})") from None
    return "file"


def _resolved(path, what: str) -> Path:
    text = str(path)
    if not text.strip():
        raise ValueError(f"{what}: the path is empty")
    try:
        return Path(path).resolve()
    except (OSError, RuntimeError) as err:  # a symlink loop
        raise ValueError(f"{what} {text}: cannot be resolved ({err})") from None


def _probe(folder: Path, what: str, shown) -> None:
    """Create and remove an empty file in ``folder``: a ``ValueError`` with the reason if that
    fails."""
    try:
        tmp, fd = _temporary_sibling(folder / ".write-probe")
        os.close(fd)
        tmp.unlink()
    except OSError as err:
        raise ValueError(f"{what} {shown}: cannot write in {folder} ({os_reason(err)})") from None


def prepare_output(path, what: str) -> Path:
    """Check an output file before any work: create its folders and check that a file can be written
    there.

    Refused (``ValueError`` naming ``what``, the path and the reason): an empty path, a name ending
    in a slash, a directory, an existing file that is not a regular file (a pipe or a device), this
    process's standard output or error, a folder that cannot be created or written. Returns the
    resolved path.
    """
    text = str(path)
    if text.strip() and text.endswith(("/", os.sep)):
        raise ValueError(f"{what} {text}: names a folder; give a file name")
    check_not_standard_stream(path, what)
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        st = None
    if st is not None and not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
        raise ValueError(f"{what} {path}: exists and is not a regular file (a pipe or a device); give a file name")
    resolved = _resolved(path, what)
    try:
        if resolved.is_dir():
            raise ValueError(f"{what} {resolved}: is a directory; give a file name")
        if resolved.exists() and not resolved.is_file():
            raise ValueError(f"{what} {resolved}: exists and is not a regular file (a pipe or a device); give a "
                             f"file name")
        resolved.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"{what} {resolved}: cannot write here ({os_reason(err)})") from None
    _probe(resolved.parent, what, resolved)
    return resolved


def prepare_folder(path, what: str) -> Path:
    """Check an output folder before any work: create it (and its parents) and check that it can be
    written in.

    Refused (``ValueError`` naming ``what``, the path and the reason): an empty path, an existing
    file, a folder that cannot be created or written. Returns the resolved path.
    """
    resolved = _resolved(path, what)
    try:
        if resolved.exists() and not resolved.is_dir():
            raise ValueError(f"{what} {resolved}: exists and is not a directory")
        resolved.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(f"{what} {resolved}: cannot create this folder ({os_reason(err)})") from None
    _probe(resolved, what, resolved)
    return resolved
