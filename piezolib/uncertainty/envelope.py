"""Relative-error envelope of a model set, its exact bound over the box, and weight coverage.

E(omega) = max_k |G_k(j omega)/G(j omega) - 1| over the members of a
:class:`~piezolib.uncertainty.modelset.ModelSet`; why its peak must be refined
off the grid and how the box bound is computed: ``docs/uncertainty.md``.
"""

import itertools
from collections import namedtuple

import numpy as np
import scipy.optimize as opt

from piezolib._checks import (check_bisection_tol, check_finite_array, check_integer, check_model,
                              check_proper, check_siso, check_stable)
from piezolib.uncertainty.modelset import (check_model_set, frequency_basis, member_poles,
                                           model_set, unstable_members)
from piezolib.uncertainty.polynomials import (
    check_frequencies, check_plant, check_spread, coefficient_scale, jw_powers,
    plant_polynomials, rectangle_half_widths, scale_coefficients)

__all__ = [
    "MEMBERS", "relative_errors", "relative_error_envelope", "envelope_peak",
    "relative_error_bound", "Coverage", "coverage", "SpreadBracket", "largest_covered_spread",
]

#: Accepted values of the ``members`` argument: the stable members only, or all.
MEMBERS = ("stable", "all")


def relative_errors(mset, omega):
    """|G_k(j omega)/G(j omega) - 1| for every member, shape (M, len(omega)).

    Since only the denominator varies, G_k/G - 1 = (a - a_k)/a_k; the
    difference a - a_k is evaluated from the perturbation itself, so small
    errors carry no cancellation.

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Frequencies [rad/s], positive.

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.uncertainty import model_set
    >>> mset = model_set(ct.tf([1], [1, 0.2, 1]), 0.1)        # +-10 % on a0 and a1: 9 members
    >>> omega = np.logspace(-1, 1, 200)
    >>> errors = relative_errors(mset, omega)
    >>> errors.shape, bool(np.allclose(errors.max(axis=0), relative_error_envelope(mset, omega)))
    ((9, 200), True)
    """
    a, _, ws, V = frequency_basis(mset, omega)
    V = V[:, :len(a)]
    diff = mset.spread * mset.offsets * scale_coefficients(a, ws, len(a) - 1)[:-1]
    members = mset.scaled_coefficients(ws)
    # real matrix products: (j w)^k is real or imaginary, and real BLAS is faster
    num2 = (diff @ V[:, :-1].real.T) ** 2 + (diff @ V[:, :-1].imag.T) ** 2
    den2 = (members @ V.real.T) ** 2 + (members @ V.imag.T) ** 2
    return np.sqrt(num2 / den2)


def relative_error_envelope(mset, omega, members="stable"):
    """The envelope E(omega) = max_k |G_k/G - 1| on a grid.

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Frequencies [rad/s].
    members : {"stable", "all"}
        Maximise over the stable members only, or over all members.

    Returns
    -------
    ndarray, shape (len(omega),)

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.uncertainty import model_set
    >>> mset = model_set(ct.tf([1], [1, 0.2, 1]), 0.1)        # +-10 % on a0 and a1: 9 members
    >>> omega = np.logspace(-1, 1, 200)
    >>> E = relative_error_envelope(mset, omega)      # max over the members of |G_i/G - 1|
    >>> E.shape, round(float(E.max()), 2), round(float(omega[E.argmax()]), 2)
    ((200,), 0.6, 0.94)
    """
    mask = _member_mask(mset, members)
    return relative_errors(mset, omega)[mask].max(axis=0)


def envelope_peak(mset, omega, members="stable", candidates=8):
    """Peak of E with its frequency, refined off the grid.

    Lightly damped members make E so sharp that its grid maximum depends on
    the grid.  The peak is searched on the grid and at every member's own pole
    frequencies, and the best ``candidates`` points are refined by a bounded
    scalar search.

    Parameters
    ----------
    mset : ModelSet
    omega : array_like
        Grid [rad/s]; the refinement stays within it.
    members : {"stable", "all"}
    candidates : int
        Points refined, from the grid and from the pole frequencies each.

    Returns
    -------
    peak : float
    omega_peak : float
        [rad/s]
    member : int
        Index of the member attaining the peak.

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.uncertainty import model_set
    >>> mset = model_set(ct.tf([1], [1, 0.2, 1]), 0.1)        # +-10 % on a0 and a1: 9 members
    >>> omega = np.logspace(-1, 1, 200)
    >>> peak, w_peak, member = envelope_peak(mset, omega)     # refined between grid points
    >>> round(peak, 3), round(w_peak, 3), bool(peak >= relative_error_envelope(mset, omega).max())
    (0.599, 0.94, True)
    """
    mask = _member_mask(mset, members)
    omega = check_frequencies(omega)
    idx = np.flatnonzero(mask)
    ws = mset.time_scale
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


