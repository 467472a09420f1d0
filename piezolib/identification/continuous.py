"""Continuous-time models from sampled data: exact ZOH inverse, 3-zero refit, :func:`identify`.

Steps II-III of the paper's Fig. 3 end to end (:func:`identify`), the exact
inverse of the ZOH discretisation (:func:`d2c`) and its forward direction
(:func:`zoh_coefficients`, :func:`zoh_simulate`), the numerator refit with
the poles fixed (:func:`refit_numerator`), and the coefficients and pole pairs
of the result.  Time in seconds, frequencies in rad/s.

Why the numerator is refitted: ``docs/stage.md``.
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg as la
import scipy.signal as sg

from piezolib._checks import (check_finite_array, check_finite_lti, check_integer, check_positive,
                              check_siso)
from piezolib.identification.oe import OutputErrorModel, fit_output_error
from piezolib.identification.arx import (DEFAULT_INITIAL_GAIN, check_io, discrete_tf,
                                         least_squares)
from piezolib.robust.lti import balance, scale_time, time_scale_of, to_scaled

__all__ = [
    "d2c", "zoh_coefficients", "zoh_simulate", "refit_numerator", "IdentifiedModel",
    "identify", "identify_record", "pole_pairs", "monic_coefficients",
]


# --- continuous <-> discrete ----------------------------------------------------------
def d2c(sysd, method="zoh"):
    """Continuous-time model whose ZOH (or Tustin) discretisation is ``sysd``.

    With M = [[A, B], [0, 0]], exp(M T) = [[Ad, Bd], [0, I]], so the
    continuous model is the principal matrix logarithm of [[Ad, Bd], [0, I]]
    divided by T.  (python-control has ``c2d`` but no inverse.)

    ``method="tustin"`` inverts ``control.c2d(sys, T, "tustin")`` (bilinear map
    z = (1 + sT/2) / (1 - sT/2), no pre-warping) algebraically:
    A = (2/T)(I - 2 (Ad + I)^-1), B = (2/T)(Ad + I)^-1 Bd,
    C = 2 Cd (Ad + I)^-1, D = Dd - Cd (Ad + I)^-1 Bd.  It exists for any
    model without a pole at z = -1; the map keeps the Hankel singular values,
    so balanced truncation of the result, mapped back, is a balanced
    truncation of ``sysd`` (how notebook 10 reduces a discrete model).

    Parameters
    ----------
    sysd : control.LTI
        Discrete-time model with a numeric sample time.
    method : {"zoh", "tustin"}
        The exact zero-order-hold inverse (default) or the bilinear inverse.

    Returns
    -------
    control.StateSpace
        Continuous model (same signal names), states balanced.

    Raises
    ------
    ValueError
        For a continuous or unspecified-dt model, or a pole at z = 0 or on
        the negative real axis, where no real ZOH-equivalent model exists.

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> Gc = d2c(ct.c2d(G, 1e-3, "zoh"))                  # the exact inverse of the ZOH
    >>> np.sort_complex(Gc.poles()).round(6)
    array([-5.-8.660254j, -5.+8.660254j])
    """
    check_finite_lti("sysd", sysd)
    if method not in ("zoh", "tustin"):
        raise ValueError(f"method must be 'zoh' or 'tustin', got {method!r}")
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
    if method == "tustin":
        if np.any(np.abs(poles + 1) < 1e-9):
            raise ValueError("sysd has a pole at z = -1: no Tustin-equivalent continuous model")
        Mi = la.inv(A + np.eye(n))
        return ct.ss(2 / dt * (np.eye(n) - 2 * Mi), 2 / dt * Mi @ B, 2 * C @ Mi, D - C @ Mi @ B,
                     inputs=sysd.input_labels, outputs=sysd.output_labels,
                     name=f"{sysd.name}_c" if sysd.name else None)
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

    Examples
    --------
    >>> b, a = zoh_coefficients(ct.tf([1], [0.1, 1]), 0.01)      # tau = 0.1 s at 100 Hz
    >>> b.round(4), a.round(4)                                  # 1 - e^-0.1 = 0.0952
    (array([0.    , 0.0952]), array([ 1.    , -0.9048]))
    """
    check_siso("sys", sys)
    check_finite_lti("sys", sys)
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
    from rest, at the sampling instants.

    Examples
    --------
    >>> y = zoh_simulate(ct.tf([1], [0.1, 1]), np.ones(4), fs=100.0)   # a step through ZOH
    >>> y.round(4)
    array([0.    , 0.0952, 0.1813, 0.2592])
    """
    check_finite_lti("sys", sys)
    fs = check_positive("fs", fs)
    u = check_finite_array("u", u, ndim=1, min_length=1, real=True)
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

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = zoh_simulate(G, u, fs=1000.0)
    >>> refit_numerator(G.poles(), u, y, fs=1000.0, n_zeros=0).num[0][0].round(3)
    array([100.])
    """
    u, y = check_io(u, y)
    fs = check_positive("fs", fs)
    poles = check_finite_array("poles", poles, ndim=1, min_length=1)
    n = len(poles)
    n_zeros = check_integer("n_zeros", n_zeros, minimum=0)
    if n_zeros >= n:
        raise ValueError(f"n_zeros ({n_zeros}) must be below the number of poles ({n})")
    if np.any(poles.real >= 0):
        raise ValueError(f"poles must be stable, got {poles[poles.real >= 0]}")
    # a complex pole without its conjugate has no real denominator (taking the
    # real part of np.poly silently turned -1+1j into -1)
    unmatched = [p for p in poles if p.imag != 0 and np.min(np.abs(poles - np.conj(p)))
                 > 1e-9 * max(abs(p), 1e-300)]
    if unmatched:
        raise ValueError(f"poles must be closed under complex conjugation; no conjugate for "
                         f"{np.asarray(unmatched)}")
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
    coef_p = least_squares(basis, y)
    # G(s) = sum_j c_j p^j / a_p(p), p = s / ws  ->  b_j = c_j ws^(n-j), a_k = a_p,k ws^(n-k)
    powers = np.arange(n_zeros + 1)
    b = coef_p * time_scale ** (n - powers)               # b_0 ... b_nz
    a = den_p[::-1] * time_scale ** (n - np.arange(n + 1))  # a_0 ... a_n (a_n = 1)
    return ct.tf(b[::-1], a[::-1], inputs="u", outputs="y", name="identified")


