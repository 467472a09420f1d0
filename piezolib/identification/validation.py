"""Validation of identified models (Step IV of Fig. 3): simulated fit, residual whiteness,
empirical frequency response, coefficient comparison."""

from dataclasses import dataclass

import numpy as np
import scipy.signal as sg
import scipy.stats as stats

from piezolib._checks import (check_finite_array, check_integer, check_model, check_positive,
                              check_same_length, check_siso)
from piezolib.identification.continuous import monic_coefficients
from piezolib.identification.arx import check_io

__all__ = ["fit_percent", "Whiteness", "whiteness", "empirical_frequency_response",
           "coefficient_table"]


# --- Step IV: validation -------------------------------------------------------------------
def fit_percent(y, y_hat):
    """Normalised fit 100 (1 - ||y - y_hat|| / ||y - mean(y)||) in %.

    Examples
    --------
    >>> y = np.sin(np.linspace(0, 6, 100))
    >>> fit_percent(y, y)
    100.0
    >>> round(fit_percent(y, 0.9 * y), 1)                    # 10 % amplitude error
    90.0
    """
    y = check_finite_array("y", y, ndim=1, min_length=2, real=True)
    y_hat = check_finite_array("y_hat", y_hat, ndim=1, min_length=2, real=True)
    check_same_length(y=y, y_hat=y_hat)
    spread = np.linalg.norm(y - y.mean())
    if spread == 0:
        raise ValueError("y is constant: the fit is undefined")
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / spread))


@dataclass(frozen=True)
class Whiteness:
    """Autocorrelation test of a residual sequence.

    Attributes
    ----------
    lags : ndarray
        1 ... max_lag.
    autocorrelation : ndarray
        Normalised autocorrelation R(i)/R(0) at ``lags``.
    bound : float
        95 % band for a white sequence, 1.96 / sqrt(N).
    n_outside : int
        Lags with |R(i)/R(0)| > bound (about 5 % expected for white noise).
    q_statistic, p_value : float
        Ljung-Box portmanteau statistic over all lags and its p-value.
    passed : bool
        p_value >= alpha: whiteness not rejected at level alpha.

    Examples
    --------
    >>> w = whiteness(np.random.default_rng(1).standard_normal(500), max_lag=20)
    >>> w.autocorrelation.shape, round(w.bound, 4), bool(0 < w.p_value < 1)
    ((20,), 0.0877, True)
    """

    lags: np.ndarray
    autocorrelation: np.ndarray
    bound: float
    n_outside: int
    q_statistic: float
    p_value: float
    passed: bool


def whiteness(residual, max_lag=20, alpha=0.05):
    """Test a residual for whiteness (Step IV of Fig. 3).

    The normalised autocorrelation at lags 1 ... ``max_lag`` is compared with
    the 95 % band +-1.96/sqrt(N); the decision is the Ljung-Box test
    Q = N (N + 2) sum R(i)^2 / (N - i) against chi-square(max_lag) at level
    ``alpha`` (the mean is removed first).

    Examples
    --------
    >>> w = whiteness(np.random.default_rng(1).standard_normal(500), max_lag=20)
    >>> w.passed, w.lags[[0, -1]]
    (True, array([ 1, 20]))
    >>> whiteness(np.sin(np.arange(500) / 5.0)).passed         # a correlated residual
    False
    """
    e = check_finite_array("residual", residual, ndim=1, real=True)
    max_lag = check_integer("max_lag", max_lag, minimum=1)
    alpha = check_positive("alpha", alpha)
    if not alpha < 1:
        raise ValueError(f"alpha must be a significance level in (0, 1), got {alpha!r}")
    n = len(e)
    if n < 5 * max_lag:
        raise ValueError(f"residual too short ({n} samples) for {max_lag} lags")
    e = e - e.mean()
    r0 = e @ e
    if r0 == 0:
        raise ValueError("residual is identically zero: nothing to test")
    lags = np.arange(1, max_lag + 1)
    r = np.array([e[i:] @ e[:-i] for i in lags]) / r0
    bound = 1.96 / np.sqrt(n)
    q = n * (n + 2) * np.sum(r ** 2 / (n - lags))
    p = float(stats.chi2.sf(q, max_lag))
    return Whiteness(lags, r, float(bound), int(np.sum(np.abs(r) > bound)), float(q), p,
                     p >= alpha)


def coefficient_table(identified, reference, names=("identified", "published")):
    """a0 ... a5, b0 ... b3 of two 6-pole / 3-zero models side by side.

    Parameters
    ----------
    identified, reference : control.LTI
        SISO continuous-time models with 6 poles and at most 3 zeros.
    names : pair of str, optional
        Column labels of the two models.

    Returns
    -------
    pandas.DataFrame
        Index a0 ... b3; columns ``names`` and the relative error
        (first - second) / second.
    """
    import pandas as pd
    if (isinstance(names, str) or not hasattr(names, "__len__") or len(names) != 2
            or not all(isinstance(n, str) for n in names)):
        raise TypeError(f"names must be a pair of str, got {names!r}")
    (a1, b1), (a2, b2) = (_six_three("identified", identified), _six_three("reference", reference))
    index = [f"a{i}" for i in range(len(a1))] + [f"b{i}" for i in range(len(b1))]
    first, second = np.concatenate((a1, b1)), np.concatenate((a2, b2))
    return pd.DataFrame({names[0]: first, names[1]: second,
                         "relative error": (first - second) / second},
                        index=pd.Index(index, name="coefficient"))


def _six_three(name, sys):
    """monic_coefficients of a 6-pole / 3-zero model, errors naming the argument."""
    check_model(name, sys)
    check_siso(name, sys)
    try:
        return monic_coefficients(sys)
    except ValueError as exc:
        raise ValueError(f"{name}: {exc}") from None


def empirical_frequency_response(u, y, fs, nperseg=2048):
    """Frequency response estimate y/u from data: Welch cross spectrum over
    input spectrum (H1 estimator).

    Returns
    -------
    omega : ndarray
        Frequencies [rad/s] (DC excluded).
    response : ndarray
        Complex response at ``omega``.

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.identification import zoh_simulate
    >>> u = np.random.default_rng(0).standard_normal(4096)
    >>> y = zoh_simulate(ct.tf([1], [0.01, 1]), u, fs=1000.0)      # corner at 100 rad/s
    >>> omega, H = empirical_frequency_response(u, y, fs=1000.0, nperseg=256)
    >>> round(float(omega[0]), 2), omega.shape == H.shape        # 2 pi fs / nperseg, DC excluded
    (24.54, True)
    """
    u, y = check_io(u, y)
    fs = check_positive("fs", fs)
    nperseg = check_integer("nperseg", nperseg, minimum=8)
    if len(u) < nperseg:
        raise ValueError(f"data ({len(u)} samples) shorter than nperseg ({nperseg})")
    f, puu = sg.welch(u, fs, nperseg=nperseg)
    _, puy = sg.csd(u, y, fs, nperseg=nperseg)
    keep = (f > 0) & (puu > 0)
    return 2 * np.pi * f[keep], puy[keep] / puu[keep]
