"""Robust-stability margins of a loop against the real coefficient perturbations of its plant.

The exact parametric margin (zero exclusion over the box of spread delta) and
what the complex, small-gain view certifies for comparison.  The method is
described in ``docs/uncertainty.md``.
"""

from collections import namedtuple

import control as ct
import numpy as np
import numpy.polynomial.polynomial as npoly
import scipy.optimize as opt

from piezolib._checks import (check_bisection_tol, check_continuous, check_finite_array,
                              check_finite_lti, check_nonnegative, check_positive, check_proper, check_siso,
                              check_stable)
from piezolib import robust
from piezolib.uncertainty.envelope import (SpreadBracket, largest_covered_spread,
                                           relative_error_bound)
from piezolib.uncertainty.polynomials import (check_frequencies, check_plant, loop_polynomials,
                                              rectangle_half_widths)

__all__ = ["ParametricMargin", "stability_gauge", "parametric_stability_margin",
           "small_gain_spread", "weight_certified_spread"]

ParametricMargin = namedtuple("ParametricMargin", [
    "spread", "omega", "offsets", "nominal_stable", "bounded", "spread_max"])
ParametricMargin.__doc__ = """Result of :func:`parametric_stability_margin`.

spread : float
    delta*: every member of the box with spread < delta* is stable, and the
    member ``offsets`` at spread delta* has a pole at +-j ``omega``
    (``spread_max`` when ``bounded`` is False; 0 when the nominal loop is
    unstable).
omega : float
    Critical frequency [rad/s] (nan when not bounded or nominal unstable).
offsets : ndarray
    Normalised offsets q (in [-1, 1]) of a critical member.
nominal_stable : bool
bounded : bool
    False when delta* exceeds ``spread_max`` (the search stops there).
spread_max : float
"""


def stability_gauge(G, K, omega):
    """Smallest spread at which the value set of the closed loop contains 0, at each frequency.

    With h = a + b K the gauge is max(|Re h|/R, |Im h|/I), R and I the
    half-widths of the perturbation rectangle (derivation in
    ``docs/uncertainty.md``).

    Parameters
    ----------
    G : control.LTI
        SISO proper plant.
    K : control.LTI or None
        SISO proper controller; ``None`` for the open loop (K = 0).
    omega : array_like
        Frequencies [rad/s] (>= 0).

    Returns
    -------
    ndarray
        Gauge [-] on the grid.
    """
    polys = loop_polynomials(G, K)
    omega = check_finite_array("omega", omega, ndim=1, min_length=1, real=True)
    if np.any(omega < 0):
        raise ValueError("omega must be non-negative")
    return _gauge(polys, omega / polys.ws)


