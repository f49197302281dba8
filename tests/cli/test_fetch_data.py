"""The ``fetch-data`` command (``replication/cli/fetch.py``) on file-system problems: a destination
under a file, in a read-only folder or equal to its mirror refused before downloading, a disk error
while writing a message; a stub serves the manifest's one file (no network)."""
import os

import pytest

from conftest import _disk_full
from replication.cli import main
from replication.rig import fetch


@pytest.fixture
def one_entry(monkeypatch):
    """A manifest of one small file, served by a stub: no network, and the download counted."""
    content = b"t w x y z\n1 2 3 4 5\n"
    entry = fetch.ManifestEntry("f", "a.txt", len(content), fetch.sha256_of(content), "o/r", "0" * 40, "p/a.txt",
                                "MIT", "x")
    served = []
    monkeypatch.setattr(fetch, "load_manifest", lambda *a: [entry])
    monkeypatch.setattr(fetch, "_download", lambda url, timeout: served.append(url) or content)
    return served


def test_fetch_data_into_a_path_under_a_file_is_refused_before_downloading(tmp_path, one_entry, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("keep")
    assert main(["fetch-data", str(blocker / "real")]) == 2
    err = capsys.readouterr().err
    assert f"DEST {blocker / 'real'}: cannot create this folder (Not a directory)" in err, err
    assert not one_entry and blocker.read_text() == "keep"
    assert main(["fetch-data", str(blocker)]) == 2
    assert f"{blocker}: exists and is not a directory" in capsys.readouterr().err
    assert not one_entry and blocker.read_text() == "keep"


def test_fetch_data_into_a_read_only_folder_is_refused_before_downloading(locked, one_entry, capsys):
    assert main(["fetch-data", str(locked / "real")]) == 2
    assert f"DEST {locked / 'real'}: cannot create this folder (Permission denied)" in capsys.readouterr().err
    assert main(["fetch-data", str(locked)]) == 2
    assert f"cannot write in {locked} (Permission denied)" in capsys.readouterr().err
    assert not one_entry


def test_fetch_data_reports_a_disk_error_while_writing(tmp_path, one_entry, monkeypatch, capsys):
    monkeypatch.setattr(fetch, "write_atomic", _disk_full)
    assert main(["fetch-data", str(tmp_path / "real")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'real' / 'f' / 'a.txt'}: cannot write (No space left on device)" in err
    assert "Traceback" not in err and not (tmp_path / "real" / "f" / "a.txt").exists()


def test_fetch_data_refuses_its_mirror_as_destination(tmp_path, one_entry, capsys):
    mirror = tmp_path / "mirror"
    (mirror / "f").mkdir(parents=True)
    (mirror / "f" / "a.txt").write_bytes(b"a stale copy")
    assert main(["fetch-data", str(mirror), "--mirror", str(mirror)]) == 2
    assert f"{mirror} is the --mirror folder {mirror}" in capsys.readouterr().err
    link = tmp_path / "dest"
    (link / "f").mkdir(parents=True)
    os.symlink(mirror / "f" / "a.txt", link / "f" / "a.txt")
    assert main(["fetch-data", str(link), "--mirror", str(mirror)]) == 2
    assert f"{link / 'f' / 'a.txt'} is the --mirror file {mirror / 'f' / 'a.txt'}" in capsys.readouterr().err
    assert (mirror / "f" / "a.txt").read_bytes() == b"a stale copy"
