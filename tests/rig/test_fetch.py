"""The real-data manifest and ``fetch-data``: checksums and the download logic, without network.

The checksum logic is checked against the shared copies (``$REPLICATION_REAL_DATA`` or
``../shared/data/real``) used as a mirror; the download path is checked with a stubbed downloader.
"""
import json
import pickle
import re
import shutil
import socket
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from conftest import needs_real
from replication.rig import fetch
from replication.rig import realdata as rd

ROOT = Path(__file__).resolve().parents[2]


def _files_the_project_reads():
    """File names of the real-data folder that notebook 07 and the tests open."""
    nb = json.loads((ROOT / "notebooks" / "07_real_data.ipynb").read_text())
    text = "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")
    text += (ROOT / "tests" / "rig" / "test_realdata.py").read_text()
    text += (ROOT / "benchmarks" / "bench_calibrate.py").read_text()
    names = set(re.findall(r"[\w.-]+\.(?:txt|csv|yaml)", text))
    runs = re.findall(r'"(\w*traj_run\w*)"', text)  # names built from a run label
    names |= {f"orbslam3_{r}.txt" for r in runs}
    return names


#: Names the scanned files write themselves (scratch files of test_realdata.py), not real
#: recordings.
SCRATCH_FILES = {"bad.txt", "c.yaml", "cam.txt", "imu.csv", "none.csv", "rep.txt", "robot.txt", "t.txt",
                 "b.csv", "data.csv", "flip.csv", "m.csv", "mocap.csv", "rep.csv", "s.csv", "x.csv",
                 "ns.csv", "whole.csv", "half.csv", "gt.csv", "s.yaml", "none.yaml"}


def test_manifest_lists_every_real_data_file_the_project_reads():
    """Without looking at the data folder: every file name the scanned code opens is in the manifest
    or is a scratch file of the tests (a new real file not added to the manifest fails here with or
    without the data)."""
    entries = fetch.load_manifest()
    listed = {e.file for e in entries}
    used = _files_the_project_reads() - SCRATCH_FILES
    assert used - listed == set(), f"read but not in the manifest: {sorted(used - listed)}"
    assert not SCRATCH_FILES & listed  # a scratch name that became a real file must not be ignored here
    assert {"orbslam3_mono_cam0_traj_runA.txt", "gt_body_MH_01_easy_tum.txt", "imu0_data.csv"} <= used
    assert all(e.url.startswith("https://raw.githubusercontent.com/") and e.commit in e.url for e in entries)


@needs_real
def test_shared_copies_match_the_manifest():
    report = fetch.verify(rd.data_root())
    assert report and set(report.values()) == {"ok"}, report


@needs_real
def test_fetch_from_a_mirror_verifies_writes_and_keeps(tmp_path):
    dest = tmp_path / "real"
    log = []
    report = fetch.fetch(dest, mirror=rd.data_root(), log=log.append)
    assert set(report.values()) == {"ok"} and all(line.startswith("fetched") for line in log)
    assert not list(dest.rglob("*.part"))
    log.clear()
    fetch.fetch(dest, mirror=rd.data_root(), log=log.append)  # second run: nothing to do
    assert all(line.startswith("ok") for line in log)


@needs_real
def test_a_corrupt_source_is_refused_and_not_written(tmp_path):
    entries = [e for e in fetch.load_manifest() if e.folder == "tabb_rwhe_ds1"]
    mirror = tmp_path / "mirror"
    shutil.copytree(rd.data_root() / "tabb_rwhe_ds1", mirror / "tabb_rwhe_ds1")
    bad = mirror / "tabb_rwhe_ds1" / "cali.txt"
    bad.chmod(0o644)
    bad.write_bytes(bad.read_bytes().replace(b"0.99", b"0.98", 1))
    log = []
    report = fetch.fetch(tmp_path / "dest", mirror=mirror, entries=entries, log=log.append)
    assert report["tabb_rwhe_ds1/cali.txt"] == "missing" and report["tabb_rwhe_ds1/robot_cali.txt"] == "ok"
    assert any(line.startswith("FAILED   tabb_rwhe_ds1/cali.txt") and "sha256" in line for line in log)
    # an existing file that does not match is replaced by the verified one
    good = tmp_path / "dest2" / "tabb_rwhe_ds1" / "transformations.txt"
    good.parent.mkdir(parents=True)
    good.write_text("truncated")
    assert fetch.verify(tmp_path / "dest2", entries)["tabb_rwhe_ds1/transformations.txt"].startswith("size")
    fetch.fetch(tmp_path / "dest2", mirror=rd.data_root(), entries=entries, log=lambda _: None)
    assert fetch.verify(tmp_path / "dest2", entries)["tabb_rwhe_ds1/transformations.txt"] == "ok"


def test_download_follows_git_lfs_pointers(tmp_path, monkeypatch):
    content = b"t w x y z\n1 2 3 4 5\n"
    entry = fetch.ManifestEntry("f", "a.txt", len(content), fetch.sha256_of(content), "o/r", "0" * 40, "p/a.txt",
                                "MIT", "x")
    served = {entry.url: b"version https://git-lfs.github.com/spec/v1\noid sha256:abc\nsize 22\n",
              entry.lfs_url: content}
    monkeypatch.setattr(fetch, "_download", lambda url, timeout: served[url])
    assert fetch.fetch(tmp_path, entries=[entry], log=lambda _: None) == {"f/a.txt": "ok"}
    assert (tmp_path / "f" / "a.txt").read_bytes() == content


