"""The command line: ``python -m piezolib {reproduce,data}``."""

import io
import os
import subprocess
import sys
import time

import pytest

from piezolib.workbook import cli


def test_unknown_notebook_prefix_is_a_usage_error(tmp_path, monkeypatch):
    (tmp_path / "notebooks").mkdir()
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    proc = subprocess.run([sys.executable, "-m", "piezolib", "reproduce", "99"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "no notebook matches" in lines[0]
    assert proc.stdout == ""


def test_commands_and_usage(capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "reproduce" in out and "data" in out and "report" in out
    with pytest.raises(SystemExit) as exc:
        cli.main(["data", "--help"])
    assert exc.value.code == 0
    with pytest.raises(SystemExit) as exc:
        cli.main([])                                   # a command is required
    assert exc.value.code == 2


def test_data_writes_the_experiment_files(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    # what a run killed inside atomic_path leaves, an hour old: removed by the next data run
    stale = tmp_path / "data" / ".chirp_identification.csv.abcd1234.tmp.csv"
    stale.parent.mkdir()
    stale.write_text("t,u\n")
    os.utime(stale, (time.time() - 3600,) * 2)
    lines = []

    class Stream:
        def write(self, text):
            lines.append(text)

    assert cli.main(["data"], stream=Stream()) == 0
    written = sorted(p.name for p in (tmp_path / "data").glob("*.csv"))
    assert "chirp_identification.csv" in written and "hysteresis_loop_40V.csv" in written
    text = "".join(lines)
    assert "Case I hysteresis at   40 V" in text and text.rstrip().splitlines()[-1].startswith("done")
    assert not stale.exists()


def test_list_studies_and_bad_study(capsys):
    buf = io.StringIO()
    assert cli.main(["reproduce", "--list"], stream=buf) == 0
    out = buf.getvalue()
    for name in ("reference", "uncertainty_3pct", "wide_error_weight"):
        assert name in out
    assert out.splitlines()[0].startswith("reference")
    assert cli.main(["reproduce", "--study", "no_such_study"]) == 2
    assert "no study named 'no_such_study'" in capsys.readouterr().err


@pytest.mark.parametrize("timeout", ["0", "-5", "nan", "inf", "soon"])
def test_a_timeout_that_is_no_limit_is_a_usage_error(timeout, capsys):
    with pytest.raises(SystemExit) as exc:
        cli.main(["reproduce", "--timeout", timeout])
    assert exc.value.code == 2
    assert "positive number of seconds" in capsys.readouterr().err


def test_compare_refuses_unknown_unrun_and_identical_studies(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "unrun.toml").write_text("name = 'unrun'\n[weights]\nomega_e = 2000.0\n")
    for argv, message in ((["compare", "reference", "nope"], "no study named 'nope'"),
                          (["compare", "reference", "unrun"], "'unrun' has no results yet"),
                          (["compare", "reference", "reference"], "both arguments name")):
        assert cli.main(argv) == 2
        assert message in capsys.readouterr().err


def test_list_names_a_broken_study_file_and_fails(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "good.toml").write_text("name = 'good'\ndescription = 'fine'\n")
    (tmp_path / "studies" / "bad.toml").write_text("name = 'bad'\n[loop]\nfs_Hz = -1.0\n")
    buf = io.StringIO()
    assert cli.main(["reproduce", "--list"], stream=buf) == 1
    out = buf.getvalue()
    assert "good" in out and "fine" in out
    assert "BROKEN" in out and "loop.fs_Hz" in out
