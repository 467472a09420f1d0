"""Notebook kernels forked from one warm process: the workbook's imports paid once per run.

Every notebook's kernel imports python-control, scipy, pandas, matplotlib and the
workbook (about 2.7 CPU-s of a notebook's 8-30).  ``reproduce`` starts a
:class:`WarmKernels` server that imports them once; each kernel is then a
``fork`` of it, with the state of a fresh interpreter that has imported those
modules and nothing else (no notebook code has run in the server).

How a kernel starts: jupyter_client launches the small *launcher*
``python -m piezolib.workbook.warm_kernels launch -f <connection file>`` (standard
library only) in place of ``ipykernel_launcher``.  The launcher hands the
server its connection file, working folder, environment and standard
streams; the server forks, and the child becomes an ipykernel on that
connection file.  The launcher stays as the process jupyter_client knows:
it forwards SIGINT (an interrupt) and SIGTERM to the kernel and exits with
the kernel's status; when the launcher is killed, the kernel sees its
connection close and exits.

POSIX only (``os.fork``, UNIX sockets, passing file descriptors); elsewhere,
or when the server cannot start, kernels start as usual.
"""

import array
import functools
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

__all__ = ["WarmKernels", "available", "SOCKET_ENV", "PRELOAD"]

#: Environment variable naming the server's socket (set for the kernels' launchers).
SOCKET_ENV = "PIEZOLIB_WARM_KERNELS"

#: Modules the server imports before it forks kernels: what every notebook imports.
PRELOAD = ("numpy", "scipy.linalg", "scipy.signal", "scipy.optimize", "pandas", "control",
           "matplotlib", "matplotlib.pyplot", "ipykernel.kernelapp", "piezolib.workbook.session",
           "piezolib.problem.paper", "piezolib.workbook.pipeline")

_READY_TIMEOUT_S = 10.0
_MESSAGE_LIMIT = 1 << 20


def available():
    """True where kernels can be forked: POSIX with ``os.fork`` and UNIX sockets.

    Examples
    --------
    >>> isinstance(available(), bool)
    True
    """
    return hasattr(os, "fork") and hasattr(socket, "AF_UNIX") and hasattr(socket, "send_fds")


