"""Preisach hysteresis operator with ramped relays: grid, bounded least-squares fit, inverse.

x = x0 + w_lin v + sum_k w_k R_k[v], each element R_k of half-width r_i and
centre c_j a *ramped relay* (a Krasnosel'skii-Pokrovskii discretisation of
the Preisach plane): the play of threshold r_i (:func:`~piezolib.hysteresis.pi.play_outputs`,
the workbook's one play kernel), shifted by c_j and clipped to +-1 over a
ramp one grid step wide, R_k = clip((F_{r_i}[v] - c_j) / (step / 2), -1, 1).
It switches up around v = c_j + r_i and down around v = c_j - r_i, linearly,
so the sum is continuous, and for a fixed history it is non-decreasing in
the current input.  The grid has ``levels`` steps over the input range
[lo, hi] (step = (hi - lo) / levels): half-widths r_i = i step,
i = 0 ... levels // 2, centres c_j = lo + j step, j = 0 ... levels, the
elements with |c_j - (lo + hi) / 2| + r_i <= (hi - lo) / 2 + step.

Unlike a Prandtl-Ishlinskii operator (a density that depends on the
half-width r only), the weights depend on r and c: the virgin curve and the
loop branches are not tied to one another (Masing's rule), and the loops may
be asymmetric and their branches may steepen at large inputs.  Weights >= 0
make each element, and so the model, monotone: :meth:`PreisachModel.feedforward`
solves each sample for its input (the output is piecewise linear and
non-decreasing in it) by a safeguarded Newton iteration, compiled with numba.

Beyond the grid.  While the input stays in [lo, hi], the play of threshold
r_i stays in [lo + r_i, hi - r_i] (its part of the grid); only the records'
start may leave it.  Beyond that part, the element whose ramp ends it (up
ramp at c_j + r_i = hi, down ramp at c_j - r_i = lo) continues with its
ramp's slope, and the others keep their value there.  So beyond each edge
the model keeps its local slope at that edge, and a stroke beyond the grid
moves as a PI operator whose density is that of the edge's elements (a play
per threshold, the plays that move adding their slopes): a reversal beyond
the grid starts a branch whose slope grows as the plays join, as a PI
model's does.  The alternatives were worse: saturated relays leave the
model flat beyond the grid (on notebook 08's stage a Preisach Hammerstein
fitted to a sine of 0.4-3.6 V validated at 3.2 % of stroke on a 0-3 V
triangle, 1.5 % with the edges kept); a linear term alone is collinear with
the static ramps inside the grid, so the records cannot tell its slope; a
grid wider than the records leaves its outer elements unidentified (weight
0: flat again); and the mean slope over the last two steps instead of the
edge's own extrapolated fits to the inner 80 % of the foreign records' range
no better (better on one family of three:
:attr:`~piezolib.hysteresis.hammerstein.HammersteinFit.extrapolation_scores`).
Inside the grid the output is that of plain ramped relays; weights >= 0
keep it monotone everywhere, and the inverse solves beyond the grid as
inside.

The r = 0 elements (static ramps) sum to a straight line, inside the grid
and, with their edge ramps continued, beyond it: a linear term is collinear
with them, so :func:`fit_preisach` fits the elements and the offset, then
moves the part all static ramps share into ``linear`` (the output is
unchanged).
"""

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize as opt

from piezolib._checks import check_count, check_finite_array
from piezolib.hysteresis.common import (FitScores, FitWarning, check_loops, covariance, estimates,
                                        loop_errors, loop_pairs, warn_about)
from piezolib.hysteresis.dahl import NotInvertibleError
from piezolib.hysteresis.pi import PI_STARTS, play_outputs

# preisach_regressors and fold_linear are shared with hammerstein.py, not part of the API
__all__ = ["PreisachModel", "PreisachFit", "fit_preisach", "MAX_LEVELS",
           "MAX_REGRESSOR_ENTRIES"]

