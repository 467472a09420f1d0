"""Prandtl-Ishlinskii hysteresis model: play operators, NNLS fit, exact inverse feedforward.

x = x0 + sum_i w_i F_{r_i}[v], with F_r the play (backlash) operator of
threshold r (r_0 = 0: F_0[v] = v, the linear part).  Rate independent, as
the Dahl model.  :func:`fit_pi` finds the weights of fixed thresholds by
non-negative least squares (one linear problem: no starting point, no local
minima); :meth:`PIModel.inverse` is the exact inverse, another PI operator
with thresholds r^_j = sum_{i<=j} w_i (r_j - r_i) and weights
w^_0 = 1/w_0, w^_j = -w_j / (W_j W_{j-1}) (W_j = w_0 + ... + w_j), so that
:meth:`PIModel.feedforward` followed by :meth:`PIModel.simulate` is the
identity.  Both models share the interface of
:class:`~piezolib.hysteresis.common.HysteresisModel`.
"""

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize as opt

from piezolib._checks import check_count, check_finite_array, check_integer
from piezolib.hysteresis.common import (FitScores, FitWarning, check_loops, covariance, estimates,
                                        loop_errors, loop_pairs, warn_about)
from piezolib.hysteresis.dahl import NotInvertibleError, strokes

# pi_regressors is shared with hammerstein.py (checked inputs), not part of the API
__all__ = ["PI_STARTS", "MAX_PLAYS", "PIModel", "PIFit", "play_outputs", "fit_pi",
           "FitWarning"]

#: Initial play states: "rest" as if lowered to the first input (y_i = v_0 + r_i, the
#: descending branch: a stage at rest, or a record cut at an input minimum), "virgin" every
#: play centred on it (y_i = v_0), "maximum" as if raised to it (y_i = v_0 - r_i, the
#: ascending branch: a record cut at an input maximum).
PI_STARTS = ("rest", "virgin", "maximum")
#: Most play operators of a fit: its regressor holds one column per play and sample, and
#: the fit's time grows faster than the plays (a 20,000-sample loop: 1000 plays 6 min and
#: 1.1 GB, 100 plays 22 s, on a shared 2-core machine, ``benchmarks/bench_size_limits.py``).
MAX_PLAYS = 100


def play_outputs(v, thresholds, y0):
    """Outputs of the play operators F_{r_i} for input records: the workbook's one play kernel.

    Parameters
    ----------
    v : ndarray, shape (N,) or (N, m)
        Input [v-unit]: one record, or m independent records (columns).
    thresholds : ndarray
        Thresholds r_i >= 0 [v-unit].
    y0 : ndarray, shape (len(thresholds),) or (m, len(thresholds))
        Play outputs before the first sample (clipped to [v_0 - r, v_0 + r]).

    Returns
    -------
    ndarray, shape (N, len(thresholds)) or (N, m, len(thresholds))
        y[k] = min(max(y[k-1], v[k] - r), v[k] + r).  Along a rising stroke
        that is y = max(y_start, v - r), along a falling one y = min(y_start,
        v + r): a record with few strokes takes one numpy operation per
        stroke, one with many (a multisine) one per sample over all columns.
        Both are exact (maxima and minima), so they give the same numbers.

    Examples
    --------
    A play of threshold 0.5 on a triangle lags the input by 0.5 on each stroke:

    >>> v = np.array([0.0, 1.0, 2.0, 1.0, 0.0])
    >>> play_outputs(v, np.array([0.0, 0.5]), np.zeros(2))[:, 1]
    array([0. , 0.5, 1.5, 1.5, 0.5])
    """
    v = check_finite_array("v", v, real=True)
    if v.ndim not in (1, 2) or v.shape[0] < 1:
        raise ValueError(f"v must have shape (N,) or (N, m) with N >= 1, got {v.shape}")
    r = check_finite_array("thresholds", thresholds, ndim=1, min_length=1, real=True)
    if np.any(r < 0):
        raise ValueError(f"thresholds must be >= 0, got {r}")
    columns = v.reshape(v.shape[0], -1)
    y0 = check_finite_array("y0", y0, real=True)
    if y0.shape not in ((r.size,), (columns.shape[1], r.size)):
        raise ValueError(f"y0 must have shape ({r.size},) or ({columns.shape[1]}, {r.size}), "
                         f"got {y0.shape}")
    y = np.clip(np.broadcast_to(y0, (columns.shape[1], r.size)),
                columns[0][:, None] - r, columns[0][:, None] + r)
    turns = np.count_nonzero(np.diff(np.sign(np.diff(columns, axis=0)), axis=0))
    Y = (_plays_by_stroke(columns, r, y) if turns * 4 < columns.size
         else _plays_by_sample(columns, r, y))
    return Y[:, 0] if v.ndim == 1 else Y


