"""System identification: RLS (eq. 1-3), ARX/output-error, exact ZOH inverse.

The four steps of the paper's Fig. 3 on sampled input/output data ``u``,
``y`` [V] at the sampling frequency ``fs`` [Hz]: recursive least squares
(:func:`rls`) on ARX regressors (:func:`fit_arx`), Steiglitz-McBride passes to
the output-error estimate (:func:`fit_output_error`), the exact inverse of the
ZOH discretisation (:func:`d2c`), a numerator refit with the poles fixed
(:func:`refit_numerator`), all in :func:`identify`; validation by simulated
fit (:func:`fit_percent`), residual whiteness (:func:`whiteness`) and an
empirical frequency response.  Returned models have the neutral signal names
``u`` -> ``y``.  Time in seconds, frequencies in rad/s.

Why output-error passes follow ARX, and why the numerator is refitted:
``docs/stage.md``.

Examples
--------
Noise-free data of a known resonance give it back:

>>> import control as ct, numpy as np
>>> G = ct.tf([2e6], [1.0, 200.0, 1e6])
>>> u = np.random.default_rng(0).standard_normal(4000)
>>> y = zoh_simulate(G, u, fs=10e3)
>>> model = identify(u, y, fs=10e3, n_poles=2, n_zeros=0).model
>>> model.input_labels, model.output_labels, round(float(model.dcgain()), 6)
(['u'], ['y'], 2.0)
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la
import scipy.signal as sg
import scipy.stats as stats

from piezolib._checks import (check_finite_array, check_integer, check_lti, check_positive,
                              check_same_length, check_siso)
from piezolib.robust.lti import balance, scale_time, time_scale_of, to_scaled

__all__ = [
    "RLSResult", "rls", "arx_regressors", "ArxModel", "fit_arx", "DEFAULT_INITIAL_GAIN",
    "MIN_SAMPLES_PER_PARAMETER",
    "OutputErrorModel", "fit_output_error", "d2c",
    "zoh_coefficients", "zoh_simulate", "refit_numerator", "IdentifiedModel",
    "identify", "fit_percent", "Whiteness", "whiteness", "pole_pairs",
    "monic_coefficients", "coefficient_table", "empirical_frequency_response",
]


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
        W(0) = initial_gain * I; large values mean little confidence in the
        initial parameters (the result then approaches batch least squares).
    initial_parameters : array_like, shape (p,), optional
        Psi(0); default zeros.

    Returns
    -------
    RLSResult
    """
    phi = check_finite_array("regressors", regressors, ndim=2)
    n, p = phi.shape
    y = check_finite_array("y", y, ndim=1)
    check_same_length(regressors=phi, y=y)
    if n == 0 or p == 0:
        raise ValueError(f"regressors must be non-empty, got shape {phi.shape}")
    initial_gain = check_positive("initial_gain", initial_gain)
    psi = (np.zeros(p) if initial_parameters is None else
           check_finite_array("initial_parameters", initial_parameters, shape=(p,)).copy())
    W = initial_gain * np.eye(p)
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
    """
    u, y = _check_io(u, y)
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
    """

    a: np.ndarray
    b: np.ndarray
    dt: float
    rls: RLSResult
    system: ct.TransferFunction


#: Fewest equations per estimated parameter that :func:`fit_arx` accepts.
MIN_SAMPLES_PER_PARAMETER = 10

