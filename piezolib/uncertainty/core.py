"""Parametric uncertainty of the plant (paper Sec. III-B, eq. 5-8, Fig. 6).

The paper perturbs each denominator coefficient a_0 ... a_5 of G(s) (eq. 4)
by 0 and +-5 % and takes the relative error envelope

    E_m(omega) = max_k |G_k(j omega) / G(j omega) - 1|                 (eq. 7)

over the 3**6 = 729 models; the multiplicative weight H_m (eq. 8) must bound
it.  This module builds that set for any spread and level count, evaluates
all members at once, checks and fits covering weights, and computes the exact
robust-stability margin of a closed loop against the *real* coefficient
perturbations (zero exclusion), to compare with what the complex
multiplicative (small-gain / mu) view certifies.

Conventions
-----------
* A member of the set has denominator a_i (1 + spread * q_i), i < n, with the
  normalised offsets q_i in [-1, 1] (``levels`` equally spaced values); the
  leading s^n coefficient stays 1 and the numerator is untouched.
* "The box" is the continuous set q in [-1, 1]^n: the polytope whose
  vertices the 3-level grid contains.  Exact margins refer to the box.
* Frequencies are in rad/s.  Internally polynomials are evaluated in scaled
  frequency p = s / omega_s (omega_s near the plant's pole magnitudes), so the
  1e23 coefficients of the paper's plant become O(1) numbers.
"""

import itertools
from collections import namedtuple
from dataclasses import dataclass

import control as ct
import numpy as np
import numpy.polynomial.polynomial as npoly
import scipy.optimize as opt
from scipy.signal import find_peaks, peak_widths

from piezolib._checks import (check_finite_array, check_integer, check_positive,
                      check_proper, check_siso)
from piezolib import paper, robust

__all__ = [
    "ModelSet", "model_set", "level_offsets", "perturbed_plant", "set_response",
    "relative_errors",
    "member_poles", "member_closed_loop_poles", "unstable_members", "relative_error_envelope",
    "envelope_peak", "relative_error_bound", "Coverage", "coverage",
    "SpreadBracket", "largest_covered_spread", "fit_covering_weight",
    "ParametricMargin", "stability_gauge", "parametric_stability_margin",
    "small_gain_spread", "weight_certified_spread",
]

_MEMBERS = ("stable", "all")


# --- the parametric model set -------------------------------------------------
@dataclass(frozen=True, eq=False)
class ModelSet:
    """Models of G with perturbed denominator coefficients.

    Attributes
    ----------
    plant : control.TransferFunction
        The nominal model G (SISO, proper).
    spread : float
        Relative perturbation of each a_i (0.05 for +-5 %).
    levels : int
        Values per coefficient, equally spaced in [-spread, +spread].
    offsets : ndarray, shape (M, n)
        Normalised offsets q in [-1, 1]; column i perturbs a_i (s^i).
    """

    plant: ct.TransferFunction
    spread: float
    levels: int
    offsets: np.ndarray

    @property
    def size(self):
        """Number of models M = levels ** n."""
        return self.offsets.shape[0]

    @property
    def order(self):
        """Denominator degree n of the plant."""
        return self.offsets.shape[1]

    @property
    def denominators(self):
        """(M, n+1) denominator coefficients, highest power first, seconds."""
        return _member_coefficients(self)[:, ::-1]

    def member(self, k):
        """Member ``k`` as a transfer function named ``G_k`` (same signals as G)."""
        k = check_integer("k", k, minimum=0)
        if k >= self.size:
            raise ValueError(f"k must be < {self.size}, got {k}")
        return perturbed_plant(self.plant, self.spread, self.offsets[k], name=f"G_{k}")


def level_offsets(levels, n):
    """All ``levels**n`` combinations of ``levels`` values in [-1, 1].

    Returns an array of shape (levels**n, n); row 0 is all -1 and the rows
    run through the combinations in lexicographic order.
    """
    levels = check_integer("levels", levels, minimum=2)
    n = check_integer("n", n, minimum=1)
    values = np.linspace(-1.0, 1.0, levels)
    return np.array(list(itertools.product(values, repeat=n)), dtype=float)


def perturbed_plant(G, spread, offsets, name=None):
    """The member of G's box with normalised offsets q: denominator
    a_i (1 + spread q_i), i < n, same numerator and signals (e.g. the
    critical member of :func:`parametric_stability_margin`).

    Parameters
    ----------
    G : control.LTI or None
        Nominal SISO proper plant; ``None`` for the published plant.
    spread : float
        Relative spread, 0 < spread < 1.
    offsets : array_like, shape (n,)
        q_i in [-1, 1], lowest power first.
    name : str, optional
        Name of the returned model.

    Returns
    -------
    control.TransferFunction
    """
    G = _nominal(G)
    spread = _check_spread(spread)
    a, b = _plant_polynomials(G)
    q = check_finite_array("offsets", offsets, shape=(len(a) - 1,))
    if np.any(np.abs(q) > 1):
        raise ValueError("offsets must lie in [-1, 1]")
    den = np.r_[a[:-1] * (1 + spread * q), 1.0]
    return ct.tf(b[::-1], den[::-1], inputs=G.input_labels, outputs=G.output_labels,
                 name=name)


