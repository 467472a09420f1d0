"""Multiplicative uncertainty weights: a shape given by its parameters, or a fit that covers.

:func:`inverse_notch_weight` builds the classic shape (gain, inverse notches
at the plant's resonances, a first-order low-pass) from explicit parameters;
:func:`fit_covering_weight` fits a stable, minimum-phase weight of given order
that covers a relative-error envelope, in the spirit of MATLAB's ``ucover``
(the gain-and-sections model of :mod:`piezolib.robust.sos`; the method is
described in ``docs/uncertainty.md``).
"""

import control as ct
import numpy as np
import scipy.optimize as opt
from scipy.signal import find_peaks, peak_widths

from piezolib._checks import check_finite_array, check_integer, check_nonnegative, check_positive
from piezolib.robust import sos
from piezolib.uncertainty.polynomials import check_frequencies

__all__ = ["inverse_notch_weight", "fit_covering_weight"]


def inverse_notch_weight(gain, notches, lowpass_rad_s, lowpass_dc_gain=1.0, lowpass_hf_gain=0.0,
                         *, inputs="u", outputs="y_Delta", name="W_m"):
    """Weight of inverse notches in series with a first-order low-pass.

    W(s) = g prod_i (s^2 + 2 zeta_z,i omega_i s + omega_i^2)
    / (s^2 + 2 zeta_p,i omega_i s + omega_i^2) * (eps s + omega_c) / (s + omega_c / M).

    Each section has unit gain far from omega_i and gain zeta_z,i / zeta_p,i
    at omega_i: with zeta_z > zeta_p it lifts |W| around a resonance, where a
    set of plant models spreads most.  The low-pass has gain M at low and eps
    at high frequency, so |W| tends to g M at DC and g eps at high frequency.

    Parameters
    ----------
    gain : float
        g > 0 (dimensionless: a relative model error).
    notches : array_like of shape (k, 3)
        One row (omega_i [rad/s] > 0, zeta_z,i >= 0, zeta_p,i > 0) per
        section; k = 0 (an empty sequence) leaves only the low-pass.
    lowpass_rad_s : float
        omega_c > 0 [rad/s]: the low-pass's pole is at -omega_c / M, its zero
        at -omega_c / eps.
    lowpass_dc_gain : float, optional
        M > 0, the low-pass's gain at DC.
    lowpass_hf_gain : float, optional
        eps >= 0, its gain at high frequency (0: W is strictly proper).
    inputs, outputs, name : str, optional
        Signal and system names (default ``u -> y_Delta``, ``W_m``).

    Returns
    -------
    control.TransferFunction
        Stable weight of order 2 k + 1 (minimum phase when eps > 0 and every
        zeta_z,i > 0).

    Raises
    ------
    ValueError, TypeError
        When a parameter is not finite or outside its range, or ``notches``
        is not k rows of three numbers (the message names the argument).
    """
    g = check_positive("gain", gain)
    rows = check_finite_array("notches", notches, real=True)
    if rows.size == 0:
        rows = rows.reshape(0, 3)
    if rows.ndim != 2 or rows.shape[1] != 3:
        raise ValueError("notches must be rows of (omega_rad_s, zeta_zeros, zeta_poles), "
                         f"got shape {rows.shape}")
    omega_c = check_positive("lowpass_rad_s", lowpass_rad_s)
    M = check_positive("lowpass_dc_gain", lowpass_dc_gain)
    eps = check_nonnegative("lowpass_hf_gain", lowpass_hf_gain)
    num, den = np.ones(1), np.ones(1)
    for i, (omega, zeta_z, zeta_p) in enumerate(rows):
        omega = check_positive(f"notches[{i}] omega_rad_s", omega)
        zeta_z = check_nonnegative(f"notches[{i}] zeta_zeros", zeta_z)
        # a zero pole damping puts poles on the imaginary axis
        zeta_p = check_positive(f"notches[{i}] zeta_poles", zeta_p)
        num = np.polymul(num, [1, 2 * zeta_z * omega, omega ** 2])
        den = np.polymul(den, [1, 2 * zeta_p * omega, omega ** 2])
    num = g * np.polymul(num, [eps, omega_c])
    den = np.polymul(den, [1, omega_c / M])
    return ct.tf(num, den, inputs=inputs, outputs=outputs, name=name)

#: Bounds of every damping ratio of the weight's sections.
_ZETA_RANGE = (1e-4, 1e2)


