"""File integrity: atomic writes, manifests of row count, rate and checksums, sealed JSON.

:func:`atomic_write` and :func:`atomic_path` write a file through a
temporary file in the same folder and :func:`os.replace`, so a reader never
sees a partial file; a write that the system refuses (full disk, read-only
file system, no permission) raises an :class:`OSError` that names the file.
:func:`remove_stale_temporaries` removes the temporary files that a killed
writer left behind.  :func:`manifest_entry` and :func:`verify_file` check a
file against a stored row count, sampling rate and SHA-256 (with block
checksums that locate a change to a range of lines).  A file that fails its
check raises the :class:`~piezolib.records.RecordError` of a record file,
which names the file and the line.  :func:`check_writable` tries a folder
before work that writes to it starts; :func:`exclusive_lock` keeps a second
process out of work that one process at a time must do.  :func:`seal` adds a SHA-256 of its
content to a JSON document and :func:`seal_problem` checks it on reading.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> folder = tempfile.TemporaryDirectory()
>>> path = atomic_write(Path(folder.name) / "loop.csv", "t,v\\n0.0,1.0\\n0.5,2.0\\n")
>>> entry = manifest_entry(path, rows=2, fs=2.0)
>>> entry["rows"], entry["lines"], entry["sample_rate_Hz"]
(2, 3, 2.0)
>>> verify_file(path, entry, rows=2, fs=2.0)            # intact: returns None
>>> path = atomic_write(path, "t,v\\n0.0,1.0\\n")
>>> verify_file(path, entry)
Traceback (most recent call last):
...
piezolib.records...RecordError: ...loop.csv, line 3: truncated: the file ends after line 2, ...
>>> folder.cleanup()
"""

import contextlib
import errno
import hashlib
import json
import logging
import os
import re
import socket
import stat
import tempfile
import time
from pathlib import Path

from piezolib._checks import check_integer, check_nonnegative, check_positive
from piezolib.records import RecordError

__all__ = ["atomic_write", "atomic_path", "remove_stale_temporaries", "STALE_AFTER_S",
           "check_writable", "exclusive_lock", "LockHeld",
           "manifest_entry", "verify_file", "BLOCK_LINES", "CONTENT_KEY", "content_sha256",
           "seal", "seal_problem"]

logger = logging.getLogger(__name__)

#: Lines per block checksum in a manifest entry.
BLOCK_LINES = 1000

#: Age [s] (since its last write) from which :func:`remove_stale_temporaries`
#: takes a temporary file of :func:`atomic_path` for one a killed writer left.
#: Every writer of the library writes a file in one call from memory, so a
#: live temporary file is seconds old at most; 10 minutes is two orders of
#: magnitude above that and above the clock skew of a network file system.
#: Too short a value would make a stalled writer fail loudly (its
#: ``os.replace`` finds no file), never corrupt the target; too long a value
#: only leaves a hidden file until a later run.
STALE_AFTER_S = 600.0

#: Errors of the file system itself (not of the caller's code) that
#: :func:`atomic_path` reports with the target's path when they carry no file name.
_WRITE_ERRNOS = frozenset(getattr(errno, name) for name in
                          ("ENOSPC", "EDQUOT", "EROFS", "EACCES", "EPERM", "EIO", "EFBIG")
                          if hasattr(errno, name))

#: Names of the temporary files of :func:`atomic_path`:
#: ``.<name>.<8 characters of tempfile>.tmp<suffix of name>``.
_TEMPORARY = re.compile(r"^\.(?P<name>.+)\.[a-z0-9_]{8}\.tmp(?P<suffix>(\.[^.]*)?)$")


