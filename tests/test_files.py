"""File integrity: atomic writes leave no partial file; manifests locate truncation and changes."""

import os

import numpy as np
import pytest

from piezolib import files as F
from piezolib.records import RecordError

FS = 5000.0


def write(path, lines):
    path.write_text("".join(line + "\n" for line in lines))
    return path


def data_lines(n, fs=FS):
    return ["t,v,x"] + [f"{k / fs:.6f},{np.sin(k / 5):.5f},{3 * np.sin(k / 5):.5f}"
                        for k in range(n)]


def test_atomic_write_leaves_no_partial_file(tmp_path):
    path = tmp_path / "out.csv"
    F.atomic_write(path, "old\n")
    with pytest.raises(RuntimeError):
        with F.atomic_path(path) as tmp:
            tmp.write_text("half of the new cont")
            raise RuntimeError("writer died")
    assert path.read_text() == "old\n"
    assert os.listdir(tmp_path) == ["out.csv"]                       # temporary file removed
    F.atomic_write(path, b"new\n")
    assert path.read_bytes() == b"new\n" and os.listdir(tmp_path) == ["out.csv"]
    assert oct(path.stat().st_mode & 0o777) != oct(0o600)            # not mkstemp's private mode
    with pytest.raises(TypeError, match="data"):
        F.atomic_write(path, 3)


def test_manifest_detects_truncation_and_changes_with_the_line(tmp_path):
    lines = data_lines(2500)
    path = write(tmp_path / "m.csv", lines)
    entry = F.manifest_entry(path, rows=2500, fs=FS)
    F.verify_file(path, entry, rows=2500, fs=FS)                      # intact
    write(path, lines[:1800])                                         # cut at a line end
    with pytest.raises(RecordError, match="truncated") as info:
        F.verify_file(path, entry)
    assert info.value.line == 1801
    write(path, lines[:1500] + [lines[1500].replace("0", "1", 1)] + lines[1501:])
    with pytest.raises(RecordError, match="lines 1001-2000") as info:
        F.verify_file(path, entry)
    assert info.value.line == 1001
    write(path, lines)
    with pytest.raises(RecordError, match="rate"):
        F.verify_file(path, entry, fs=10e3)
