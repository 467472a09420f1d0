"""Stable, minimum-phase rational fits of magnitude data (the D-step of DK-iteration).

The D-scalings of the mu upper bound are positive numbers d(omega) known on a
frequency grid; only their magnitude matters (a phase factor is a unitary
scaling that leaves sigma_max unchanged).  DK-iteration needs them as stable,
minimum-phase, biproper transfer functions d(s) so that both d(s) and 1/d(s)
can multiply the plant.

:func:`fit_magnitude` fits log|d(j omega)| by weighted nonlinear least squares
over the gain-and-sections model of :mod:`piezolib.robust.sos` (logarithms of
the gain, the section frequencies and dampings), so every parameter value is a
stable, minimum-phase model and no projection is needed.  The fit is
deterministic (fixed starts, ``scipy.optimize.least_squares`` with the
model's analytic Jacobian).  The problem is not convex: three deterministic
starts (plus a warm start from the previous DK iteration) are tried and the
best is kept, which recovers known functions exactly in the tests but can
still end in a local minimum on awkward data.
(SLICOT SB10YD fits complex data, which would first need a phase from the
Bode gain-phase relation; fitting the magnitude directly avoids that.)
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.optimize as opt

from piezolib._checks import check_finite_array, check_integer, check_same_length
from piezolib.robust import sos

__all__ = ["MagnitudeFit", "fit_magnitude"]

_ZETA_BOUNDS = (0.03, 30.0)


@dataclass(frozen=True)
class MagnitudeFit:
    """A stable minimum-phase fit of magnitude data.

    Attributes
    ----------
    tf : control.TransferFunction
        The fitted d(s), biproper, stable and minimum phase.
    order : int
        Its order.
    rms_log_error : float
        Weighted RMS of log|d_fit| - log|d| (natural log).
    max_log_error : float
        Largest |log|d_fit| - log|d|| on the grid.
    parameters : ndarray
        ``theta`` of :mod:`piezolib.robust.sos` (log gain, log section
        frequencies and dampings); a warm start for the next fit.

    Examples
    --------
    >>> w = np.logspace(-1, 2, 40)
    >>> f = fit_magnitude(w, np.abs(10 * (1j * w + 1) / (1j * w + 10)), order=1)
    >>> f.order, bool(f.max_log_error < 1e-6), f.parameters.shape
    (1, True, (3,))
    """

    tf: ct.TransferFunction
    order: int
    rms_log_error: float
    max_log_error: float
    parameters: np.ndarray


def _starts(logw, order, logk, n_starts):
    lo, hi = logw.min(), logw.max()
    starts = []
    for j in range(n_starts):
        # section frequencies spread over the grid; each start shifts them
        n_sec = order // 2 + order % 2
        frac = (np.arange(n_sec) + 0.5 + 0.3 * (j - (n_starts - 1) / 2)) / max(n_sec, 1)
        centres = lo + np.clip(frac, 0.02, 0.98) * (hi - lo)
        theta = [logk]
        for c in centres[:order // 2]:
            theta += [c, np.log(0.7), c + 0.05, np.log(0.7)]
        if order % 2:
            theta += [centres[-1], centres[-1] + 0.05]
        starts.append(np.array(theta))
    return starts


def fit_magnitude(omega, magnitude, order, weight=None, *, n_starts=3, initial=None):
    """Fit a stable minimum-phase biproper d(s) of ``order`` to |d(j omega)|.

    Parameters
    ----------
    omega : array_like
        Frequencies [rad/s] (any consistent unit: the fit is in the same one).
    magnitude : array_like
        Positive magnitudes |d(j omega)|.
    order : int
        Order of d(s) (0 gives the best constant).
    weight : array_like, optional
        Non-negative weights of the log-magnitude residuals (default 1).
    n_starts : int, optional
        Deterministic starting points tried; the best fit is kept.
    initial : MagnitudeFit, optional
        A previous fit of the same order, used as an extra start.

    Returns
    -------
    MagnitudeFit

    Examples
    --------
    >>> w = np.logspace(-1, 2, 40)
    >>> d = np.abs(10 * (1j * w + 1) / (1j * w + 10))          # |d| of 10 (s + 1) / (s + 10)
    >>> f = fit_magnitude(w, d, order=1)
    >>> f.tf.num[0][0].round(4), f.tf.den[0][0].round(4)
    (array([10., 10.]), array([ 1., 10.]))
    """
    omega = check_finite_array("omega", omega, ndim=1, min_length=2, real=True)
    magnitude = check_finite_array("magnitude", magnitude, ndim=1, real=True)
    check_same_length(omega=omega, magnitude=magnitude)
    if np.any(omega <= 0):
        raise ValueError("omega must be positive")
    if np.any(magnitude <= 0):
        raise ValueError("magnitude must be positive")
    order = check_integer("order", order, minimum=0)
    n_starts = check_integer("n_starts", n_starts, minimum=1)
    if weight is None:
        weight = np.ones_like(omega)
    weight = check_finite_array("weight", weight, ndim=1, real=True)
    check_same_length(omega=omega, weight=weight)
    if np.any(weight < 0) or not np.any(weight > 0):
        raise ValueError("weight must be non-negative and not all zero")
    logw, target = np.log(omega), np.log(magnitude)
    sw = np.sqrt(weight / weight.sum())
    logk = float(np.sum(weight * target) / weight.sum())
    if order == 0:
        theta = np.array([logk])
    else:
        if 2 * order + 1 > omega.size:
            raise ValueError(f"order {order} needs at least {2 * order + 1} frequencies")
        lower, upper = sos.parameter_bounds(
            order, (logw.min() - np.log(10), logw.max() + np.log(10)),
            (np.log(_ZETA_BOUNDS[0]), np.log(_ZETA_BOUNDS[1])))
        starts = _starts(logw, order, logk, n_starts)
        if initial is not None and initial.order == order:
            starts.append(np.asarray(initial.parameters, float))
        best = None
        for start in starts:
            start = np.clip(start, lower + 1e-9, upper - 1e-9)
            res = opt.least_squares(
                lambda th: sw * (sos.log_magnitude(th, logw, order) - target), start,
                jac=lambda th: sw[:, None] * sos.log_magnitude(th, logw, order, jacobian=True)[1],
                bounds=(lower, upper), method="trf", x_scale="jac", max_nfev=100 * (order + 1))
            if best is None or res.cost < best.cost:
                best = res
        theta = best.x
    err = sos.log_magnitude(theta, logw, order) - target
    return MagnitudeFit(tf=sos.transfer_function(theta, order), order=order,
                        rms_log_error=float(np.sqrt(np.sum(sw ** 2 * err ** 2))),
                        max_log_error=float(np.max(np.abs(err))), parameters=theta)
