"""The real recordings notebook 07 and the tests read: manifest, checksums, download from their
public origins. Theory and measured numbers: ``docs/reading.md``, section
``replication.rig.fetch``."""
from __future__ import annotations

import csv
import hashlib
from dataclasses import dataclass
from pathlib import Path

from .._extras import shipped
from .._io import os_reason, prepare_folder, same_file, write_atomic
from .datafile import fail, read_text

__all__ = ["MANIFEST", "MANIFEST_NAME", "ManifestEntry", "NoNetwork", "load_manifest", "verify", "fetch", "sha256_of"]

#: The manifest shipped with the project (the clone's ``data/``, or the copy an installed wheel
#: carries).
MANIFEST_NAME = "data/real_data_manifest.csv"
MANIFEST = shipped(MANIFEST_NAME)
COLUMNS = ["folder", "file", "bytes", "sha256", "repository", "commit", "path", "licence", "citation"]
_LFS_POINTER = b"version https://git-lfs.github.com/spec/v1"


@dataclass(frozen=True)
class ManifestEntry:
    """One file of the real-data folder and where it comes from."""

    folder: str
    file: str
    bytes: int
    sha256: str
    repository: str
    commit: str
    path: str
    licence: str
    citation: str

    @property
    def relpath(self) -> Path:
        """``<folder>/<file>`` inside the real-data folder."""
        return Path(self.folder) / self.file

    @property
    def url(self) -> str:
        """The file at its pinned commit on GitHub."""
        return f"https://raw.githubusercontent.com/{self.repository}/{self.commit}/{self.path}"

    @property
    def lfs_url(self) -> str:
        """The same file from GitHub's LFS media host (for repositories that store it with Git
        LFS)."""
        return f"https://media.githubusercontent.com/media/{self.repository}/{self.commit}/{self.path}"


def load_manifest(path=MANIFEST) -> list[ManifestEntry]:
    """Read and validate the manifest; errors name the file, line and column."""
    path = Path(path)
    rows = list(csv.reader(read_text(path, "the real-data manifest").splitlines()))
    if not rows or rows[0] != COLUMNS:
        fail(path, f"header must be {','.join(COLUMNS)}", line=1)
    entries = []
    for line, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        if len(row) != len(COLUMNS):
            fail(path, f"expected {len(COLUMNS)} columns, got {len(row)}", line=line)
        values = dict(zip(COLUMNS, row))
        for column in COLUMNS:
            if not values[column].strip():
                fail(path, "empty", line=line, column=column)
        if not values["bytes"].isdigit():
            fail(path, f"not a whole number ({values['bytes']!r})", line=line, column="bytes")
        if len(values["sha256"]) != 64 or any(c not in "0123456789abcdef" for c in values["sha256"]):
            fail(path, "not 64 lowercase hex digits", line=line, column="sha256")
        if len(values["commit"]) != 40:
            fail(path, "not a full 40-character commit hash", line=line, column="commit")
        entries.append(ManifestEntry(**{**values, "bytes": int(values["bytes"])}))
    seen = set()
    for e in entries:
        if e.relpath in seen:
            fail(path, f"{e.relpath} is listed twice")
        seen.add(e.relpath)
    return entries


