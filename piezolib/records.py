"""Measured experiments: a record type, a strict CSV loader and helpers.

A :class:`Record` is one sampled experiment of a single-input single-output
device: the input (e.g. an amplifier or actuator voltage) and the output
(e.g. a displacement) at a constant sampling rate, each with its unit, and a
metadata dict.  :func:`load_csv` reads one from a delimited text file of any
column layout and checks it line by line; every error is a
:class:`RecordError` naming the file and the line.  Helpers cut a record at
the turning points of its input (:func:`cut_at_turning_points`), remove an
offset or trend (:func:`detrend`), lower its rate behind an anti-alias filter
(:func:`decimate`) and split it for validation (:func:`split`).

Writing files atomically and checking them against a manifest is
:mod:`piezolib.files`.

Examples
--------
A file of two sine periods at 1 kHz, no header (time, volts, micrometres):

>>> import tempfile
>>> folder = tempfile.TemporaryDirectory()
>>> path = Path(folder.name) / "loop.csv"
>>> t = np.arange(500) / 1000.0
>>> v = 5.0 + 5.0 * np.sin(2 * np.pi * 4.0 * t)
>>> np.savetxt(path, np.column_stack([t, v, 1.5 * v]), delimiter=",")
>>> rec = load_csv(path, time=0, input=1, output=2, input_unit="V", output_unit="um")
>>> rec.fs, len(rec)
(1000.0, 500)
>>> train, test = split(cut_at_turning_points(rec), 0.5)  # whole strokes, then halves
>>> len(train), len(test)
(188, 188)
>>> folder.cleanup()
"""

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import scipy.signal as sg

from piezolib._checks import check_finite_array, check_integer, check_positive

__all__ = [
    "Record", "RecordError", "read_table", "load_csv", "turning_points",
    "cut_at_turning_points", "detrend", "decimate", "split", "MIN_SAMPLES", "RATE_TOLERANCE",
]

#: Fewest samples :func:`load_csv` accepts by default.
MIN_SAMPLES = 16
#: Default largest relative deviation of one time step from the median step.
RATE_TOLERANCE = 1e-3


class RecordError(ValueError):
    """A record file or array that cannot be used; names the file and the line.

    Attributes
    ----------
    path : str or None
        The file (None for in-memory data).
    line : int or None
        1-based line number in the file (None when the problem is not on one line).
    """

    def __init__(self, message, path=None, line=None):
        self.path, self.line = (None if path is None else str(path)), line
        where = "" if path is None else f"{path}" + ("" if line is None else f", line {line}")
        super().__init__(f"{where}: {message}" if where else message)


@dataclass(frozen=True, eq=False)
class Record:
    """One sampled experiment: input and output at a constant rate.

    Attributes
    ----------
    input, output : ndarray
        The signals in ``input_unit`` and ``output_unit`` (read-only, finite,
        equal length).
    fs : float
        Sampling rate [Hz]; sample k is at ``t0 + k / fs``.
    input_unit, output_unit : str
        Units, e.g. ``"V"`` and ``"um"``.
    input_name, output_name : str
        Signal names (used to label identified models).
    t0 : float
        Time of the first sample [s].
    metadata : dict
        Anything known about the experiment (source file, header lines, ...).
    """

    input: np.ndarray
    output: np.ndarray
    fs: float
    input_unit: str = "V"
    output_unit: str = "V"
    input_name: str = "u"
    output_name: str = "y"
    t0: float = 0.0
    metadata: dict = field(default_factory=dict)

    def __post_init__(self):
        u = check_finite_array("input", self.input, ndim=1, min_length=2)
        y = check_finite_array("output", self.output, ndim=1, min_length=2)
        if len(u) != len(y):
            raise RecordError(f"input and output must have equal lengths, got {len(u)} "
                              f"and {len(y)}")
        for arr in (u, y):
            arr.setflags(write=False)
        object.__setattr__(self, "input", u)
        object.__setattr__(self, "output", y)
        object.__setattr__(self, "fs", check_positive("fs", self.fs))
        t0 = float(self.t0)
        if not math.isfinite(t0):
            raise ValueError(f"t0 must be finite, got {self.t0!r}")
        object.__setattr__(self, "t0", t0)
        for name in ("input_unit", "output_unit", "input_name", "output_name"):
            if not isinstance(getattr(self, name), str):
                raise TypeError(f"{name} must be a string, got {getattr(self, name)!r}")
        object.__setattr__(self, "metadata", dict(self.metadata))

    @classmethod
    def from_time(cls, time, input, output, rate_tolerance=RATE_TOLERANCE, **kwargs):
        """A record from a time vector [s] that must be evenly spaced.

        Parameters
        ----------
        time : array_like
            Sample times [s], strictly increasing.
        input, output : array_like
        rate_tolerance : float, optional
            Largest relative deviation of a step from the median step.
        **kwargs
            Other :class:`Record` fields (units, names, metadata).

        Raises
        ------
        RecordError
            Non-increasing or uneven time, naming the sample index.
        """
        t = check_finite_array("time", time, ndim=1, min_length=2)
        fs, t0 = _rate_of(t, check_positive("rate_tolerance", rate_tolerance),
                          lambda i, msg: RecordError(f"time sample {i}: {msg}"))
        return cls(input, output, fs, t0=t0, **kwargs)

    def __len__(self):
        return len(self.input)

    @property
    def time(self):
        """Sample times t0 + k / fs [s]."""
        return self.t0 + np.arange(len(self)) / self.fs

    @property
    def duration(self):
        """len / fs [s]."""
        return len(self) / self.fs

    def segment(self, start=None, stop=None):
        """Samples ``start:stop`` (step 1) as a record with the right ``t0``."""
        first, last, step = slice(start, stop).indices(len(self))
        if last - first < 2:
            raise RecordError(f"segment {start}:{stop} of a {len(self)}-sample record keeps "
                              "fewer than 2 samples")
        return replace(self, input=self.input[first:last], output=self.output[first:last],
                       t0=self.t0 + first / self.fs)

    def with_signals(self, input=None, output=None, **changes):
        """A copy with new signals and/or fields (same rate unless ``fs`` is given)."""
        return replace(self, input=self.input if input is None else input,
                       output=self.output if output is None else output, **changes)

    def __repr__(self):
        return (f"Record({len(self)} samples at {self.fs:g} Hz, {self.input_name} "
                f"[{self.input_unit}] -> {self.output_name} [{self.output_unit}])")