@contextlib.contextmanager
def atomic_path(path):
    """Context manager yielding a temporary path next to ``path``; on success
    the temporary file replaces ``path`` in one step (``os.replace``), on an
    exception it is removed and ``path`` is left as it was.

    The temporary name keeps the suffix of ``path`` so that writers choosing a
    format by suffix (matplotlib) still work.

    Raises
    ------
    OSError
        Of the type the system raised (full disk, read-only file system, no
        permission, ...), naming ``path`` (its ``filename``) instead of the
        temporary file or nothing: raised while creating, writing (an error
        without a file name or naming the temporary file) or renaming it.
        An error naming another file is the caller's and passes unchanged.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     target = Path(folder) / "out.txt"
    ...     with atomic_path(target) as tmp:
    ...         _ = tmp.write_text("done")            # target does not exist yet
    ...         print(target.exists(), tmp.suffix)
    ...     print(target.read_text(), tmp.exists())
    False .txt
    done False
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}",
                                   dir=path.parent)
        os.close(fd)
    except OSError as exc:
        raise _naming(exc, path) from exc
    try:
        yield Path(tmp)
        # mkstemp makes the file private (0600); give it the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException as exc:
        # a failed removal must not hide why the write failed
        with contextlib.suppress(OSError):
            os.remove(tmp)
        if isinstance(exc, OSError) and _about_the_write(exc, tmp):
            raise _naming(exc, path) from exc
        raise


def _about_the_write(exc, tmp):
    """Whether ``exc`` (raised inside :func:`atomic_path`) is about writing its file."""
    if exc.filename is None:
        # fh.write or fsync: ENOSPC and its kind carry no name; other errors
        # without one (a socket's, say) may come from the caller's own code
        return exc.errno in _WRITE_ERRNOS
    return str(exc.filename) == str(tmp)


def _naming(exc, path):
    """A copy of ``exc`` (same type and errno) whose message and ``filename`` name ``path``."""
    reason = exc.strerror or str(exc)
    args = (exc.errno, f"cannot write {path}: {reason}", str(path))
    try:
        return type(exc)(*args)
    except TypeError:                   # a subclass with another signature (BlockingIOError)
        return OSError(*args)


def atomic_write(path, data):
    """Write text (UTF-8, ``\\n`` line ends) or bytes to ``path`` atomically.

    Returns
    -------
    Path

    Raises
    ------
    OSError
        The system refused the write (full disk, ...): naming ``path``, which
        is left as it was (:func:`atomic_path`).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = atomic_write(Path(folder) / "sub" / "note.txt", "hello")  # makes sub/
    ...     print(path.name, path.read_text())
    note.txt hello
    """
    if isinstance(data, str):
        data = data.encode("utf-8")
    if not isinstance(data, (bytes, bytearray)):
        raise TypeError(f"data must be str or bytes, got {type(data).__name__}")
    path = Path(path)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
    return path


def remove_stale_temporaries(directory, older_than_s=STALE_AFTER_S):
    """Remove the temporary files of :func:`atomic_path` that a killed writer left.

    Only regular files whose name is the pattern of :func:`atomic_path`
    (``.<name>.XXXXXXXX.tmp<suffix of name>``) are candidates, so no file of
    the user's is touched; of those, only files not written to for
    ``older_than_s`` seconds, so the live file of a concurrent writer stays
    (:data:`STALE_AFTER_S`).  Each removal is logged (warning).

    Parameters
    ----------
    directory : str or Path
        Searched with its sub-folders (symbolic links are not followed); a
        missing folder has nothing to remove.
    older_than_s : float, optional

    Returns
    -------
    list of Path
        The files removed.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     left = Path(folder) / ".data.csv.abcd1234.tmp.csv"    # as a killed writer leaves it
    ...     _ = left.write_text("partial")
    ...     _ = (Path(folder) / "data.csv").write_text("mine")    # not a temporary: kept
    ...     removed = remove_stale_temporaries(folder, older_than_s=0)
    ...     print([p.name for p in removed], sorted(p.name for p in Path(folder).iterdir()))
    ['.data.csv.abcd1234.tmp.csv'] ['data.csv']
    """
    older_than_s = check_nonnegative("older_than_s", older_than_s)
    now = time.time()
    removed = []
    for folder, _, names in os.walk(directory):
        for name in names:
            path = Path(folder) / name
            if not _is_temporary_name(name):
                continue
            try:
                info = path.lstat()
                if not stat.S_ISREG(info.st_mode):     # a link or a folder is not ours
                    continue
                age = now - info.st_mtime
                if age < older_than_s:
                    continue
                path.unlink()
            except FileNotFoundError:
                continue                      # its writer finished or removed it meanwhile
            logger.warning("removed %s: a temporary file left by an interrupted write "
                           "(%.0f s old)", path, age)
            removed.append(path)
    return removed


def check_writable(folder):
    """Raise the system's OSError, naming ``folder``, unless a file can be written in it.

    A small file is written (and synced) in ``folder`` and removed, so that a
    read-only file system, a missing permission or a full disk is met before
    any work whose results go there starts, not after it.  ``folder`` is made
    when it is missing.

    Returns
    -------
    Path

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as root:
    ...     print(check_writable(Path(root) / "out").name, sorted(Path(root, "out").iterdir()))
    out []
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".write-test.", dir=folder)
        try:
            os.write(fd, b"probe\n" * 64)
            os.fsync(fd)
        finally:
            os.close(fd)
            with contextlib.suppress(OSError):
                os.remove(probe)
    except OSError as exc:
        raise type(exc)(exc.errno, f"cannot write in {folder}: {exc.strerror or exc}",
                        str(folder)) from None
    return folder


