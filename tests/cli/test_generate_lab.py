"""The ``generate-lab`` command (``replication/cli/lab.py``): the simulated lab's recordings written
where asked, loadable, and different for another seed."""


def test_generate_lab_writes_a_loadable_recording(tmp_path, capsys):
    """(That the committed data/lab equal the generator's output is tests/study/test_lab.py's
    check.)"""
    from replication.cli import main
    from replication.study.lab import load_lab

    assert main(["generate-lab", "--out", str(tmp_path / "a"), "--seed", "7"]) == 0
    assert "seed 7" in capsys.readouterr().out
    rec = load_lab(tmp_path / "a")
    assert rec.truth["camera_from_sensor"].shape == (3, 3)
    assert main(["generate-lab", "--out", str(tmp_path / "b"), "--seed", "8"]) == 0
    assert (tmp_path / "a" / "static_imu.csv").read_text() != (tmp_path / "b" / "static_imu.csv").read_text()