def _plays_by_stroke(columns, r, y):
    """:func:`play_outputs` of each column, one numpy operation per stroke."""
    Y = np.empty((columns.shape[0], columns.shape[1], r.size))
    Y[0] = y
    for j in range(columns.shape[1]):
        v, yj = columns[:, j], y[j]
        for start, stop, s in strokes(v):
            seg = v[start + 1:stop + 1, None]
            Y[start + 1:stop + 1, j] = np.maximum(yj, seg - r) if s > 0 else np.minimum(yj, seg + r)
            yj = Y[stop, j]
    return Y


def _plays_by_sample(columns, r, y):
    """:func:`play_outputs` of all columns at once, one numpy operation per sample."""
    Y = np.empty((columns.shape[0], columns.shape[1], r.size))
    Y[0] = y
    for k in range(1, columns.shape[0]):
        vk = columns[k][:, None]
        y = np.minimum(np.maximum(y, vk - r), vk + r)
        Y[k] = y
    return Y


@dataclass(frozen=True)
class PIModel:
    """Prandtl-Ishlinskii model x = x0 + sum_i w_i F_{r_i}[v].

    Attributes
    ----------
    thresholds : tuple of float
        r_0 = 0 <= r_1 <= ... [v-unit] (non-decreasing; r_0 = 0 is the linear term).
    weights : tuple of float
        w_i [x-unit per v-unit]; the fitted model has w_i >= 0 and w_0 > 0,
        the inverse has negative weights.
    x0 : float, optional
        Output offset [x-unit].
    start : {"rest", "virgin", "maximum"}, optional
        Initial play state relative to the first input v_0 (:data:`PI_STARTS`).

    Examples
    --------
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> pi.simulate(np.array([0.0, 1.0, 2.0, 1.0, 0.0]))     # the loop opens on the way down
    array([0.  , 1.15, 2.65, 1.65, 0.35])
    >>> pi.invertible, pi.static_part                            # (sum of weights, x0)
    (True, (1.5, 0.0))
    >>> x_r = np.array([0.0, 1.0, 2.0, 1.0, 0.0])
    >>> bool(np.allclose(pi.simulate(pi.feedforward(x_r)), x_r))   # exact inverse
    True
    """

    thresholds: tuple
    weights: tuple
    x0: float = 0.0
    start: str = "rest"

    def __post_init__(self):
        r = check_finite_array("thresholds", self.thresholds, ndim=1, min_length=1)
        w = check_finite_array("weights", self.weights, ndim=1)
        if np.iscomplexobj(r) or np.iscomplexobj(w):
            raise TypeError("thresholds and weights must be real")
        if w.size != r.size:
            raise ValueError(f"weights must hold one weight per threshold ({r.size}), "
                             f"got {w.size}")
        if r[0] != 0 or np.any(np.diff(r) < 0):
            raise ValueError("thresholds must start at 0 and be non-decreasing, "
                             f"got {tuple(r)}")
        if not math.isfinite(self.x0):
            raise ValueError(f"x0 must be finite, got {self.x0!r}")
        if self.start not in PI_STARTS:
            raise ValueError(f"start must be one of {PI_STARTS}, got {self.start!r}")
        object.__setattr__(self, "thresholds", tuple(float(x) for x in r))
        object.__setattr__(self, "weights", tuple(float(x) for x in w))
        object.__setattr__(self, "x0", float(self.x0))

    @property
    def invertible(self):
        """w_0 > 0 and every w_i >= 0: x rises strictly with v along every stroke."""
        return self.weights[0] > 0 and min(self.weights) >= 0

    @property
    def static_part(self):
        """(W, x0) with W = sum_i w_i: the line x = W v + x0 the loops are centred on.

        Each play stays within its threshold of the input (|F_r[v] - v| <= r),
        so x = W v + x0 - sum_i w_i (v - F_{r_i}[v]) with a bounded,
        direction-dependent hysteretic term: W is the slope of the loop's
        branches once every play moves (strokes beyond 2 r_max), the
        counterpart of the Dahl model's g_a, and x0 its offset.  The map a
        feedforward without hysteresis compensation inverts, v = (x_r - x0) / W.
        """
        return float(np.sum(self.weights)), self.x0

    def initial_state(self, v0):
        """Play outputs before the first sample, for the first input ``v0`` [v-unit]."""
        r = np.asarray(self.thresholds)
        return v0 + {"rest": 1.0, "virgin": 0.0, "maximum": -1.0}[self.start] * r

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
        y0 = self.initial_state(v[0]) if state is None else \
            check_finite_array("state", state, shape=(len(self.thresholds),))
        return self.x0 + play_outputs(v, self.thresholds, y0) @ np.asarray(self.weights)

    def inverse(self, v0=0.0):
        """The exact inverse operator, for a forward model that starts at input ``v0``.

        Returns
        -------
        model : PIModel
            Thresholds r^_j and weights w^_j of the module docstring, x0 = 0:
            it maps x - x0 back to v.
        state : ndarray
            Its play outputs before the first sample, from the forward
            model's initial state y_i:
            y^_j = W_j y_j + sum_{i>j} w_i y_i (for j = 0 this is x - x0 itself).

        Raises
        ------
        NotInvertibleError
            When w_0 <= 0 or a weight is negative.
        """
        if not self.invertible:
            raise NotInvertibleError(
                "the PI model is invertible only with w_0 > 0 and w_i >= 0, got weights "
                f"{self.weights}")
        r, w = np.asarray(self.thresholds), np.asarray(self.weights)
        W = np.cumsum(w)
        r_hat = np.array([np.sum(w[:j + 1] * (r[j] - r[:j + 1])) for j in range(r.size)])
        w_hat = np.empty(r.size)
        w_hat[0] = 1.0 / w[0]
        w_hat[1:] = -w[1:] / (W[1:] * W[:-1])
        y = self.initial_state(v0)
        above = np.r_[np.cumsum((w * y)[::-1])[::-1][1:], 0.0]     # sum_{i>j} w_i y_i
        state = W * y + above
        return PIModel(tuple(np.maximum.accumulate(r_hat)), tuple(w_hat)), state

    def feedforward(self, x_r):
        """Input [v-unit] that makes the model follow ``x_r`` [x-unit] exactly.

        The inverse operator driven by x_r - x0, started in the state that
        matches the model's ``start`` at the input v_0 giving x_r[0].
        """
        x_r = _real_record("x_r", x_r)
        w = np.asarray(self.weights)
        if not self.invertible:
            self.inverse()                      # raises the explanatory error
        side = {"rest": 1.0, "virgin": 0.0, "maximum": -1.0}[self.start]
        shift = side * float(w @ np.asarray(self.thresholds))
        v0 = (x_r[0] - self.x0 - shift) / float(w.sum())
        inv, state = self.inverse(v0)
        return inv.simulate(x_r - self.x0, state=state)