def relative_error_bound(G, spread, omega):
    """Exact sup of |G_q/G - 1| over the continuous box q in [-1, 1]^n.

    At each frequency the maximum lies on the edges of a rectangle of the
    complex plane and is found in closed form (derivation in
    ``docs/uncertainty.md``).  The box contains every level set of the same
    spread, so this bounds their envelopes too.

    Parameters
    ----------
    G : control.LTI
        Nominal SISO proper plant.
    spread : float
        Relative spread, 0 < spread < 1.
    omega : array_like
        Grid [rad/s], positive.

    Returns
    -------
    ndarray
        Bound [-] on the grid ``omega``; ``inf`` where some member of the box
        has a pole at j omega.
    """
    G = check_plant(G)
    spread = check_spread(spread)
    omega = check_frequencies(omega)
    a, _ = plant_polynomials(G)
    ws = coefficient_scale(a)
    w = omega / ws
    a_scaled = scale_coefficients(a, ws, len(a) - 1)
    half_re, half_im = rectangle_half_widths(a_scaled[:-1], w)
    half_re, half_im = spread * half_re, spread * half_im
    av = jw_powers(w, len(a)) @ a_scaled
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
        c2, c1 = alpha * (beta2 - beta), 2 * alpha * (gamma2 - gamma)
        c0 = beta * gamma2 - gamma * beta2
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

    Examples
    --------
    >>> import control as ct
    >>> from piezolib.uncertainty import model_set
    >>> mset = model_set(ct.tf([1], [1, 0.2, 1]), 0.1)        # +-10 % on a0 and a1: 9 members
    >>> omega = np.logspace(-1, 1, 200)
    >>> E = relative_error_envelope(mset, omega)
    >>> c = coverage(ct.tf([0.7], [1]), omega, E)             # a constant 0.7 covers the peak 0.6
    >>> c.covers, round(c.worst_ratio, 3)
    (True, 1.17)
    >>> coverage(ct.tf([0.5], [1]), omega, E).covers
    False
    """
    check_siso("weight", weight)
    check_model("weight", weight, proper=True)
    check_stable("weight", weight)
    omega = check_frequencies(omega)
    env = check_finite_array("envelope", envelope, real=True)
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


def largest_covered_spread(weight, G, omega, levels=3, members="stable", spread_max=0.5,
                           rtol=1e-3, scan=12):
    """Largest spread whose relative-error envelope the weight covers on the grid.

    The continuous box is searched first (its exact bound is monotone in the
    spread): a log-spaced scan, then bisection.  For a level set the box
    result is a verified lower end, and a second scan upward from it and a
    bisection give the set's value (its envelope need not be monotone in the
    spread).  Details in ``docs/uncertainty.md``.

    Parameters
    ----------
    weight : control.LTI
        SISO proper weight.
    G : control.LTI
        Nominal plant.
    omega : array_like
        Grid [rad/s].
    levels : int or None, optional
        Level count of the model set (default 3), or ``None`` for the
        continuous box.
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
    G = check_plant(G)
    omega = check_frequencies(omega)
    spread_max = check_spread(spread_max, "spread_max")
    if members not in MEMBERS:
        raise ValueError(f"members must be one of {MEMBERS}, got {members!r}")
    rtol = check_bisection_tol("rtol", rtol)
    scan = check_integer("scan", scan, minimum=2)

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


# --- internals -----------------------------------------------------------------
def _member_mask(mset, members):
    check_model_set(mset)
    if members not in MEMBERS:
        raise ValueError(f"members must be one of {MEMBERS}, got {members!r}")
    mask = np.ones(mset.size, dtype=bool)
    if members == "stable":
        mask[unstable_members(mset)] = False
        if not mask.any():
            raise ValueError("no member of the set is stable")
    return mask


def _member_error(mset, rows, w, ws):
    """|a - a_k| / |a_k| for members ``rows`` at frequencies ``w`` (same shape)."""
    a, _ = plant_polynomials(mset.plant)
    scaled_a = scale_coefficients(a, ws, len(a) - 1)
    offsets = mset.offsets[rows]                             # (..., n)
    coeff = np.concatenate([scaled_a[:-1] * (1 + mset.spread * offsets),
                            np.ones(offsets.shape[:-1] + (1,))], axis=-1)
    powers = (1j * np.asarray(w) / ws)[..., None] ** np.arange(len(a))
    ak = np.sum(coeff * powers, axis=-1)
    diff = np.sum((coeff[..., :-1] - scaled_a[:-1]) * powers[..., :-1], axis=-1)
    return np.abs(diff / ak)


def _largest_passing(passes, spread_max, rtol, scan, start=0.0):
    """Scan (start, spread_max] geometrically for the first failure, then bisect.

    ``start`` must be known to pass (0 is trivially "passing").
    """
    first = start * (1 + 10 * rtol) if start > 0 else spread_max * 1e-3
    grid = np.geomspace(min(first, spread_max), spread_max, scan)
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
