"""Reference and excitation signals sampled at the DAQ rate.

All generators take the sampling frequency ``fs`` [Hz] and return
``(t, y)`` with ``t`` in seconds starting at 0.

Examples
--------
>>> t, v = triangle(4.0, 10.0, fs=10e3, periods=2)   # 0 -> 4 -> 0, twice
>>> len(t), float(v.max())
(2001, 4.0)
"""

import numpy as np
import scipy.signal as sg

from piezolib._checks import check_integer, check_positive

__all__ = ["time_vector", "triangle", "chirp"]


def time_vector(duration_s, fs):
    """Sample times 0, 1/fs, ... covering ``duration_s`` seconds (end excluded).

    Parameters
    ----------
    duration_s : float
        Length [s].
    fs : float
        Sampling frequency [Hz].

    Returns
    -------
    ndarray
        ``round(duration_s * fs)`` sample times [s].

    Raises
    ------
    ValueError
        For a non-positive argument or fewer than 2 samples.

    Examples
    --------
    >>> t = time_vector(0.01, fs=1e3)            # 10 ms at 1 kHz
    >>> len(t), float(t[1]), float(t[-1])
    (10, 0.001, 0.009)
    """
    duration_s = check_positive("duration_s", duration_s)
    fs = check_positive("fs", fs)
    n = int(round(duration_s * fs))
    if n < 2:
        raise ValueError(f"duration_s={duration_s} at fs={fs} Hz gives fewer than 2 samples")
    return np.arange(n) / fs


def triangle(peak, frequency_Hz, fs, periods=1, minimum=0.0):
    """Symmetric triangle wave rising from ``minimum`` to ``peak`` and back.

    The wave starts at ``minimum`` at t = 0, reaches ``peak`` at half a
    period and returns to ``minimum`` at the end of each period, as in the
    paper's hysteresis (Table 4) and tracking (Table 5) experiments.  One
    extra sample closes the last period.

    Parameters
    ----------
    peak : float
        Maximum value (any unit: V or um).
    frequency_Hz : float
        Triangle frequency [Hz].
    fs : float
        Sampling frequency [Hz], at least 4 x ``frequency_Hz``.
    periods : int, optional
        Number of full periods.
    minimum : float, optional
        Minimum value; must be below ``peak``.

    Returns
    -------
    t : ndarray
        Time [s].
    y : ndarray
        The triangle, same unit as ``peak``.

    Raises
    ------
    ValueError
        For ``peak <= minimum``, a non-positive frequency or too low ``fs``.

    Examples
    --------
    >>> t, y = triangle(2.0, 1.0, fs=8.0, minimum=-2.0)   # one period, 8 samples + closure
    >>> y
    array([-2., -1.,  0.,  1.,  2.,  1.,  0., -1., -2.])
    """
    frequency_Hz = check_positive("frequency_Hz", frequency_Hz)
    fs = check_positive("fs", fs)
    periods = check_integer("periods", periods, minimum=1)
    if not np.isfinite(peak) or not np.isfinite(minimum) or peak <= minimum:
        raise ValueError(f"peak ({peak}) must be finite and exceed minimum ({minimum})")
    if fs < 4 * frequency_Hz:
        raise ValueError(f"fs ({fs} Hz) must be at least 4 x frequency_Hz ({frequency_Hz} Hz)")
    n = int(round(periods * fs / frequency_Hz)) + 1
    t = np.arange(n) / fs
    phase = (t * frequency_Hz) % 1.0
    phase[-1] = 1.0 if phase[-1] < 0.5 else phase[-1]  # exact closure at the end
    shape = 1.0 - np.abs(2.0 * phase - 1.0)            # 0 -> 1 -> 0 per period
    return t, minimum + (peak - minimum) * shape


def chirp(amplitude, f0_Hz, f1_Hz, duration_s, fs, method="logarithmic"):
    """Cosine sweep ``amplitude * cos(phi(t))`` from ``f0_Hz`` to ``f1_Hz``.

    The sweep starts at its crest (phase 0 at t = 0), so ``amplitude - y``
    starts at zero with zero slope: a sweep added to a held level enters
    without a step.

    Parameters
    ----------
    amplitude : float
        Peak value (any unit), > 0.
    f0_Hz, f1_Hz : float
        Start and end frequencies [Hz], 0 < f0 < f1 < fs/2.
    duration_s : float
        Length [s]; the instantaneous frequency reaches ``f1_Hz`` at the end.
    fs : float
        Sampling frequency [Hz].
    method : {"logarithmic", "linear"}, optional
        Exponential sweep (equal time per octave) or linear sweep.

    Returns
    -------
    t : ndarray
        Time [s], ``round(duration_s * fs)`` samples from 0.
    y : ndarray
        The sweep, same unit as ``amplitude``.

    Raises
    ------
    ValueError
        Unless 0 < ``f0_Hz`` < ``f1_Hz`` < ``fs``/2, or for an unknown ``method``.

    Examples
    --------
    >>> t, y = chirp(1.0, 1.0, 100.0, duration_s=2.0, fs=1e3)   # 1 -> 100 Hz in 2 s
    >>> len(y), float(y[0]), bool(abs(y).max() <= 1.0)
    (2000, 1.0, True)
    """
    amplitude = check_positive("amplitude", amplitude)
    f0_Hz = check_positive("f0_Hz", f0_Hz)
    f1_Hz = check_positive("f1_Hz", f1_Hz)
    fs = check_positive("fs", fs)
    if not f0_Hz < f1_Hz < fs / 2:
        raise ValueError(f"need 0 < f0_Hz < f1_Hz < fs/2 = {fs / 2:g} Hz, "
                         f"got f0_Hz={f0_Hz:g}, f1_Hz={f1_Hz:g}")
    if method not in ("logarithmic", "linear"):
        raise ValueError(f"method must be 'logarithmic' or 'linear', got {method!r}")
    t = time_vector(duration_s, fs)
    return t, amplitude * sg.chirp(t, f0_Hz, duration_s, f1_Hz, method=method, phi=0.0)
