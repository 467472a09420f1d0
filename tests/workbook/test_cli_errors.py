"""The command line's error paths: one line on stderr naming the file, never a traceback."""

import errno
import os

import pytest

from piezolib import files
from piezolib.workbook import cli, sweep, sweep_spec


def test_data_on_a_folder_it_cannot_write_is_one_line_naming_the_file(tmp_path, monkeypatch,
                                                                      capsys):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    (tmp_path / "data").write_text("a file where data/ goes: nothing can be written in it")
    assert cli.main(["data"]) == 1                       # a traceback before
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("python -m piezolib data: cannot write ")
    assert "chirp_identification.csv" in lines[0]


def test_data_on_a_full_disk_is_one_line_naming_the_file(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))

    def full(path, data):
        raise OSError(errno.ENOSPC, f"cannot write {path}: No space left on device", str(path))

    monkeypatch.setattr(files, "atomic_write", full)
    assert cli.main(["data"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith("chirp_identification.csv: No space left on device")


def test_an_os_error_without_its_file_in_the_message_is_named():
    assert cli.error_line(PermissionError(13, "Permission denied", "runs/x")) == \
        "runs/x: Permission denied"
    assert cli.error_line(ValueError("first\nsecond")) == "first"


@pytest.fixture
def spec_file(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    path = tmp_path / "one.toml"
    path.write_text("[set]\ndesign.max_iter = 1\n[grid]\nweights.omega_e = [1000.0]\n")
    return path


def test_a_sweep_that_runs_already_is_refused_in_one_line(spec_file, capsys):
    spec = sweep_spec.load_spec(spec_file)
    with files.exclusive_lock(spec.directory / sweep.LOCK_NAME, "sweep one"):
        assert cli.main(["sweep", str(spec_file)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"sweep one is already running: process {os.getpid()}" in err[0]


def test_a_sweep_into_an_unwritable_folder_is_refused_before_it_designs(spec_file, capsys):
    spec = sweep_spec.load_spec(spec_file)
    spec.directory.parent.mkdir(parents=True)
    spec.directory.write_text("not a folder")
    assert cli.main(["sweep", str(spec_file)]) == 1       # the real evaluation: never reached
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sweeps/one" in err[0] and "cannot write" in err[0]


def test_a_sweep_of_more_points_than_the_limit_fails_in_its_dry_run(spec_file, capsys):
    values = ", ".join(str(1000.0 + k) for k in range(200))
    spec_file.write_text(f"[grid]\nweights.omega_e = [{values}]\n"
                         f"weights.omega_y = [{', '.join(str(1e5 + k) for k in range(40))}]\n"
                         f"uncertainty.spread = [{', '.join(str(0.01 + k / 1e3) for k in range(40))}]\n")
    assert cli.main(["sweep", str(spec_file), "--dry-run"]) == 2        # 320,000 points
    err = capsys.readouterr().err
    assert "[grid] gives 320000 points" in err and "at most 10000" in err