@dataclass(frozen=True)
class IdentifiedModel:
    """Everything :func:`identify` estimated.

    Attributes
    ----------
    discrete : OutputErrorModel
        Discrete model from RLS (Steiglitz-McBride passes, parameter
        histories in each pass), input delay included.
    continuous_full : control.StateSpace
        d2c of the discrete model without the extra delay (``n_poles`` poles,
        up to ``nb - 1`` zeros).
    model : control.TransferFunction
        The ``n_poles``-pole / ``n_zeros``-zero model (eq. 4: 6 and 3),
        seconds, input -> output with the names given to :func:`identify`;
        the extra delay is not in it (see ``delay_s``).
    dropped_share : float
        Largest ratio, up to the Nyquist frequency, of the numerator terms
        above s^n_zeros of ``continuous_full`` to its terms up to s^n_zeros
        (zero for an exact ZOH model of that structure): how much the
        reduced numerator leaves out.
    delay_samples : int
        Input delay beyond the one sample of the ZOH, ``nk - 1``.
    delay_s : float
        The same in seconds; the plant is ``model`` times exp(-s delay_s).
    input_unit, output_unit : str or None
        Units of the data; the model's gain is in output_unit / input_unit.

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = zoh_simulate(G, u, fs=1000.0)
    >>> m = identify(u, y, fs=1000.0, n_poles=2, n_zeros=0)
    >>> m.delay_samples, m.continuous_full.nstates, bool(m.dropped_share < 1e-3)
    (0, 2, True)
    """

    discrete: OutputErrorModel
    continuous_full: ct.StateSpace
    model: ct.TransferFunction
    dropped_share: float
    delay_samples: int = 0
    delay_s: float = 0.0
    input_unit: object = None
    output_unit: object = None


