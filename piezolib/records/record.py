"""The record type: one sampled experiment of a single-input single-output device (input and
output at a constant rate, their units and names, metadata), and the error every record
tool raises (:class:`RecordError`, naming the file and the line).
"""

import math
from dataclasses import dataclass, field, replace

import numpy as np

from piezolib._checks import check_finite_array, check_positive

__all__ = ["Record", "RecordError", "RATE_TOLERANCE"]

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

    Examples
    --------
    >>> err = RecordError("text in a number column", "run1.csv", 12)
    >>> str(err), err.line
    ('run1.csv, line 12: text in a number column', 12)
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

    Examples
    --------
    >>> rec = Record(np.array([0.0, 1.0, 2.0, 1.0]), np.array([0.0, 3.1, 6.0, 2.9]), fs=100.0,
    ...              input_unit="V", output_unit="um")
    >>> rec, rec.duration
    (Record(4 samples at 100 Hz, u [V] -> y [um]), 0.04)
    >>> Record.from_time([0.5, 0.51, 0.52], [1, 2, 3], [2, 4, 6]).t0    # rate from the times
    0.5
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
    # deviations from the median step, in place: no more copies of a long record
    steps -= dt
    np.abs(steps, out=steps)
    uneven = np.flatnonzero(steps > tol * dt)
    if uneven.size:
        i = int(uneven[0]) + 1
        raise error(i, f"uneven sampling: step {t[i] - t[i - 1]:.6g} s differs from the "
                       f"median {dt:.6g} s by more than {tol:g} of it")
    # the rate from the whole span is more accurate than from one step
    return (len(t) - 1) / (t[-1] - t[0]), float(t[0])