#: W(0) / I of the identification.  The 10 kHz regressors are strongly
#: correlated (condition number of the regressor matrix ~4e3 on the chirps),
#: so W(0) = 1e6 I still acts as a visible regularisation; 1e10 makes the RLS
#: result equal to batch least squares to about 1e-6 and is numerically safe.
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
        W(0) = initial_gain * I.

    Returns
    -------
    ArxModel

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, fewer than 10 samples per parameter, a
        constant input, or regressors that are not persistently exciting.
    """
    fs = check_positive("fs", fs)
    phi, target = _checked_regressors(u, y, na, nb, nk)
    result = rls(phi, target, initial_gain=initial_gain)
    a = np.concatenate(([1.0], result.parameters[:na]))
    b = np.concatenate((np.zeros(nk), result.parameters[na:]))
    return ArxModel(a, b, 1.0 / fs, result, _discrete_tf(b, a, 1.0 / fs, "arx"))


def _discrete_tf(b, a, dt, name):
    """B(q)/A(q) from coefficients of z^0, z^-1, ... as a transfer function in z
    (both padded to one length first, so that every power of z is right)."""
    length = max(len(a), len(b))
    num = np.concatenate((b, np.zeros(length - len(b))))
    den = np.concatenate((a, np.zeros(length - len(a))))
    return ct.tf(np.trim_zeros(num, "f"), den, dt, inputs="u", outputs="y", name=name)


def _checked_regressors(u, y, na, nb, nk):
    """ARX regressors after the checks of :func:`fit_arx` (length, excitation)."""
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


def _gram(phi):
    return phi.T @ phi


def _least_squares(phi, target):
    """Batch least squares by column-scaled normal equations (accurate to
    about cond(phi)^2 * eps, 1e-9 on the chirps)."""
    scale = np.sqrt(np.mean(phi ** 2, axis=0))
    scaled = phi / scale
    return la.solve(_gram(scaled), scaled.T @ target, assume_a="pos") / scale


def _check_io(u, y):
    u = check_finite_array("u", u, ndim=1)
    y = check_finite_array("y", y, ndim=1)
    check_same_length(u=u, y=y)
    if len(u) < 2 or np.ptp(u) == 0:
        raise ValueError("u is constant: a constant input does not excite the system")
    return u, y


# --- continuous <-> discrete ----------------------------------------------------------
def d2c(sysd, method="zoh"):
    """Continuous-time model whose ZOH discretisation is ``sysd``.

    With M = [[A, B], [0, 0]], exp(M T) = [[Ad, Bd], [0, I]], so the
    continuous model is the principal matrix logarithm of [[Ad, Bd], [0, I]]
    divided by T.  (python-control has ``c2d`` but no inverse.)

    Parameters
    ----------
    sysd : control.LTI
        Discrete-time model with a numeric sample time.
    method : {"zoh"}
        Only the zero-order-hold inverse is provided.

    Returns
    -------
    control.StateSpace
        Continuous model (same signal names), states balanced.

    Raises
    ------
    ValueError
        For a continuous or unspecified-dt model, or a pole at z = 0 or on
        the negative real axis, where no real ZOH-equivalent model exists.
    """
    check_lti("sysd", sysd)
    if method != "zoh":
        raise ValueError(f"method must be 'zoh', got {method!r}")
    dt = sysd.dt
    if dt is None or dt is True or dt == 0 or isinstance(dt, bool):
        raise ValueError("sysd must be discrete-time with a numeric sample time, "
                         f"got dt={dt!r}")
    dt = check_positive("sysd.dt", float(dt))
    ss = ct.ss(sysd)
    A, B, C, D = (np.asarray(m, dtype=float) for m in (ss.A, ss.B, ss.C, ss.D))
    n, m = B.shape
    if n == 0:
        return ct.ss([], [], [], D, inputs=sysd.input_labels, outputs=sysd.output_labels)
    poles = la.eigvals(A)
    scale = max(1.0, float(np.max(np.abs(poles))))
    bad = poles[(np.abs(poles) < 1e-12 * scale)
                | ((poles.real <= 0) & (np.abs(poles.imag) < 1e-9 * scale))]
    if bad.size:
        raise ValueError("sysd has pole(s) at z = 0 or on the negative real axis "
                         f"({np.round(bad, 6)}): no real ZOH-equivalent continuous model")
    # balance A (diagonal similarity) before the logarithm
    bal = balance(ss)
    A, B, C = bal.A, bal.B, bal.C
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:], M[n:, n:] = A, B, np.eye(m)
    L = la.logm(M)
    if np.iscomplexobj(L):
        if np.max(np.abs(L.imag)) > 1e-8 * max(1.0, np.max(np.abs(L.real))):
            raise ValueError("the matrix logarithm of the ZOH model is not real: "
                             "no real ZOH-equivalent continuous model")
        L = L.real
    L = L / dt
    return ct.ss(L[:n, :n], L[:n, n:], C, D, inputs=sysd.input_labels,
                 outputs=sysd.output_labels, name=f"{sysd.name}_c" if sysd.name else None)


def zoh_coefficients(sys, dt):
    """Direct-form coefficients of the exact ZOH discretisation of a SISO model.

    Computed from a balanced realisation in scaled time
    (:func:`piezolib.robust.lti.to_scaled` at
    :func:`~piezolib.robust.lti.time_scale_of` the model), so that models with
    coefficients up to 1e23 give accurate coefficients.

    Parameters
    ----------
    sys : control.LTI
        SISO continuous-time model.
    dt : float
        Sample time [s].

    Returns
    -------
    b, a : ndarray
        Numerator and denominator in powers of z^-1 (highest power of z
        first, a[0] = 1; b[0] = 0 exactly without direct feedthrough), for
        ``scipy.signal.lfilter``.
    """
    check_siso("sys", sys)
    if not sys.isctime(strict=True):
        raise ValueError("sys must be a continuous-time model")
    dt = check_positive("dt", dt)
    w = time_scale_of(sys)
    ss = to_scaled(sys, w)
    n = ss.nstates
    D = np.asarray(ss.D, dtype=float).reshape(1, 1)
    if n == 0:
        return D.ravel().copy(), np.array([1.0])
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = ss.A * (w * dt), ss.B * (w * dt)    # the sample time in scaled time
    E = la.expm(M)
    b, a = sg.ss2tf(E[:n, :n], E[:n, n:], ss.C, D)
    b = np.asarray(b, dtype=float).ravel() / a[0]
    a = np.asarray(a, dtype=float) / a[0]
    if D[0, 0] == 0:
        b[0] = 0.0                   # exactly: no direct feedthrough
    return b, a


def zoh_simulate(sys, u, fs):
    """Response of a continuous SISO model to a sampled input held by a ZOH,
    from rest, at the sampling instants."""
    fs = check_positive("fs", fs)
    u = check_finite_array("u", u, ndim=1, min_length=1)
    b, a = zoh_coefficients(sys, 1.0 / fs)
    return sg.lfilter(b, a, u)


# --- 3-zero structure ------------------------------------------------------------------
def refit_numerator(poles, u, y, fs, n_zeros=3, time_scale=None):
    """Output-error least-squares fit of b0 ... b_nz with the poles fixed.

    The simulated response of b(s)/a(s) to the ZOH input is linear in the
    numerator coefficients: y_hat = sum_j b_j y_j with y_j the response of
    s^j/a(s).  The basis responses are computed in scaled time
    (s = time_scale * p) and the fit is ordinary least squares.

    Parameters
    ----------
    poles : array_like
        Continuous poles [rad/s], closed under conjugation, all stable.
    u, y : array_like
        Input and output deviations [V], from rest.
    fs : float
        Sampling frequency [Hz].
    n_zeros : int, optional
        Numerator degree (3 in eq. 4).
    time_scale : float, optional
        Internal scaling [rad/s]; default the geometric mean of the smallest
        and the largest pole magnitude (the rule of
        :func:`piezolib.robust.lti.time_scale_of`).

    Returns
    -------
    control.TransferFunction
        b(s)/a(s) with a monic of degree len(poles), time in seconds,
        ``u`` -> ``y``.
    """
    u, y = _check_io(u, y)
    fs = check_positive("fs", fs)
    poles = check_finite_array("poles", poles, ndim=1, min_length=1)
    n = len(poles)
    n_zeros = check_integer("n_zeros", n_zeros, minimum=0)
    if n_zeros >= n:
        raise ValueError(f"n_zeros ({n_zeros}) must be below the number of poles ({n})")
    if np.any(poles.real >= 0):
        raise ValueError(f"poles must be stable, got {poles[poles.real >= 0]}")
    if time_scale is None:
        magnitudes = np.abs(poles)
        time_scale = float(np.sqrt(magnitudes.min() * magnitudes.max()))
    time_scale = check_positive("time_scale", time_scale)
    den_p = np.real(np.poly(poles / time_scale))         # monic in p
    basis = []
    for j in range(n_zeros + 1):
        num_p = np.zeros(j + 1)
        num_p[0] = 1.0                                    # p^j
        basis.append(zoh_simulate(ct.tf(num_p, den_p), u, fs / time_scale))  # T in p-time
    basis = np.column_stack(basis)
    coef_p = _least_squares(basis, y)
    # G(s) = sum_j c_j p^j / a_p(p), p = s / ws  ->  b_j = c_j ws^(n-j), a_k = a_p,k ws^(n-k)
    powers = np.arange(n_zeros + 1)
    b = coef_p * time_scale ** (n - powers)               # b_0 ... b_nz
    a = den_p[::-1] * time_scale ** (n - np.arange(n + 1))  # a_0 ... a_n (a_n = 1)
    return ct.tf(b[::-1], a[::-1], inputs="u", outputs="y", name="identified")


@dataclass(frozen=True)
class OutputErrorModel:
    """Discrete output-error model B/A from Steiglitz-McBride iterations.

    Attributes
    ----------
    a, b : ndarray
        Final [1, a1 ... a_na] and [0 ... 0, b1 ... b_nb] (as in ArxModel).
    dt : float
        Sample time [s].
    final : ArxModel
        The RLS estimate (eq. 1-3, with parameter histories) on the data
        prefiltered by the converged denominator; ``a`` and ``b`` are its
        parameters.
    prefilters : tuple of ndarray
        Denominators A_i of the prefiltering passes (pass 0: plain ARX).
    converged : bool
        True when the passes converged within ``tol``.
    system : control.TransferFunction
        B/A as a discrete-time transfer function.
    """

    a: np.ndarray
    b: np.ndarray
    dt: float
    final: ArxModel
    prefilters: tuple
    converged: bool
    system: ct.TransferFunction


def fit_output_error(u, y, fs, na=6, nb=6, nk=1, iterations=50, tol=1e-8,
                     initial_gain=DEFAULT_INITIAL_GAIN):
    """Output-error estimate by RLS on prefiltered ARX regressors.

    With white measurement noise on y, the ARX (equation-error) estimate is
    biased: the noise enters the regression multiplied by A(q), which weights
    the high frequencies where the stage's response is small.  The
    Steiglitz-McBride iteration removes the bias: pass i fits the ARX
    regression to u and y filtered by 1/A_{i-1}(q), the denominator of the
    previous pass (pass 0 is plain ARX).  At convergence the equation error
    of the filtered data is the output error y - (B/A) u.  The prefiltering
    passes use batch least squares (the limit of RLS for large W(0), and
    fifty times faster); the final estimate is RLS, eq. 1-3, on the data
    filtered by the converged denominator.

    Parameters
    ----------
    u, y : array_like
        Input and output deviations [V], from rest.
    fs : float
        Sampling frequency [Hz].
    na, nb, nk : int, optional
        Orders and delay.
    iterations : int, optional
        Maximum number of prefiltering passes.
    tol : float, optional
        Stop when max |change of a parameter| / max |parameter| < tol.
    initial_gain : float, optional
        RLS W(0) = initial_gain * I in every pass.

    Returns
    -------
    OutputErrorModel
    """
    iterations = check_integer("iterations", iterations, minimum=1)
    tol = check_positive("tol", tol)
    fs = check_positive("fs", fs)
    _checked_regressors(u, y, na, nb, nk)          # raw data: length, excitation
    u, y = np.asarray(u, dtype=float), np.asarray(y, dtype=float)
    den = np.array([1.0])
    prefilters, previous, converged = [], None, False
    for _ in range(iterations):
        phi, target, _ = arx_regressors(sg.lfilter([1.0], den, u),
                                        sg.lfilter([1.0], den, y), na, nb, nk)
        params = _least_squares(phi, target)
        den = np.concatenate(([1.0], params[:na]))
        if np.any(np.abs(np.roots(den)) >= 1):
            raise ValueError("an intermediate model is unstable, so it cannot prefilter "
                             "the data: check the excitation and the model order")
        prefilters.append(den)
        if previous is not None and (np.max(np.abs(params - previous))
                                     < tol * np.max(np.abs(params))):
            converged = True
            break
        previous = params
    final = fit_arx(sg.lfilter([1.0], den, u), sg.lfilter([1.0], den, y), fs,
                    na, nb, nk, initial_gain)
    return OutputErrorModel(final.a, final.b, final.dt, final, tuple(prefilters),
                            converged, _discrete_tf(final.b, final.a, final.dt, "oe"))


@dataclass(frozen=True)
class IdentifiedModel:
    """Everything :func:`identify` estimated.

    Attributes
    ----------
    discrete : OutputErrorModel
        Discrete model from RLS (Steiglitz-McBride passes, parameter
        histories in each pass).
    continuous_full : control.StateSpace
        d2c of the discrete model (6 poles, up to 5 zeros).
    model : control.TransferFunction
        The 6-pole / 3-zero model of eq. 4 (``u`` -> ``y``, seconds).
    dropped_share : float
        Largest ratio, up to the Nyquist frequency, of the numerator terms
        above s^3 of ``continuous_full`` to its terms up to s^3 (zero for an
        exact ZOH model of eq. 4's structure): how much the 3-zero
        structure leaves out.
    """

    discrete: OutputErrorModel
    continuous_full: ct.StateSpace
    model: ct.TransferFunction
    dropped_share: float


def identify(u, y, fs, n_poles=6, n_zeros=3, initial_gain=DEFAULT_INITIAL_GAIN):
    """Steps II-III of Fig. 3: discrete output-error model by RLS, d2c,
    3-zero refit.

    Parameters
    ----------
    u, y : array_like
        Input and output deviations from the operating point [V], starting
        at rest.
    fs : float
        Sampling frequency [Hz].
    n_poles, n_zeros : int, optional
        Continuous structure (eq. 4: 6 and 3).
    initial_gain : float, optional
        RLS W(0) = initial_gain * I.

    Returns
    -------
    IdentifiedModel
    """
    n_poles = check_integer("n_poles", n_poles, minimum=1)
    discrete = fit_output_error(u, y, fs, na=n_poles, nb=n_poles, nk=1,
                                initial_gain=initial_gain)
    full = d2c(discrete.system)
    poles = la.eigvals(full.A)
    if np.any(poles.real >= 0):
        raise ValueError(f"the identified model is unstable (poles {poles[poles.real >= 0]})")
    model = refit_numerator(poles, u, y, fs, n_zeros=n_zeros)
    num = monic_coefficients(full, n_poles, n_poles - 1)[1][::-1]   # s^(n-1) ... s^0
    s_grid = 1j * np.linspace(0.0, np.pi * fs, 512)[1:]
    high = np.polyval(np.concatenate((num[:n_poles - 1 - n_zeros], np.zeros(n_zeros + 1))),
                      s_grid)
    low = np.polyval(num[n_poles - 1 - n_zeros:], s_grid)
    return IdentifiedModel(discrete, full, model, float(np.max(np.abs(high / low))))


# --- Step IV: validation -------------------------------------------------------------------
def fit_percent(y, y_hat):
    """Normalised fit 100 (1 - ||y - y_hat|| / ||y - mean(y)||) in %."""
    y = check_finite_array("y", y, ndim=1, min_length=2)
    y_hat = check_finite_array("y_hat", y_hat, ndim=1, min_length=2)
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
    """
    e = check_finite_array("residual", residual, ndim=1)
    max_lag = check_integer("max_lag", max_lag, minimum=1)
    alpha = check_positive("alpha", alpha)
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


def pole_pairs(sys):
    """Natural frequencies and damping ratios of a model's complex pole pairs.

    Parameters
    ----------
    sys : control.LTI
        SISO continuous-time model.

    Returns
    -------
    wn : ndarray
        Natural frequencies [rad/s], ascending.
    zeta : ndarray
        Damping ratios, in the same order.
    """
    check_siso("sys", sys)
    w = time_scale_of(sys)
    poles = la.eigvals(to_scaled(sys, w).A) * w          # computed in scaled time
    upper = poles[poles.imag > 0]
    wn = np.abs(upper)
    order = np.argsort(wn)
    return wn[order], (-upper.real / wn)[order]


def monic_coefficients(sys, n_poles=6, n_zeros=3, time_scale=None):
    """Coefficients of b(s)/a(s) with a monic, lowest power first.

    Parameters
    ----------
    sys : control.LTI
        SISO continuous-time model with ``n_poles`` poles and at most
        ``n_zeros`` zeros.
    n_poles, n_zeros : int, optional
        The structure (eq. 4: 6 and 3).
    time_scale : float, optional
        Internal scaling [rad/s] for accuracy; default
        :func:`piezolib.robust.lti.time_scale_of` of ``sys``.

    Returns
    -------
    a : ndarray
        a0 ... a_{n-1} (time in seconds; a_n = 1 is left out).
    b : ndarray
        b0 ... b_m, m = ``n_zeros``.

    Raises
    ------
    ValueError
        When ``sys`` has another number of poles or more zeros.
    """
    check_siso("sys", sys)
    time_scale = time_scale_of(sys) if time_scale is None else check_positive(
        "time_scale", time_scale)
    tf = ct.tf(scale_time(sys, time_scale))
    den = np.atleast_1d(tf.den[0][0]).astype(float)
    num = np.atleast_1d(tf.num[0][0]).astype(float) / den[0]
    den = den / den[0]
    if len(den) != n_poles + 1:
        raise ValueError(f"sys has {len(den) - 1} poles, expected {n_poles}")
    num = np.trim_zeros(num, "f")
    if len(num) > n_zeros + 1:
        raise ValueError(f"sys has {len(num) - 1} zeros, expected at most {n_zeros}")
    num = np.concatenate((np.zeros(n_zeros + 1 - len(num)), num))
    a = den[::-1][:-1] * time_scale ** (n_poles - np.arange(n_poles))
    b = num[::-1] * time_scale ** (n_poles - np.arange(n_zeros + 1))
    return a, b


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
    a1, b1 = monic_coefficients(identified)
    a2, b2 = monic_coefficients(reference)
    index = [f"a{i}" for i in range(len(a1))] + [f"b{i}" for i in range(len(b1))]
    first, second = np.concatenate((a1, b1)), np.concatenate((a2, b2))
    return pd.DataFrame({names[0]: first, names[1]: second,
                         "relative error": (first - second) / second},
                        index=pd.Index(index, name="coefficient"))


def empirical_frequency_response(u, y, fs, nperseg=2048):
    """Frequency response estimate y/u from data: Welch cross spectrum over
    input spectrum (H1 estimator).

    Returns
    -------
    omega : ndarray
        Frequencies [rad/s] (DC excluded).
    response : ndarray
        Complex response at ``omega``.
    """
    u, y = _check_io(u, y)
    fs = check_positive("fs", fs)
    nperseg = check_integer("nperseg", nperseg, minimum=8)
    if len(u) < nperseg:
        raise ValueError(f"data ({len(u)} samples) shorter than nperseg ({nperseg})")
    f, puu = sg.welch(u, fs, nperseg=nperseg)
    _, puy = sg.csd(u, y, fs, nperseg=nperseg)
    keep = (f > 0) & (puu > 0)
    return 2 * np.pi * f[keep], puy[keep] / puu[keep]
