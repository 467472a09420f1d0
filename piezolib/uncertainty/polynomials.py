"""Polynomial arithmetic of the coefficient-perturbation model, shared by the uncertainty modules.

Coefficient arrays are ordered lowest power first.  The plant's polynomials
are evaluated in scaled frequency p = s / omega_s with omega_s from
:func:`coefficient_scale`, which turns coefficients as large as 1e23 into
numbers of order one.  See ``docs/uncertainty.md`` for the conventions.
"""

from collections import namedtuple

import control as ct
import numpy as np
import numpy.polynomial.polynomial as npoly

from piezolib._checks import (check_finite_array, check_finite_lti, check_positive, check_proper,
                              check_siso)

__all__ = [
    "check_plant", "check_spread", "check_frequencies", "plant_polynomials",
    "coefficient_scale", "scale_coefficients", "jw_powers", "batched_roots",
    "rectangle_half_widths", "LoopPolynomials", "loop_polynomials",
]


def check_plant(G, name="G"):
    """Return ``G`` as a continuous-time SISO proper transfer function with a pole.

    Raises
    ------
    TypeError
        ``G`` is not a python-control LTI system.
    ValueError
        ``G`` is not SISO, not proper, discrete-time, or has no pole.
    """
    check_siso(name, G)
    check_finite_lti(name, G)
    check_proper(name, G)
    if not isinstance(G, ct.TransferFunction):
        G = ct.tf(G)
    if not G.isctime(strict=False):
        raise ValueError(f"{name} must be a continuous-time model")
    a, _ = plant_polynomials(G)
    if len(a) < 2:
        raise ValueError(f"{name} must have at least one pole (denominator degree >= 1)")
    return G


def check_spread(spread, name="spread"):
    """Return ``spread`` as a float after checking 0 < spread < 1 (a relative spread)."""
    spread = check_positive(name, spread)
    if spread >= 1:
        raise ValueError(f"{name} must be below 1 (a relative spread), got {spread}")
    return spread


def check_frequencies(omega, name="omega"):
    """Return ``omega`` as a 1-D float array of positive frequencies [rad/s]."""
    omega = check_finite_array(name, omega, ndim=1, min_length=1, real=True)
    if np.any(omega <= 0):
        raise ValueError(f"{name} must be positive [rad/s]")
    return omega


def plant_polynomials(G):
    """Denominator a and numerator b of SISO ``G``, lowest power first, a monic.

    Returns
    -------
    a, b : ndarray
    """
    num = np.trim_zeros(np.atleast_1d(np.asarray(G.num[0][0], dtype=float)), "f")
    den = np.trim_zeros(np.atleast_1d(np.asarray(G.den[0][0], dtype=float)), "f")
    if num.size == 0:
        num = np.zeros(1)
    return den[::-1] / den[0], num[::-1] / den[0]


def coefficient_scale(a):
    """Frequency scale [rad/s] of the monic polynomial ``a`` (lowest power first).

    max_k |a_k|^(1/(n-k)): a bound of the root magnitudes taken from the
    coefficients themselves (no realisation needed), so that the coefficients
    of a(omega_s p) / omega_s^n are at most one in magnitude.
    """
    n = len(a) - 1
    mags = [abs(a[k]) ** (1.0 / (n - k)) for k in range(n) if a[k] != 0]
    return max(mags) if mags else 1.0


def scale_coefficients(c, omega_s, degree):
    """Coefficients (lowest first, along the last axis) of c(omega_s p) / omega_s**degree."""
    c = np.asarray(c, dtype=float)
    return c * omega_s ** (np.arange(c.shape[-1]) - degree)


def jw_powers(w, columns):
    """(len(w), columns) matrix of (j w)^k, k = 0 ... columns-1 (w in scaled frequency)."""
    return (1j * np.asarray(w, dtype=float))[:, None] ** np.arange(columns)


def batched_roots(low):
    """Roots of each row of an (M, m+1) coefficient array (lowest power first).

    One batched eigenvalue call on the M companion matrices.

    Returns
    -------
    ndarray, shape (M, m), complex
    """
    low = low / low[:, -1:]
    m = low.shape[1] - 1
    comp = np.zeros((low.shape[0], m, m))
    comp[:, 0, :] = -low[:, m - 1::-1]
    comp[:, 1:, :-1] = np.eye(m - 1)
    return np.linalg.eigvals(comp)


def rectangle_half_widths(a_scaled, w):
    """Half-widths R(w) = sum_even |a_i| w^i and I(w) = sum_odd |a_i| w^i.

    sum_i q_i a_i (j w)^i over the box q in [-1, 1]^n fills the axis-parallel
    rectangle [-R, R] x [-I, I] of the complex plane.
    """
    powers = np.asarray(w, dtype=float)[:, None] ** np.arange(len(a_scaled))
    terms = np.abs(a_scaled) * powers
    return terms[:, 0::2].sum(axis=1), terms[:, 1::2].sum(axis=1)


LoopPolynomials = namedtuple("LoopPolynomials", ["a", "b", "n", "d", "c0", "ws"])
LoopPolynomials.__doc__ = """Scaled polynomials of the loop of G = b/a and K = n/d.

Returned by :func:`loop_polynomials`.

a, b, n, d : ndarray
    Plant and controller polynomials in scaled frequency, lowest power first
    (a and d monic before scaling).
c0 : ndarray
    Nominal closed-loop characteristic polynomial a d + b n (scaled).
ws : float
    The frequency scale [rad/s] (:func:`coefficient_scale` of a).
"""


def loop_polynomials(G, K):
    """Scaled polynomials of the loop of plant ``G`` and controller ``K``.

    Parameters
    ----------
    G : control.LTI
        SISO proper plant.
    K : control.LTI or None
        SISO proper controller; ``None`` for the open loop (K = 0).

    Returns
    -------
    LoopPolynomials

    Raises
    ------
    ValueError
        When 1 + G K vanishes at infinity (the closed loop loses its degree).
    """
    G = check_plant(G)
    a, b = plant_polynomials(G)
    if K is None:
        n_k, d_k = np.zeros(1), np.ones(1)
    else:
        n_k, d_k = _controller_polynomials(K)
    ws = coefficient_scale(a)
    deg = len(a) - 1 + len(d_k) - 1
    a_s, b_s = scale_coefficients(a, ws, len(a) - 1), scale_coefficients(b, ws, len(a) - 1)
    n_s, d_s = scale_coefficients(n_k, ws, len(d_k) - 1), scale_coefficients(d_k, ws, len(d_k) - 1)
    c0 = npoly.polyadd(npoly.polymul(a_s, d_s), npoly.polymul(b_s, n_s))
    c0 = np.r_[c0, np.zeros(deg + 1 - len(c0))]
    if c0[deg] == 0:
        raise ValueError("the closed-loop characteristic polynomial loses its degree "
                         "(1 + G K vanishes at infinity)")
    return LoopPolynomials(a=a_s, b=b_s, n=n_s, d=d_s, c0=c0, ws=ws)


def _controller_polynomials(K):
    """(n, d) of K, lowest power first, d monic."""
    check_siso("K", K)
    check_finite_lti("K", K)
    check_proper("K", K)
    if not K.isctime(strict=False):
        raise ValueError("K must be a continuous-time model")
    K = K if isinstance(K, ct.TransferFunction) else ct.tf(K)
    return plant_polynomials(K)[::-1]