def _rate_of(t, tol, error):
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise error(i, f"time {t[i]!r} is not after the previous {t[i - 1]!r} "
                       "(time must increase)")
    dt = float(np.median(steps))
    uneven = np.flatnonzero(np.abs(steps - dt) > tol * dt)
    if uneven.size:
        i = int(uneven[0]) + 1
        raise error(i, f"uneven sampling: step {steps[i - 1]:.6g} s differs from the "
                       f"median {dt:.6g} s by more than {tol:g} of it")
    # the rate from the whole span is more accurate than from one step
    return (len(t) - 1) / (t[-1] - t[0]), float(t[0])


# --- reading -----------------------------------------------------------------------------
def _column_index(spec, names, what, path, line):
    if isinstance(spec, str):
        if names is None:
            raise ValueError(f"{what}={spec!r} names a column but header=False; give a "
                             "0-based column number or set header=True")
        if spec not in names:
            raise RecordError(f"missing column {spec!r} ({what}); the header has {names}",
                              path, line)
        return names.index(spec)
    return check_integer(what, spec, minimum=0)


def read_table(path, columns, header=False, delimiter=",", comment="#"):
    """Read numeric columns of a delimited text file, checking every line.

    Parameters
    ----------
    path : str or Path
    columns : dict
        ``{key: column}`` with a 0-based column number or, with ``header``, a
        column name.
    header : bool, optional
        The first non-comment, non-blank line holds the column names.
    delimiter : str, optional
    comment : str, optional
        Lines starting with it are comments; ``key = value`` comments are
        returned in the metadata.

    Returns
    -------
    data : dict
        ``{key: ndarray}`` of floats.
    metadata : dict
        ``key = value`` comment lines (values parsed as int or float when
        possible).
    lines : ndarray of int
        1-based file line of every data row.

    Raises
    ------
    FileNotFoundError
        Missing file.
    RecordError
        Missing column, too few fields, text or NaN/inf in a number column;
        the message names the file, the line and the column.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such file") from None
    except UnicodeDecodeError as exc:
        raise RecordError(f"not a text file ({exc.reason})", path) from None
    metadata, rows, numbers, names, header_line = {}, [], [], None, None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if comment and stripped.startswith(comment):
            body = stripped[len(comment):].strip()
            if " = " in body:
                key, value = body.split(" = ", 1)
                metadata[key.strip()] = _parse_value(value.strip())
            continue
        if header and names is None:
            names, header_line = [c.strip() for c in stripped.split(delimiter)], number
            continue
        rows.append(stripped.split(delimiter))
        numbers.append(number)
    if header and names is None:
        raise RecordError("no header line and no data", path)
    index = {key: _column_index(spec, names, f"columns[{key!r}]", path, header_line)
             for key, spec in columns.items()}
    width = max(index.values()) + 1
    data = {}
    short = [k for k, r in enumerate(rows) if len(r) < width]
    if short:
        k = short[0]
        raise RecordError(f"{len(rows[k])} field(s), need at least {width} (column "
                          f"{width - 1} is used)", path, numbers[k])
    for key, col in index.items():
        cells = [r[col] for r in rows]
        shown = names[col] if names else col
        label = repr(shown) if str(shown) == str(key) else f"{shown!r} ({key})"
        try:
            values = np.array(cells, dtype=float)
        except ValueError:
            values = None
        if values is None:
            for k, cell in enumerate(cells):
                try:
                    float(cell)
                except ValueError:
                    raise RecordError(f"column {label}: {cell.strip()!r} is not a "
                                      "number", path, numbers[k]) from None
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            k = int(bad[0])
            raise RecordError(f"column {label}: {cells[k].strip()!r} is not a finite "
                              "number", path, numbers[k])
        data[key] = values
    return data, metadata, np.array(numbers, dtype=int)


def _parse_value(text):
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text


def load_csv(path, *, input, output, time=None, fs=None, header=False, delimiter=",",
             comment="#", input_unit="V", output_unit="V", input_scale=1.0, output_scale=1.0,
             time_scale=1.0, input_name="u", output_name="y",
             rate_tolerance=RATE_TOLERANCE, min_samples=MIN_SAMPLES, metadata=None):
    """Load a measured experiment from a delimited text file.

    Parameters
    ----------
    path : str or Path
    input, output : int or str
        Column of the input and of the output: 0-based number, or a name
        from the header line (``header=True``).
    time : int or str, optional
        Column of the sample times; the rate is then taken from it and the
        sampling is checked to be even within ``rate_tolerance``.
    fs : float, optional
        Sampling rate [Hz]; required without a time column.  With both, they
        must agree within ``rate_tolerance``.
    header : bool, optional
        The first non-comment line holds column names.
    delimiter, comment : str, optional
    input_unit, output_unit : str, optional
        Units of the signals after scaling.
    input_scale, output_scale, time_scale : float, optional
        Factors applied to the file's numbers (e.g. ``output_scale=1e6`` for
        metres to micrometres, ``time_scale=1e-3`` for milliseconds).
    input_name, output_name : str, optional
    rate_tolerance : float, optional
        Largest relative deviation of a time step from the median step.
    min_samples : int, optional
        Fewest data rows accepted.
    metadata : dict, optional
        Added to the record's metadata (after the file's ``key = value``
        comments and ``source``).

    Returns
    -------
    Record

    Raises
    ------
    FileNotFoundError
        Missing file.
    RecordError
        Missing column, text/NaN in a number column, non-increasing or uneven
        time, too few rows: the message names the file and the line.
    ValueError
        Contradictory arguments (no rate, names without a header).
    """
    if time is None and fs is None:
        raise ValueError("give the sampling rate fs [Hz] or a time column (time=...)")
    for name, value in (("input_scale", input_scale), ("output_scale", output_scale)):
        if not (isinstance(value, (int, float, np.number)) and math.isfinite(value)
                and value != 0):
            raise ValueError(f"{name} must be a finite non-zero number, got {value!r}")
    time_scale = check_positive("time_scale", time_scale)
    min_samples = check_integer("min_samples", min_samples, minimum=2)
    rate_tolerance = check_positive("rate_tolerance", rate_tolerance)
    columns = {"input": input, "output": output}
    if time is not None:
        columns["time"] = time
    data, meta, lines = read_table(path, columns, header, delimiter, comment)
    if len(lines) < min_samples:
        raise RecordError(f"too short: {len(lines)} data row(s), need at least {min_samples}",
                          path, int(lines[-1]) if len(lines) else None)
    t0 = 0.0
    if time is not None:
        t = data["time"] * time_scale
        rate, t0 = _rate_of(t, rate_tolerance,
                            lambda i, msg: RecordError(msg, path, int(lines[i])))
        if fs is not None:
            fs = check_positive("fs", fs)
            if abs(rate - fs) > rate_tolerance * fs:
                raise RecordError(f"the time column gives {rate:.6g} Hz, but fs={fs:g} Hz",
                                  path)
        fs = rate
    meta = {"source": str(path), **meta, **(metadata or {})}
    return Record(data["input"] * input_scale, data["output"] * output_scale, fs,
                  input_unit, output_unit, input_name, output_name, t0, meta)


# --- helpers -------------------------------------------------------------------------------
def _check_record(record):
    if not isinstance(record, Record):
        raise TypeError(f"record must be a piezolib.records.Record, got "
                        f"{type(record).__name__}")
    return record


def turning_points(x, threshold=0.02):
    """Indices of the extrema of a signal where it reverses by more than a threshold.

    A point is a turning point when the signal, after it, moves away from it
    by more than ``threshold`` x range(x) before passing it again, so noise
    and plateaus do not create turning points.

    Parameters
    ----------
    x : array_like
        Signal (normally the input of a loop experiment).
    threshold : float, optional
        Reversal needed, as a fraction of the signal's range (0 < threshold < 1).

    Returns
    -------
    ndarray of int
        Ascending indices (the last sample of a plateau at the extreme).
    """
    x = check_finite_array("x", x, ndim=1, min_length=2)
    threshold = check_positive("threshold", threshold)
    if threshold >= 1:
        raise ValueError(f"threshold must be below 1, got {threshold}")
    span = float(np.ptp(x))
    if span == 0:
        return np.array([], dtype=int)
    h = threshold * span
    points, direction, hi, lo = [], 0, 0, 0
    for k in range(1, len(x)):
        if direction == 0:                       # the start is never a turning point
            if x[k] - x[0] > h:
                direction, hi = 1, k
            elif x[0] - x[k] > h:
                direction, lo = -1, k
        elif direction > 0:
            if x[k] >= x[hi]:
                hi = k                           # >=: the last sample of a plateau
            elif x[hi] - x[k] > h:
                points.append(hi)
                direction, lo = -1, k
        else:
            if x[k] <= x[lo]:
                lo = k
            elif x[k] - x[lo] > h:
                points.append(lo)
                direction, hi = 1, k
    return np.array(points, dtype=int)


def cut_at_turning_points(record, threshold=0.02, first=0, last=-1):
    """The record from one turning point of its input to another (whole strokes).

    Starting a hysteresis fit at a turning point removes the start-up (rest,
    a voltage step, the virgin curve) from the data.

    Parameters
    ----------
    record : Record
    threshold : float, optional
        See :func:`turning_points`.
    first, last : int, optional
        Which turning points to cut at (Python indices into the list of
        turning points; default the first and the last).

    Returns
    -------
    Record
        Samples from turning point ``first`` to turning point ``last``,
        inclusive; ``metadata["cut"]`` holds the sample indices.

    Raises
    ------
    RecordError
        Fewer than two turning points.
    """
    _check_record(record)
    points = turning_points(record.input, threshold)
    if len(points) < 2:
        raise RecordError(f"the input has {len(points)} turning point(s) reversing by more "
                          f"than {threshold:g} of its range; need 2 to cut whole strokes")
    a, b = int(points[first]), int(points[last])
    if b <= a:
        raise ValueError(f"turning point last={last} is not after first={first}")
    cut = record.segment(a, b + 1)
    return replace(cut, metadata={**record.metadata, "cut": (a, b + 1)})


def detrend(record, which="output", kind="constant"):
    """Remove the mean or a straight line from signals of a record.

    Parameters
    ----------
    record : Record
    which : {"output", "input", "both"}, optional
    kind : {"constant", "linear"}, optional

    Returns
    -------
    Record
    """
    _check_record(record)
    if which not in ("output", "input", "both"):
        raise ValueError(f"which must be 'output', 'input' or 'both', got {which!r}")
    if kind not in ("constant", "linear"):
        raise ValueError(f"kind must be 'constant' or 'linear', got {kind!r}")
    u = sg.detrend(record.input, type=kind) if which in ("input", "both") else None
    y = sg.detrend(record.output, type=kind) if which in ("output", "both") else None
    return record.with_signals(u, y)


def decimate(record, factor):
    """Lower the sampling rate by an integer factor behind an anti-alias filter.

    Both signals pass the same zero-phase FIR low-pass
    (``scipy.signal.decimate``, cut-off 0.8 x the new Nyquist frequency)
    before every ``factor``-th sample is kept, so the input-output relation
    below the new Nyquist frequency is unchanged and noise above it is not
    folded back.

    Parameters
    ----------
    record : Record
    factor : int
        >= 1; 1 returns the record unchanged.

    Returns
    -------
    Record
        At ``fs / factor``.
    """
    _check_record(record)
    factor = check_integer("factor", factor, minimum=1)
    if factor == 1:
        return record
    if len(record) < 20 * factor:
        raise RecordError(f"record of {len(record)} samples too short to decimate by "
                          f"{factor} (need {20 * factor})")
    u = sg.decimate(record.input, factor, ftype="fir", zero_phase=True)
    y = sg.decimate(record.output, factor, ftype="fir", zero_phase=True)
    return record.with_signals(u, y, fs=record.fs / factor)


def split(record, fraction=0.5):
    """Split a record in two consecutive parts (estimation, validation).

    Parameters
    ----------
    record : Record
    fraction : float, optional
        Share of the samples in the first part, 0 < fraction < 1.

    Returns
    -------
    first, second : Record
    """
    _check_record(record)
    fraction = check_positive("fraction", fraction)
    if fraction >= 1:
        raise ValueError(f"fraction must be below 1, got {fraction}")
    k = int(round(fraction * len(record)))
    if k < 2 or len(record) - k < 2:
        raise RecordError(f"fraction {fraction} of {len(record)} samples leaves a part with "
                          "fewer than 2 samples")
    return record.segment(0, k), record.segment(k)