class LockHeld(RuntimeError):
    """The lock of :func:`exclusive_lock` is held by another running process.

    Attributes
    ----------
    path : Path
        The lock file.
    holder : dict
        What the holder wrote in it: ``pid``, ``host``, ``since`` (UTC), ``what``
        (empty when it could not be read).
    """

    def __init__(self, path, holder):
        self.path, self.holder = Path(path), dict(holder)
        who = (f"process {holder['pid']} on {holder.get('host', '?')} since "
               f"{holder.get('since', '?')}" if "pid" in holder else "another process")
        super().__init__(f"{holder.get('what') or 'the work'} is already running: {who} "
                         f"holds {path}")


@contextlib.contextmanager
def exclusive_lock(path, what=""):
    """Hold the lock file ``path`` for the block: one process at a time runs it.

    The file holds the holder's pid, host, start time and ``what`` (for the
    message of a process that is refused).  The lock is the operating
    system's (``flock``), which ends with its process: a lock file left by a
    killed holder is taken over (logged, with the dead holder's pid).

    Parameters
    ----------
    path : str or Path
        The lock file (its folder is made when missing).
    what : str
        What the lock guards, for the messages (``"sweep demo"``).

    Raises
    ------
    LockHeld
        Another running process holds the lock (names it and the file).
    OSError
        The lock file cannot be written (naming it).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as root:
    ...     lock = Path(root) / "run.lock"
    ...     with exclusive_lock(lock, "demo"):
    ...         try:
    ...             with exclusive_lock(lock, "demo"):
    ...                 pass
    ...         except LockHeld as exc:
    ...             print(exc.holder["pid"] == os.getpid(), "holds" in str(exc))
    ...     print(lock.exists())                        # removed when the block ends
    True True
    False
    """
    import fcntl           # POSIX only: imported here so that the rest of the module works anywhere

    path = Path(path)
    fd = _locked_fd(fcntl, path)
    try:
        left = _holder(fd)
        if left.get("pid") not in (None, os.getpid()):
            logger.warning("took over %s: its holder, process %s on %s, is no longer running",
                           path, left.get("pid"), left.get("host", "?"))
        doc = {"pid": os.getpid(), "host": socket.gethostname(), "what": str(what),
               "since": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(doc) + "\n").encode("utf-8"), 0)
            os.fsync(fd)
        except OSError as exc:
            raise _naming(exc, path) from exc
        yield path
    finally:
        # removed while still locked: a process that opened it meanwhile sees another file
        # at the path once it gets the lock and starts again (_locked_fd)
        with contextlib.suppress(OSError):
            os.remove(path)
        os.close(fd)


def _locked_fd(fcntl, path):
    """A descriptor of ``path`` locked by this process; raise LockHeld if another holds it."""
    while True:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        except OSError as exc:
            raise _naming(exc, path) from exc
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise LockHeld(path, holder) from None
        try:
            if os.fstat(fd).st_ino == os.stat(path).st_ino:
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)          # the holder removed it between our open and our lock


def _holder(fd):
    """The JSON a lock file's holder wrote (empty when there is none)."""
    try:
        doc = json.loads(os.pread(fd, 4096, 0).decode("utf-8"))
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _is_temporary_name(name):
    """Whether ``name`` is one :func:`atomic_path` gives its temporary files."""
    match = _TEMPORARY.match(name)
    return bool(match) and Path(match["name"]).suffix == match["suffix"]


def _blocks(lines):
    return [hashlib.sha256(b"".join(lines[i:i + BLOCK_LINES])).hexdigest()
            for i in range(0, len(lines), BLOCK_LINES)]


def manifest_entry(path, rows, fs):
    """What :func:`verify_file` checks a file against.

    Parameters
    ----------
    path : str or Path
    rows : int
        Number of data rows.
    fs : float
        Sampling rate [Hz].

    Returns
    -------
    dict
        ``rows``, ``sample_rate_Hz``, ``lines`` (of the file), ``sha256`` and
        ``block_sha256`` (one per :data:`BLOCK_LINES` lines).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = atomic_write(Path(folder) / "r.csv", "t,v\\n0,1\\n1,2\\n3,4\\n")
    ...     entry = manifest_entry(path, rows=3, fs=1.0)
    >>> entry["rows"], entry["lines"], len(entry["sha256"]), len(entry["block_sha256"])
    (3, 4, 64, 1)
    """
    raw = Path(path).read_bytes()
    lines = raw.splitlines(keepends=True)
    return {"rows": check_integer("rows", rows, minimum=0),
            "sample_rate_Hz": check_positive("fs", fs), "lines": len(lines),
            "sha256": hashlib.sha256(raw).hexdigest(), "block_sha256": _blocks(lines)}


