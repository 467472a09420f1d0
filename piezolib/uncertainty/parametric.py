"""Real parametric LFT of the denominator coefficients and the robust-stability margin by mu.

A member of the box of :mod:`piezolib.uncertainty.modelset` has denominator
a_i (1 + spread q_i), q_i real in [-1, 1].  Here the box is written as an
upper LFT G_q = F_u(P, diag(q)) with one real 1 x 1 block per coefficient, so
that the toolkit's mixed mu (:func:`piezolib.robust.mu.mussv` with real blocks)
sees the uncertainty as it really is.  The derivation is in
:func:`parametric_lft`; with a controller the blocks see a rank-one matrix
(:func:`parametric_loop_response`), for which mu with real blocks equals
1 / :func:`~piezolib.uncertainty.margin.stability_gauge` (zero exclusion).
"""

from collections import namedtuple

import control as ct
import numpy as np

from piezolib._checks import check_positive
from piezolib.robust.lti import from_scaled
from piezolib.robust.mu import mussv
from piezolib.uncertainty.polynomials import (check_frequencies, check_plant, coefficient_scale,
                                              jw_powers, loop_polynomials, plant_polynomials,
                                              scale_coefficients)

__all__ = ["ParametricLFT", "parametric_lft", "parametric_response", "parametric_loop_response",
           "MuMargin", "mu_stability_margin"]

ParametricLFT = namedtuple("ParametricLFT", ["P", "blk", "spread", "time_scale"])
ParametricLFT.__doc__ = """Result of :func:`parametric_lft`.

P : control.StateSpace
    Inputs ``w_0 ... w_{n-1}`` then the plant input; outputs ``z_0 ... z_{n-1}``
    then the plant output (ordinary time).  F_u(P, diag(q)) is the member with
    offsets q.
blk : tuple of (int, int)
    ``n`` real scalar blocks ``(-1, 0)`` in MATLAB ``mussv`` convention.
spread : float
    Relative spread built into P (q in [-1, 1] covers +-spread).
time_scale : float
    Frequency scale omega_s [rad/s] the realisation was built in.
"""

MuMargin = namedtuple("MuMargin", ["spread", "spread_upper", "omega", "mu", "real"])
MuMargin.__doc__ = """Result of :func:`mu_stability_margin`.

spread : float
    Certified spread 1 / max_omega mu_upper: every member of the box of a
    smaller spread keeps the loop stable (for the structure analysed).
spread_upper : float
    1 / max_omega mu_lower: the box of this spread holds a destabilising
    member (inf when the lower bound is 0 everywhere).
omega : float
    Frequency [rad/s] of the upper-bound peak.
mu : piezolib.robust.mu.MuResult
    Bounds of mu at unit spread on the (refined) grid, sorted by frequency.
real : bool
    True when the coefficients were treated as real blocks, False as complex ones.
"""


def _coefficients(G):
    """Scaled (a, b) of G (lowest power first, a monic) and the frequency scale."""
    a, b = plant_polynomials(G)
    ws = coefficient_scale(a)
    n = len(a) - 1
    return scale_coefficients(a, ws, n), scale_coefficients(b, ws, n), ws


def _check_spread(spread):
    return check_positive("spread", spread)


def parametric_lft(G, spread, *, input_name=None, output_name=None, name="G_par"):
    """Upper LFT of G whose real scalar blocks are the denominator coefficients.

    With G = b(s)/a(s), a monic of degree n, the member with offsets q has
    a_q(s) = a(s) + spread sum_i q_i a_i s^i.  From a_q y = b u,

        y = G u + sum_i h_i w_i,   h_i = -spread a_i s^i / a(s),
        z_i = y,   w_i = q_i z_i,

    so F_u(P, diag(q)) = b / a_q for every real q (exactly, not to first
    order).  The realisation is the observable canonical form of the common
    denominator a (n states), built in scaled time s / omega_s and scaled back.

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper continuous-time plant.
    spread : float
        Relative spread (> 0) carried by P: q_i in [-1, 1] is +-spread on a_i.
    input_name, output_name : str, optional
        Names of the plant input and output (default: those of G).
    name : str, optional
        Name of P.

    Returns
    -------
    ParametricLFT

    Examples
    --------
    >>> import control as ct
    >>> lft = parametric_lft(ct.tf([2.0], [1.0, 3.0, 2.0]), 0.1)
    >>> lft.blk
    ((-1, 0), (-1, 0))
    """
    G = check_plant(G)
    spread = _check_spread(spread)
    a, b, ws = _coefficients(G)
    n = len(a) - 1
    b = np.r_[b, np.zeros(n + 1 - len(b))]
    d0 = b[n]                                  # feedthrough (a is monic)
    strict = b - d0 * a                        # numerator of G - d0, degree < n
    # observable canonical form: x_1 = y - d0 u, row j carries the s^(n-1-j) terms
    A = np.zeros((n, n))
    A[:, 0] = -a[n - 1::-1]
    A[:-1, 1:] = np.eye(n - 1)
    B_u = strict[n - 1::-1].reshape(n, 1)
    B_w = np.zeros((n, n))
    B_w[n - 1 - np.arange(n), np.arange(n)] = -spread * a[:n]
    C = np.zeros((n + 1, n))
    C[:, 0] = 1.0
    D = np.zeros((n + 1, n + 1))
    D[:, n] = d0
    u = input_name or G.input_labels[0]
    y = output_name or G.output_labels[0]
    inputs = [f"w_{i}" for i in range(n)] + [u]
    outputs = [f"z_{i}" for i in range(n)] + [y]
    Ps = ct.ss(A, np.hstack([B_w, B_u]), C, D)
    P = from_scaled(Ps, ws, inputs, outputs, name=name)
    return ParametricLFT(P=P, blk=((-1, 0),) * n, spread=spread, time_scale=ws)