def parametric_stability_margin(G, K=None, spread_max=1.0, omega=None, *, delay=0.0):
    """Exact largest spread for which every member of the box is stable.

    Zero exclusion: delta* is the minimum over omega >= 0 of
    :func:`stability_gauge`, located exactly among the real roots of four
    polynomials and a dense grid, then polished (``docs/uncertainty.md``).
    A critical member (q on the boundary of the box) is returned; its closed
    loop has poles at +-j omega*.

    With a loop delay tau (``delay`` > 0) the characteristic function is the
    quasi-polynomial a d + b n e^{-s tau}; zero exclusion still holds (the
    delay term is fixed, the box enters only a), but its minimum is located on
    the dense grid only (no polynomial roots) before polishing, and nominal
    stability is checked on the loop with a 12th-order Pade approximation of
    the delay (accurate to 1e-6 in phase up to omega tau = 6).

    Parameters
    ----------
    G : control.LTI
        SISO proper plant.
    K : control.LTI or None
        SISO proper controller; ``None`` gives the open-loop margin (the
        largest spread with every member of the box stable).
    spread_max : float
        Upper end of the search; the result is reported as unbounded beyond it.
    omega : array_like, optional
        Extra grid [rad/s] for the polishing step; default 1e-4 ... 1e4 times
        the plant's frequency scale, 4000 points (16000 with a delay).
    delay : float, optional
        Loop delay tau [s] (>= 0) between the controller and the plant, e.g.
        (d + 1/2) / fs for a sampled loop with d samples of computation delay.

    Returns
    -------
    ParametricMargin

    Examples
    --------
    Open-loop margin of 1/(s^3 + 2 s^2 + 2 s + 1): the box loses stability when
    a2 a1 = a0, i.e. 4 (1 - d)^2 = 1 + d, d = (9 - sqrt(33)) / 8.

    >>> m = parametric_stability_margin(ct.tf([1], [1, 2, 2, 1]))
    >>> round(m.spread, 4), round((9 - 33 ** 0.5) / 8, 4), m.offsets, m.bounded
    (0.4069, 0.4069, array([ 1., -1., -1.]), True)
    """
    polys = loop_polynomials(G, K)
    spread_max = check_positive("spread_max", spread_max)
    delay = check_nonnegative("delay", delay)
    if delay > 0 and K is None:
        raise ValueError("delay needs a controller K (the open loop has no loop delay)")
    tau = delay * polys.ws                               # in scaled time
    n = len(polys.a) - 1
    if not _nominally_stable(polys, G, K, delay):
        return ParametricMargin(0.0, float("nan"), np.zeros(n), False, True, spread_max)
    span = (-4, 4, 4000) if tau == 0 else (-4, 4, 16000)
    if omega is None:
        w_grid = np.r_[0.0, np.logspace(*span)]
    else:
        w_grid = np.r_[0.0, check_finite_array("omega", omega, ndim=1) / polys.ws]
    candidates = np.r_[w_grid, _critical_frequencies(polys)] if tau == 0 else w_grid
    values = _gauge(polys, candidates, tau)
    order = np.argsort(values)[:12]
    best_w, best = candidates[order[0]], values[order[0]]
    for w0 in candidates[order]:
        if w0 <= 0:
            continue
        res = opt.minimize_scalar(lambda lw: _gauge(polys, np.array([np.exp(lw)]), tau)[0],
                                  bounds=(np.log(w0) - 5e-3, np.log(w0) + 5e-3),
                                  method="bounded", options={"xatol": 1e-12})
        if res.fun < best:
            best, best_w = float(res.fun), float(np.exp(res.x))
    if best > spread_max:
        return ParametricMargin(spread_max, float("nan"), np.zeros(n), True, False, spread_max)
    return ParametricMargin(float(best), float(best_w * polys.ws),
                            _critical_offsets(polys, best_w, best, tau), True, True, spread_max)


#: Order of the Pade approximation of the loop delay in the nominal-stability check.
_PADE_ORDER = 12


#: A delay whose phase stays below this [rad] up to the loop's fastest pole or zero moves no
#: closed-loop pole beyond rounding: the loop is judged without it (see _nominally_stable).
_NEGLIGIBLE_DELAY_PHASE = 1e-6


def _nominally_stable(polys, G, K, delay):
    """Nominal closed loop stable (with the delay as a 12th-order Pade approximation).

    A delay far below every time constant of the loop (phase below
    :data:`_NEGLIGIBLE_DELAY_PHASE` at its fastest pole or zero) is a singular
    perturbation: the loop's poles are those without it, plus fast poles that
    are stable exactly when |L(j inf)| < 1.  The Pade polynomial of such a delay
    would span hundreds of decades (its roots lost to rounding), so that case is
    decided without it.
    """
    if delay == 0:
        return bool(np.all(npoly.polyroots(polys.c0).real < 0))
    loop_num = np.trim_zeros(npoly.polymul(polys.b, polys.n), "b")
    loop_den = np.trim_zeros(npoly.polymul(polys.a, polys.d), "b")
    corners = np.abs(np.r_[npoly.polyroots(loop_num), npoly.polyroots(loop_den)])
    fastest = corners.max() if corners.size else 1.0            # scaled rad/s
    if delay * polys.ws * max(fastest, 1.0) < _NEGLIGIBLE_DELAY_PHASE:
        gain_at_infinity = (abs(loop_num[-1] / loop_den[-1]) if loop_num.size == loop_den.size
                            else 0.0)
        return bool(gain_at_infinity < 1 and np.all(npoly.polyroots(polys.c0).real < 0))
    num, den = ct.pade(delay * polys.ws, _PADE_ORDER)
    pade_num, pade_den = np.asarray(num, float)[::-1], np.asarray(den, float)[::-1]
    c = npoly.polyadd(npoly.polymul(npoly.polymul(polys.a, polys.d), pade_den),
                      npoly.polymul(npoly.polymul(polys.b, polys.n), pade_num))
    c = np.trim_zeros(c, "b")
    return bool(np.all(npoly.polyroots(c / np.abs(c).max()).real < 0))


