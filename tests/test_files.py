"""File integrity: atomic writes leave no partial file and name the file they cannot write;
stale temporary files are removed; manifests locate truncation and changes; sealed JSON."""

import errno
import json
import logging
import os
import subprocess
import sys
import time
from pathlib import Path

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


# --- a refused write names the file -----------------------------------------------------------

def refuse(code):
    def fail(*args, **kwargs):
        raise OSError(code, os.strerror(code))
    return fail


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EIO])
def test_a_full_disk_names_the_file_and_leaves_no_temporary(tmp_path, monkeypatch, code):
    path = tmp_path / "loop.csv"
    F.atomic_write(path, "old\n")
    monkeypatch.setattr(os, "fsync", refuse(code))
    with pytest.raises(OSError) as info:
        F.atomic_write(path, "new\n")
    assert info.value.errno == code and type(info.value) is OSError
    assert info.value.filename == str(path)
    assert str(path) in str(info.value) and os.strerror(code) in str(info.value)
    assert path.read_text() == "old\n" and os.listdir(tmp_path) == ["loop.csv"]


def test_a_refused_file_keeps_its_error_type_and_names_the_target(tmp_path, monkeypatch):
    path = tmp_path / "sub" / "fig.png"
    monkeypatch.setattr(F.tempfile, "mkstemp", refuse(errno.EROFS))      # read-only mount
    with pytest.raises(OSError, match=r"cannot write .*fig\.png: Read-only") as info:
        F.atomic_write(path, b"png")
    assert info.value.errno == errno.EROFS and info.value.filename == str(path)
    monkeypatch.undo()
    # a writer that opens the temporary file itself (as matplotlib does): the error names
    # the target, not the hidden temporary name, and keeps its type
    with pytest.raises(PermissionError) as info:
        with F.atomic_path(path) as tmp:
            raise PermissionError(errno.EACCES, "Permission denied", str(tmp))
    assert info.value.filename == str(path) and "cannot write" in str(info.value)
    assert not path.exists() and os.listdir(path.parent) == []
    # an error about another file is the caller's: unchanged
    other = tmp_path / "input.csv"
    with pytest.raises(FileNotFoundError) as info:
        with F.atomic_path(path):
            other.read_text()
    assert info.value.filename == str(other)


# --- stale temporary files ---------------------------------------------------------------------

KILLED_WRITE = """
import os, sys
from piezolib import files
with files.atomic_path(sys.argv[1]) as tmp:
    tmp.write_text("half of a fi")
    os._exit(9)                       # killed: no clean-up runs
"""


def killed_write(path):
    """The temporary file a writer killed inside atomic_path leaves."""
    subprocess.run([sys.executable, "-c", KILLED_WRITE, str(path)], check=False,
                   env={**os.environ, "PYTHONPATH": str(Path(F.__file__).parents[1])})
    [left] = [p for p in path.parent.iterdir() if p.name.startswith(f".{path.name}.")]
    return left


def age(path, seconds):
    t = time.time() - seconds
    os.utime(path, (t, t))
    return path


def test_stale_temporaries_are_removed_and_nothing_else(tmp_path, caplog):
    (tmp_path / "deep" / "er").mkdir(parents=True)
    stale = age(killed_write(tmp_path / "chirp.csv"), 2 * F.STALE_AFTER_S)
    deep = age(killed_write(tmp_path / "deep" / "er" / "K.json"), 2 * F.STALE_AFTER_S)
    assert stale.name.endswith(".tmp.csv") and stale.read_text() == "half of a fi"
    live = killed_write(tmp_path / "fig.png")                   # a concurrent writer's
    # the user's files, old as they are, whatever they resemble
    users = [tmp_path / name for name in
             ("chirp.csv", ".hidden.csv", "notes.tmp.csv", ".x.csv.abc.tmp.csv",
              ".x.csv.abcdefgh.tmp.json", ".x.csv.ABCDEFGH.tmp.csv", ".x.csv.abcdefgh.tmp.csv~")]
    for path in users:
        age(write(path, ["mine"]), 10 * F.STALE_AFTER_S)
    (tmp_path / ".d.csv.abcdefgh.tmp.csv").mkdir()              # a folder is not ours
    (tmp_path / ".l.csv.abcdefgh.tmp.csv").symlink_to(users[0])  # nor is a link
    with caplog.at_level(logging.WARNING, logger=F.__name__):
        removed = F.remove_stale_temporaries(tmp_path)
    assert sorted(removed) == sorted([stale, deep])
    assert not stale.exists() and not deep.exists() and live.exists()
    assert all(path.read_text() == "mine\n" for path in users)
    assert (tmp_path / ".d.csv.abcdefgh.tmp.csv").is_dir()
    assert (tmp_path / ".l.csv.abcdefgh.tmp.csv").is_symlink()
    assert str(stale) in caplog.text and "interrupted write" in caplog.text
    assert F.remove_stale_temporaries(tmp_path / "missing") == []
    assert F.remove_stale_temporaries(tmp_path, older_than_s=0) == [live]
    with pytest.raises(ValueError, match="older_than_s"):
        F.remove_stale_temporaries(tmp_path, older_than_s=-1)


# --- sealed JSON --------------------------------------------------------------------------------

def test_a_sealed_document_detects_any_change_but_not_its_formatting():
    doc = F.seal({"format": 1, "model": {"alpha": 0.1 + 0.2, "form": "printed"}})
    assert list(doc) == ["format", F.CONTENT_KEY, "model"]
    assert F.seal_problem(json.loads(json.dumps(doc))) is None           # floats survive JSON
    assert F.seal_problem(json.loads(json.dumps(doc, indent=4, sort_keys=True))) is None
    assert F.seal(doc) == doc                                            # sealing again: same
    # the checksum is of the values: the same double written otherwise is the same content,
    # the next double is not
    same = json.loads(json.dumps(doc).replace("0.30000000000000004", "0.300000000000000044"))
    assert F.seal_problem(same) is None
    edited = json.loads(json.dumps(doc).replace("0.30000000000000004", "0.3000000000000001"))
    assert "differs from its checksum" in F.seal_problem(edited)
    assert "no content checksum" in F.seal_problem({"format": 1})