def model_set(G=None, spread=paper.UNCERTAINTY_SPREAD,
              levels=paper.UNCERTAINTY_LEVELS):
    """The parametric model set of Sec. III-B.

    Parameters
    ----------
    G : control.LTI, optional
        Nominal SISO proper model; default the published plant (eq. 4).
    spread : float, optional
        Relative spread of every denominator coefficient, 0 < spread < 1
        (default 0.05, the paper's +-5 %).
    levels : int, optional
        Values per coefficient, >= 2 (default 3: nominal and both extremes).

    Returns
    -------
    ModelSet
        ``levels ** n`` models, n = degree of G's denominator.
    """
    G = _nominal(G)
    spread = _check_spread(spread)
    a, _ = _plant_polynomials(G)
    return ModelSet(plant=G, spread=spread, levels=check_integer("levels", levels, minimum=2),
                    offsets=level_offsets(levels, len(a) - 1))


def set_response(mset, omega):
    """Frequency responses of every member, shape (M, len(omega)), complex.

    Evaluated as one matrix product of the (M, n+1) scaled coefficient array
    with the Vandermonde matrix of j omega / omega_s (no loop over models).
    """
    _check_model_set(mset)
    omega = _check_omega(omega)
    a, b = _plant_polynomials(mset.plant)
    ws = _time_scale(a)
    V = _vandermonde(omega / ws, max(len(a), len(b)))
    num = _scaled(b, ws, len(a) - 1) @ V[:, :len(b)].T
    return num[None, :] / (_scaled_members(mset, ws) @ V[:, :len(a)].T)


def relative_errors(mset, omega):
    """|G_k(j omega)/G(j omega) - 1| for every member, shape (M, len(omega)).

    Since only the denominator varies, G_k/G - 1 = (a - a_k)/a_k; the
    difference a - a_k is evaluated from the perturbation itself, so small
    errors carry no cancellation.
    """
    _check_model_set(mset)
    omega = _check_omega(omega)
    a, _ = _plant_polynomials(mset.plant)
    ws = _time_scale(a)
    V = _vandermonde(omega / ws, len(a))
    diff = mset.spread * mset.offsets * _scaled(a, ws, len(a) - 1)[:-1]
    members = _scaled_members(mset, ws)
    # real matrix products: (j w)^k is real or imaginary, and real BLAS is faster
    num2 = (diff @ V[:, :-1].real.T) ** 2 + (diff @ V[:, :-1].imag.T) ** 2
    den2 = (members @ V.real.T) ** 2 + (members @ V.imag.T) ** 2
    return np.sqrt(num2 / den2)


def member_poles(mset):
    """Poles [rad/s] of every member, shape (M, n), from stacked companion
    matrices in scaled time (one batched eigenvalue call)."""
    _check_model_set(mset)
    a, _ = _plant_polynomials(mset.plant)
    ws = _time_scale(a)
    return _batched_roots(_scaled_members(mset, ws)) * ws


def unstable_members(mset, K=None):
    """Indices of the members with a pole in Re s >= 0.

    With a controller ``K`` the closed-loop poles of each member are tested
    instead (see :func:`member_closed_loop_poles`).
    """
    poles = member_poles(mset) if K is None else member_closed_loop_poles(mset, K)
    return np.flatnonzero(poles.real.max(axis=1) >= 0)


def member_closed_loop_poles(mset, K):
    """Closed-loop poles [rad/s] of every member with controller K.

    The characteristic polynomials a_k d + b n of all members are formed as
    one (M, n + deg d + 1) array in scaled time and their roots found from
    stacked companion matrices.

    Returns
    -------
    ndarray, shape (M, n + deg d)
    """
    _check_model_set(mset)
    polys = _loop_polynomials(mset.plant, K)
    members = _scaled_members(mset, polys.ws)                 # (M, n+1) low first
    c = np.zeros((mset.size, members.shape[1] + len(polys.d) - 1))
    for j, dj in enumerate(polys.d):
        c[:, j:j + members.shape[1]] += dj * members
    bn = npoly.polymul(polys.b, polys.n)
    c[:, :len(bn)] += bn
    return _batched_roots(c) * polys.ws


def relative_error_envelope(mset, omega, members="stable"):
    """E_m(omega) of eq. 7 on a grid.

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Frequencies [rad/s].
    members : {"stable", "all"}
        Maximise over the stable members only, or over all members.
    """
    mask = _member_mask(mset, members)
    return relative_errors(mset, omega)[mask].max(axis=0)