#: Most grid levels of a Preisach operator: (levels / 2 + 1) x (levels + 1) elements at most,
#: one regressor column each (32 levels: 325 elements).
MAX_LEVELS = 32
#: Most entries (samples x elements) of a fit's regressor (240 MB of float64; the default
#: 16 levels, 97 elements, on a 144,000-sample record is 1.4e7).
MAX_REGRESSOR_ENTRIES = 30_000_000

_SIDE = {"rest": 1.0, "virgin": 0.0, "maximum": -1.0}


def _grid(v_range, levels):
    """(step, half-widths r (P,), centres c (levels + 1,), play index, centre index) of a grid."""
    lo, hi = v_range
    step = (hi - lo) / levels
    r = step * np.arange(levels // 2 + 1)
    c = lo + step * np.arange(levels + 1)
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    i, j = np.nonzero(np.abs(c[None, :] - mid) + r[:, None] <= half + step * (1 + 1e-9))
    return step, r, c, i, j


def _check_range(name, v_range):
    lo_hi = check_finite_array(name, v_range, shape=(2,), real=True)
    if not lo_hi[1] > lo_hi[0]:
        raise ValueError(f"{name} must be (lo, hi) with hi > lo [v-unit], got {tuple(lo_hi)}")
    return float(lo_hi[0]), float(lo_hi[1])


def _elements(plays, step, c, i, j, levels):
    """Element outputs (N, elements) from the play outputs (N, P) (module docstring).

    Inside its play's part of the grid, knots i ... levels + 1 - i of
    :meth:`PreisachModel._tables` (where the play's output stays while the
    input stays in the grid), an element is the ramped relay; beyond it the
    element whose ramp ends there (c_j -+ r_i = lo, hi) continues with its
    ramp's slope and the others keep their value at that end.
    """
    p = np.arange(plays.shape[1])
    low, high = c[0] - step / 2 + step * p, c[0] - step / 2 + step * (levels + 1 - p)
    inside = np.clip(plays, low, high)            # per play: cheaper than per element
    out = inside[:, i]
    out -= c[j]
    out *= 2 / step
    np.clip(out, -1.0, 1.0, out=out)
    top, bottom = _edges(levels, i, j)
    beyond = plays - inside                       # < 0 below the play's part, > 0 above
    out[:, bottom] += 2 / step * np.minimum(beyond[:, i[bottom]], 0.0)
    out[:, top] += 2 / step * np.maximum(beyond[:, i[top]], 0.0)
    return out


def _edges(levels, i, j):
    """(top, bottom): the elements whose up (down) ramp is centred on the grid's hi (lo).

    Element (r_i, c_j) switches up around c_j + r_i and down around c_j - r_i:
    c_j + r_i = hi for j = levels - i, c_j - r_i = lo for j = i.
    """
    return j == levels - i, j == i


def preisach_regressors(data, v_range, levels, start):
    """Element outputs of already validated loops, one (E, weight) per loop.

    ``data`` is what :func:`~piezolib.hysteresis.common.check_loops` returns;
    ``weight`` = 1 / (output range x sqrt(samples used)), as
    :func:`~piezolib.hysteresis.pi.pi_regressors`.
    """
    step, r, c, i, j = _grid(v_range, levels)
    out = []
    for v, x, used in data:
        plays = play_outputs(v, r, v[0] + _SIDE[start] * r)
        out.append((_elements(plays, step, c, i, j, levels),
                    1.0 / (np.ptp(x[used]) * math.sqrt(used.size))))
    return out


def pruned_regressors(data, v_range, levels, start, offset):
    """(regs, keep): :func:`preisach_regressors` on the :func:`independent_columns` ``keep``."""
    regs = preisach_regressors(data, v_range, levels, start)
    keep = independent_columns(data, regs, offset)
    # column-major: the Hammerstein fit filters each column along time (40 % faster)
    return [(np.asfortranarray(E[:, keep]), weight) for E, weight in regs], keep


def scatter(keep, weights, n):
    """All ``n`` element weights from those of the kept columns (the others 0)."""
    w = np.zeros(n)
    w[keep] = weights
    return w


def independent_columns(data, regs, offset, rtol=1e-9):
    """Indices of element columns that are not (numerically) combinations of the others.

    An element that never switches on the records is a constant (collinear
    with the offset), two that switch together are equal: their weights are
    not identifiable, and a singular normal matrix sends every later solve to
    a QR of the tall regressor (10 x dearer).  A pivoted Cholesky of the
    weighted Gram matrix (the offset first) keeps each column whose part
    orthogonal to the kept ones is above ``rtol`` of its norm; the dropped
    elements get weight 0 (what they add is a kept column's, or nothing).
    """
    G = 0.0
    for (v, x, used), (E, weight) in zip(data, regs):
        A = weight * np.hstack([E[used]] + ([np.ones((used.size, 1))] if offset else []))
        G = G + A.T @ A
    n = G.shape[0] - (1 if offset else 0)
    diag = np.diag(G).copy()
    L = np.zeros_like(G)
    kept, order = [], ([n] if offset else []) + list(np.argsort(-diag[:n]))
    for k in order:
        res = G[k, k] - L[k, :len(kept)] @ L[k, :len(kept)]
        if not res > rtol * diag[k] or diag[k] == 0:
            continue
        col = len(kept)
        L[:, col] = (G[:, k] - L[:, :col] @ L[k, :col]) / math.sqrt(res)
        kept.append(k)
    return np.array(sorted(k for k in kept if k < n), dtype=int)


def fold_linear(v_range, levels, weights, x0):
    """(weights, linear, x0) with the share of the r = 0 ramps common to all moved to ``linear``.

    The static ramps sum to (2 / step) (v - mid), inside the grid and (their
    edge ramps continued) beyond it: a weight m on each equals
    m (2 / step) v - m (2 / step) mid, so the output is unchanged.
    """
    step, r, c, i, j = _grid(v_range, levels)
    w = np.array(weights, dtype=float)
    static = i == 0
    m = float(np.min(w[static])) if np.any(static) else 0.0
    if m <= 0:
        return w, 0.0, float(x0)
    w[static] -= m
    linear = 2 * m / step
    return w, linear, float(x0) - linear * (v_range[0] + v_range[1]) / 2


@dataclass(frozen=True)
class PreisachModel:
    """Preisach operator of ramped relays x = x0 + w_lin v + sum_k w_k R_k[v] (module docstring).

    Attributes
    ----------
    v_range : tuple of float
        (lo, hi): the input range the grid covers [v-unit].
    levels : int
        Grid steps over ``v_range`` (2 ... :data:`MAX_LEVELS`).
    weights : tuple of float
        w_k >= 0 [x-unit], one per element in the order of :attr:`elements`.
    linear : float, optional
        w_lin >= 0 [x-unit per v-unit].
    x0 : float, optional
        Output offset [x-unit].
    start : {"rest", "virgin", "maximum"}, optional
        Initial play state relative to the first input v_0, as
        :data:`~piezolib.hysteresis.pi.PI_STARTS`: "rest" (as if lowered to
        v_0), "virgin" (demagnetised at v_0: the relays centred below v_0 up,
        those above down, the state a decaying alternation leaves), "maximum"
        (as if raised to v_0).

    Examples
    --------
    A relay of half-width 1 centred at 0 on a grid of 4 steps over [-2, 2]:

    >>> m = PreisachModel(v_range=(-2.0, 2.0), levels=4, weights=(0.0,) * 7 + (1.0,) + (0.0,) * 5,
    ...                   linear=0.5, start="maximum")
    >>> m.elements[7]                                   # (half-width r, centre c)
    (1.0, 0.0)
    >>> v = np.array([0.0, 2.0, 0.0, -2.0, 0.0])
    >>> m.simulate(v)                                    # up at v = 1.5, down at v = -1.5
    array([-1.,  2.,  1., -2., -1.])
    >>> bool(np.allclose(m.simulate(m.feedforward(m.simulate(v))), m.simulate(v)))
    True
    """

    v_range: tuple
    levels: int
    weights: tuple
    linear: float = 0.0
    x0: float = 0.0
    start: str = "rest"

    def __post_init__(self):
        v_range = _check_range("v_range", self.v_range)
        levels = check_count("levels", self.levels, maximum=MAX_LEVELS, minimum=2,
                             why="the fit's regressor has a column per element and sample")
        n = _grid(v_range, levels)[3].size
        w = check_finite_array("weights", self.weights, ndim=1, real=True)
        if w.size != n:
            raise ValueError(f"weights must hold one weight per element ({n} for {levels} "
                             f"levels), got {w.size}")
        if np.any(w < 0):
            raise ValueError(f"weights must be >= 0 (a monotone operator), got {w.min():g}")
        for name in ("linear", "x0"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating,
                                                                 np.integer)):
                raise TypeError(f"{name} must be a real number, got {value!r}")
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
        if self.linear < 0:
            raise ValueError(f"linear must be >= 0 (a monotone operator), got {self.linear!r}")
        if self.start not in PI_STARTS:
            raise ValueError(f"start must be one of {PI_STARTS}, got {self.start!r}")
        object.__setattr__(self, "v_range", v_range)
        object.__setattr__(self, "levels", levels)
        object.__setattr__(self, "weights", tuple(float(x) for x in w))
        object.__setattr__(self, "linear", float(self.linear))
        object.__setattr__(self, "x0", float(self.x0))

    @property
    def elements(self):
        """(half-width r, centre c) of every element [v-unit], in the order of ``weights``."""
        step, r, c, i, j = _grid(self.v_range, self.levels)
        return tuple((float(r[a]), float(c[b])) for a, b in zip(i, j))

    @property
    def thresholds(self):
        """The play thresholds r_i of the grid [v-unit] (the plays the elements are built on)."""
        return tuple(float(x) for x in _grid(self.v_range, self.levels)[1])

    @property
    def invertible(self):
        """Every output has an input: the slope beyond the grid is > 0 on both sides.

        With both :attr:`edge_slopes` 0 (w_lin = 0 and no weight on the
        elements at the grid's edges) the model is flat beyond the grid, so
        it reaches only a bounded range of outputs.
        """
        return min(self.edge_slopes) > 0

    @property
    def static_part(self):
        """(W, x0') of the line x = W v + x0' the loops are centred on.

        W = w_lin + 2 sum_k w_k / (hi - lo): the chord slope of a stroke that
        switches every element; the line passes through the demagnetised
        ("virgin") output at the middle of the grid.
        """
        step, r, c, i, j = _grid(self.v_range, self.levels)
        lo, hi = self.v_range
        mid = (lo + hi) / 2
        w = np.asarray(self.weights)
        slope = self.linear + 2 * float(np.sum(w)) / (hi - lo)
        x_mid = self.x0 + self.linear * mid + float(w @ np.sign(mid - c[j]))
        return slope, x_mid - slope * mid

    def initial_state(self, v0):
        """Play outputs (one per threshold) before the first sample, for the first input ``v0``."""
        return v0 + _SIDE[self.start] * np.asarray(self.thresholds)

    def _tables(self):
        """Knots (K,), per-play values (P, K) of the piecewise-linear sums of the elements, and
        per-play slopes (P,) below the first knot and above the last (module docstring)."""
        step, r, c, i, j = _grid(self.v_range, self.levels)
        knots = self.v_range[0] - step / 2 + step * np.arange(self.levels + 2)
        w = np.asarray(self.weights)
        table = np.zeros((r.size, knots.size))
        np.add.at(table, i, w[:, None] * _elements(np.tile(knots[:, None], (1, r.size)), step,
                                                   c, i, j, self.levels).T)
        top, bottom = _edges(self.levels, i, j)
        slope_lo, slope_hi = np.zeros(r.size), np.zeros(r.size)
        np.add.at(slope_lo, i[bottom], w[bottom] * 2 / step)
        np.add.at(slope_hi, i[top], w[top] * 2 / step)
        return knots, table, slope_lo, slope_hi

    @property
    def edge_slopes(self):
        """(below, above): the output's slope beyond the grid [x-unit per v-unit].

        Far below lo (above hi) with every play moving: w_lin plus the weights
        of the elements that switch at the edge, times 2 / step (the slope of
        their ramp, which the model keeps beyond the edge).
        """
        knots, table, slope_lo, slope_hi = self._tables()
        return self.linear + float(np.sum(slope_lo)), self.linear + float(np.sum(slope_hi))

    def simulate(self, v, state=None):
        """Displacement [x-unit] for the input record ``v`` [v-unit].

        Parameters
        ----------
        v : array_like
            Input, 1-D, at least 2 samples.
        state : array_like, optional
            Play outputs before the first sample (default: the model's ``start``).
        """
        v = _real_record("v", v)
        r = np.asarray(self.thresholds)
        y0 = self.initial_state(v[0]) if state is None else \
            check_finite_array("state", state, shape=(r.size,), real=True)
        plays = play_outputs(v, r, y0)
        knots, table, slope_lo, slope_hi = self._tables()
        out = self.x0 + self.linear * v
        for p in range(r.size):
            y = plays[:, p]
            out = out + np.interp(y, knots, table[p])
            if slope_lo[p]:
                out = out + slope_lo[p] * np.minimum(y - knots[0], 0.0)
            if slope_hi[p]:
                out = out + slope_hi[p] * np.maximum(y - knots[-1], 0.0)
        return out

    def feedforward(self, x_r):
        """Input [v-unit] that makes the model follow ``x_r`` [x-unit] (to rounding).

        Sample by sample the plays' states are known, and the output is a
        piecewise-linear non-decreasing function of the current input: a
        safeguarded Newton iteration (bisection where a Newton step leaves the
        bracket) finds the input, compiled with numba.  The first input v_0
        is solved with the model's ``start`` relative to it.  Where the output
        is flat (no element switching, w_lin = 0) any input of the flat part
        is returned.

        Raises
        ------
        NotInvertibleError
            Where x_r leaves the outputs the model can reach (only where an
            :attr:`edge_slopes` is 0), naming the sample.
        """
        x_r = _real_record("x_r", x_r)
        knots, table, slope_lo, slope_hi = self._tables()
        r = np.asarray(self.thresholds)
        step = (self.v_range[1] - self.v_range[0]) / self.levels
        below, above = self.edge_slopes
        v, bad = _inverse_kernel()(x_r - self.x0, r, knots, table, slope_lo, slope_hi,
                                   self.linear, step, _SIDE[self.start],
                                   0.5 * (self.v_range[0] + self.v_range[1]), below > 0,
                                   above > 0)
        if bad >= 0:
            top = self.x0 + float(np.sum(table[:, -1]))
            low = self.x0 + float(np.sum(table[:, 0]))
            raise NotInvertibleError(
                f"x_r[{bad}] = {x_r[bad]:.6g} is beyond the outputs the Preisach model reaches "
                f"(its slope beyond the grid is 0 {'above' if x_r[bad] > top else 'below'} it: "
                f"{low:.6g} ... {top:.6g} at most)")
        return v


