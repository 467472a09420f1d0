"""A record made ready for fitting: the turning points of its input, the start-up of a raw
record (rest, a voltage step, the ringing after it, the virgin stroke), cutting at turning
points, detrending, decimation behind an anti-alias filter, splitting for validation.
"""

import logging
from dataclasses import dataclass, replace

import numpy as np
import scipy.signal as sg

from piezolib._checks import check_finite_array, check_integer, check_positive
from piezolib.records.record import Record, RecordError

__all__ = ["turning_points", "cut_at_turning_points", "StartUp", "find_start_up", "detrend",
           "decimate", "split"]

# the package's logger: what cut_at_turning_points drops is logged as piezolib.records
logger = logging.getLogger("piezolib.records")


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

    Examples
    --------
    >>> turning_points([0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 2.0, 3.0, 2.0])  # max, min, max
    array([2, 4, 7])
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


@dataclass(frozen=True)
class StartUp:
    """How a raw record starts: rest, a step, the ringing after it, the virgin stroke.

    Attributes
    ----------
    rest_end : int
        First sample at which the input leaves its initial value (1: it
        moves from the start, no rest).
    step : int or None
        The sample at which the input jumps by more than the turning-point
        threshold in one sample, right after the rest (None: no step).
    settled : int
        First sample after the output's ringing from the step died out
        (``rest_end`` without a step).
    first_turning_point : int
        The first turning point of the input at or after ``settled`` whose
        stroke began after the step: where a hysteresis record free of the
        start-up begins.  Everything before it (rest, step, ringing and the
        stroke from the step's level, the virgin stroke) is start-up.
    note : str
        One line saying what the start-up holds, in samples and seconds.

    Examples
    --------
    >>> u = np.concatenate([np.zeros(50), np.cos(2 * np.pi * np.arange(300) / 100)])
    >>> s = find_start_up(Record(u, u, fs=100.0))   # rest, a step to 1, then cosine strokes
    >>> s.rest_end, s.step, s.first_turning_point
    (50, 50, 100)
    """

    rest_end: int
    step: object
    settled: int
    first_turning_point: int
    note: str


def _ringing_end(y, step, stop):
    """Last sample in ``step .. stop`` whose second difference of ``y`` stands out of noise.

    The noise level of the second difference is its median absolute deviation
    over the whole record (robust: ringing is a small share of the samples);
    a sample "stands out" at more than 5 of those standard deviations.
    """
    d2 = np.diff(y, 2)
    sigma = 1.4826 * float(np.median(np.abs(d2 - np.median(d2))))
    window = np.abs(d2[step:max(stop - 1, step + 1)])
    loud = np.flatnonzero(window > 5.0 * sigma)
    return step + int(loud[-1]) + 2 if loud.size else step


def find_start_up(record, threshold=0.02):
    """Find the start-up of a raw record: rest, step, ringing and virgin stroke.

    A raw record of a stage often starts at rest, jumps to the first value
    of the excitation (a voltage step, which rings the stage's resonances)
    and only then follows the periodic excitation.  None of that is a
    hysteresis loop: a rate-independent model cannot follow the ringing, and
    the first stroke starts from a state no model start assumes.

    Parameters
    ----------
    record : Record
    threshold : float, optional
        Fraction of the input's range: a one-sample change larger than this is
        a step, and turning points reverse by more (:func:`turning_points`).

    Returns
    -------
    StartUp
        The ringing ends at the last sample after the step, before the next
        turning point, whose output second difference exceeds 5 standard
        deviations of its noise (median absolute deviation over the record).

    Raises
    ------
    RecordError
        No turning point after the start-up (the record holds no stroke
        that a hysteresis fit could start from).

    Examples
    --------
    A record at rest for 0.5 s that steps to the crest of a cosine: the step
    and the first stroke down from it are start-up.

    >>> u = np.concatenate([np.zeros(50), np.cos(2 * np.pi * np.arange(300) / 100)])
    >>> s = find_start_up(Record(u, 2 * u, fs=100.0))
    >>> s.step, s.first_turning_point
    (50, 100)
    >>> s.note
    'start-up of 100 samples (1 s): rest 50 samples (0.5 s); a step of +1 V at sample 50 ...'
    """
    _check_record(record)
    threshold = check_positive("threshold", threshold)
    if threshold >= 1:
        raise ValueError(f"threshold must be below 1, got {threshold}")
    u, y, fs = record.input, record.output, record.fs
    span = float(np.ptp(u))
    if span == 0:
        raise RecordError("the input is constant: no start-up and no stroke to find")
    moved = np.flatnonzero(np.abs(u - u[0]) > 1e-3 * span)
    rest_end = int(moved[0]) if moved.size else 0
    points = turning_points(u, threshold)
    jump = rest_end > 0 and abs(u[rest_end] - u[rest_end - 1]) > threshold * span
    step = rest_end if jump else None
    if step is not None:
        # the ringing is searched up to the end of the first stroke leaving the step's
        # level (the step's own plateau can be the first turning point)
        off_level = np.flatnonzero(u[step:] != u[step])
        moving = step + int(off_level[0]) if off_level.size else len(u)
        later = points[points >= moving]
        settled = _ringing_end(y, step, int(later[0]) if later.size else len(u))
    else:
        settled = rest_end
    # the first stroke that began after the step: a plateau at the step's level is start-up
    first_move = rest_end if step is None else moving
    candidates = points[(points >= first_move) & (points >= settled)]
    if len(candidates) == 0:
        raise RecordError(f"no turning point of the input after the start-up (rest to sample "
                          f"{rest_end}, settled at {settled}): nothing left to fit")
    first = int(candidates[0])
    parts = [f"rest {rest_end} samples ({rest_end / fs:.3g} s)" if rest_end > 1 else "no rest"]
    if step is not None:
        parts.append(f"a step of {u[step] - u[step - 1]:+.4g} {record.input_unit} at sample "
                     f"{step} ({step / fs:.3g} s), ringing until sample {settled} "
                     f"({(settled - step) / fs * 1e3:.3g} ms)")
    parts.append(f"the virgin stroke up to the first turning point after it, sample {first} "
                 f"({first / fs:.3g} s)")
    return StartUp(rest_end, step, settled, first,
                   f"start-up of {first} samples ({first / fs:.3g} s): " + "; ".join(parts))


