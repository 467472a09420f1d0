"""The command line: ``python -m piezolib {reproduce,data}``."""

import io
import subprocess
import sys

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
    assert "reproduce" in out and "data" in out
    with pytest.raises(SystemExit) as exc:
        cli.main(["data", "--help"])
    assert exc.value.code == 0
    with pytest.raises(SystemExit) as exc:
        cli.main([])                                   # a command is required
    assert exc.value.code == 2


def test_data_writes_the_experiment_files(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    lines = []

    class Stream:
        def write(self, text):
            lines.append(text)

    assert cli.main(["data"], stream=Stream()) == 0
    written = sorted(p.name for p in (tmp_path / "data").glob("*.csv"))
    assert "chirp_identification.csv" in written and "hysteresis_loop_40V.csv" in written
    text = "".join(lines)
    assert "Case I hysteresis at   40 V" in text and text.rstrip().splitlines()[-1].startswith("done")


def test_list_studies_and_bad_study(capsys):
    buf = io.StringIO()
    assert cli.main(["reproduce", "--list"], stream=buf) == 0
    out = buf.getvalue()
    for name in ("reference", "uncertainty_3pct", "wide_error_weight"):
        assert name in out
    assert out.splitlines()[0].startswith("reference")
    assert cli.main(["reproduce", "--study", "no_such_study"]) == 2
    assert "no study named 'no_such_study'" in capsys.readouterr().err