def verify_file(path, entry, rows=None, fs=None):
    """Check a file against its manifest entry.

    Parameters
    ----------
    path : str or Path
    entry : dict
        From :func:`manifest_entry`.
    rows : int, optional
        Data rows as read by a loader, compared with the entry's row count.
    fs : float, optional
        Sampling rate as read, compared with the entry's rate.

    Raises
    ------
    RecordError
        Naming the file and the line: where a truncated file ends, or the
        first line of the first block of lines that differ.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = atomic_write(Path(folder.name) / "r.csv", "t,v\\n0,1\\n1,2\\n")
    >>> entry = manifest_entry(path, rows=2, fs=1.0)
    >>> verify_file(path, entry, rows=2, fs=1.0) is None              # intact
    True
    >>> _ = atomic_write(path, "t,v\\n0,1\\n1,3\\n")                  # one value changed
    >>> verify_file(path, entry)
    Traceback (most recent call last):
    ...
    piezolib.records...RecordError: ...r.csv, line 1: content differs from the manifest (SHA-256) in lines 1-3
    >>> folder.cleanup()
    """
    path = Path(path)
    raw = path.read_bytes()
    lines = raw.splitlines(keepends=True)
    n_expected = entry["lines"]
    if len(lines) < n_expected or (len(lines) == n_expected and raw and
                                   not raw.endswith(b"\n") and
                                   hashlib.sha256(raw).hexdigest() != entry["sha256"]):
        ends = len(lines) + (0 if raw.endswith(b"\n") or not raw else -1)
        raise RecordError(f"truncated: the file ends after line {ends}, the manifest "
                          f"expects {n_expected} lines ({entry['rows']} data rows)",
                          path, ends + 1)
    if len(lines) > n_expected:
        raise RecordError(f"{len(lines)} lines, the manifest expects {n_expected}",
                          path, n_expected + 1)
    if rows is not None and rows != entry["rows"]:
        raise RecordError(f"{rows} data rows, the manifest expects {entry['rows']}", path)
    if fs is not None and abs(fs - entry["sample_rate_Hz"]) > 1e-9 * entry["sample_rate_Hz"]:
        raise RecordError(f"sampling rate {fs:g} Hz, the manifest expects "
                          f"{entry['sample_rate_Hz']:g} Hz", path)
    if hashlib.sha256(raw).hexdigest() != entry["sha256"]:
        for b, (got, want) in enumerate(zip(_blocks(lines), entry["block_sha256"])):
            if got != want:
                first = b * BLOCK_LINES + 1
                raise RecordError(f"content differs from the manifest (SHA-256) in lines "
                                  f"{first}-{min(first + BLOCK_LINES - 1, len(lines))}",
                                  path, first)
        raise RecordError("content differs from the manifest (SHA-256)", path)


#: Key of a JSON document's SHA-256 (:func:`seal`).
CONTENT_KEY = "content_sha256"


def content_sha256(doc):
    """SHA-256 (hex) of a JSON document's canonical form, its :data:`CONTENT_KEY` left out.

    The canonical form (sorted keys, no spaces, floats as ``repr``) does not
    depend on how the file was indented, so a writer may format as it likes.

    Examples
    --------
    >>> a = content_sha256({"format": 1, "gain": 0.5})
    >>> a == content_sha256({"gain": 0.5, "format": 1}), len(a)     # key order does not matter
    (True, 64)
    >>> a == content_sha256({"format": 1, "gain": 0.5, CONTENT_KEY: "old"})  # key left out
    True
    """
    body = {key: value for key, value in doc.items() if key != CONTENT_KEY}
    canonical = json.dumps(body, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def seal(doc):
    """``doc`` with its :func:`content_sha256` under :data:`CONTENT_KEY`, after its first key.

    After the first key (a format version, which a reader checks first) rather
    than last, so that adding the checksum to an existing file adds one line
    and changes no other.

    Returns
    -------
    dict
        A new dict; ``doc`` is not changed.

    Examples
    --------
    >>> doc = seal({"format": 2, "fs": 10e3})
    >>> list(doc)
    ['format', 'content_sha256', 'fs']
    >>> doc[CONTENT_KEY] == content_sha256({"format": 2, "fs": 10e3})
    True
    """
    items = [(key, value) for key, value in doc.items() if key != CONTENT_KEY]
    return dict(items[:1] + [(CONTENT_KEY, content_sha256(doc))] + items[1:])


def seal_problem(doc):
    """Why ``doc`` (read from a file of :func:`seal`) fails its checksum, or None.

    Returns
    -------
    str or None
        ``"it has no content checksum ..."``, ``"content differs from its
        checksum: ..."``, or None for an intact document.

    Examples
    --------
    >>> doc = seal({"format": 1, "gain": 0.1})
    >>> list(doc) == ["format", CONTENT_KEY, "gain"], seal_problem(doc)
    (True, None)
    >>> seal_problem({**doc, "gain": 0.2})
    'content differs from its checksum: the file was edited or corrupted'
    """
    stored = doc.get(CONTENT_KEY)
    if stored is None:
        return f"it has no content checksum ({CONTENT_KEY})"
    if stored != content_sha256(doc):
        return "content differs from its checksum: the file was edited or corrupted"
    return None