def small_gain_spread(G, K, omega, rtol=1e-4):
    """Largest spread certified by the complex (small-gain) view, with no rational weight.

    The box is treated as multiplicative complex uncertainty bounded pointwise
    by its exact envelope (:func:`~piezolib.uncertainty.envelope.relative_error_bound`);
    a spread is certified when max_omega E(omega) |T(j omega)| < 1 and every
    member is open-loop stable.  Bisection on [0, open-loop margin].

    Parameters
    ----------
    G : control.LTI
        SISO proper plant.
    K : control.LTI
        SISO proper controller (required: the certificate is about a closed loop).
    omega : array_like
        Grid [rad/s]; the peak of E |T| is refined off the grid near its
        grid maximum.
    rtol : float, optional
        Relative width of the final bracket.

    Returns
    -------
    SpreadBracket
        ``upper`` is the first spread found to fail (or the open-loop margin).
    """
    G = check_plant(G)
    _check_controller(K)
    omega = check_frequencies(omega)
    rtol = check_bisection_tol("rtol", rtol)
    if not robust.is_stable(G, K):
        return SpreadBracket(0.0, 0.0, 0.0, True)
    T = robust.loop_functions(G, K).T
    t_mag = np.abs(np.ravel(T(1j * omega)))
    open_loop = parametric_stability_margin(G, None)

    def certified(spread):
        E_T = relative_error_bound(G, spread, omega) * t_mag
        k = int(np.argmax(E_T))
        peak = E_T[k]
        if np.isfinite(peak) and 0 < k < omega.size - 1:
            res = opt.minimize_scalar(
                lambda lw: -(relative_error_bound(G, spread, np.exp([lw]))[0]
                             * np.abs(np.ravel(T(1j * np.exp(lw))))[0]),
                bounds=(np.log(omega[k - 1]), np.log(omega[k + 1])), method="bounded")
            peak = max(peak, -res.fun)
        return bool(peak < 1.0)

    hi = open_loop.spread if open_loop.bounded else open_loop.spread_max
    lo = 0.0
    if certified(hi * (1 - 1e-9)):
        return SpreadBracket(hi, hi, hi, open_loop.bounded)
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if certified(mid) else (lo, mid)
    return SpreadBracket(lo, lo, hi, True)


def weight_certified_spread(weight, G, K, omega, rtol=1e-3):
    """Spread certified by a rational weight W with the small-gain test.

    W certifies the box of spread delta when ||W T||_inf < 1 and |W| covers
    the exact box envelope (which implies every member is open-loop stable).

    Parameters
    ----------
    weight : control.LTI
        SISO proper multiplicative weight.
    G, K : control.LTI
        Plant and controller (both required).
    omega : array_like
        Grid [rad/s] of the coverage test.
    rtol : float, optional
        Relative width of the final bracket.

    Returns
    -------
    norm_WT : float
        ||W T||_inf.
    bracket : SpreadBracket
        Largest spread covered (spread 0 when ||W T||_inf >= 1).
    """
    check_siso("weight", weight)
    check_finite_lti("weight", weight)
    check_proper("weight", weight)
    check_continuous("weight", weight)
    check_stable("weight", weight)
    G = check_plant(G)
    _check_controller(K)
    T = robust.loop_functions(G, K).T
    norm, _ = robust.hinf_norm(ct.ss(weight) * T)
    if norm >= 1:
        return float(norm), SpreadBracket(0.0, 0.0, 0.0, True)
    return float(norm), largest_covered_spread(weight, G, omega, levels=None, rtol=rtol,
                                               spread_max=0.99)


# --- internals -----------------------------------------------------------------
def _check_controller(K):
    if K is None:
        raise TypeError("K is required: the certificate is about a closed loop")
    check_siso("K", K)
    check_proper("K", K)