def _real_record(name, v):
    return check_finite_array(name, v, ndim=1, min_length=2, real=True)


@functools.cache
def _inverse_kernel():
    """The compiled sample-by-sample inverse (numba imported and compiled or loaded once)."""
    import numba

    global _output

    @numba.njit(cache=True, nogil=True)
    def _output(v, y, r, knots, table, slope_lo, slope_hi, linear, step, side, first):
        # output and right slope at input v from play states y (first: y relative to v)
        f, slope = linear * v, linear
        k0, nk = knots[0], knots.size
        for p in range(r.size):
            if first:
                yp, moving = v + side * r[p], True
            else:
                yp, moving = y[p], False
                if v - r[p] >= yp:
                    yp, moving = v - r[p], True
                elif v + r[p] < yp:
                    yp, moving = v + r[p], True
            if yp <= k0:
                f += table[p, 0] + slope_lo[p] * (yp - k0)
                g = (table[p, 1] - table[p, 0]) / step if yp == k0 else slope_lo[p]
            elif yp >= knots[nk - 1]:
                f += table[p, nk - 1] + slope_hi[p] * (yp - knots[nk - 1])
                g = slope_hi[p]
            else:
                m = min(int((yp - k0) / step), nk - 2)
                t = (yp - knots[m]) / step
                f += table[p, m] + t * (table[p, m + 1] - table[p, m])
                g = (table[p, m + 1] - table[p, m]) / step
            if moving:
                slope += g
        return f, slope

    @numba.njit(cache=True, nogil=True)
    def run(target, r, knots, table, slope_lo, slope_hi, linear, step, side, guess,
            open_below, open_above):
        n = target.size
        v = np.empty(n)
        y = np.zeros(r.size)
        scale = (abs(linear) + np.sum(slope_lo) + np.sum(slope_hi)) * (knots[-1] - knots[0]) \
            + np.sum(np.abs(table)) + 1e-300
        tol = 1e-14 * scale
        reach = (knots[-1] - knots[0]) + 2 * r[-1] + 4 * step
        prev = guess
        model = (r, knots, table, slope_lo, slope_hi, linear, step, side)
        for k in range(n):
            first = k == 0
            t = target[k]
            x = prev
            f, g = _output(x, y, *model, first)
            if abs(f - t) <= tol:
                lo, hi = x, x
            elif f < t:                         # bracket upwards
                lo, d = x, step
                while True:
                    hi = lo + d
                    fh, gh = _output(hi, y, *model, first)
                    if fh >= t:
                        break
                    if not open_above and hi - prev > reach:
                        return v, k
                    lo, d = hi, 2 * d
            else:                               # downwards
                hi, d = x, step
                while True:
                    lo = hi - d
                    fl, gl = _output(lo, y, *model, first)
                    if fl <= t:
                        break
                    if not open_below and prev - lo > reach:
                        return v, k
                    hi, d = lo, 2 * d
            if lo != hi:
                x = 0.5 * (lo + hi)
                for _ in range(200):
                    f, g = _output(x, y, *model, first)
                    if abs(f - t) <= tol:
                        break
                    if f < t:
                        lo = x
                    else:
                        hi = x
                    if hi - lo <= 1e-15 * max(1.0, abs(x)):
                        break
                    x_new = x - (f - t) / g if g > 0 else 0.5 * (lo + hi)
                    if not lo < x_new < hi:
                        x_new = 0.5 * (lo + hi)
                    x = x_new
            v[k] = x
            for p in range(r.size):             # the plays move with the solved input
                if first:
                    y[p] = x + side * r[p]
                else:
                    y[p] = min(max(y[p], x - r[p]), x + r[p])
            prev = x
        return v, -1

    return run


