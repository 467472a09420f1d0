"""Figures of merit of the paper's experiments (Sec. V).

:func:`hysteresis_percent` implements eq. 25-26: the width of a hysteresis
loop at the midpoint of the input range, relative to the output range.

:func:`tracking_error_percent` is the tracking error % of Table 5 (the
largest |x_r - x| relative to the commanded range; its docstring says why
this reading) and :func:`improvement_percent` the improvement rows of
Tables 4-5.
"""

from dataclasses import dataclass

import numpy as np

from piezolib._checks import check_finite_array, check_same_length, check_positive

__all__ = ["HysteresisMeasure", "hysteresis_measure", "hysteresis_percent", "tracking_error",
           "tracking_error_percent", "peak_to_peak_error_percent", "improvement_percent"]


@dataclass(frozen=True)
class HysteresisMeasure:
    """The quantities of eq. 25-26 measured on one record.

    Attributes
    ----------
    percent : float
        Hysteresis % = |x_up - x_lo| / (x_max - x_min) * 100.
    v_mid : float
        Midpoint input V_M = (V_MAX - V_MIN)/2 + V_MIN (eq. 25), input unit.
    x_up, x_lo : float
        Output at V_M on the ascending-input and descending-input branches,
        averaged over all strokes of the record (output unit).
    x_max, x_min : float
        Output at V_MAX and V_MIN, averaged over the turning points.
    n_up, n_down : int
        Number of ascending and descending strokes that were used.
    """

    percent: float
    v_mid: float
    x_up: float
    x_lo: float
    x_max: float
    x_min: float
    n_up: int
    n_down: int


def hysteresis_measure(v, x, band=0.02):
    """Measure the hysteresis of eq. 25-26 on an input/output record.

    The record is split into monotone strokes of the input at its turning
    points (a reversal counts once the input has moved back by half its
    range, so noise on ``v`` does not create strokes).  On every stroke that
    crosses the midpoint V_M, the output at V_M is the value at V_M of a
    straight line fitted to the samples whose input lies within
    ``band * (V_MAX - V_MIN)`` of V_M; this averages out output noise (when
    fewer than two samples lie there, the line through the two samples on
    either side of V_M is used).  The
    branch values are averaged over strokes of the same direction, so
    several periods may be given.  X_MAX and X_MIN are the mean outputs of
    the samples within a tenth of that band of V_MAX and V_MIN.

    Parameters
    ----------
    v : array_like
        Input (e.g. actuator voltage [V] or reference [V]), 1-D.
    x : array_like
        Output (e.g. displacement [um]), same length as ``v``.
    band : float, optional
        Half-width of the fitting windows as a fraction of the input range.

    Returns
    -------
    HysteresisMeasure

    Raises
    ------
    ValueError
        For NaN, unequal lengths, a constant input, or a record without at
        least one full ascending and one full descending stroke.
    """
    v = check_finite_array("v", v, ndim=1, min_length=8)
    x = check_finite_array("x", x, ndim=1, min_length=8)
    check_same_length(v=v, x=x)
    band = check_positive("band", band)
    if band >= 0.25:
        raise ValueError(f"band must be below 0.25 (a fraction of the range), got {band}")
    v_min, v_max = float(v.min()), float(v.max())
    span = v_max - v_min
    if span <= 1e-12 * max(1.0, abs(v_max)):
        raise ValueError("v is constant: a hysteresis loop needs a varying input")
    v_mid = v_min + (v_max - v_min) / 2          # eq. 25
    half_width = band * span

    up, down = [], []
    for lo, hi, direction in _strokes(v, span / 2):
        seg_v, seg_x = v[lo:hi + 1], x[lo:hi + 1]
        if not (seg_v.min() <= v_mid - half_width and seg_v.max() >= v_mid + half_width):
            continue                               # stroke does not cross V_M fully
        near = np.abs(seg_v - v_mid) <= half_width
        if np.count_nonzero(near) < 2:
            # the input jumps across the window: use the two samples around V_M
            k = int(np.argmax(direction * (seg_v - v_mid) >= 0))
            near = np.zeros(seg_v.size, dtype=bool)
            near[max(k - 1, 0):k + 1] = True
        value = _line_value_at(seg_v[near], seg_x[near], v_mid)
        (up if direction > 0 else down).append(value)
    if not up or not down:
        raise ValueError("the record has no full cycle: need at least one ascending "
                         f"and one descending stroke through V_M={v_mid:.6g} "
                         f"(found {len(up)} ascending, {len(down)} descending)")
    x_up, x_lo = float(np.mean(up)), float(np.mean(down))
    # a narrower window at the turning points, where x bends with time
    x_max = float(np.mean(x[v >= v_max - half_width / 10]))
    x_min = float(np.mean(x[v <= v_min + half_width / 10]))
    if x_max == x_min:
        raise ValueError("x does not change between V_MIN and V_MAX")
    percent = abs((x_up - x_lo) / (x_max - x_min)) * 100     # eq. 26
    return HysteresisMeasure(percent, v_mid, x_up, x_lo, x_max, x_min, len(up), len(down))


def hysteresis_percent(v, x, band=0.02):
    """Hysteresis % of eq. 25-26; see :func:`hysteresis_measure`."""
    return hysteresis_measure(v, x, band=band).percent