def parametric_response(G, spread, omega):
    """Frequency response of the LFT of :func:`parametric_lft`, from the polynomials.

    Evaluated in scaled frequency without a realisation (an independent check
    of the state-space model).

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper plant.
    spread : float
        Relative spread (> 0).
    omega : array_like
        Frequencies [rad/s] (> 0).

    Returns
    -------
    ndarray, shape (nf, n+1, n+1)
        Outputs [z_0 ... z_{n-1}, y], inputs [w_0 ... w_{n-1}, u].
    """
    G = check_plant(G)
    spread = _check_spread(spread)
    omega = check_frequencies(omega)
    a, b, ws = _coefficients(G)
    n = len(a) - 1
    V = jw_powers(omega / ws, n + 1)
    den = V[:, :n + 1] @ a
    g = (V[:, :len(b)] @ b) / den
    h = -spread * a[:n] * V[:, :n] / den[:, None]
    row = np.hstack([h, g[:, None]])
    return np.repeat(row[:, None, :], n + 1, axis=1)


def parametric_loop_response(G, K, spread, omega):
    """The n x n matrix seen by the coefficient blocks when K closes the loop.

    For the loop u = -K y (K on the error r - y) the blocks see
    M(jw) = 1 m^T with m_i = h_i S = -spread a_i (jw)^i d / (a d + b n),
    where K = n/d and S = 1/(1 + G K); it has rank one.  Computed from the
    polynomials in scaled frequency.

    Parameters
    ----------
    G, K : control.LTI
        SISO proper plant and controller (continuous time).
    spread : float
        Relative spread (> 0); M is linear in it.
    omega : array_like
        Frequencies [rad/s] (> 0).

    Returns
    -------
    ndarray, shape (nf, n, n)
    """
    polys = loop_polynomials(G, K)
    spread = _check_spread(spread)
    omega = check_frequencies(omega)
    a, d, c0 = polys.a, polys.d, polys.c0
    n = len(a) - 1
    V = jw_powers(omega / polys.ws, max(len(c0), n + 1, len(d)))
    m = -spread * a[:n] * V[:, :n] * (V[:, :len(d)] @ d)[:, None] / (V[:, :len(c0)] @ c0)[:, None]
    return np.repeat(m[:, None, :], n, axis=1)


def mu_stability_margin(G, K, omega, *, real=True, lower=False, xatol=1e-9, peak=False):
    """Robust-stability margin of the loop (G, K) against the coefficient box, by mu.

    mu is computed at unit spread on :func:`parametric_loop_response` (M is
    linear in the spread, so mu_RS(spread) = spread mu(omega)).  The peak of
    the upper bound found on the grid is refined by a bounded scalar search
    in log-frequency within the neighbouring grid cells; the certified margin
    is 1 / (refined peak).  The lower bound at the refined peak frequency
    gives ``spread_upper`` (a destabilising member exists there).

    Parameters
    ----------
    G, K : control.LTI
        SISO plant and controller; K closes u = -K y.  The nominal loop must
        be stable (mu says nothing otherwise).
    omega : array_like
        Frequency grid [rad/s] (positive, increasing, at least 3 points).
    real : bool, optional
        Real blocks (mixed mu, the true structure) or complex ones.
    lower : bool, optional
        Also compute the lower bound on the whole grid (slower); otherwise
        ``mu.lower`` is 0 on the grid.
    xatol : float, optional
        Tolerance of the peak search in log10(omega).
    peak : bool, optional
        Bound the grid for its peak only (``mussv(..., peak=True)``): the margin is the
        same, ``mu`` holds valid bounds that are tight only where a frequency could set
        the peak.  Not with ``lower``.

    Returns
    -------
    MuMargin
        ``mu`` holds the grid bounds (unit spread).

    Raises
    ------
    ValueError
        Bad grid, or an unstable nominal loop.
    """
    import scipy.optimize as opt

    omega = check_frequencies(omega)
    if omega.size < 3 or np.any(np.diff(omega) <= 0):
        raise ValueError("omega must hold at least 3 increasing frequencies")
    if not isinstance(real, bool) or not isinstance(lower, bool) or not isinstance(peak, bool):
        raise TypeError("real, lower and peak must be True or False")
    if peak and lower:
        raise ValueError("peak=True bounds the peak only: it does not combine with lower=True")
    polys = loop_polynomials(G, K)
    if not np.all(np.roots(polys.c0[::-1]).real < 0):
        raise ValueError("the nominal loop (G, K) is unstable: no robust-stability margin")
    n = len(polys.a) - 1
    blk = [(-1, 0) if real else (1, 1)] * n

    def upper_at(w):
        return mussv(parametric_loop_response(G, K, 1.0, [w]), blk, lower=False).upper[0]

    mu = mussv(parametric_loop_response(G, K, 1.0, omega), blk, omega, lower=lower, peak=peak)
    k = int(np.argmax(mu.upper))
    lo, hi = np.log10(omega[max(k - 1, 0)]), np.log10(omega[min(k + 1, omega.size - 1)])
    found = opt.minimize_scalar(lambda x: -upper_at(10 ** x), bounds=(lo, hi),
                                method="bounded", options={"xatol": xatol})
    w_peak, peak = (10 ** found.x, -found.fun) if -found.fun > mu.upper[k] else (omega[k],
                                                                                   mu.upper[k])
    at_peak = mussv(parametric_loop_response(G, K, 1.0, [w_peak]), blk)
    low = float(max(at_peak.lower[0], mu.lower.max()))
    return MuMargin(spread=1.0 / float(peak), spread_upper=np.inf if low == 0 else 1.0 / low,
                    omega=float(w_peak), mu=mu, real=real)