@dataclass(frozen=True)
class PreisachFit(FitScores):
    """Result of :func:`fit_preisach`.

    Attributes
    ----------
    model : PreisachModel
    x_model : list of ndarray
        Model displacement for each loop's whole input record [x-unit].
    residuals : list of ndarray
        ``x_model - x`` per loop on the samples from ``discard`` on [x-unit].
    rms, rms_percent, max_percent : ndarray
        RMS residual per loop [x-unit], and RMS and largest |residual| in % of
        that loop's output range.
    parameters : tuple of ParameterEstimate
        The element weights (many on their bound 0: a grid has more elements
        than a record calls for) and x0, with 95 % intervals.
    start_scores : dict
        With ``start="auto"``: the weighted residual norm from each initial
        state (the smallest kept); empty otherwise.

    Examples
    --------
    >>> m = PreisachModel((-2.0, 2.0), 4, (0.0,) * 7 + (1.0,) + (0.0,) * 5, linear=0.5, x0=1.0)
    >>> v = 2 * np.sin(np.linspace(0, 9, 200))
    >>> fit = fit_preisach([(v, m.simulate(v))], levels=4, v_range=(-2.0, 2.0), start="rest")
    >>> type(fit).__name__, round(fit.pooled_rms_percent, 9)
    ('PreisachFit', 0.0)
    """

    model: PreisachModel
    x_model: list
    residuals: list
    rms: np.ndarray
    rms_percent: np.ndarray
    max_percent: np.ndarray
    parameters: tuple = ()
    start_scores: dict = None


