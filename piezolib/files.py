"""File integrity: atomic writes and manifests of row count, rate and checksums.

:func:`atomic_write` and :func:`atomic_path` write a file through a
temporary file in the same folder and :func:`os.replace`, so a reader never
sees a partial file; :func:`manifest_entry` and :func:`verify_file` check a
file against a stored row count, sampling rate and SHA-256 (with block
checksums that locate a change to a range of lines).  A file that fails its
check raises the :class:`~piezolib.records.RecordError` of a record file,
which names the file and the line.

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
piezolib.records.RecordError: ...loop.csv, line 3: truncated: the file ends after line 2, ...
>>> folder.cleanup()
"""

import contextlib
import hashlib
import os
import tempfile
from pathlib import Path

from piezolib._checks import check_integer, check_positive
from piezolib.records import RecordError

__all__ = ["atomic_write", "atomic_path", "manifest_entry", "verify_file", "BLOCK_LINES"]

#: Lines per block checksum in a manifest entry.
BLOCK_LINES = 1000


@contextlib.contextmanager
def atomic_path(path):
    """Context manager yielding a temporary path next to ``path``; on success
    the temporary file replaces ``path`` in one step (``os.replace``), on an
    exception it is removed and ``path`` is left as it was.

    The temporary name keeps the suffix of ``path`` so that writers choosing a
    format by suffix (matplotlib) still work.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=f".tmp{path.suffix}",
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        # mkstemp makes the file private (0600); give it the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.remove(tmp)
        raise


def atomic_write(path, data):
    """Write text (UTF-8, ``\\n`` line ends) or bytes to ``path`` atomically.

    Returns
    -------
    Path
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