def envelope_peak(mset, omega, members="stable", candidates=8):
    """Peak of E_m with its frequency, refined off the grid.

    Lightly damped members make E_m so sharp that its grid maximum depends on
    the grid.  The peak is searched on the grid and at every member's own pole
    frequencies, and the best ``candidates`` points are refined by a bounded
    scalar search.

    Returns
    -------
    peak : float
    omega_peak : float
        [rad/s]
    member : int
        Index of the member attaining the peak.
    """
    mask = _member_mask(mset, members)
    omega = _check_omega(omega)
    idx = np.flatnonzero(mask)
    a, _ = _plant_polynomials(mset.plant)
    ws = _time_scale(a)
    err = relative_errors(mset, omega)[idx]
    # each member at its own (in-range) pole frequencies
    w_pole = np.abs(member_poles(mset)[idx].imag)
    w_pole = np.clip(w_pole, omega.min(), omega.max())
    e_pole = _member_error(mset, idx[:, None], w_pole, ws)
    pts = [(err[i, j], idx[i], omega[j]) for i, j in
           zip(*np.unravel_index(np.argsort(err, axis=None)[-candidates:], err.shape))]
    pts += [(e_pole[i, j], idx[i], w_pole[i, j]) for i, j in
            zip(*np.unravel_index(np.argsort(e_pole, axis=None)[-candidates:], e_pole.shape))]
    best = max(pts)
    step = np.exp(np.mean(np.diff(np.log(omega)))) if omega.size > 1 else 1.01
    for value, k, w in pts:
        res = opt.minimize_scalar(
            lambda lw: -_member_error(mset, np.array([k]), np.array([np.exp(lw)]), ws)[0],
            bounds=(np.log(w / step), np.log(w * step)), method="bounded",
            options={"xatol": 1e-10})
        if -res.fun > best[0]:
            best = (-res.fun, k, float(np.exp(res.x)))
    return float(best[0]), float(best[2]), int(best[1])