def identify(u, y, fs, n_poles=6, n_zeros=3, initial_gain=DEFAULT_INITIAL_GAIN, *, nb=None,
             nk=1, input_name="u", output_name="y", input_unit=None, output_unit=None):
    """Steps II-III of Fig. 3: discrete output-error model by RLS, d2c,
    numerator refit.

    Parameters
    ----------
    u, y : array_like
        Input and output deviations from the operating point (any units,
        e.g. V and um), starting at rest.
    fs : float
        Sampling frequency [Hz].
    n_poles, n_zeros : int, optional
        Continuous structure (eq. 4: 6 and 3).
    initial_gain : float, optional
        RLS W(0) relative to the data power (dimensionless, see ``rls``).
    nb : int, optional
        Numerator terms of the discrete model, 1 ... ``n_poles``; default
        ``n_poles`` (the most a ZOH model of ``n_poles`` poles has).
    nk : int, optional
        Input delay of the discrete model in samples, >= 1: 1 is the ZOH's
        own delay; each extra sample is a pure delay, removed before d2c and
        reported as ``delay_s``.
    input_name, output_name : str, optional
        Signal names of the returned model.
    input_unit, output_unit : str, optional
        Units, carried into the result.

    Returns
    -------
    IdentifiedModel

    Examples
    --------
    Noise-free data of a textbook resonance give it back:

    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = zoh_simulate(G, u, fs=1000.0)
    >>> m = identify(u, y, fs=1000.0, n_poles=2, n_zeros=0).model
    >>> m.num[0][0].round(2), m.den[0][0].round(2)
    (array([100.]), array([  1.,  10., 100.]))
    """
    n_poles = check_integer("n_poles", n_poles, minimum=1)
    nb = n_poles if nb is None else check_integer("nb", nb, minimum=1)
    if nb > n_poles:
        raise ValueError(f"nb ({nb}) must not exceed n_poles ({n_poles}): more numerator "
                         "terms put poles at z = 0, which have no continuous equivalent")
    nk = check_integer("nk", nk, minimum=1)
    for name, value in (("input_name", input_name), ("output_name", output_name)):
        if not isinstance(value, str) or not value:
            raise TypeError(f"{name} must be a non-empty string, got {value!r}")
    discrete = fit_output_error(u, y, fs, na=n_poles, nb=nb, nk=nk, initial_gain=initial_gain)
    delay = nk - 1
    undelayed = discrete_tf(discrete.b[delay:], discrete.a, discrete.dt, "oe")
    full = d2c(undelayed)
    poles = la.eigvals(full.A)
    if np.any(poles.real >= 0):
        raise ValueError(f"the identified model is unstable (poles {poles[poles.real >= 0]})")
    u, y = check_io(u, y)
    u_delayed = np.concatenate((np.zeros(delay), u[:len(u) - delay]))
    refit = refit_numerator(poles, u_delayed, y, fs, n_zeros=n_zeros)
    model = ct.tf(refit.num, refit.den, inputs=input_name, outputs=output_name,
                  name="identified")
    num = monic_coefficients(full, n_poles, n_poles - 1)[1][::-1]   # s^(n-1) ... s^0
    s_grid = 1j * np.linspace(0.0, np.pi * fs, 512)[1:]
    high = np.polyval(np.concatenate((num[:n_poles - 1 - n_zeros], np.zeros(n_zeros + 1))),
                      s_grid)
    low = np.polyval(num[n_poles - 1 - n_zeros:], s_grid)
    return IdentifiedModel(discrete, full, model, float(np.max(np.abs(high / low))),
                           delay, delay / fs, input_unit, output_unit)


def identify_record(record, n_poles=6, n_zeros=3, *, nb=None, nk=1,
                    initial_gain=DEFAULT_INITIAL_GAIN):
    """:func:`identify` on a :class:`piezolib.records.Record`, with its rate,
    signal names and units.

    The record's signals are used as they are: subtract the operating point
    first (e.g. with :func:`piezolib.records.detrend` or a segment that
    starts at rest).

    Returns
    -------
    IdentifiedModel

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> u = np.random.default_rng(0).standard_normal(2000)
    >>> y = zoh_simulate(G, u, fs=1000.0)
    >>> from piezolib.records import Record
    >>> rec = Record(u, y, fs=1000.0, input_unit="V", output_unit="um")
    >>> m = identify_record(rec, n_poles=2, n_zeros=0)
    >>> m.model.den[0][0].round(2), m.output_unit
    (array([  1.,  10., 100.]), 'um')
    """
    from piezolib.records import Record
    if not isinstance(record, Record):
        raise TypeError(f"record must be a piezolib.records.Record, got "
                        f"{type(record).__name__}")
    return identify(record.input, record.output, record.fs, n_poles, n_zeros, initial_gain,
                    nb=nb, nk=nk, input_name=record.input_name,
                    output_name=record.output_name, input_unit=record.input_unit,
                    output_unit=record.output_unit)


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

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> pole_pairs(G)                                    # natural frequencies, dampings
    (array([10.]), array([0.5]))
    """
    check_siso("sys", sys)
    check_finite_lti("sys", sys)
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

    Examples
    --------
    >>> G = ct.tf([100], [1, 10, 100])                   # w_n = 10 rad/s, zeta = 0.5
    >>> a, b = monic_coefficients(G, n_poles=2, n_zeros=0)   # s^2 + a1 s + a0, b0
    >>> a.round(6), b.round(6)
    (array([100.,  10.]), array([100.]))
    """
    check_siso("sys", sys)
    check_finite_lti("sys", sys)
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