def _real_record(name, v):
    v = check_finite_array(name, v, ndim=1, min_length=2)
    if np.iscomplexobj(v):
        raise TypeError(f"{name} must be real, got complex values")
    return v


@dataclass(frozen=True)
class PIFit(FitScores):
    """Result of :func:`fit_pi`.

    Attributes
    ----------
    model : PIModel
    x_model : list of ndarray
        Model displacement for each loop's whole input record [x-unit].
    residuals : list of ndarray
        ``x_model - x`` per loop on the samples from ``discard`` on [x-unit].
    rms, rms_percent, max_percent : ndarray
        RMS residual per loop [x-unit], and RMS and largest |residual| in % of
        that loop's output range.
    parameters : tuple of ParameterEstimate
        w_0 ... w_n (and x0) with 95 % confidence intervals; a weight on its
        bound 0 is a play the data do not call for.
    start_scores : dict
        With ``start="auto"``: the weighted residual norm of the fit from each
        initial state (the smaller one was kept); empty otherwise.

    Examples
    --------
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20), np.linspace(0.2, 4, 20)]
    >>> fit = fit_pi([(v, pi.simulate(v))], offset=False, start="virgin",
    ...              thresholds=pi.thresholds)
    >>> type(fit).__name__, fit.rms_percent.shape, round(fit.pooled_rms_percent, 6)
    ('PIFit', (1,), 0.0)
    >>> fit.parameter_table().index[0]
    'w_0 (r = 0)'
    """

    model: PIModel
    x_model: list
    residuals: list
    rms: np.ndarray
    rms_percent: np.ndarray
    max_percent: np.ndarray
    parameters: tuple = ()
    start_scores: dict = None