def relative_error_bound(G=None, spread=paper.UNCERTAINTY_SPREAD, omega=None):
    """Exact sup of |G_q/G - 1| over the continuous box q in [-1, 1]^n.

    At each frequency a_q(j omega) - a(j omega) runs over an axis-parallel
    rectangle e with half-widths spread*R, spread*I (R: even, I: odd powers).
    |e/(a + e)| has no interior maximum (its log is harmonic away from its
    zero and pole), so its maximum lies on the rectangle's edges: the four
    vertices and the stationary points of the quadratic ratio along each edge.
    The box contains every level set of the same spread, so this bounds their
    envelopes too.

    Parameters
    ----------
    G : control.LTI, optional
        Nominal SISO proper plant; default the published plant.
    spread : float, optional
        Relative spread, 0 < spread < 1 (default 0.05).
    omega : array_like, optional
        Grid [rad/s]; default 1 ... 1e6 rad/s, 2000 points.

    Returns
    -------
    ndarray
        Bound [-] on the grid ``omega``; ``inf`` where some member of the box
        has a pole at j omega.
    """
    G = _nominal(G)
    spread = _check_spread(spread)
    omega = _check_omega(omega if omega is not None else robust.frequency_grid(1, 1e6, 2000))
    a, _ = _plant_polynomials(G)
    ws = _time_scale(a)
    w = omega / ws
    half_re, half_im = _rectangle_half_widths(_scaled(a, ws, len(a) - 1)[:-1], w)
    half_re, half_im = spread * half_re, spread * half_im
    av = _vandermonde(w, len(a)) @ _scaled(a, ws, len(a) - 1)
    inside = (np.abs(av.real) <= half_re) & (np.abs(av.imag) <= half_im)

    def ratio(e):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.abs(e) / np.abs(av + e)

    best = np.zeros_like(w)
    for sr, si in itertools.product((-1, 1), repeat=2):
        best = np.maximum(best, ratio(sr * half_re + 1j * si * half_im))
    # edges e0 + t u, t in [-1, 1]: stationary points of |e|^2 / |a + e|^2
    for e0, u in [(s * half_re, 1j * half_im) for s in (-1, 1)] + \
                 [(1j * s * half_im, half_re + 0j) for s in (-1, 1)]:
        alpha = np.abs(u) ** 2
        beta = 2 * np.real(np.conj(e0) * u)
        gamma = np.abs(e0) ** 2
        beta2 = 2 * np.real(np.conj(av + e0) * u)
        gamma2 = np.abs(av + e0) ** 2
        c2, c1, c0 = alpha * (beta2 - beta), 2 * alpha * (gamma2 - gamma), beta * gamma2 - gamma * beta2
        disc = np.sqrt(np.maximum(c1 ** 2 - 4 * c2 * c0, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            roots = [np.where(c2 != 0, (-c1 + sgn * disc) / (2 * c2),
                              np.where(c1 != 0, -c0 / c1, 0.0)) for sgn in (-1, 1)]
        for t in roots:
            t = np.clip(np.nan_to_num(t), -1.0, 1.0)
            best = np.maximum(best, np.nan_to_num(ratio(e0 + t * u), nan=0.0))
    return np.where(inside, np.inf, best)


# --- weights against the envelope ---------------------------------------------
Coverage = namedtuple("Coverage", ["covers", "worst_ratio", "omega_worst",
                                   "max_excess_dB", "mean_excess_dB"])
Coverage.__doc__ = """Result of :func:`coverage`.

covers : bool
    |W| >= E on every grid point.
worst_ratio : float
    min over the grid of |W(j omega)| / E(omega) (< 1: not covered).
omega_worst : float
    Frequency of the worst ratio [rad/s].
max_excess_dB, mean_excess_dB : float
    Largest and mean 20 log10(|W|/E) over the grid (how loose the weight is).
"""


def coverage(weight, omega, envelope):
    """Check |W(j omega)| >= E(omega) on a grid.

    Parameters
    ----------
    weight : control.LTI
        SISO proper weight.
    omega : array_like
        Frequencies [rad/s].
    envelope : array_like
        E(omega) >= 0 on the same grid (``inf`` allowed: never covered).

    Returns
    -------
    Coverage
    """
    check_siso("weight", weight)
    check_proper("weight", weight)
    omega = _check_omega(omega)
    env = np.asarray(envelope, dtype=float)
    if env.shape != omega.shape:
        raise ValueError(f"envelope must have the shape of omega {omega.shape}, got {env.shape}")
    if np.any(np.isnan(env)) or np.any(env < 0):
        raise ValueError("envelope must be non-negative and not NaN")
    mag = np.abs(np.ravel(weight(1j * omega)))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(env > 0, mag / env, np.inf)
    k = int(np.argmin(ratio))
    finite = np.isfinite(ratio) & (ratio > 0)
    excess = 20 * np.log10(ratio[finite]) if finite.any() else np.array([np.nan])
    return Coverage(covers=bool(ratio[k] >= 1.0), worst_ratio=float(ratio[k]),
                    omega_worst=float(omega[k]), max_excess_dB=float(excess.max()),
                    mean_excess_dB=float(excess.mean()))


SpreadBracket = namedtuple("SpreadBracket", ["spread", "lower", "upper", "bounded"])
SpreadBracket.__doc__ = """Result of a bounded search for the largest spread.

spread : float
    Best estimate (= lower: the largest spread verified to pass).
lower, upper : float
    The property holds at ``lower`` and fails at ``upper`` (upper is
    ``spread_max`` with ``bounded=False`` when it never failed).
bounded : bool
    False when the property held up to ``spread_max``.
"""


def largest_covered_spread(weight, G=None, omega=None, levels=paper.UNCERTAINTY_LEVELS,
                           members="stable", spread_max=0.5, rtol=1e-3, scan=12):
    """Largest spread whose relative-error envelope the weight covers on the grid.

    First the continuous box (exact bound :func:`relative_error_bound`,
    monotone in the spread): a log-spaced scan over
    (spread_max * 1e-3, spread_max] finds the first failing spread and
    bisection follows.  For a level set (a subset of the box) the box result
    is a verified lower end; a second scan upward from it and a bisection
    give the set's value.  The level-set envelope is not guaranteed monotone
    in the spread (the set at one spread is not a subset of the set at a
    larger one), hence the scans before bisecting.

    Parameters
    ----------
    weight : control.LTI
        SISO proper weight (e.g. :func:`piezolib.paper.uncertainty_weight`).
    G : control.LTI, optional
        Nominal plant; default the published plant.
    omega : array_like, optional
        Grid [rad/s]; default 1 ... 1e6 rad/s, 2000 points.
    levels : int or None
        Level count of the model set, or ``None`` for the continuous box.
    members : {"stable", "all"}
        Members entering the grid envelope (ignored for the box).
    spread_max : float
        Upper end of the search, < 1.
    rtol : float
        Relative width of the final bracket.
    scan : int
        Points of the initial scan.

    Returns
    -------
    SpreadBracket
    """
    check_siso("weight", weight)
    check_proper("weight", weight)
    G = _nominal(G)
    omega = _check_omega(omega if omega is not None else robust.frequency_grid(1, 1e6, 2000))
    spread_max = _check_spread(spread_max, "spread_max")
    if members not in _MEMBERS:
        raise ValueError(f"members must be one of {_MEMBERS}, got {members!r}")

    def covered_box(spread):
        return coverage(weight, omega, relative_error_bound(G, spread, omega)).covers

    def covered_set(spread):
        env = relative_error_envelope(model_set(G, spread, levels), omega, members)
        return coverage(weight, omega, env).covers

    box = _largest_passing(covered_box, spread_max, rtol, scan)
    if levels is None or not box.bounded:
        return box
    # the level set lies in the box, so the box result is a verified lower end
    return _largest_passing(covered_set, spread_max, rtol, scan, start=box.lower)


def fit_covering_weight(omega, envelope, order, starts=2, max_iter=60, fit_points=250):
    """Stable, minimum-phase weight of a given order that covers an envelope.

    In the spirit of MATLAB's ``ucover``: W has ``order`` poles and zeros,
    |W(j omega)| >= E(omega) on every grid point, and the worst-case excess
    max 20 log10(|W|/E) is made as small as the optimiser can.

    W is a gain times order//2 second-order sections
    (s^2 + 2 zeta_z w_z s + w_z^2)/(s^2 + 2 zeta_p w_p s + w_p^2), normalised
    to unit DC gain, and one first-order section (s/w_z + 1)/(s/w_p + 1) when
    the order is odd.  All frequencies and dampings are positive (they are
    optimised as logarithms), so W is stable and minimum phase by
    construction.  Since the gain only shifts l = log|W| - log E, the excess
    after lifting W onto E is the range max l - min l:

    1. pick the fitting points (see ``fit_points``); start from sections placed on the most prominent peaks of E (an
       inverse notch whose height matches the peak) plus neutral sections,
       and a few perturbed starts;
    2. least-squares fit of the shape of log E (``scipy.optimize.least_squares``);
    3. minimax polish: minimise max l - min l by sequential linear
       programming with a trust region (analytic Jacobian);
    4. tightening: minimise the mean excess with the worst case held within
       0.1 dB of step 3's;
    5. lift: the gain is set so that the weight covers E on the whole grid.

    The optimisation is local (with a few deterministic starts): the excess
    is the least found, not a proven global minimum.

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

    Returns
    -------
    control.TransferFunction
        ``W_m`` from ``u_c`` to ``y_Delta`` (the signals of H_m).  Use
        :func:`coverage` to read its excess over E.
    """
    omega = _check_omega(omega)
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
    log_env = np.log(env)
    lower, upper = _section_bounds(omega, order)

    def shape_residual(theta):
        l, J = _log_weight(theta, omega, order)
        l = l - log_env
        return l - l.mean(), J - J.mean(axis=0)

    best = None
    for theta0 in _initial_sections(omega, env, order, starts):
        theta0 = np.clip(theta0, lower + 1e-9, upper - 1e-9)
        ls = opt.least_squares(lambda th: shape_residual(th)[0], theta0,
                               jac=lambda th: shape_residual(th)[1],
                               bounds=(lower, upper), max_nfev=max_iter)
        theta = _minimax_sections(ls.x, omega, log_env, order, lower, upper, max_iter)
        l = _log_weight(theta, omega, order)[0] - log_env
        if best is None or np.ptp(l) < best[0]:
            best = (np.ptp(l), theta, l.min())
    best_range, theta, _ = best
    # second stage: least mean excess with the worst case held within 0.1 dB
    theta = _minimax_sections(theta, omega, log_env, order, lower, upper, max_iter,
                              cap=best_range + 0.1 * np.log(10) / 20)
    l_min = (_log_weight(theta, omega, order)[0] - log_env).min()
    W = _weight_from_sections(theta, order, np.exp(-l_min))
    # lift onto the full grid (the fit used a subset of it)
    shortfall = np.max(full_env / np.abs(np.ravel(W(1j * full_omega))))
    W = ct.tf(W.num[0][0] * max(1.0, shortfall) * (1 + 1e-12), W.den[0][0],
              inputs="u_c", outputs="y_Delta", name="W_m")
    return W


# --- exact margin against the real coefficient perturbations ------------------
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
    """Smallest spread at which the value set contains 0, at each frequency.

    With G = b/a and K = n/d, the closed-loop characteristic polynomial of a
    member is c(s) = a(s) d(s) + b(s) n(s) + spread * d(s) sum_i q_i a_i s^i:
    affine in q.  At s = j omega the perturbation term is d(j omega) times an
    axis-parallel rectangle of half-widths R = sum_even |a_i| omega^i and
    I = sum_odd |a_i| omega^i, so 0 is in the value set exactly when

        |Re h| <= spread R  and  |Im h| <= spread I,   h = c_0 / d = a + b K.

    The gauge max(|Re h|/R, |Im h|/I) is that smallest spread.  (The box
    makes a an interval polynomial; the rectangle's corners are the values of
    its four Kharitonov polynomials.)

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
    polys = _loop_polynomials(G, K)
    omega = check_finite_array("omega", omega, ndim=1, min_length=1)
    if np.any(omega < 0):
        raise ValueError("omega must be non-negative")
    return _gauge(polys, omega / polys.ws)


def parametric_stability_margin(G=None, K=None, spread_max=1.0, omega=None):
    """Exact largest spread for which every member of the box is stable.

    The family of closed-loop characteristic polynomials is a polytope of
    constant degree, so it is stable if and only if the nominal member is and
    0 stays outside every value set (zero exclusion).  delta* is the infimum
    over omega >= 0 of :func:`stability_gauge`.  That infimum is found
    exactly: the gauge is the maximum of two rational functions, so its
    minimum lies at omega = 0, at a stationary point of the dominating one or
    where the two are equal; these are the real roots of four polynomials,
    which are solved for, joined with a dense grid, and polished by bounded
    scalar minimisation.  A critical member (q on the boundary of the box) is
    returned; its closed loop has poles at +-j omega*.

    Parameters
    ----------
    G : control.LTI, optional
        SISO proper plant; default the published plant.
    K : control.LTI or None
        SISO proper controller; ``None`` gives the open-loop margin (the
        largest spread with every member of the box stable).
    spread_max : float
        Upper end of the search; the result is reported as unbounded beyond it.
    omega : array_like, optional
        Extra grid [rad/s] for the polishing step; default 1e-4 ... 1e4 times
        the internal time scale, 4000 points.

    Returns
    -------
    ParametricMargin
    """
    G = _nominal(G)
    polys = _loop_polynomials(G, K)
    spread_max = check_positive("spread_max", spread_max)
    n = len(polys.a) - 1
    if not np.all(npoly.polyroots(polys.c0).real < 0):
        return ParametricMargin(0.0, float("nan"), np.zeros(n), False, True, spread_max)
    if omega is None:
        w_grid = np.r_[0.0, np.logspace(-4, 4, 4000)]
    else:
        w_grid = np.r_[0.0, check_finite_array("omega", omega, ndim=1) / polys.ws]
    candidates = np.r_[w_grid, _critical_frequencies(polys)]
    values = _gauge(polys, candidates)
    order = np.argsort(values)[:12]
    best_w, best = candidates[order[0]], values[order[0]]
    for w0 in candidates[order]:
        if w0 <= 0:
            continue
        res = opt.minimize_scalar(lambda lw: _gauge(polys, np.array([np.exp(lw)]))[0],
                                  bounds=(np.log(w0) - 5e-3, np.log(w0) + 5e-3),
                                  method="bounded", options={"xatol": 1e-12})
        if res.fun < best:
            best, best_w = float(res.fun), float(np.exp(res.x))
    if best > spread_max:
        return ParametricMargin(spread_max, float("nan"), np.zeros(n), True, False, spread_max)
    return ParametricMargin(float(best), float(best_w * polys.ws),
                            _critical_offsets(polys, best_w, best), True, True, spread_max)


def small_gain_spread(G=None, K=None, omega=None, rtol=1e-4):
    """Largest spread certified by the complex (small-gain) view, no rational fit.

    Treats the box as multiplicative complex uncertainty bounded pointwise by
    its exact envelope (:func:`relative_error_bound`) and certifies a spread
    when max_omega E(omega) |T(j omega)| < 1, T the nominal complementary
    sensitivity.  The certificate also needs every member open-loop stable
    (else its multiplicative perturbation is unstable), so the search is
    bracketed by [0, open-loop margin]; the box is nested in the spread, so
    the condition is monotone and bisection is exact up to ``rtol``.

    Parameters
    ----------
    G, K : control.LTI
        Plant (default published) and controller (required).
    omega : array_like, optional
        Grid [rad/s]; default 1 ... 1e6 rad/s, 4000 points.  The peak of
        E |T| is refined off the grid near its grid maximum.
    rtol : float

    Returns
    -------
    SpreadBracket
        ``upper`` is the first spread found to fail (or the open-loop margin).
    """
    G = _nominal(G)
    if K is None:
        raise TypeError("K is required: the certificate is about a closed loop")
    check_siso("K", K)
    check_proper("K", K)
    omega = _check_omega(omega if omega is not None else robust.frequency_grid(1, 1e6, 4000))
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


def weight_certified_spread(weight, G=None, K=None, omega=None, rtol=1e-3):
    """Spread certified by a rational weight W with the small-gain test.

    W certifies the box of spread delta when ||W T||_inf < 1 and |W| covers
    the exact box envelope (which implies every member is open-loop stable).

    Returns
    -------
    norm_WT : float
        ||W T||_inf.
    bracket : SpreadBracket
        Largest spread covered (spread 0 when ||W T||_inf >= 1).
    """
    check_siso("weight", weight)
    check_proper("weight", weight)
    G = _nominal(G)
    if K is None:
        raise TypeError("K is required: the certificate is about a closed loop")
    check_siso("K", K)
    T = robust.loop_functions(G, K).T
    norm, _ = robust.hinf_norm(ct.ss(weight) * T)
    if norm >= 1:
        return float(norm), SpreadBracket(0.0, 0.0, 0.0, True)
    return float(norm), largest_covered_spread(weight, G, omega, levels=None, rtol=rtol,
                                               spread_max=0.99)


# --- internals -----------------------------------------------------------------
_LoopPolys = namedtuple("_LoopPolys", ["a", "b", "n", "d", "c0", "ws"])


def _nominal(G):
    if G is None:
        return paper.plant()
    check_siso("G", G)
    check_proper("G", G)
    if not isinstance(G, ct.TransferFunction):
        G = ct.tf(G)
    if not G.isctime(strict=False):
        raise ValueError("G must be a continuous-time model")
    a, _ = _plant_polynomials(G)
    if len(a) < 2:
        raise ValueError("G must have at least one pole (denominator degree >= 1)")
    return G


def _plant_polynomials(G):
    """(a, b) lowest power first with a monic."""
    num = np.trim_zeros(np.atleast_1d(np.asarray(G.num[0][0], dtype=float)), "f")
    den = np.trim_zeros(np.atleast_1d(np.asarray(G.den[0][0], dtype=float)), "f")
    if num.size == 0:
        num = np.zeros(1)
    return den[::-1] / den[0], num[::-1] / den[0]


def _controller_polynomials(K):
    check_siso("K", K)
    check_proper("K", K)
    if not K.isctime(strict=False):
        raise ValueError("K must be a continuous-time model")
    K = K if isinstance(K, ct.TransferFunction) else ct.tf(K)
    return _plant_polynomials(K)[::-1]      # (n, d) with d monic


def _check_spread(spread, name="spread"):
    spread = check_positive(name, spread)
    if spread >= 1:
        raise ValueError(f"{name} must be below 1 (a relative spread), got {spread}")
    return spread


def _check_omega(omega):
    omega = check_finite_array("omega", omega, ndim=1, min_length=1)
    if np.any(omega <= 0):
        raise ValueError("omega must be positive [rad/s]")
    return omega


def _check_model_set(mset):
    if not isinstance(mset, ModelSet):
        raise TypeError(f"mset must be a ModelSet (see model_set()), got {type(mset).__name__}")


def _member_mask(mset, members):
    _check_model_set(mset)
    if members not in _MEMBERS:
        raise ValueError(f"members must be one of {_MEMBERS}, got {members!r}")
    mask = np.ones(mset.size, dtype=bool)
    if members == "stable":
        mask[unstable_members(mset)] = False
        if not mask.any():
            raise ValueError("no member of the set is stable")
    return mask


def _time_scale(a):
    """Bound on the pole magnitudes of the monic polynomial a (low first)."""
    n = len(a) - 1
    mags = [abs(a[k]) ** (1.0 / (n - k)) for k in range(n) if a[k] != 0]
    return max(mags) if mags else 1.0


def _scaled(c, ws, degree):
    """Coefficients (low first) of c(ws p) / ws**degree."""
    c = np.asarray(c, dtype=float)
    return c * ws ** (np.arange(c.shape[-1]) - degree)


def _member_coefficients(mset):
    """(M, n+1) member denominators, lowest power first, monic."""
    a, _ = _plant_polynomials(mset.plant)
    return np.c_[a[:-1] * (1 + mset.spread * mset.offsets), np.ones(mset.size)]


def _scaled_members(mset, ws):
    return _scaled(_member_coefficients(mset), ws, mset.order)


def _batched_roots(low):
    """Roots of each row of an (M, m+1) coefficient array (lowest power
    first), by one batched eigenvalue call on the companion matrices."""
    low = low / low[:, -1:]
    m = low.shape[1] - 1
    comp = np.zeros((low.shape[0], m, m))
    comp[:, 0, :] = -low[:, m - 1::-1]
    comp[:, 1:, :-1] = np.eye(m - 1)
    return np.linalg.eigvals(comp)


def _vandermonde(w, columns):
    """(len(w), columns) matrix of (j w)^k, w in scaled frequency."""
    return (1j * np.asarray(w, dtype=float))[:, None] ** np.arange(columns)


def _member_error(mset, rows, w, ws):
    """|a - a_k| / |a_k| for members ``rows`` at frequencies ``w`` (same shape)."""
    a, _ = _plant_polynomials(mset.plant)
    scaled_a = _scaled(a, ws, len(a) - 1)
    offsets = mset.offsets[rows]                             # (..., n)
    coeff = np.concatenate([scaled_a[:-1] * (1 + mset.spread * offsets),
                            np.ones(offsets.shape[:-1] + (1,))], axis=-1)
    powers = (1j * np.asarray(w) / ws)[..., None] ** np.arange(len(a))
    ak = np.sum(coeff * powers, axis=-1)
    diff = np.sum((coeff[..., :-1] - scaled_a[:-1]) * powers[..., :-1], axis=-1)
    return np.abs(diff / ak)


def _rectangle_half_widths(a_scaled, w):
    """R(w) = sum over even i of |a_i| w^i, I(w) likewise over odd i."""
    powers = np.asarray(w, dtype=float)[:, None] ** np.arange(len(a_scaled))
    terms = np.abs(a_scaled) * powers
    return terms[:, 0::2].sum(axis=1), terms[:, 1::2].sum(axis=1)


def _largest_passing(passes, spread_max, rtol, scan, start=0.0):
    """Scan (start, spread_max] geometrically for the first failure, then bisect.

    ``start`` must be known to pass (0 is trivially "passing").
    """
    first = start * (1 + 10 * rtol) if start > 0 else spread_max * 1e-3
    grid = np.geomspace(min(first, spread_max), spread_max,
                        check_integer("scan", scan, minimum=2))
    last_ok = float(start)
    for spread in grid:
        if passes(spread):
            last_ok = spread
        else:
            lo, hi = last_ok, spread
            break
    else:
        return SpreadBracket(float(spread_max), float(spread_max), float(spread_max), False)
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
    return SpreadBracket(float(lo), float(lo), float(hi), True)


_ZETA_RANGE = (1e-4, 1e2)


def _fit_points(env, count):
    """Indices of about ``count`` evenly spaced grid points plus every local
    maximum of the envelope and its two neighbours."""
    count = check_integer("fit_points", count, minimum=10)
    picks = np.unique(np.linspace(0, env.size - 1, min(count, env.size)).round().astype(int))
    peaks, _ = find_peaks(env)
    peaks = peaks[np.argsort(env[peaks])[::-1][:max(10, count // 5)]]
    near = np.clip(np.r_[peaks - 1, peaks, peaks + 1], 0, env.size - 1)
    return np.union1d(picks, near)


def _section_bounds(omega, order):
    """Bounds of the log-parameters: frequencies within 1e-2 ... 1e2 times the grid."""
    lw = (np.log(omega.min() / 100), np.log(omega.max() * 100))
    lz = tuple(np.log(_ZETA_RANGE))
    quad = [lw, lz, lw, lz] * (order // 2)
    first = [lw, lw] * (order % 2)
    bounds = np.array(quad + first)
    return bounds[:, 0], bounds[:, 1]


def _log_weight(theta, omega, order):
    """log|W(j omega)| of unit-DC-gain sections and its Jacobian in theta.

    theta holds, per second-order section, log w_z, log zeta_z, log w_p,
    log zeta_p, then log w_z, log w_p of the first-order section.
    """
    theta = np.asarray(theta, dtype=float)
    out = np.zeros(omega.size)
    J = np.zeros((omega.size, theta.size))
    for j in range(order // 2):
        for off, sign in ((0, 1.0), (2, -1.0)):
            r2 = (omega / np.exp(theta[4 * j + off])) ** 2
            z2 = np.exp(2 * theta[4 * j + off + 1])
            D = (1 - r2) ** 2 + 4 * z2 * r2
            out += sign * 0.5 * np.log(D)
            J[:, 4 * j + off] = sign * (2 * r2 * (1 - r2) - 4 * z2 * r2) / D
            J[:, 4 * j + off + 1] = sign * 4 * z2 * r2 / D
    if order % 2:
        for off, sign in ((-2, 1.0), (-1, -1.0)):
            r2 = (omega / np.exp(theta[off])) ** 2
            out += sign * 0.5 * np.log1p(r2)
            J[:, theta.size + off] = -sign * r2 / (1 + r2)
    return out, J


def _initial_sections(omega, env, order, starts):
    """Starting points of the weight fit.

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


def _minimax_sections(theta, omega, log_env, order, lower, upper, max_iter, cap=None):
    """Sequential linear programming on l = log|W| - log E over the grid.

    With ``cap=None``: minimise the range max l - min l (the worst excess
    after the lift) -- the classical Osborne-Watson trust-region scheme for
    minimax fits.  With a ``cap``: minimise the mean excess mean(l) - min(l)
    while keeping the range below ``cap``.  Each step solves the LP of the
    linearisation l + J step inside a box |step| <= radius; a step is kept
    when the true merit improves.
    """
    n = theta.size
    ones, zeros = np.ones((omega.size, 1)), np.zeros((omega.size, 1))

    def merit(l):
        if cap is None:
            return np.ptp(l)
        return l.mean() - l.min() if np.ptp(l) <= cap else np.inf

    l, J = _log_weight(theta, omega, order)
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
        l_new, J_new = _log_weight(trial, omega, order)
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


def _weight_from_sections(theta, order, gain):
    num, den = np.array([gain]), np.ones(1)
    for j in range(order // 2):
        wz, zz, wp, zp = np.exp(theta[4 * j:4 * j + 4])
        num = np.polymul(num, [1 / wz ** 2, 2 * zz / wz, 1.0])
        den = np.polymul(den, [1 / wp ** 2, 2 * zp / wp, 1.0])
    if order % 2:
        wz, wp = np.exp(theta[-2:])
        num = np.polymul(num, [1 / wz, 1.0])
        den = np.polymul(den, [1 / wp, 1.0])
    return ct.tf(num / den[0], den / den[0])


def _loop_polynomials(G, K):
    G = _nominal(G)
    a, b = _plant_polynomials(G)
    if K is None:
        n_k, d_k = np.zeros(1), np.ones(1)
    else:
        n_k, d_k = _controller_polynomials(K)
    ws = _time_scale(a)
    deg = len(a) - 1 + len(d_k) - 1
    a_s, b_s = _scaled(a, ws, len(a) - 1), _scaled(b, ws, len(a) - 1)
    n_s, d_s = _scaled(n_k, ws, len(d_k) - 1), _scaled(d_k, ws, len(d_k) - 1)
    c0 = npoly.polyadd(npoly.polymul(a_s, d_s), npoly.polymul(b_s, n_s))
    c0 = np.r_[c0, np.zeros(deg + 1 - len(c0))]
    if c0[deg] == 0:
        raise ValueError("the closed-loop characteristic polynomial loses its degree "
                         "(1 + G K vanishes at infinity)")
    return _LoopPolys(a=a_s, b=b_s, n=n_s, d=d_s, c0=c0, ws=ws)


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


def _gauge(polys, w):
    U, V, rho, iota = (npoly.polyval(w, p) for p in _gauge_polynomials(polys))
    with np.errstate(divide="ignore", invalid="ignore"):
        f_re = np.where(rho > 0, np.abs(U) / rho, np.where(np.abs(U) > 0, np.inf, 0.0))
        f_im = np.where(iota > 0, np.abs(V) / iota, np.where(np.abs(V) > 0, np.inf, 0.0))
    return np.maximum(f_re, f_im)


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


def _critical_offsets(polys, w, spread):
    """Offsets q in the box putting a root of c at j w for the given spread."""
    h = npoly.polyval(1j * w, polys.c0) / npoly.polyval(1j * w, polys.d)
    R, I = _rectangle_half_widths(polys.a[:-1], np.array([w]))
    x = -h.real / (spread * R[0]) if R[0] > 0 else 0.0
    y = -h.imag / (spread * I[0]) if I[0] > 0 else 0.0
    k = np.arange(len(polys.a) - 1)
    unit = 1j ** k
    # sum_i q_i a_i (j w)^i = spread^-1 * (-h): even terms real, odd imaginary
    sign = np.sign(polys.a[:-1]) * np.where(k % 2 == 0, np.round(unit.real), np.round(unit.imag))
    q = np.where(k % 2 == 0, np.clip(x, -1, 1), np.clip(y, -1, 1)) * sign
    return q