def default_range(data):
    """The grid's input range for validated loops: theirs, widened by 0.1 % of it each side."""
    lo = min(float(np.min(v)) for v, x, used in data)
    hi = max(float(np.max(v)) for v, x, used in data)
    pad = 1e-3 * (hi - lo)
    return lo - pad, hi + pad


def check_levels(levels, data):
    """``levels`` checked against :data:`MAX_LEVELS` and the regressor's size, before any work."""
    levels = check_count("levels", levels, maximum=MAX_LEVELS, minimum=2,
                         why="the fit's regressor has a column per element and sample")
    n = _grid((0.0, 1.0), levels)[3].size
    samples = sum(v.size for v, x, used in data)
    if n * samples > MAX_REGRESSOR_ENTRIES:
        raise ValueError(f"levels = {levels} on {samples:,} samples needs a regressor of "
                         f"{n * samples:,} entries, at most {MAX_REGRESSOR_ENTRIES:,}: fewer "
                         "levels or shorter records")
    return levels


def fit_preisach(loops, levels=16, offset=True, start="auto", discard=0, v_range=None):
    """Fit the element weights of a ramped-relay Preisach operator to loops (bounded LS).

    With the grid fixed the output is linear in the weights and the offset:
    one bounded linear least-squares problem (weights >= 0, offset free,
    :func:`scipy.optimize.lsq_linear`), each loop's residual divided by its
    output range and sqrt(samples used), as :func:`~piezolib.hysteresis.pi.fit_pi`.
    The part the static ramps share becomes the linear weight (module
    docstring).

    Parameters
    ----------
    loops : sequence of (v, x)
        Input [v-unit] and measured output [x-unit] records (or one pair).
    levels : int, optional
        Grid steps over the input range (2 ... :data:`MAX_LEVELS`; samples x
        elements at most :data:`MAX_REGRESSOR_ENTRIES`).
    offset : bool, optional
        Fit the output offset x0.
    start : {"auto", "rest", "virgin", "maximum"}, optional
        Initial play state (:class:`PreisachModel`); "auto" fits from each
        and keeps the smallest residual.
    discard : int, optional
        Samples at the start of each record left out of the residuals.
    v_range : (float, float), optional
        The grid's input range [v-unit]; default the loops' input range
        widened by 0.1 % each side.

    Returns
    -------
    PreisachFit
        A :class:`~piezolib.hysteresis.common.FitWarning` when every weight
        is 0 (the records show no hysteresis the grid can hold) or the
        output does not rise with the input; zero weights of single
        elements are normal for a grid and not warned about.

    Raises
    ------
    ValueError
        For loops without an ascending and a descending stroke of v after
        ``discard``, or a grid too large.

    Examples
    --------
    >>> m = PreisachModel((-2.0, 2.0), 4, (0.0,) * 7 + (1.0,) + (0.0,) * 5, linear=0.5, x0=1.0)
    >>> v = 2 * np.sin(np.linspace(0, 9, 200))
    >>> fit = fit_preisach([(v, m.simulate(v))], levels=4, v_range=(-2.0, 2.0), start="rest")
    >>> round(fit.model.weights[7], 9), round(fit.model.linear, 9)
    (1.0, 0.5)
    """
    data = check_loops(loops, discard, 1)
    if start != "auto" and start not in PI_STARTS:
        raise ValueError(f"start must be 'auto' or one of {PI_STARTS}, got {start!r}")
    if not isinstance(offset, (bool, np.bool_)):
        raise TypeError(f"offset must be True or False, got {offset!r}")
    levels = check_levels(levels, data)
    v_range = default_range(data) if v_range is None else _check_range("v_range", v_range)
    starts = PI_STARTS if start == "auto" else (start,)
    n_all = _grid(v_range, levels)[3].size
    solved = {}
    for s0 in starts:
        regs, keep = pruned_regressors(data, v_range, levels, s0, offset)
        solved[s0] = (*_solve(data, regs, offset), keep)
    norms = {s0: float(np.linalg.norm(A @ th - b)) for s0, (A, b, th, k) in solved.items()}
    scores = norms if start == "auto" else {}
    start = min(starts, key=norms.get)
    A, b, theta, keep = solved[start]
    x0 = float(theta[-1]) if offset else 0.0
    model = preisach_model(v_range, levels, scatter(keep, theta[:keep.size], n_all), x0, start)
    parameters = preisach_parameters(model, A, b, theta, offset, keep)
    what = f"fit_preisach (start {start!r})"
    warn_about([p for p in parameters if p.name == "x0"], what)
    preisach_warnings(model, what)
    pairs = loop_pairs(loops)
    x_model = [model.simulate(np.asarray(p[0], dtype=float)) for p in pairs]
    res, rms, rms_pct, max_pct = loop_errors(x_model, pairs, discard)
    return PreisachFit(model=model, x_model=x_model, residuals=res, rms=rms,
                       rms_percent=rms_pct, max_percent=max_pct, parameters=tuple(parameters),
                       start_scores=scores)


