"""The hysteresis measure of eq. 25-26: loop width at mid-input relative to the output range.

:func:`hysteresis_measure` returns every quantity of eq. 25-26 measured on
an input/output record of one or several periods; :func:`hysteresis_percent`
only the percentage.
"""

from dataclasses import dataclass

import numpy as np

from piezolib._checks import check_finite_array, check_positive, check_same_length

__all__ = ["HysteresisMeasure", "hysteresis_measure", "hysteresis_percent"]


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

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> h = hysteresis_measure(v, pi.simulate(v))
    >>> h.v_mid, round(h.x_up, 3), round(h.x_lo, 3), h.n_up, h.n_down
    (2.0, 2.65, 3.35, 2, 2)
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

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> h = hysteresis_measure(v, pi.simulate(v))
    >>> round(h.percent, 2)                # |x_up - x_lo| / (x_max - x_min) * 100
    12.92
    >>> round(abs(h.x_up - h.x_lo) / (h.x_max - h.x_min) * 100, 2)
    12.92
    """
    v = check_finite_array("v", v, ndim=1, min_length=8, real=True)
    x = check_finite_array("x", x, ndim=1, min_length=8, real=True)
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
    """Hysteresis % of eq. 25-26; see :func:`hysteresis_measure`.

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> from piezolib.signals import triangle
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> round(hysteresis_percent(v, pi.simulate(v)), 2)
    12.92
    >>> round(hysteresis_percent(v, 2.0 * v + 1.0), 2)       # a straight line: no loop
    0.0
    """
    return hysteresis_measure(v, x, band=band).percent


def _strokes(v, reversal):
    """Monotone strokes (start, end, direction) between turning points of v."""
    v = np.asarray(v, dtype=float).tolist()     # Python floats: the same comparisons, 5x faster
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