def sha256_of(data_or_path) -> str:
    """SHA-256 (hex) of bytes or of a file's content."""
    if isinstance(data_or_path, (bytes, bytearray)):
        return hashlib.sha256(data_or_path).hexdigest()
    h = hashlib.sha256()
    with open(data_or_path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _status(path: Path, entry: ManifestEntry) -> str:
    if not path.is_file():
        return "missing"
    size = path.stat().st_size
    if size != entry.bytes:
        return f"size {size} != {entry.bytes}"
    digest = sha256_of(path)
    if digest != entry.sha256:
        return f"sha256 {digest[:12]}... != {entry.sha256[:12]}..."
    return "ok"


def verify(root, entries=None) -> dict:
    """``{relative path: "ok" | "missing" | "size ... != ..." | "sha256 ... != ..."}`` for a
    real-data folder."""
    root = Path(root)
    entries = load_manifest() if entries is None else entries
    return {str(e.relpath): _status(root / e.relpath, e) for e in entries}


class NoNetwork(ConnectionError):
    """A download could not reach its server (no network, a host name that does not resolve, a
    refused or reset connection, a timeout): :func:`fetch` stops there, as every other download
    would fail alike.

    Attributes
    ----------
    url : str
        The first URL that could not be reached.
    reason : str
        Why (the operating system's or urllib's words).
    pending : int or None
        How many files of the manifest were left unfetched (None: not counted yet).
    """

    def __init__(self, url: str, reason, pending: int | None = None):
        self.url, self.reason, self.pending = url, str(reason), pending
        left = "" if pending is None else f"; {pending} file{'s' if pending != 1 else ''} not fetched"
        super().__init__(
            f"no network: {url} could not be reached ({self.reason}){left}. Connect and run again (files already "
            f"verified are kept), or copy the files from a local copy laid out like DEST with --mirror FOLDER; "
            f"{MANIFEST_NAME} (fetch-data --help says where it is) lists each file's repository, commit, path, size "
            "and SHA-256")

    def __reduce__(self):
        return type(self), (self.url, self.reason, self.pending)


def _download(url: str, timeout: float) -> bytes:
    """The bytes at ``url``; a server that answers with an error raises ``OSError`` naming the URL
    and the HTTP status, a server not reached :class:`NoNetwork`."""
    import urllib.error
    import urllib.request

    try:
        with urllib.request.urlopen(url, timeout=timeout) as response:  # noqa: S310 (https URLs from the manifest)
            return response.read()
    except urllib.error.HTTPError as err:  # the server answered: a problem of this file only
        raise OSError(f"{url}: HTTP error {err.code} ({err.reason})") from None
    except urllib.error.URLError as err:
        reason = err.reason
        raise NoNetwork(url, os_reason(reason) if isinstance(reason, OSError) else reason) from None
    except (TimeoutError, ConnectionError) as err:
        raise NoNetwork(url, os_reason(err) or type(err).__name__) from None


def _obtain(entry: ManifestEntry, mirror, timeout: float) -> bytes:
    if mirror is not None:
        source = Path(str(mirror).removeprefix("file://")) / entry.relpath
        if not source.is_file():
            raise FileNotFoundError(f"{source}: not in the mirror")
        return source.read_bytes()
    data = _download(entry.url, timeout)
    if data.startswith(_LFS_POINTER):  # the repository keeps this file in Git LFS
        data = _download(entry.lfs_url, timeout)
    return data


def _check_destination(dest: Path, mirror, todo) -> None:
    """Before any download: ``dest`` is not the mirror (no file written onto itself) and every
    folder a file goes to can be created and written (``ValueError`` with the path and the
    reason)."""
    if mirror is not None:
        source = Path(str(mirror).removeprefix("file://"))
        if same_file(dest, source):
            raise ValueError(f"{dest} is the --mirror folder {source}: the files would be written onto themselves "
                             "(--check verifies a folder in place)")
        for e in todo:
            if same_file(dest / e.relpath, source / e.relpath):
                raise ValueError(f"{dest / e.relpath} is the --mirror file {source / e.relpath}: it would be written "
                                 "onto itself")
    prepare_folder(dest, "DEST")
    for folder in sorted({(dest / e.relpath).parent for e in todo}):
        prepare_folder(folder, "DEST")


def fetch(dest, *, mirror=None, entries=None, timeout: float = 60.0, log=print) -> dict:
    """Download (or copy from ``mirror``) every manifest file into ``dest`` and verify it.

    Files already present with the right checksum are kept. Returns :func:`verify`'s report after
    the fetch; a file whose download fails or does not match is reported, not written. Before any
    download, ``dest`` and its folders are created and checked: a file in the way, a folder that
    cannot be created or written, or ``dest`` being the mirror raises ``ValueError``
    (``NotADirectoryError`` for an existing file) naming the path and the reason; a write that fails
    later (a full disk) too, the files fetched before it kept. A server that cannot be reached (no
    network) stops the fetch with :class:`NoNetwork` (a ``ConnectionError``) naming the URL, the
    reason and how many files are left; the files fetched before it are kept.
    """
    dest = Path(dest)
    if dest.exists() and not dest.is_dir():
        raise NotADirectoryError(f"{dest}: exists and is not a directory")
    entries = load_manifest() if entries is None else entries
    status = {e.relpath: _status(dest / e.relpath, e) for e in entries}
    todo = [e for e in entries if status[e.relpath] != "ok"]
    if todo:
        _check_destination(dest, mirror, todo)
    for e in entries:
        target = dest / e.relpath
        if status[e.relpath] == "ok":
            log(f"ok       {e.relpath}")
            continue
        try:
            data = _obtain(e, mirror, timeout)
        except NoNetwork as err:  # every other download would fail alike: stop, said once
            pending = sum(_status(dest / x.relpath, x) != "ok" for x in entries)
            raise NoNetwork(err.url, err.reason, pending) from None
        except (OSError, ValueError) as err:  # an HTTP error is an OSError
            log(f"FAILED   {e.relpath}: {err}")
            continue
        digest = sha256_of(data)
        if len(data) != e.bytes or digest != e.sha256:
            log(f"FAILED   {e.relpath}: got {len(data)} bytes, sha256 {digest[:12]}...; expected {e.bytes} bytes, "
                f"{e.sha256[:12]}... (source: {mirror or e.url})")
            continue
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            write_atomic(target, data)
        except OSError as err:
            raise ValueError(f"{target}: cannot write ({os_reason(err)}); nothing was written there, the files "
                             "fetched before it are kept") from None
        log(f"fetched  {e.relpath} ({e.bytes} bytes)")
    return verify(dest, entries)