def preisach_model(v_range, levels, w, x0, start):
    """The :class:`PreisachModel` of fitted element weights (linear share folded)."""
    w = np.maximum(np.asarray(w, dtype=float), 0.0)
    w[w <= 1e-12 * max(float(np.sum(w)), 1e-300)] = 0.0      # rounding of the active set
    w, linear, x0 = fold_linear(v_range, levels, w, x0)
    return PreisachModel(v_range, levels, tuple(w), linear=linear, x0=x0, start=start)


def preisach_parameters(model, A, b, theta, offset, keep):
    """ParameterEstimate of each fitted element weight (as fitted, before the fold) and x0.

    The elements the records cannot tell apart from others (not in ``keep``) are not listed.
    """
    n = A.shape[1] - (1 if offset else 0)
    at_bound = list(theta[:n] <= 1e-12 * max(float(np.sum(theta[:n])), 1e-300)) + \
        ([False] if offset else [])
    free = ~np.array(at_bound)
    cov = np.full((theta.size, theta.size), np.nan)    # a weight on its bound: no interval
    cov[np.ix_(free, free)] = covariance(A[:, free], A @ theta - b, int(np.count_nonzero(free)))
    elements = model.elements
    names = [f"w (r = {elements[k][0]:.4g}, c = {elements[k][1]:.4g})" for k in keep] + \
        (["x0"] if offset else [])
    units = ["x"] * n + (["x"] if offset else [])
    return estimates(names, units, np.r_[np.where(at_bound[:n], 0.0, theta[:n]), theta[n:]],
                     [False] * theta.size, cov, at_bound)


def preisach_warnings(model, what):
    """FitWarning when every weight is 0 or the model does not rise with the input."""
    import warnings
    if not any(model.weights) and model.linear == 0:
        warnings.warn(f"{what}: every weight is 0 (the output does not follow the input)",
                      FitWarning, stacklevel=3)
    elif model.static_part[0] <= 0:
        warnings.warn(f"{what}: the output does not rise with the input", FitWarning,
                      stacklevel=3)


def _solve(data, regs, offset):
    """Bounded least squares of the element weights (and offset) from one initial state."""
    rows, rhs = [], []
    for (v, x, used), (E, weight) in zip(data, regs):
        cols = [E[used]] + ([np.ones((used.size, 1))] if offset else [])
        rows.append(weight * np.hstack(cols))
        rhs.append(weight * x[used])
    A, b = np.vstack(rows), np.concatenate(rhs)
    n = A.shape[1] - (1 if offset else 0)
    lower = np.r_[np.zeros(n), [-np.inf] if offset else []]
    theta = opt.lsq_linear(A, b, bounds=(lower, np.inf), method="bvls").x
    return A, b, theta


