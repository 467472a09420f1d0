"""Reference and excitation signals sampled at the DAQ rate.

All generators return ``(t, y)`` with ``t`` in seconds starting at 0 and
sampled at ``fs`` [Hz] (default: the paper's 10 kHz).
"""

import numpy as np

from . import paper
from ._checks import check_positive, check_integer

__all__ = ["time_vector", "triangle"]


def time_vector(duration_s, fs=paper.SAMPLING_FREQUENCY_HZ):
    """Sample times 0, 1/fs, ... covering ``duration_s`` seconds (end excluded)."""
    duration_s = check_positive("duration_s", duration_s)
    fs = check_positive("fs", fs)
    n = int(round(duration_s * fs))
    if n < 2:
        raise ValueError(f"duration_s={duration_s} at fs={fs} Hz gives fewer than 2 samples")
    return np.arange(n) / fs


def triangle(peak, frequency_hz, periods=1, fs=paper.SAMPLING_FREQUENCY_HZ, minimum=0.0):
    """Symmetric triangle wave rising from ``minimum`` to ``peak`` and back.

    The wave starts at ``minimum`` at t = 0, reaches ``peak`` at half a
    period and returns to ``minimum`` at the end of each period, as in the
    paper's hysteresis (Table 4) and tracking (Table 5) experiments.  One
    extra sample closes the last period.

    Parameters
    ----------
    peak : float
        Maximum value (any unit: V or um).
    frequency_hz : float
        Triangle frequency [Hz].
    periods : int, optional
        Number of full periods.
    fs : float, optional
        Sampling frequency [Hz].
    minimum : float, optional
        Minimum value; must be below ``peak``.

    Returns
    -------
    t : ndarray
        Time [s].
    y : ndarray
        The triangle, same unit as ``peak``.
    """
    frequency_hz = check_positive("frequency_hz", frequency_hz)
    fs = check_positive("fs", fs)
    periods = check_integer("periods", periods, minimum=1)
    if not np.isfinite(peak) or not np.isfinite(minimum) or peak <= minimum:
        raise ValueError(f"peak ({peak}) must be finite and exceed minimum ({minimum})")
    if fs < 4 * frequency_hz:
        raise ValueError(f"fs ({fs} Hz) must be at least 4 x frequency_hz ({frequency_hz} Hz)")
    n = int(round(periods * fs / frequency_hz)) + 1
    t = np.arange(n) / fs
    phase = (t * frequency_hz) % 1.0
    phase[-1] = 1.0 if phase[-1] < 0.5 else phase[-1]  # exact closure at the end
    shape = 1.0 - np.abs(2.0 * phase - 1.0)            # 0 -> 1 -> 0 per period
    return t, minimum + (peak - minimum) * shape