def pi_regressors(data, thresholds, start):
    """Play outputs of already validated loops, one (Y, weight) per loop.

    ``data`` is what :func:`~piezolib.hysteresis.common.check_loops` returns;
    ``Y`` holds the play outputs of the model start ``start`` on every sample
    of the (thinned) loop, ``weight`` = 1 / (output range x sqrt(samples used)).
    Shared by :func:`fit_pi` and the Hammerstein fit.
    """
    template = PIModel(tuple(thresholds), tuple(np.ones(len(thresholds))), start=start)
    r = np.asarray(template.thresholds)
    out = []
    for v, x, used in data:
        Y = play_outputs(v, r, template.initial_state(v[0]))
        out.append((Y, 1.0 / (np.ptp(x[used]) * math.sqrt(used.size))))
    return out


def _solve_weights(data, r, offset, start):
    """Bounded least squares of the weights (and offset) from one initial state."""
    rows, rhs = [], []
    for (v, x, used), (Y, weight) in zip(data, pi_regressors(data, r, start)):
        cols = [Y[used]] + ([np.ones((used.size, 1))] if offset else [])
        rows.append(weight * np.hstack(cols))
        rhs.append(weight * x[used])
    A, b = np.vstack(rows), np.concatenate(rhs)
    slope = np.linalg.lstsq(A[:, :1] - A[:, :1].mean(), b - b.mean(), rcond=None)[0][0] \
        if offset else np.linalg.lstsq(A[:, :1], b, rcond=None)[0][0]
    if not slope > 0:
        raise ValueError("the loops must show x increasing with v (positive mean slope): "
                         "the data cannot support a hysteresis model")
    lower = np.r_[np.zeros(r.size), [-np.inf] if offset else []]
    theta = opt.lsq_linear(A, b, bounds=(lower, np.inf), method="bvls").x
    return A, b, theta