class WarmKernels:
    """The warm server as a context manager: started on entry, stopped with its kernels on exit;
    inside, :data:`SOCKET_ENV` names its socket (the kernels started then fork from it).

    Parameters
    ----------
    folder : pathlib.Path
        A private folder for the server's socket (e.g. a temporary one).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as tmp:                 # doctest: +SKIP
    ...     with WarmKernels(pathlib.Path(tmp)):
    ...         pass                                              # kernels started here fork
    """

    def __init__(self, folder):
        from unittest import mock

        self.socket_path = folder / "warm-kernels.sock"
        self.process = None
        self._environment = mock.patch.dict(os.environ, {SOCKET_ENV: str(self.socket_path)})

    def __enter__(self):
        self.process = subprocess.Popen(
            [sys.executable, "-m", "piezolib.workbook.warm_kernels", "serve",
             str(self.socket_path)], stdin=subprocess.DEVNULL)
        self._environment.start()
        return self

    def __exit__(self, *exc):
        self._environment.stop()
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()          # the server kills the kernels it forked
            try:
                self.process.wait(10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.socket_path.unlink(missing_ok=True)
        return False


@functools.cache
def kernel_manager_class():
    """A jupyter_client KernelManager whose kernels start through the launcher."""
    from jupyter_client.manager import AsyncKernelManager

    class WarmKernelManager(AsyncKernelManager):
        def format_kernel_cmd(self, extra_arguments=None):
            return [sys.executable, "-m", "piezolib.workbook.warm_kernels", "launch", "-f",
                    os.path.realpath(self.connection_file)]

    return WarmKernelManager


# -- the server ----------------------------------------------------------------------------


def serve(socket_path):
    """Listen, import :data:`PRELOAD`, then fork a kernel for each launcher that connects.

    The socket exists before the imports: a launcher that connects meanwhile waits in
    the backlog, and one that finds nobody listening (the server has died) starts a
    kernel of its own.
    """
    import importlib

    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(socket_path)
    listener.listen(16)
    for name in PRELOAD:
        importlib.import_module(name)
    if threading.active_count() != 1:
        # a fork copies only the forking thread: a lock another thread holds would stay held
        raise SystemExit(f"warm kernels: {threading.active_count()} threads after the imports")
    children = {}                                   # pid -> connection to its launcher

    def stop(*_):
        for pid in children:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        os._exit(0)

    signal.signal(signal.SIGTERM, stop)
    listener.settimeout(0.2)
    while True:
        _reap(children)
        try:
            conn, _ = listener.accept()
        except socket.timeout:
            continue
        conn.settimeout(None)
        try:
            request, fds = _receive_request(conn)
        except (OSError, ValueError):
            conn.close()
            continue
        pid = os.fork()
        if pid == 0:
            listener.close()
            for other in children.values():         # the other kernels' launchers
                other.close()
            _become_kernel(conn, request, fds)      # never returns
        for fd in fds:
            os.close(fd)
        conn.sendall(json.dumps({"pid": pid}).encode() + b"\n")
        children[pid] = conn


def _reap(children):
    """Tell each launcher whose kernel has exited its status."""
    while children:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        conn = children.pop(pid, None)
        if conn is not None:
            code = os.waitstatus_to_exitcode(status)
            try:
                conn.sendall(json.dumps({"exit": code}).encode() + b"\n")
            except OSError:
                pass
            conn.close()


def _receive_request(conn):
    """(request dict, [stdin, stdout, stderr fds]) sent by a launcher: its streams with
    the first bytes, then a line of JSON (which may arrive in pieces)."""
    fds = array.array("i")
    msg, ancdata, _, _ = conn.recvmsg(65536, socket.CMSG_LEN(3 * fds.itemsize))
    for level, kind, data in ancdata:
        if level == socket.SOL_SOCKET and kind == socket.SCM_RIGHTS:
            fds.frombytes(data[:len(data) - (len(data) % fds.itemsize)])
    while msg and not msg.endswith(b"\n") and len(msg) < _MESSAGE_LIMIT:
        more = conn.recv(65536)
        if not more:
            break
        msg += more
    if len(fds) != 3 or not msg.endswith(b"\n"):
        for fd in fds:
            os.close(fd)
        raise ValueError("a launcher sends its three standard streams and one line of JSON")
    return json.loads(msg.decode()), list(fds)


def _become_kernel(conn, request, fds):
    """In the forked child: the launcher's streams, folder and environment, then ipykernel."""
    try:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        for target, fd in enumerate(fds):
            os.dup2(fd, target)
            os.close(fd)
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        threading.Thread(target=_follow_launcher, args=(conn,), daemon=True).start()
        from ipykernel import kernelapp

        argv = list(request["argv"])
        if "JPY_PARENT_PID" in os.environ:
            # ipykernel read this variable when the server imported it (unset there); without
            # a parent it prints its "ipython kernel" banner to the launcher's stdout
            argv.append(f"--IPKernelApp.parent_handle={int(os.environ['JPY_PARENT_PID'])}")
        sys.argv = ["ipykernel_launcher", *argv]
        kernelapp.launch_new_instance()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException:                            # noqa: B036 -- the kernel's last word
        import traceback

        traceback.print_exc()
        code = 1
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def _follow_launcher(conn):
    """Signals the launcher forwards; its connection closing (killed) ends the kernel."""
    while True:
        try:
            data = conn.recv(16)
        except OSError:
            data = b""
        if not data:
            os._exit(1)
        for name in data.decode(errors="ignore").split():
            if name in ("INT", "TERM"):
                os.kill(os.getpid(), getattr(signal, f"SIG{name}"))


# -- the launcher --------------------------------------------------------------------------


def launch(argv):
    """Start a kernel through the server named by :data:`SOCKET_ENV`; return its exit status.

    Falls back to a kernel of its own (``ipykernel_launcher``) when the server is not
    there (:func:`_connect`) or dies before forking the kernel.
    """
    conn = _connect(os.environ.get(SOCKET_ENV, ""))
    stream = None
    if conn is not None:
        request = {"argv": argv, "cwd": os.getcwd(), "env": dict(os.environ)}
        try:
            conn.sendmsg([json.dumps(request).encode() + b"\n"],
                         [(socket.SOL_SOCKET, socket.SCM_RIGHTS, array.array("i", [0, 1, 2]))])
            stream = conn.makefile("rb")
            first = stream.readline()
        except OSError:
            first = b""
    if conn is None or not first:       # no server, or it died before forking this kernel
        os.execv(sys.executable, [sys.executable, "-m", "ipykernel_launcher", *argv])
    pid = json.loads(first)["pid"]

    def forward(signum, _frame):
        try:
            conn.sendall(b"INT " if signum == signal.SIGINT else b"TERM ")
        except OSError:
            pass

    signal.signal(signal.SIGINT, forward)
    signal.signal(signal.SIGTERM, forward)
    line = stream.readline()
    if not line:                                     # the server died: so did the kernel
        _kill_quietly(pid)
        return 1
    return int(json.loads(line)["exit"])


def _connect(path):
    """A connection to the server at ``path``; None when its socket does not appear within
    :data:`_READY_TIMEOUT_S` s or nobody listens on it (the server has died)."""
    if not path:
        return None
    deadline = time.monotonic() + _READY_TIMEOUT_S
    while not os.path.exists(path):
        if time.monotonic() > deadline:
            return None
        time.sleep(0.05)
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(path)
        return conn
    except OSError:
        conn.close()
        return None


def _kill_quietly(pid):
    try:
        os.kill(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


if __name__ == "__main__":
    if len(sys.argv) >= 3 and sys.argv[1] == "serve":
        serve(sys.argv[2])
    elif len(sys.argv) >= 2 and sys.argv[1] == "launch":
        sys.exit(launch(sys.argv[2:]))
    else:
        sys.exit("usage: python -m piezolib.workbook.warm_kernels serve SOCKET | launch -f FILE")