def fit_covering_weight(omega, envelope, order, starts=2, max_iter=60, fit_points=250, *,
                        inputs="u", outputs="y_Delta", name="W_m"):
    """Stable, minimum-phase weight W of a given order with |W(j omega)| >= E(omega).

    W has ``order`` poles and zeros, covers E on every grid point, and its
    worst-case excess max 20 log10(|W|/E) is made as small as the optimiser
    can: least squares on the shape of log E, a minimax polish by sequential
    linear programming, a tightening of the mean excess, then a lift of the
    gain onto E (steps in ``docs/uncertainty.md``).  The optimisation is local
    (a few deterministic starts): the excess is the least found, not a proven
    global minimum.

    Parameters
    ----------
    omega : array_like
        Grid [rad/s], positive.
    envelope : array_like
        E(omega) > 0, finite, same shape.
    order : int
        Number of poles (= zeros) of the weight, >= 1.
    starts : int
        Number of starting points tried (>= 1); the best result is kept.
    max_iter : int
        Iteration limit of each optimisation stage.
    fit_points : int
        The optimisation runs on about this many grid points (log-spaced
        picks plus every local maximum of E and its neighbours); the final
        lift uses the whole grid, so coverage holds on every grid point.
    inputs, outputs, name : str, optional
        Signal and system names of W (default ``u -> y_Delta``, ``W_m``).

    Returns
    -------
    control.TransferFunction
        W; use :func:`~piezolib.uncertainty.envelope.coverage` to read its
        excess over E.

    Raises
    ------
    ValueError
        When E is not positive and finite on the grid, or ``order < 1``.

    Examples
    --------
    >>> from piezolib.uncertainty import model_set, relative_error_envelope, coverage
    >>> omega = np.logspace(-1, 1, 100)
    >>> E = relative_error_envelope(model_set(ct.tf([1], [1, 0.2, 1]), 0.1), omega)
    >>> W = fit_covering_weight(omega, E, order=2)
    >>> c = coverage(W, omega, E)
    >>> c.covers, bool(c.worst_ratio >= 1), bool(c.max_excess_dB < 6), W.name
    (True, True, True, 'W_m')
    """
    omega = check_frequencies(omega)
    env = check_finite_array("envelope", envelope, ndim=1)
    if env.shape != omega.shape:
        raise ValueError(f"envelope must have the shape of omega {omega.shape}, got {env.shape}")
    if np.any(env <= 0):
        raise ValueError("envelope must be positive on the grid")
    order = check_integer("order", order, minimum=1)
    starts = check_integer("starts", starts, minimum=1)
    max_iter = check_integer("max_iter", max_iter, minimum=1)
    full_omega, full_env = omega, env
    keep = _fit_points(env, fit_points)
    omega, env = omega[keep], env[keep]
    log_omega, log_env = np.log(omega), np.log(env)
    # the gain only shifts log|W| - log E: the shape fit runs on the sections alone
    lower, upper = sos.parameter_bounds(
        order, (np.log(omega.min() / 100), np.log(omega.max() * 100)), tuple(np.log(_ZETA_RANGE)))
    lower, upper = lower[1:], upper[1:]

    def shape_residual(theta):
        l, J = _log_sections(theta, log_omega, order)
        l = l - log_env
        return l - l.mean(), J - J.mean(axis=0)

    best = None
    for theta0 in _initial_sections(omega, env, order, starts):
        theta0 = np.clip(theta0, lower + 1e-9, upper - 1e-9)
        ls = opt.least_squares(lambda th: shape_residual(th)[0], theta0,
                               jac=lambda th: shape_residual(th)[1],
                               bounds=(lower, upper), max_nfev=max_iter)
        theta = _minimax_sections(ls.x, log_omega, log_env, order, lower, upper, max_iter)
        l = _log_sections(theta, log_omega, order)[0] - log_env
        if best is None or np.ptp(l) < best[0]:
            best = (np.ptp(l), theta, l.min())
    best_range, theta, _ = best
    # second stage: least mean excess with the worst case held within 0.1 dB
    theta = _minimax_sections(theta, log_omega, log_env, order, lower, upper, max_iter,
                              cap=best_range + 0.1 * np.log(10) / 20)
    l_min = (_log_sections(theta, log_omega, order)[0] - log_env).min()
    W = sos.transfer_function(np.r_[-l_min, theta], order)
    # lift onto the full grid (the fit used a subset of it)
    shortfall = np.max(full_env / np.abs(np.ravel(W(1j * full_omega))))
    num, den = W.num[0][0] * max(1.0, shortfall) * (1 + 1e-12), W.den[0][0]
    return ct.tf(num, den, inputs=inputs, outputs=outputs, name=name)


def _log_sections(theta, log_omega, order):
    """log|W| of the unit-gain sections ``theta`` (the sos model without its
    gain entry) and its Jacobian."""
    value, J = sos.log_magnitude(np.r_[0.0, theta], log_omega, order, jacobian=True)
    return value, J[:, 1:]


