"""Recursive least squares (eq. 1-3, Step III of Fig. 3) and ARX models at the sampling rate.

Data ``u``, ``y`` [V] are deviations from the operating point, sampled at
``fs`` [Hz]; models have the neutral signal names ``u`` -> ``y``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la

from piezolib._checks import (check_finite_array, check_integer, check_positive,
                              check_same_length)

__all__ = [
    "RLSResult", "rls", "arx_regressors", "ArxModel", "fit_arx", "DEFAULT_INITIAL_GAIN",
    "MIN_SAMPLES_PER_PARAMETER", "MAX_INITIAL_GAIN", "least_squares", "check_io",
    "excitation_band",
]   # discrete_tf, checked_arx_regressors: shared with oe.py and continuous.py, not API


# --- Step III: recursive least squares, eq. 1-3 -------------------------------------
@dataclass(frozen=True)
class RLSResult:
    """Output of :func:`rls`.

    Attributes
    ----------
    parameters : ndarray, shape (p,)
        Final estimate Psi_hat.
    history : ndarray, shape (N, p)
        Psi_hat after each update (row k: after the sample y[k]).
    a_priori_errors : ndarray, shape (N,)
        e0(t+1) = y(t+1) - Psi_hat(t)^T theta(t), eq. 1.
    gain_matrix : ndarray, shape (p, p)
        Final W.

    Examples
    --------
    >>> t = np.arange(50.0)
    >>> r = rls(np.c_[np.ones(50), t], 2.0 + 0.5 * t)
    >>> r.a_priori_errors.shape, r.gain_matrix.shape, bool(abs(r.a_priori_errors[-1]) < 1e-3)
    ((50,), (2, 2), True)
    """

    parameters: np.ndarray
    history: np.ndarray
    a_priori_errors: np.ndarray
    gain_matrix: np.ndarray


def rls(regressors, y, initial_gain=1e6, initial_parameters=None):
    """Recursive least squares with a priori error and gain-matrix update.

    For each sample, with theta = ``regressors[k]`` (theta(t)) and
    ``y[k]`` (y(t+1)):

    * eq. 1: e0 = y - Psi^T theta
    * eq. 3: W <- W - W theta theta^T W / (1 + theta^T W theta)
    * eq. 2: Psi <- Psi + W theta e0   (with the updated W)

    Parameters
    ----------
    regressors : array_like, shape (N, p)
        Row k is the regressor theta(t) that predicts ``y[k]``.
    y : array_like, shape (N,)
        Measurements y(t+1).
    initial_gain : float, optional
        Dimensionless: W(0) = initial_gain * diag(1 / mean(theta_j^2)), i.e.
        the eq. 3 initial covariance relative to the data's power in each
        regressor, so that scaling u or y (a change of units) scales the
        estimates and nothing else.  Large values mean little confidence in
        the initial parameters (the result then approaches batch least
        squares); at most ``MAX_INITIAL_GAIN``.
    initial_parameters : array_like, shape (p,), optional
        Psi(0); default zeros.

    Returns
    -------
    RLSResult

    Raises
    ------
    ValueError
        Empty, non-finite or mismatched data, or ``initial_gain`` outside
        (0, MAX_INITIAL_GAIN].

    Examples
    --------
    Fit y = 2 + 0.5 t by RLS on the regressors (1, t):

    >>> t = np.arange(50.0)
    >>> r = rls(np.c_[np.ones(50), t], 2.0 + 0.5 * t)
    >>> r.parameters.round(4), r.history.shape
    (array([2. , 0.5]), (50, 2))
    """
    phi = check_finite_array("regressors", regressors, ndim=2, real=True)
    n, p = phi.shape
    y = check_finite_array("y", y, ndim=1, real=True)
    check_same_length(regressors=phi, y=y)
    if n == 0 or p == 0:
        raise ValueError(f"regressors must be non-empty, got shape {phi.shape}")
    initial_gain = check_positive("initial_gain", initial_gain)
    if initial_gain > MAX_INITIAL_GAIN:
        raise ValueError(f"initial_gain must be <= {MAX_INITIAL_GAIN:g} (relative to the "
                         f"data power; larger values lose every digit of eq. 3 in double "
                         f"precision), got {initial_gain:g}")
    psi = (np.zeros(p) if initial_parameters is None else
           check_finite_array("initial_parameters", initial_parameters, shape=(p,), real=True).copy())
    size = np.max(np.abs(phi), axis=0)
    # W(0) ~ 1 / theta^2 and eq. 3 squares theta: outside this range a square
    # overflows or W underflows to 0, and the estimate silently stays at Psi(0)
    bad = (size > 1e150) | ((size > 0) & (size < 1e-150))
    if np.any(bad):
        j = int(np.flatnonzero(bad)[0])
        raise ValueError(f"regressors: column {j} has magnitude {size[j]:.3g}, outside "
                         "[1e-150, 1e150] where eq. 3 can be evaluated in double precision; "
                         "rescale the data (another unit)")
    power = np.mean(phi ** 2, axis=0)
    power[power == 0] = 1.0                          # all-zero regressor: unit scale
    W = np.diag(initial_gain / power)
    history = np.empty((n, p))
    errors = np.empty(n)
    for k in range(n):
        theta = phi[k]
        e0 = y[k] - psi @ theta                      # eq. 1
        w_theta = W @ theta
        # eq. 3; W is symmetric, so W theta theta^T W = (W theta)(W theta)^T
        W = W - np.outer(w_theta, w_theta) / (1.0 + theta @ w_theta)
        psi = psi + (W @ theta) * e0                 # eq. 2
        history[k] = psi
        errors[k] = e0
    return RLSResult(psi, history, errors, W)


# --- ARX structure at the sampling rate -----------------------------------------------
def arx_regressors(u, y, na, nb, nk=1):
    """Regressors of y[k] + a1 y[k-1] + ... + a_na y[k-na]
    = b1 u[k-nk] + ... + b_nb u[k-nk-nb+1] + e[k].

    Returns
    -------
    phi : ndarray, shape (N - n0, na + nb)
        Rows [-y[k-1] ... -y[k-na], u[k-nk] ... u[k-nk-nb+1]] for k >= n0.
    target : ndarray, shape (N - n0,)
        y[k] for k >= n0.
    n0 : int
        First predicted sample, max(na, nk + nb - 1).

    Examples
    --------
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = np.zeros(500)
    >>> for k in range(1, 500):                         # y[k] = 0.9 y[k-1] + 0.5 u[k-1]
    ...     y[k] = 0.9 * y[k - 1] + 0.5 * u[k - 1]
    >>> phi, target, n0 = arx_regressors(u, y, na=1, nb=1)   # rows [-y[k-1], u[k-1]]
    >>> phi.shape, n0, bool(np.allclose(phi @ [-0.9, 0.5], target))
    ((499, 2), 1, True)
    """
    u, y = check_io(u, y)
    na = check_integer("na", na, minimum=1)
    nb = check_integer("nb", nb, minimum=1)
    nk = check_integer("nk", nk, minimum=0)
    n0 = max(na, nk + nb - 1)
    n = len(y)
    if n - n0 < na + nb:
        raise ValueError(f"data too short for the order: {n} samples give {n - n0} "
                         f"equations for {na + nb} parameters")
    cols = [-y[n0 - i:n - i] for i in range(1, na + 1)]
    cols += [u[n0 - nk - j:n - nk - j] for j in range(nb)]
    return np.column_stack(cols), y[n0:], n0


@dataclass(frozen=True)
class ArxModel:
    """An ARX model estimated by RLS.

    Attributes
    ----------
    a : ndarray
        [1, a1, ..., a_na] (coefficients of z^0 ... z^-na).
    b : ndarray
        [0, ..., 0, b1, ..., b_nb] with nk leading zeros (z^0 ... z^-(nk+nb-1)).
    dt : float
        Sample time [s].
    rls : RLSResult
        Parameter histories of the estimation.
    system : control.TransferFunction
        The model as a discrete-time transfer function in z, ``u`` -> ``y``.

    Examples
    --------
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = np.zeros(500)
    >>> for k in range(1, 500):                         # y[k] = 0.9 y[k-1] + 0.5 u[k-1]
    ...     y[k] = 0.9 * y[k - 1] + 0.5 * u[k - 1]
    >>> m = fit_arx(u, y, fs=100.0, na=1, nb=1)
    >>> m.system.dt, np.round(m.system.poles().real, 4), m.rls.history.shape
    (0.01, array([0.9]), (499, 2))
    """

    a: np.ndarray
    b: np.ndarray
    dt: float
    rls: RLSResult
    system: ct.TransferFunction


#: Largest accepted (dimensionless) W(0) gain of :func:`rls`: eq. 3 subtracts
#: terms of size initial_gain from O(1) ones, so 1e13 keeps ~3 digits.
MAX_INITIAL_GAIN = 1e13

#: Fewest equations per estimated parameter that :func:`fit_arx` accepts.
MIN_SAMPLES_PER_PARAMETER = 10

#: W(0) relative to the regressors' power (see :func:`rls`).  The 10 kHz
#: regressors are strongly correlated (condition number of the regressor
#: matrix ~4e3 on the chirps), so 1e6 still acts as a visible regularisation;
#: 1e10 makes the RLS result equal to batch least squares to about 1e-6 and is
#: numerically safe.
DEFAULT_INITIAL_GAIN = 1e10


def fit_arx(u, y, fs, na=6, nb=6, nk=1, initial_gain=DEFAULT_INITIAL_GAIN):
    """Estimate an ARX model with :func:`rls`.

    Parameters
    ----------
    u, y : array_like
        Input and output deviations from the operating point [V], equal
        lengths, sampled at ``fs``.
    fs : float
        Sampling frequency [Hz].
    na, nb, nk : int, optional
        Orders and delay (default: 6 poles, 6 numerator terms, 1 sample).
    initial_gain : float, optional
        W(0) relative to the data power (dimensionless, see :func:`rls`).

    Returns
    -------
    ArxModel

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, fewer than 10 samples per parameter, a
        constant input, or regressors that are not persistently exciting.

    Examples
    --------
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = np.zeros(500)
    >>> for k in range(1, 500):                         # y[k] = 0.9 y[k-1] + 0.5 u[k-1]
    ...     y[k] = 0.9 * y[k - 1] + 0.5 * u[k - 1]
    >>> m = fit_arx(u, y, fs=100.0, na=1, nb=1)
    >>> m.a.round(4), m.b.round(4), m.dt                    # 1 - 0.9 z^-1, 0.5 z^-1
    (array([ 1. , -0.9]), array([0. , 0.5]), 0.01)
    """
    fs = check_positive("fs", fs)
    phi, target = checked_arx_regressors(u, y, na, nb, nk)
    result = rls(phi, target, initial_gain=initial_gain)
    a = np.concatenate(([1.0], result.parameters[:na]))
    b = np.concatenate((np.zeros(nk), result.parameters[na:]))
    return ArxModel(a, b, 1.0 / fs, result, discrete_tf(b, a, 1.0 / fs, "arx"))


def discrete_tf(b, a, dt, name):
    """B(q)/A(q) from coefficients of z^0, z^-1, ... as a transfer function in z
    (both padded to one length first, so that every power of z is right).

    Returns
    -------
    control.TransferFunction
        Sample time ``dt`` [s], ``u`` -> ``y``, named ``name``.
    """
    length = max(len(a), len(b))
    num = np.concatenate((b, np.zeros(length - len(b))))
    den = np.concatenate((a, np.zeros(length - len(a))))
    return ct.tf(np.trim_zeros(num, "f"), den, dt, inputs="u", outputs="y", name=name)


def checked_arx_regressors(u, y, na, nb, nk):
    """ARX regressors after the checks of :func:`fit_arx` (length, excitation).

    Returns
    -------
    phi, target : ndarray
        As :func:`arx_regressors`.

    Raises
    ------
    ValueError
        Fewer than ``MIN_SAMPLES_PER_PARAMETER`` equations per parameter, or
        regressors that are not persistently exciting.
    """
    phi, target, _ = arx_regressors(u, y, na, nb, nk)
    p = phi.shape[1]
    if len(target) < MIN_SAMPLES_PER_PARAMETER * p:
        raise ValueError(f"data too short for the order: {len(target)} equations for {p} "
                         f"parameters; need at least {MIN_SAMPLES_PER_PARAMETER * p}")
    # persistent excitation: the column-normalised regressor matrix has full rank
    scale = np.sqrt(np.mean(phi ** 2, axis=0))
    if scale.min() == 0:
        raise ValueError(f"the regressors are not persistently exciting of order {p}: "
                         "a regressor column is identically zero")
    # singular values from the 12 x 12 Gram matrix: tall LAPACK calls are slow
    # when OpenBLAS threads compete for shared cores
    eig = la.eigvalsh(_gram(phi / scale))
    if eig[0] < 1e-14 * eig[-1]:
        raise ValueError(f"the regressors are not persistently exciting of order {p}: "
                         "use a richer input or a lower order")
    return phi, target


def excitation_band(u, fs, share=0.99):
    """Frequency below which ``share`` of an input's power lies [Hz] (mean removed).

    An identification input must excite the band of the model it is to
    give: a chirp to 2 kHz puts its power up to 2 kHz, whereas a hysteresis
    record (a slow sine, a step from rest) has nearly all its power below a
    few Hz, and a high-order model fitted to it is unsupported by the data.

    Parameters
    ----------
    u : array_like
        Input record, 1-D, at least 16 samples.
    fs : float
        Sampling rate [Hz].
    share : float, optional
        Share of the power, 0 < share < 1.

    Returns
    -------
    float
        The frequency [Hz] (0 for a constant input).

    Examples
    --------
    >>> t = np.arange(1000) / 1000.0
    >>> round(excitation_band(np.sin(2 * np.pi * 5 * t), fs=1000.0), 1)    # a 5 Hz sine
    5.0
    """
    u = check_finite_array("u", u, ndim=1, min_length=16, real=True)
    fs = check_positive("fs", fs)
    share = check_positive("share", share)
    if share >= 1:
        raise ValueError(f"share must be below 1, got {share!r}")
    power = np.abs(np.fft.rfft(u - u.mean())) ** 2
    total = float(power.sum())
    if total == 0:
        return 0.0
    k = int(np.searchsorted(np.cumsum(power) / total, share))
    return float(min(k, power.size - 1) * fs / u.size)


def _gram(phi):
    return phi.T @ phi


def least_squares(phi, target):
    """Batch least squares by column-scaled normal equations (accurate to
    about cond(phi)^2 * eps, 1e-9 on the chirps).

    Parameters
    ----------
    phi : ndarray, shape (N, p)
        Regressor matrix with no zero column.
    target : ndarray, shape (N,)
        Left-hand side.

    Returns
    -------
    ndarray, shape (p,)
        Parameters minimising ||phi @ theta - target||.

    Examples
    --------
    >>> x = np.arange(5.0)
    >>> least_squares(np.c_[np.ones(5), x], 1.0 + 2.0 * x).round(6)
    array([1., 2.])
    """
    phi = check_finite_array("phi", phi, ndim=2, min_length=1, real=True)
    target = check_finite_array("target", target, ndim=1, real=True)
    check_same_length(phi=phi, target=target)
    scale = np.sqrt(np.mean(phi ** 2, axis=0))
    if not np.all(np.isfinite(phi)) or not np.all(scale > 0):
        raise ValueError("the regressors contain a zero, NaN or inf column: the data do not "
                         "excite this model (or an output-error filter diverged)")
    scaled = phi / scale
    try:
        return la.solve(_gram(scaled), scaled.T @ target, assume_a="pos") / scale
    except la.LinAlgError:
        pass            # normal equations too ill-conditioned: orthogonal least squares
    theta, _, rank, _ = np.linalg.lstsq(scaled, target, rcond=None)
    if rank < phi.shape[1]:
        raise ValueError(
            f"the regressors are linearly dependent (rank {rank} of {phi.shape[1]}): the input "
            "does not excite a model of this order; subtract the operating point, cut constant "
            "segments (records.cut_at_turning_points, records.split) or lower the orders")
    return theta / scale


def check_io(u, y):
    """Check input/output data: finite 1-D arrays of equal length, ``u`` not constant.

    Returns
    -------
    u, y : ndarray
        The data as float arrays.

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, or a constant input.

    Examples
    --------
    >>> u, y = check_io([0, 1, 0, 1], [0.0, 0.1, 0.2, 0.1])
    >>> u.dtype, len(y)
    (dtype('float64'), 4)
    >>> check_io([1.0, 1.0, 1.0], [0.0, 0.1, 0.2])
    Traceback (most recent call last):
    ...
    ValueError: u is constant: a constant input does not excite the system
    """
    u = check_finite_array("u", u, ndim=1, real=True)
    y = check_finite_array("y", y, ndim=1, real=True)
    check_same_length(u=u, y=y)
    if len(u) < 2:
        raise ValueError(f"u and y are {'empty' if len(u) == 0 else 'too short'}: got "
                         f"{len(u)} sample(s); identification needs a record of many samples")
    if np.ptp(u) == 0:
        raise ValueError("u is constant: a constant input does not excite the system")
    return u, y