def _strokes(v, reversal):
    """Monotone strokes (start, end, direction) between turning points of v."""
    turning = [0]
    direction = 0
    extreme_i = 0
    for i in range(1, len(v)):
        if direction >= 0 and v[i] > v[extreme_i] or direction <= 0 and v[i] < v[extreme_i]:
            if direction == 0:
                direction = 1 if v[i] > v[turning[-1]] else -1
            extreme_i = i
        elif abs(v[i] - v[extreme_i]) >= reversal:
            if direction == 0:
                direction = 1 if v[extreme_i] > v[turning[-1]] else -1
            turning.append(extreme_i)
            direction = -direction
            extreme_i = i
    if turning[-1] != len(v) - 1:
        turning.append(len(v) - 1)
    out = []
    for a, b in zip(turning[:-1], turning[1:]):
        if b > a:
            out.append((a, b, 1 if v[b] > v[a] else -1))
    return out


def _line_value_at(vs, xs, v0):
    """Value at v0 of the least-squares line through (vs, xs)."""
    if len(vs) == 1 or np.ptp(vs) == 0:
        return float(np.mean(xs))
    slope, intercept = np.polyfit(vs - v0, xs, 1)
    return float(intercept)


# --- tracking error (Table 5) and improvement rows (Tables 4-5) ----------------
def tracking_error(x_r, x):
    """Tracking error e = x_r - x, same unit as the inputs (e.g. um).

    Parameters
    ----------
    x_r : array_like
        Desired displacement, 1-D.
    x : array_like
        Displacement reached (e.g. measured, 3 um/V * v_y), same length.

    Returns
    -------
    ndarray
    """
    x_r = check_finite_array("x_r", x_r, ndim=1, min_length=2)
    x = check_finite_array("x", x, ndim=1, min_length=2)
    check_same_length(x_r=x_r, x=x)
    return x_r - x


def _range_of(x_r, range_):
    if range_ is None:
        range_ = float(np.ptp(x_r))
        if range_ <= 0:
            raise ValueError("x_r is constant: give range_ explicitly")
        return range_
    return check_positive("range_", range_)


def peak_to_peak_error_percent(x_r, x, range_=None):
    """Peak-to-peak tracking error in % of the range: (max e - min e) / R * 100.

    The literal reading of the paper's "peak-to-peak tracking error"; the
    workbook's Table 5 metric is :func:`tracking_error_percent` (see there
    why).

    Parameters
    ----------
    x_r, x : array_like
        Desired and reached displacement, 1-D, equal lengths (one unit).
    range_ : float, optional
        R, the range the error is related to (same unit); default the
        peak-to-peak of ``x_r`` (12 um for the paper's triangles when whole
        periods are given).

    Returns
    -------
    float
    """
    e = tracking_error(x_r, x)
    return float(np.ptp(e)) / _range_of(x_r, range_) * 100


def tracking_error_percent(x_r, x, range_=None):
    """Tracking error % of Table 5: the largest error relative to the range.

    Definition used by the workbook (fixed from Case I before any Case II or
    III result was computed, never retuned)::

        tracking error % = max_k |e[k]| / R * 100,   e = x_r - x

    over the samples given, which should be whole periods of the reference
    after the start-up (the experiments of :mod:`piezolib.workbook.loop` discard the
    first period); R is the commanded range (12 um in Table 5), and x is
    what the sensor measures (3 um/V * v_y) at the same sample as x_r, i.e.
    the error the loop itself sees.

    Why max |e| and not the literal "peak-to-peak" max e - min e that the
    paper's wording suggests (Sec. IV-B, Fig. 16): the paper's own Case I
    numbers exclude the literal reading.  In Case I (open loop) x_r is
    proportional to the actuator voltage, so at the midpoint voltage V_M both
    branches of the loop have the same x_r and e_up - e_lo = x_lo - x_up;
    hence max e - min e >= hysteresis % x (loop range / R).  Table 4 gives
    12.44 % for the 40 V loop (about the 12 um of Table 5), so a
    peak-to-peak error would be at least about 12 % at 1 and 10 Hz, where
    Table 5 prints 7.33 % and 9.47 %.  max |e| >= half the loop width
    (about 6.2 %) is consistent with them, and on the virtual stage's
    Case I it also lies nearer the published row (notebook 06 shows both).
    For an error that swings symmetrically about zero, as in closed loop,
    max |e| is half of max e - min e; :func:`peak_to_peak_error_percent`
    gives the other reading.

    Parameters
    ----------
    x_r, x : array_like
        Desired and reached displacement, 1-D, equal lengths (one unit).
    range_ : float, optional
        R (same unit); default the peak-to-peak of ``x_r``.

    Returns
    -------
    float
    """
    e = tracking_error(x_r, x)
    return float(np.max(np.abs(e))) / _range_of(x_r, range_) * 100


def improvement_percent(before, after):
    """Improvement rows of Tables 4-5: 100 (before - after) / before.

    E.g. Case II w.r.t. Case I is ``improvement_percent(case_I, case_II)``:
    Table 4 at 10 V, (6.19 - 0.45) / 6.19 * 100 = 92.73 %.

    Parameters
    ----------
    before, after : float or array_like
        Errors (or hysteresis %) of the reference case and of the improved
        case; ``before`` must be positive.

    Returns
    -------
    float or ndarray
        Positive when ``after`` is smaller.
    """
    b = check_finite_array("before", before)
    a = check_finite_array("after", after)
    if np.any(b <= 0):
        raise ValueError(f"before must be positive, got {before!r}")
    try:
        out = 100 * (b - a) / b
    except ValueError:
        raise ValueError(f"before and after must have matching shapes, got {b.shape} "
                         f"and {a.shape}") from None
    return float(out) if out.ndim == 0 else out