def cut_at_turning_points(record, threshold=0.02, first=0, last=-1, skip_transient=False):
    """The record from one turning point of its input to another (whole strokes).

    Cutting at turning points keeps whole strokes.  Whether the start-up (rest, a
    voltage step, the ringing after it, the virgin stroke) goes too depends on
    the record: when the step lands on an extreme of the input, the step
    sample is itself the first turning point and the default cut keeps the
    step and its ringing.  ``skip_transient=True`` drops the start-up
    (:func:`find_start_up`) and says so.

    Parameters
    ----------
    record : Record
    threshold : float, optional
        See :func:`turning_points`.
    first, last : int, optional
        Which turning points to cut at (Python indices into the list of
        turning points, those after the start-up with ``skip_transient``;
        default the first and the last).
    skip_transient : bool, optional
        Count only turning points after the start-up: the rest, the step,
        its ringing and the virgin stroke are dropped, the fact logged
        (logger ``piezolib.records``, level INFO) and written to
        ``metadata["dropped"]`` (one line) and ``metadata["start_up"]``
        (the :class:`StartUp`), and where the cut landed is logged too
        (``metadata["cut_note"]``).  Default False: every turning point
        counts.

    Returns
    -------
    Record
        Samples from turning point ``first`` to turning point ``last``,
        inclusive; ``metadata["cut"]`` holds the sample indices,
        ``metadata["starts_at"]`` whether the first sample is an input
        "maximum" or "minimum" (the state a hysteresis fit must start from:
        "maximum", or "rest" after a descending stroke) and
        ``metadata["cut_note"]`` says so in one line, with the samples and
        the reason.

    Raises
    ------
    RecordError
        Fewer than two turning points (after the start-up with ``skip_transient``).

    Examples
    --------
    >>> from piezolib.signals import triangle
    >>> t, v = triangle(1.0, 1.0, fs=100.0, periods=3)       # 0 -> 1 -> 0, three times
    >>> cut = cut_at_turning_points(Record(v, 2 * v, fs=100.0))
    >>> cut, cut.metadata["cut"]                             # peak 1 to peak 3
    (Record(201 samples at 100 Hz, u [V] -> y [V]), (50, 251))
    >>> cut.metadata["cut_note"]
    'cut at samples 50 to 250 (0.5 s to 2.5 s): from turning point 0 of the input, a maximum of 1 V (a fit starts from the state after an ascending stroke), to turning point 4, a maximum of 1 V'
    """
    _check_record(record)
    if not isinstance(skip_transient, (bool, np.bool_)):
        raise TypeError(f"skip_transient must be True or False, got {skip_transient!r}")
    points = turning_points(record.input, threshold)
    meta = {}
    if skip_transient:
        start_up = find_start_up(record, threshold)
        points = points[points >= start_up.first_turning_point]
        meta = {"start_up": start_up, "dropped": start_up.note}
    if len(points) < 2:
        after = " after the start-up" if skip_transient else ""
        raise RecordError(f"the input has {len(points)} turning point(s){after} reversing by "
                          f"more than {threshold:g} of its range; need 2 to cut whole strokes")
    a, b = int(points[first]), int(points[last])
    if b <= a:
        raise ValueError(f"turning point last={last} is not after first={first}")
    u, fs = record.input, record.fs
    i, j = first % len(points), last % len(points)
    starts_at = _extreme(u, a, points[i + 1])
    after = " after the start-up" if skip_transient else ""
    note = (f"cut at samples {a} to {b} ({a / fs:.4g} s to {b / fs:.4g} s): from turning point "
            f"{i}{after} of the input, a {starts_at} of {u[a]:.4g} {record.input_unit} (a fit "
            f"starts from the state after "
            f"{'an ascending' if starts_at == 'maximum' else 'a descending'} stroke), to "
            f"turning point {j}, a {_extreme(u, b, points[j - 1])} of {u[b]:.4g} "
            f"{record.input_unit}")
    if skip_transient:
        logger.info("cut_at_turning_points dropped the %s", meta["dropped"])
        logger.info("cut_at_turning_points %s", note)
    cut = record.segment(a, b + 1)
    return replace(cut, metadata={**record.metadata, **meta, "cut": (a, b + 1),
                                  "starts_at": starts_at, "cut_note": note})


