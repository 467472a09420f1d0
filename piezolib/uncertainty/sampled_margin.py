"""The parametric stability margin of the sampled loop a real-time target runs.

:func:`sampled_parametric_margin`: the largest spread of G's coefficient box for
which every member's sampled loop (exact ZOH model of the member at the
controller's sample time, the discrete controller, d samples of delay z^-d) is
stable, by bisection on the spread over the box's vertices, points along its
edges and a random sample of its interior, then the member that destabilises
refined by a local search.  Beside the continuous loop's exact margin
(:func:`~piezolib.uncertainty.margin.parametric_stability_margin`), which
needs a continuous stand-in for the sampled loop's delay.
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import check_finite_lti, check_integer, check_positive, check_siso
from piezolib.uncertainty.modelset import ModelSet, level_offsets
from piezolib.uncertainty.polynomials import check_plant, check_spread, plant_polynomials
from piezolib.uncertainty.sampled import sampled_loop_poles

__all__ = ["SampledMargin", "sampled_parametric_margin"]

_EDGE_POINTS = 7        # interior points per edge of the box
_MAX_COEFFICIENTS = 12  # 2^n vertices and n 2^(n-1) edges: bounded before any work
_MAX_SAMPLE = 100_000   # random interior members
_MAX_DELAY = 1000       # samples of delay (the loop's polynomial grows with it)
_MAX_RESTARTS = 8       # bisections restarted below a member the local search destabilised


@dataclass(frozen=True)
class SampledMargin:
    """Result of :func:`sampled_parametric_margin`.

    Attributes
    ----------
    spread : float
        Largest spread [-] at which every member tried is stable (0 when the
        nominal loop is unstable; ``spread_max`` when ``bounded`` is False).
    spread_unstable : float
        Smallest spread [-] at which a member was found unstable (nan when
        not bounded): the member ``offsets`` there is a proof that the margin
        is below it.
    offsets : ndarray
        Normalised offsets q in [-1, 1] of that destabilising member (zeros
        when not bounded).
    radius : float
        Largest |z| of that member's closed-loop poles at ``spread_unstable``.
    omega : float
        Angle of that pole as a frequency [rad/s] (its |arg z| / dt).
    delay_samples : int
        The loop's computation delay d [samples].
    members_checked : int
        Members tried at ``spread``: vertices, edge points and the sample.
    sample_radius : float
        Largest |z| over the random sample of the box at ``spread`` (below 1).
    nominal_stable, bounded : bool
    """

    spread: float
    spread_unstable: float
    offsets: np.ndarray
    radius: float
    omega: float
    delay_samples: int
    members_checked: int
    sample_radius: float
    nominal_stable: bool
    bounded: bool


def _controller(Kd, float32):
    """Kd checked as a discrete SISO model; with ``float32`` its realisation rounded."""
    if not isinstance(Kd, ct.LTI):
        raise TypeError(f"Kd must be a discrete control.StateSpace or TransferFunction, got "
                        f"{type(Kd).__name__}")
    check_siso("Kd", Kd)
    check_finite_lti("Kd", Kd)
    if Kd.isctime(strict=False) or Kd.dt is True or not Kd.dt:
        raise ValueError(f"Kd must be a discrete controller with a numeric sample time, got "
                         f"dt = {Kd.dt!r}")
    if not float32:
        return Kd
    S = ct.ss(Kd)
    return ct.ss(*(np.asarray(x, float).astype(np.float32).astype(float)
                   for x in (S.A, S.B, S.C, S.D)), S.dt)


def _box_points(n, samples, seed):
    """Offsets of the vertices, of points along every edge and of a uniform sample."""
    vertices = level_offsets(2, n)
    inner = np.linspace(-1, 1, _EDGE_POINTS + 2)[1:-1]
    edges = []
    for i in range(n):
        free = np.repeat(vertices[vertices[:, i] < 0], inner.size, axis=0)
        free[:, i] = np.tile(inner, free.shape[0] // inner.size)
        edges.append(free)
    sample = np.random.default_rng(seed).uniform(-1, 1, (samples, n))
    return np.vstack([vertices, *edges]), sample


def _radii(G, offsets, spread, Kd, dt, d):
    """Largest |z| of each member's sampled-loop poles, and the poles."""
    poles = sampled_loop_poles(ModelSet(G, spread, 0, offsets), Kd, dt, d)
    return np.abs(poles).max(axis=1), poles