def test_download_failures_are_reported(tmp_path, monkeypatch):
    entry = fetch.ManifestEntry("f", "a.txt", 3, "0" * 64, "o/r", "0" * 40, "p/a.txt", "MIT", "x")

    def offline(url, timeout):
        raise OSError("network unreachable")

    monkeypatch.setattr(fetch, "_download", offline)
    log = []
    assert fetch.fetch(tmp_path, entries=[entry], log=log.append) == {"f/a.txt": "missing"}
    assert "network unreachable" in log[0]


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace("folder,file", "folder,name", 1), "line 1: header"),
    (lambda t: t.replace(",309843,", ",30984x,", 1), "line 2, column 'bytes'"),
    (lambda t: t.replace("12627d0c", "12627D0C", 1), "line 2, column 'sha256'"),
    (lambda t: t.replace("2dba07a02a16a7fb4343ff47b9e0a8fb56d60b82", "2dba07a", 1), "line 2, column 'commit'"),
])
def test_malformed_manifest_names_line_and_column(tmp_path, edit, message):
    path = tmp_path / "manifest.csv"
    path.write_text(edit(fetch.MANIFEST.read_text()))
    with pytest.raises(ValueError, match=re.escape(message)):
        fetch.load_manifest(path)
    with pytest.raises(FileNotFoundError, match="is a directory"):
        fetch.load_manifest(tmp_path)


def test_cli_help_check_and_bad_arguments(tmp_path):
    run = lambda *a: subprocess.run([sys.executable, "-m", "replication", "fetch-data", *a], cwd=ROOT,
                                    capture_output=True, text=True)
    out = run("--help")
    assert out.returncode == 0 and "real_data_manifest.csv" in out.stdout and "SHA-256" in out.stdout
    out = run(str(tmp_path), "--check")
    assert out.returncode == 1 and "missing" in out.stdout
    out = run(str(tmp_path), "--only", "nope")
    assert out.returncode == 2 and "no such folder" in out.stderr


def _unreachable(error):
    """A stand-in for ``urllib.request.urlopen`` that raises ``error`` and counts its calls."""
    calls = []

    def urlopen(url, timeout=None):
        calls.append(url)
        raise error

    return urlopen, calls


@pytest.mark.parametrize("error, reason", [
    (urllib.error.URLError(socket.gaierror(-3, "Temporary failure in name resolution")),
     "Temporary failure in name resolution"),
    (urllib.error.URLError(ConnectionRefusedError(111, "Connection refused")), "Connection refused"),
    (TimeoutError("timed out"), "timed out"),
])
def test_without_a_network_fetch_data_says_so_once(tmp_path, monkeypatch, capsys, error, reason):
    from replication.cli import main

    urlopen, calls = _unreachable(error)
    monkeypatch.setattr(urllib.request, "urlopen", urlopen)
    entries = fetch.load_manifest()
    assert main(["fetch-data", str(tmp_path / "dest")]) == 1
    out, err = capsys.readouterr()
    assert calls == [entries[0].url]  # stopped at the first server not reached
    assert "FAILED" not in out and err.count("error:") == 1 and len(err.strip().splitlines()) == 1
    assert err.startswith(f"error: no network: {entries[0].url} could not be reached ({reason}); "
                          f"{len(entries)} files not fetched.")
    assert "--mirror FOLDER" in err and "data/real_data_manifest.csv" in err


def test_a_server_that_answers_with_an_error_fails_that_file_only(tmp_path, monkeypatch, capsys):
    """The other side of the line: an HTTP error is the file's problem, said per file with its URL;
    the fetch goes on."""
    from replication.cli import main

    urlopen, calls = _unreachable(urllib.error.HTTPError("u", 404, "Not Found", {}, None))
    monkeypatch.setattr(urllib.request, "urlopen", urlopen)
    entries = fetch.load_manifest()
    assert main(["fetch-data", str(tmp_path / "dest")]) == 1
    out, err = capsys.readouterr()
    assert len(calls) == len(entries) and "no network" not in err
    assert f"FAILED   {entries[0].relpath}: {entries[0].url}: HTTP error 404 (Not Found)" in out


def test_no_network_keeps_the_files_already_verified_and_counts_the_rest(tmp_path, monkeypatch):
    good, bad = (fetch.ManifestEntry("f", name, 3, fetch.sha256_of(b"abc"), "o/r", "0" * 40, name, "MIT", "x")
                 for name in ("a.txt", "b.txt"))
    (tmp_path / "f").mkdir()
    (tmp_path / "f" / "a.txt").write_bytes(b"abc")
    urlopen, _ = _unreachable(urllib.error.URLError("no route"))
    monkeypatch.setattr(urllib.request, "urlopen", urlopen)
    with pytest.raises(fetch.NoNetwork, match=r"could not be reached \(no route\); 1 file not fetched") as info:
        fetch.fetch(tmp_path, entries=[good, bad], log=lambda _: None)
    assert isinstance(info.value, ConnectionError) and info.value.url == bad.url and info.value.pending == 1
    again = pickle.loads(pickle.dumps(info.value))
    assert type(again) is fetch.NoNetwork and str(again) == str(info.value)
    assert (tmp_path / "f" / "a.txt").read_bytes() == b"abc"