def _extreme(u, k, neighbour):
    """"maximum" or "minimum": the turning point at sample ``k`` against the neighbouring one
    (turning points alternate between the two)."""
    return "maximum" if u[k] > u[neighbour] else "minimum"


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

    Examples
    --------
    >>> rec = Record(np.array([1.0, 2.0, 3.0, 4.0]), np.array([5.0, 6.0, 7.0, 8.0]), fs=1.0)
    >>> detrend(rec).output                           # mean removed from the output
    array([-1.5, -0.5,  0.5,  1.5])
    >>> detrend(rec, kind="linear").output.round(12) + 0.0
    array([0., 0., 0., 0.])
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

    Both signals pass the same zero-phase FIR low-pass (the filter of
    ``scipy.signal.decimate``: 20 x factor + 1 taps, Hamming window, cut-off
    at the new Nyquist frequency) before every ``factor``-th sample is kept,
    so the input-output relation below the new Nyquist frequency is
    unchanged and noise above it is not folded back.  The filter sees the
    record extended by its point reflection about the first and the last
    sample, so the ends keep their values (no zero padding pulling them in).

    Parameters
    ----------
    record : Record
    factor : int
        >= 1; 1 returns the record unchanged.

    Returns
    -------
    Record
        At ``fs / factor``.

    Examples
    --------
    >>> t = np.arange(1000) / 1e3
    >>> slow = np.sin(2 * np.pi * 5 * t)
    >>> rec = Record(slow, slow + 0.1 * np.sin(2 * np.pi * 400 * t), fs=1e3)  # 400 Hz noise
    >>> d = decimate(rec, 10)
    >>> d
    Record(100 samples at 100 Hz, u [V] -> y [V])
    >>> bool(np.abs(d.output - slow[::10])[10:-10].max() < 0.01)     # the noise is filtered out
    True
    """
    _check_record(record)
    factor = check_integer("factor", factor, minimum=1)
    if factor == 1:
        return record
    if len(record) < 20 * factor:
        raise RecordError(f"record of {len(record)} samples too short to decimate by "
                          f"{factor} (need {20 * factor})")
    return record.with_signals(_low_pass_and_keep(record.input, factor),
                               _low_pass_and_keep(record.output, factor), fs=record.fs / factor)


def _low_pass_and_keep(x, factor):
    """Every ``factor``-th sample of ``x`` after scipy.signal.decimate's zero-phase FIR.

    scipy pads with zeros, so the filter pulls the first and last 10 x factor
    samples towards 0 (a +-150 V sine came out +-162.7 V with its first sample
    at -90 V); here the record is extended by its point reflection about each
    end sample (value and slope continue), which the low-pass passes unchanged.
    """
    taps = sg.firwin(20 * factor + 1, 1.0 / factor, window="hamming")
    pad = factor * -(-taps.size // factor)           # whole output samples of padding
    padded = np.pad(x, pad, mode="reflect", reflect_type="odd")
    kept = sg.resample_poly(padded, 1, factor, window=taps)
    return kept[pad // factor:pad // factor + -(-x.size // factor)]


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

    Examples
    --------
    >>> rec = Record(np.arange(10.0), np.arange(10.0), fs=10.0)
    >>> first, second = split(rec, 0.7)
    >>> len(first), len(second), second.t0
    (7, 3, 0.7)
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
