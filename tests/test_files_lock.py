"""files.exclusive_lock and files.check_writable: one process at a time, folders tried first."""

import json
import os
import subprocess
import sys

import pytest

from piezolib import files


def test_a_second_holder_is_refused_with_the_first_ones_pid(tmp_path):
    lock = tmp_path / "sub" / "run.lock"
    with files.exclusive_lock(lock, "the demo"):
        holder = json.loads(lock.read_text())
        assert holder["pid"] == os.getpid() and holder["what"] == "the demo"
        with pytest.raises(files.LockHeld, match=f"the demo is already running: process "
                                                 f"{os.getpid()} on "):
            with files.exclusive_lock(lock, "the demo"):
                pass
    assert not lock.exists()
    with files.exclusive_lock(lock):                    # free again
        pass


def test_a_lock_left_by_a_dead_process_is_taken_over(tmp_path, caplog):
    lock = tmp_path / "run.lock"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, timeout=60).stdout.strip()
    lock.write_text(json.dumps({"pid": int(dead), "host": "h"}))
    with files.exclusive_lock(lock):
        assert json.loads(lock.read_text())["pid"] == os.getpid()
    assert f"process {dead} on h, is no longer running" in caplog.text


def test_an_unwritable_folder_is_named(tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    with pytest.raises(OSError, match=r"cannot write in .*file"):
        files.check_writable(blocked / "out")
    with pytest.raises(OSError, match="run.lock"):
        with files.exclusive_lock(blocked / "run.lock"):
            pass
    assert files.check_writable(tmp_path / "new") == tmp_path / "new"
    assert list((tmp_path / "new").iterdir()) == []