def _refine(G, q, spread, Kd, dt, d, steps=40):
    """A member near ``q`` in the box with a larger sampled-loop radius: coordinate steps
    of shrinking size, each kept when it raises the radius."""
    best = _radii(G, q[None], spread, Kd, dt, d)[0][0]
    step = 0.25
    for _ in range(steps):
        n = q.size
        trial = np.clip(np.vstack([q + step * e for e in np.eye(n)]
                                  + [q - step * e for e in np.eye(n)]), -1, 1)
        r = _radii(G, trial, spread, Kd, dt, d)[0]
        k = int(np.argmax(r))
        if r[k] > best:
            best, q = r[k], trial[k]
        else:
            step /= 2
            if step < 1e-3:
                break
    return q


def sampled_parametric_margin(G, Kd, delay_samples=1, *, spread_max=0.5, rtol=1e-3,
                              samples=2000, seed=0, float32=False, known=None):
    """Largest spread of G's coefficient box whose sampled loops are all stable.

    Each member G_q (denominator coefficients a_i (1 + spread q_i), |q_i| <= 1)
    is held exactly by a zero-order hold at Kd's sample time
    (:func:`~piezolib.uncertainty.member_zoh_coefficients`) and closed with
    Kd and d samples of delay; a loop is stable when its poles lie inside the
    unit circle.  The spread is bisected; at each spread the box's 2^n
    vertices, 7 points along each of its n 2^(n-1) edges, a uniform sample
    of ``samples`` members and the most unstable member found so far (refined
    by a local search in the box) are tried.

    A bracket found before (``known``: a committed end point of this search) is
    verified instead of searched for: when every member tried is stable at its
    lower end and the local search from the most unstable of them finds no
    unstable member there, the bracket is at most ``rtol`` wide and its member
    is unstable at its upper end, the result is built from it as the search
    builds it; otherwise the search runs.

    What it certifies.  For the continuous loop the characteristic polynomial
    is affine in q, so zero exclusion over the box is exact
    (:func:`~piezolib.uncertainty.parametric_stability_margin`).  The ZOH
    model depends on q through a matrix exponential, so here the set of
    characteristic polynomials is not a polytope and neither zero exclusion nor
    a vertex or edge theorem applies: ``spread_unstable`` is certain (a member
    there is unstable, so the margin is below it), while ``spread`` only says
    that every member tried is stable; a member between them can fail earlier.

    Parameters
    ----------
    G : control.LTI
        Nominal continuous SISO proper plant with at least one pole.
    Kd : control.LTI
        Discrete SISO controller (negative feedback) at the loop's sample time.
    delay_samples : int
        Computation delay d >= 0 [samples] between Kd's output and the hold.
    spread_max : float
        Upper end of the search (< 1).
    rtol : float
        Relative width of the final bracket [spread, spread_unstable].
    samples : int
        Random members of the box tried at each spread (0 ... 100000).
    seed : int
        Seed of that sample.
    float32 : bool
        Round Kd's realisation to float32 first (what a single-precision target runs).
    known : tuple, optional
        (spread, spread_unstable, offsets) of an earlier run with these arguments:
        verified (see above), searched for only when it does not verify.

    Returns
    -------
    SampledMargin

    Examples
    --------
    >>> import control as ct
    >>> G, Kd = ct.tf([1], [1, 3, 3, 1]), ct.tf([2.0], [1], 0.05)
    >>> m = sampled_parametric_margin(G, Kd, 1, samples=200)
    >>> round(100 * m.spread, 1), m.bounded, bool(m.radius >= 1)
    (36.4, True, True)
    >>> again = sampled_parametric_margin(G, Kd, 1, samples=200,
    ...                                   known=(m.spread, m.spread_unstable, m.offsets))
    >>> (again.spread, again.spread_unstable, again.radius) == (m.spread, m.spread_unstable,
    ...                                                         m.radius)
    True
    """
    G = check_plant(G)
    Kd = _controller(Kd, float32)
    dt = float(Kd.dt)
    d = check_integer("delay_samples", delay_samples, minimum=0)
    if d > _MAX_DELAY:
        raise ValueError(f"delay_samples must be at most {_MAX_DELAY}, got {d}")
    spread_max = check_spread(spread_max, "spread_max")
    rtol = check_positive("rtol", rtol)
    samples = check_integer("samples", samples, minimum=0)
    if samples > _MAX_SAMPLE:
        raise ValueError(f"samples must be at most {_MAX_SAMPLE}, got {samples}")
    seed = check_integer("seed", seed, minimum=0)
    n = len(plant_polynomials(G)[0]) - 1
    if n > _MAX_COEFFICIENTS:
        raise ValueError(f"G has {n} denominator coefficients; the vertex and edge search "
                         f"takes at most {_MAX_COEFFICIENTS}")
    if known is not None:
        known = _known_bracket(known, n, spread_max)
    if _radii(G, np.zeros((1, n)), spread_max, Kd, dt, d)[0][0] >= 1:
        return SampledMargin(0.0, 0.0, np.zeros(n), np.nan, np.nan, d, 1, np.nan, False, True)
    corners, sample = _box_points(n, samples, seed)
    vertices, edges = corners[:2 ** n], corners[2 ** n:]
    worst = np.zeros((0, n))

    def unstable(spread, refine=False):
        """The most unstable member at ``spread`` (offsets, radius), or None; the groups
        in turn, cheapest first, and the local search only when asked."""
        nonlocal worst
        best = (None, -np.inf)
        for group in (vertices, worst, edges, sample):
            if group.shape[0]:
                r = _radii(G, group, spread, Kd, dt, d)[0]
                k = int(np.argmax(r))
                if r[k] >= 1:
                    worst = np.vstack([worst, group[k]])[-8:]
                    return group[k], r[k]
                best = max(best, (group[k], r[k]), key=lambda x: x[1])
        if refine:
            q = _refine(G, best[0], spread, Kd, dt, d)
            r = _radii(G, q[None], spread, Kd, dt, d)[0][0]
            if r >= 1:
                worst = np.vstack([worst, q])[-8:]
                return q, r
        return None

    def result(low, high, q):
        r, poles = _radii(G, q[None], high, Kd, dt, d)
        z = poles[0][np.argmax(np.abs(poles[0]))]
        sample_r = _radii(G, sample, low, Kd, dt, d)[0].max() if samples else np.nan
        return SampledMargin(spread=float(low), spread_unstable=float(high), offsets=q,
                             radius=float(r[0]), omega=float(abs(np.angle(z)) / dt),
                             delay_samples=d, members_checked=corners.shape[0] + samples,
                             sample_radius=float(sample_r), nominal_stable=True, bounded=True)

    if known is not None:
        low, high, q = known
        # the search's own end: a stable lower end (the local search included), a bracket
        # within rtol, a member unstable at the upper end
        if (0 < low < high and high - low <= rtol * high
                and _radii(G, q[None], high, Kd, dt, d)[0][0] >= 1
                and unstable(low, refine=True) is None):
            return result(low, high, q)
        worst = np.zeros((0, n))
    top = unstable(spread_max, refine=True)
    if top is None:
        return SampledMargin(spread_max, np.nan, np.zeros(n), np.nan, np.nan, d,
                             corners.shape[0] + samples, np.nan, True, False)
    low, high, critical = 0.0, spread_max, top
    for attempt in range(_MAX_RESTARTS):
        while high - low > rtol * high:
            mid = 0.5 * (low + high)
            found = unstable(mid)
            if found is None:
                low = mid
            else:
                high, critical = mid, found
        # the local search from the most unstable member at the bracket's stable end;
        # a member it destabilises there moves the bracket down
        last = attempt == _MAX_RESTARTS - 1
        found = unstable(low, refine=True) if low > 0 and not last else None
        if found is None:
            break
        low, high, critical = 0.0, low, found
    return result(low, high, critical[0])


def _known_bracket(known, n, spread_max):
    """(spread, spread_unstable, offsets) of ``known``, checked."""
    if not (isinstance(known, (tuple, list)) and len(known) == 3):
        raise TypeError(f"known must be a tuple (spread, spread_unstable, offsets), got "
                        f"{known!r}"[:200])
    low = check_positive("known spread", known[0])
    high = check_positive("known spread_unstable", known[1])
    if not low < high <= spread_max:
        raise ValueError(f"known must bracket the margin below spread_max {spread_max:g}: "
                         f"spread {low:g}, spread_unstable {high:g}")
    q = np.asarray(known[2], dtype=float)
    if q.shape != (n,) or not np.all(np.isfinite(q)) or np.any(np.abs(q) > 1):
        raise ValueError(f"known offsets must be {n} finite values in [-1, 1], got "
                         f"{known[2]!r}"[:200])
    return low, high, q
