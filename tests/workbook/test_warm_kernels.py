"""Kernels forked from the warm server: the preloaded modules are there, nothing else of the
server's; a dying kernel, a timeout and a dead server are each reported or survived."""

import io
import os
import signal
import subprocess
import sys
import time

import nbformat
import pytest

from piezolib.workbook import reproduce, warm_kernels

pytestmark = pytest.mark.skipif(not warm_kernels.available(), reason="POSIX fork only")


@pytest.fixture(autouse=True)
def warm(monkeypatch):
    """The warm server is opt-in: these tests ask for it."""
    monkeypatch.setenv(warm_kernels.SOCKET_ENV, "1")


def write_notebook(path, *sources):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(s) for s in sources])
    nbformat.write(nb, path)


def outputs(nb):
    return "".join(o.get("text", "") for c in nb.cells for o in c.get("outputs", []))


def test_a_kernel_of_the_run_has_the_preloaded_modules_and_a_fresh_namespace(workbook):
    nbs = workbook / "notebooks"
    for name in ("00_a", "01_b"):               # two kernels from one server
        write_notebook(nbs / f"{name}.ipynb",
                       "import sys, os\n"
                       "assert 'control' in sys.modules and 'piezolib.workbook.session' in "
                       "sys.modules\n"
                       "assert 'leftover' not in globals()\n"
                       "leftover = 1\n"
                       "assert os.path.basename(os.getcwd()) == 'notebooks'\n"
                       f"open('{name}.pid', 'w').write(str(os.getpid()))")
    out = io.StringIO()
    assert reproduce.run(data=False, stream=out, jobs=1) == 0, out.getvalue()
    pids = {(nbs / f"{n}.pid").read_text() for n in ("00_a", "01_b")}
    assert len(pids) == 2                                       # a process each
    assert "--existing" not in out.getvalue()                   # no kernel banner


def test_without_the_server_a_kernel_starts_as_usual(workbook, monkeypatch):
    monkeypatch.setenv(warm_kernels.SOCKET_ENV, "0")
    write_notebook(workbook / "notebooks" / "00_a.ipynb",
                   "import sys\nassert 'piezolib.workbook.session' not in sys.modules")
    assert reproduce.run(data=False, stream=io.StringIO(), jobs=1) == 0


def test_a_kernel_that_dies_is_reported_and_the_next_notebook_runs(workbook):
    nbs = workbook / "notebooks"
    write_notebook(nbs / "00_dies.ipynb", "import os\nos._exit(3)")
    write_notebook(nbs / "01_next.ipynb", "x = 1")
    out = io.StringIO()
    start = time.monotonic()
    assert reproduce.run(data=False, stream=out, jobs=1, keep_going=True) == 1
    text = out.getvalue()
    assert "00_dies.ipynb" in text and "the kernel died" in text
    assert "01_next.ipynb" in text and text.splitlines()[1].rstrip().endswith("ok")
    assert time.monotonic() - start < 120


def test_a_cell_past_its_time_limit_is_interrupted_through_the_launcher(workbook):
    write_notebook(workbook / "notebooks" / "00_slow.ipynb", "import time\ntime.sleep(600)")
    out = io.StringIO()
    assert reproduce.run(data=False, stream=out, jobs=1, timeout=3) == 1
    assert "timed out" in out.getvalue()


def test_a_launcher_without_a_listening_server_starts_its_own_kernel(tmp_path):
    # a socket file nobody listens on (a server that died): the launcher execs ipykernel
    import socket

    path = tmp_path / "dead.sock"
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.bind(str(path))
    sock.close()
    assert warm_kernels._connect(str(path)) is None
    assert warm_kernels._connect("") is None


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process table from /proc")
def test_the_kernel_ends_when_its_launcher_is_killed(tmp_path):
    with warm_kernels.WarmKernels(tmp_path) as warm:
        env = {**os.environ, warm_kernels.SOCKET_ENV: str(warm.socket_path)}
        connection = tmp_path / "kernel.json"
        from jupyter_client.connect import write_connection_file

        write_connection_file(str(connection))
        launcher = subprocess.Popen([sys.executable, "-m", "piezolib.workbook.warm_kernels",
                                     "launch", "-f", str(connection)], env=env,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        kernels = []
        while not kernels and time.monotonic() < deadline:
            time.sleep(0.2)
            kernels = _children_of(warm.process.pid)
        assert kernels, "no kernel was forked"
        launcher.send_signal(signal.SIGKILL)
        launcher.wait()
        deadline = time.monotonic() + 30
        while _alive(kernels[0]) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not _alive(kernels[0])


def _children_of(pid):
    """Live child processes of ``pid`` (from /proc: ps may not be installed)."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                found.append(int(entry))
    return found


def _alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False