def _fit_points(env, count):
    """Indices of about ``count`` evenly spaced grid points plus every local
    maximum of the envelope and its two neighbours."""
    count = check_integer("fit_points", count, minimum=10)
    picks = np.unique(np.linspace(0, env.size - 1, min(count, env.size)).round().astype(int))
    peaks, _ = find_peaks(env)
    peaks = peaks[np.argsort(env[peaks])[::-1][:max(10, count // 5)]]
    near = np.clip(np.r_[peaks - 1, peaks, peaks + 1], 0, env.size - 1)
    return np.union1d(picks, near)


def _initial_sections(omega, env, order, starts):
    """Starting section parameters (the sos layout without the gain entry).

    Inverse notches on the most prominent peaks of log E, neutral sections
    elsewhere and a first-order roll-off pole where E starts falling by at
    least 10 dB/decade.  The first start reads the peaks off E smoothed by a
    running maximum over +-5 % in frequency (a cluster of member resonances
    counts as one broad peak), the second off E itself (sharp peaks); further
    starts are deterministic random perturbations of the first.
    """
    log_w = np.log(omega)
    log_env = np.log(env)
    step = np.median(np.diff(log_w)) if omega.size > 1 else 1.0
    half = max(1, int(round(0.05 / step)))
    padded = np.pad(log_env, half, mode="edge")
    smooth = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1).max(axis=1)
    tail = []
    if order % 2:
        slope = np.gradient(log_env, log_w) if omega.size > 2 else np.zeros(omega.size)
        k = omega.size
        while k > 0 and slope[k - 1] < -0.5:
            k -= 1
        w_p = omega[k] if k < omega.size else omega.max() * 50
        tail = [np.log(omega.max() * 50), np.log(w_p)]
    spots = np.geomspace(omega.min(), omega.max(), order // 2 + 2)[1:-1]

    def from_peaks(curve):
        peaks, props = find_peaks(curve, prominence=0.1)
        widths = peak_widths(curve, peaks, rel_height=0.5)[0] if peaks.size else np.array([])
        by_prominence = np.argsort(props["prominences"])[::-1]
        theta = []
        for j in range(order // 2):
            if j < by_prominence.size:
                k = by_prominence[j]
                w0, height = omega[peaks[k]], np.exp(props["prominences"][k])
                zeta_p = float(np.clip(0.5 * np.expm1(widths[k] * step), 1e-4, 1.0))
                zeta_z = float(np.clip(zeta_p * height, 1e-3, 50.0))
                theta += [np.log(w0), np.log(zeta_z), np.log(w0), np.log(zeta_p)]
            else:
                theta += [np.log(spots[j]), np.log(0.7), np.log(spots[j]), np.log(0.7)]
        return np.array(theta + tail)

    first = from_peaks(smooth)
    candidates = [first, from_peaks(log_env)]
    rng = np.random.default_rng(0)
    candidates += [first + rng.normal(scale=0.3, size=first.size) for _ in range(starts - 2)]
    return candidates[:starts]


def _minimax_sections(theta, log_omega, log_env, order, lower, upper, max_iter, cap=None):
    """Sequential linear programming on l = log|W| - log E over the grid.

    With ``cap=None``: minimise the range max l - min l (the worst excess
    after the lift) -- the classical Osborne-Watson trust-region scheme for
    minimax fits.  With a ``cap``: minimise the mean excess mean(l) - min(l)
    while keeping the range below ``cap``.  Each step solves the LP of the
    linearisation l + J step inside a box |step| <= radius; a step is kept
    when the true merit improves.
    """
    n = theta.size
    ones, zeros = np.ones((log_omega.size, 1)), np.zeros((log_omega.size, 1))

    def merit(l):
        if cap is None:
            return np.ptp(l)
        return l.mean() - l.min() if np.ptp(l) <= cap else np.inf

    l, J = _log_sections(theta, log_omega, order)
    l = l - log_env
    radius = 0.5
    for _ in range(max_iter):
        # variables [step, lo, hi]: lo <= l + J step <= hi
        A_ub = np.vstack([np.hstack([-J, ones, zeros]), np.hstack([J, zeros, -ones])])
        b_ub = np.r_[l, -l]
        if cap is None:
            cost = np.r_[np.zeros(n), -1.0, 1.0]
        else:
            cost = np.r_[J.mean(axis=0), -1.0, 0.0]
            A_ub = np.vstack([A_ub, np.r_[np.zeros(n), -1.0, 1.0]])
            b_ub = np.r_[b_ub, cap]
        step_bounds = [(max(-radius, lo_ - t), min(radius, hi_ - t))
                       for t, lo_, hi_ in zip(theta, lower, upper)]
        res = opt.linprog(cost, A_ub=A_ub, b_ub=b_ub, method="highs",
                          bounds=step_bounds + [(None, None)] * 2)
        if res.status != 0:
            break
        if cap is None:
            predicted = np.ptp(l) - (res.x[n + 1] - res.x[n])
        else:
            predicted = merit(l) - (l.mean() + J.mean(axis=0) @ res.x[:n] - res.x[n])
        trial = theta + res.x[:n]
        l_new, J_new = _log_sections(trial, log_omega, order)
        l_new = l_new - log_env
        actual = merit(l) - merit(l_new)
        if actual > 0 and predicted > 0:
            theta, l, J = trial, l_new, J_new
            if actual > 0.75 * predicted:
                radius = min(2 * radius, 4.0)
            elif actual < 0.25 * predicted:
                radius /= 2
        else:
            radius /= 4
        if radius < 1e-4 or predicted < 1e-5:     # 1e-5 in log = 1e-4 dB
            break
    return theta