def fit_pi(loops, n_plays=10, offset=True, start="auto", discard=0, thresholds=None):
    """Fit the play weights of a PI model to one or several loops jointly (NNLS).

    With the thresholds fixed the output is linear in the weights and the
    offset, so the fit is one bounded linear least-squares problem
    (weights >= 0, offset free): no starting point, no iterations on the
    model, any sampling rate and record length.  Each loop's residual is
    divided by its output range and sqrt(samples used), as in
    :func:`~piezolib.hysteresis.fit.fit_dahl`.

    Parameters
    ----------
    loops : sequence of (v, x)
        Input [v-unit] and measured output [x-unit] records (or one pair).
    n_plays : int, optional
        Number of play operators, including the linear one (r = 0), at most
        :data:`MAX_PLAYS`.  Default thresholds r_i = i / n_plays * (largest input range) / 2.
    offset : bool, optional
        Fit the output offset x0 (default True).
    start : {"auto", "rest", "virgin", "maximum"}, optional
        The model's initial play state (:data:`PI_STARTS`).  Default
        ``"auto"``: fit from each and keep the one with the smaller residual.
        The initial state is the stage's unrecorded history, which the
        record alone decides: a record that begins after a long descending
        stroke (a cut at an input minimum, a stage lowered to rest) supports
        "rest", one cut at an input maximum (after an ascending stroke)
        "maximum", a freshly powered or depolarised actuator "virgin".  A
        wrong guess does not merely add error at the start: the weights that
        would explain the first strokes are driven to their bound 0
        (observed on a raw record: 8 of 10 weights zero from "rest" and
        twice the error of "virgin"; a record cut at its +150 V peak fitted
        at 1.36 % of stroke without the "maximum" state, 0.26 % from the
        next minimum), and the three fits cost three linear solves.  Pass
        one of :data:`PI_STARTS` to impose it.
    discard : int, optional
        Samples at the start of each record left out of the residuals (the
        plays still run through them).
    thresholds : array_like, optional
        Thresholds to use instead (first 0, non-decreasing) [v-unit].

    Returns
    -------
    PIFit
        A :class:`~piezolib.hysteresis.common.FitWarning` names every
        parameter on its bound (a weight at 0: a play the data do not call
        for; the linear weight w_0 at 0 leaves the model without an exact
        inverse) or not identifiable (95 % interval including 0).

    Raises
    ------
    ValueError
        For loops without an ascending and a descending stroke of v after
        ``discard``, or with x not increasing with v.

    Examples
    --------
    >>> pi = PIModel(thresholds=(0.0, 0.5, 1.0), weights=(1.0, 0.3, 0.2), start="virgin")
    >>> v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20), np.linspace(0.2, 4, 20)]
    >>> fit = fit_pi([(v, pi.simulate(v))], offset=False, start="virgin",
    ...              thresholds=pi.thresholds)              # one NNLS solve
    >>> np.round(fit.model.weights, 6)
    array([1. , 0.3, 0.2])
    """
    data = check_loops(loops, discard, 1)
    if start != "auto" and start not in PI_STARTS:
        raise ValueError(f"start must be 'auto' or one of {PI_STARTS}, got {start!r}")
    if not isinstance(offset, (bool, np.bool_)):
        raise TypeError(f"offset must be True or False, got {offset!r}")
    if thresholds is None:
        n_plays = check_count("n_plays", n_plays, maximum=MAX_PLAYS,
                              why="the regressor has a column per play and sample")
        half = max(float(np.ptp(v)) for v, x, used in data) / 2.0
        thresholds = half * np.arange(n_plays) / n_plays
    thresholds = check_finite_array("thresholds", thresholds, ndim=1, min_length=1, real=True)
    if thresholds.size > MAX_PLAYS:
        raise ValueError(f"thresholds must hold at most {MAX_PLAYS} plays, got {thresholds.size}")
    r = np.asarray(PIModel(tuple(thresholds), tuple(np.ones(thresholds.size))).thresholds)
    scores = {}
    if start == "auto":
        solved = {s0: _solve_weights(data, r, offset, s0) for s0 in PI_STARTS}
        scores = {s0: float(np.linalg.norm(A @ th - b)) for s0, (A, b, th) in solved.items()}
        start = min(PI_STARTS, key=lambda s0: scores[s0])        # ties: "rest", listed first
        A, b, theta = solved[start]
    else:
        A, b, theta = _solve_weights(data, r, offset, start)
    x0 = float(theta[-1]) if offset else 0.0
    model = PIModel(tuple(r), tuple(theta[:r.size]), x0=x0, start=start)
    w_fit = theta[:r.size]
    tiny = 1e-12 * float(np.sum(w_fit))               # rounding of the active set
    w_fit[w_fit <= tiny] = 0.0
    at_bound = list(w_fit <= 0) + ([False] if offset else [])
    cov = covariance(A, A @ theta - b, int(np.count_nonzero(~np.array(at_bound))))
    names = [f"w_{i} (r = {ri:.4g})" for i, ri in enumerate(r)] + (["x0"] if offset else [])
    units = ["x/v"] * r.size + (["x"] if offset else [])
    parameters = estimates(names, units, theta, [False] * theta.size, cov, at_bound)
    what = f"fit_pi (start {start!r})"
    if at_bound[0]:
        what += ": the linear weight w_0 is 0 (no exact inverse)"
    warn_about(parameters, what)
    pairs = loop_pairs(loops)
    x_model = [model.simulate(np.asarray(pair[0], dtype=float)) for pair in pairs]
    res, rms, rms_pct, max_pct = loop_errors(x_model, pairs, discard)
    return PIFit(model=model, x_model=x_model, residuals=res, rms=rms, rms_percent=rms_pct,
                 max_percent=max_pct, parameters=tuple(parameters), start_scores=scores)