def _jw_parts(c):
    """Real polynomials (low first) with c(j w) = re(w) + j im(w)."""
    k = np.arange(len(c))
    unit = 1j ** k
    return c * np.round(unit.real), c * np.round(unit.imag)


def _gauge_polynomials(polys):
    cr, ci = _jw_parts(polys.c0)
    dr, di = _jw_parts(polys.d)
    U = npoly.polyadd(npoly.polymul(cr, dr), npoly.polymul(ci, di))
    V = npoly.polysub(npoly.polymul(ci, dr), npoly.polymul(cr, di))
    D2 = npoly.polyadd(npoly.polymul(dr, dr), npoly.polymul(di, di))
    absa = np.abs(polys.a[:-1])
    R = absa * (np.arange(len(absa)) % 2 == 0)
    I = absa * (np.arange(len(absa)) % 2 == 1)
    return U, V, npoly.polymul(R, D2), npoly.polymul(I, D2)


def _gauge(polys, w, tau=0.0):
    if tau > 0:
        h = _delayed_h(polys, w, tau)
        R, I = rectangle_half_widths(polys.a[:-1], w)
        return np.maximum(_ratio(h.real, R), _ratio(h.imag, I))
    U, V, rho, iota = (npoly.polyval(w, p) for p in _gauge_polynomials(polys))
    return np.maximum(_ratio(U, rho), _ratio(V, iota))


def _ratio(value, width):
    """|value| / width, inf where the width is 0 and the value not, 0 where both are."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(width > 0, np.abs(value) / width,
                        np.where(np.abs(value) > 0, np.inf, 0.0))


def _critical_frequencies(polys):
    """Real positive roots of the polynomials whose roots hold the gauge's minimum."""
    U, V, rho, iota = _gauge_polynomials(polys)
    der = npoly.polyder
    candidates = [
        npoly.polysub(npoly.polymul(der(U), rho), npoly.polymul(U, der(rho))),
        npoly.polysub(npoly.polymul(der(V), iota), npoly.polymul(V, der(iota))),
        npoly.polysub(npoly.polymul(U, iota), npoly.polymul(V, rho)),
        npoly.polyadd(npoly.polymul(U, iota), npoly.polymul(V, rho)),
    ]
    roots = []
    for p in candidates:
        p = np.trim_zeros(p, "b")
        if p.size > 1:
            r = npoly.polyroots(p / np.abs(p).max())
            keep = (np.abs(r.imag) <= 1e-3 * np.maximum(np.abs(r), 1e-12)) & (r.real > 0)
            roots.append(r.real[keep])
    return np.concatenate(roots) if roots else np.array([])


def _delayed_h(polys, w, tau):
    """a + b (n / d) e^{-j w tau} at the scaled frequencies w (the nominal value the box shifts)."""
    s = 1j * np.asarray(w, float)
    return (npoly.polyval(s, polys.a) + npoly.polyval(s, polys.b) * npoly.polyval(s, polys.n)
            / npoly.polyval(s, polys.d) * np.exp(-s * tau))


def _critical_offsets(polys, w, spread, tau=0.0):
    """Offsets q in the box putting a root of c at j w for the given spread."""
    if tau > 0:
        h = _delayed_h(polys, np.array([w]), tau)[0]
    else:
        h = npoly.polyval(1j * w, polys.c0) / npoly.polyval(1j * w, polys.d)
    R, I = rectangle_half_widths(polys.a[:-1], np.array([w]))
    x = -h.real / (spread * R[0]) if R[0] > 0 else 0.0
    y = -h.imag / (spread * I[0]) if I[0] > 0 else 0.0
    k = np.arange(len(polys.a) - 1)
    unit = 1j ** k
    # sum_i q_i a_i (j w)^i = spread^-1 * (-h): even terms real, odd imaginary
    sign = np.sign(polys.a[:-1]) * np.where(k % 2 == 0, np.round(unit.real), np.round(unit.imag))
    q = np.where(k % 2 == 0, np.clip(x, -1, 1), np.clip(y, -1, 1)) * sign
    return q
