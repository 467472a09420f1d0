"""Least-squares fit of the Dahl model to measured loops, and the rule that picks among fits.

:func:`fit_dahl` fits the voltage-driven model (output error on x) to one or
several loops jointly, with or without the output offset x0; starting points
come from an equation-error grid search.  :func:`choose_fit` is the selection
rule (smallest pooled RMS error).  Raw, noisy records at any sampling rate
and start point are accepted: stroke directions come from the input, the
equation-error start drives the model by the measured output made monotone
along each input stroke (isotonic projection), and
:meth:`DahlFit.parameter_table` reports every parameter's 95 % confidence
interval, whether it sits on a bound and whether the data identify it (a
:class:`~piezolib.hysteresis.common.FitWarning` is issued otherwise).
Method: ``docs/hysteresis.md``.
"""

import math
import numbers
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np
import scipy.optimize as opt

from piezolib._checks import check_integer, check_positive, check_signals
from piezolib.hysteresis.common import (FitScores, check_loops, covariance, estimates, loop_errors,
                                        warn_about)
from piezolib.hysteresis.dahl import (DAHL_STARTS, FORMS, DahlModel, NotInvertibleError,
                                      _z1_driven, simulate_dahl, simulate_dahl_records,
                                      strokes)
from piezolib.progress import postfix, progress

__all__ = ["DahlFit", "fit_dahl", "MAX_FIT_SAMPLES", "rescore_dahl", "monotone_path", "choose_fit", "check_fit_options", "ALPHA1_BOUNDS",
           "ALPHA2_BOUNDS", "G_A_BOUNDS"]


@dataclass(frozen=True)
class DahlFit(FitScores):
    """Result of :func:`fit_dahl`.

    Attributes
    ----------
    model : DahlModel
        Fitted model (``beta1 = 0``, ``gamma_a`` as given).
    x_model : list of ndarray
        Model displacement for each loop's whole input record [x-unit].
    residuals : list of ndarray
        ``x_model - x`` for each loop on the samples used [x-unit].
    rms : ndarray
        RMS residual per loop [x-unit].
    rms_percent : ndarray
        RMS residual per loop in % of that loop's output range.
    max_percent : ndarray
        Largest |residual| per loop in % of that loop's output range.
    initial : DahlModel
        Starting point of the best solution.
    result : scipy.optimize.OptimizeResult
        The output-error least-squares solution (scaled parameters; x0 is
        projected out and not part of ``result.x``).
    offset : bool
        Whether the output offset ``model.x0`` was fitted (False: x0 = 0,
        the paper's eq. 13).
    parameters : tuple of ParameterEstimate
        g_a, alpha1, alpha2, beta2 (and x0) with 95 % confidence intervals,
        bound and identifiability flags, then the derived steady state
        H_ss = beta2 gamma_a / alpha2 and first-order rate alpha2 / alpha1
        (:meth:`parameter_table`).

    Examples
    --------
    >>> from piezolib.signals import triangle
    >>> true = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                  form="bliman_sorine")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)        # a 0-4 V triangle, 81 samples
    >>> fit = fit_dahl([(v, true.simulate(v))], gamma_a=0.5, starts=1)
    >>> type(fit).__name__, fit.offset, len(fit.x_model[0])
    ('DahlFit', False, 81)
    >>> [p.name for p in fit.parameters][:4]
    ['g_a', 'alpha1', 'alpha2', 'beta2']
    """

    model: DahlModel
    x_model: list
    residuals: list
    rms: np.ndarray
    rms_percent: np.ndarray
    max_percent: np.ndarray
    initial: DahlModel
    result: object
    offset: bool = False
    parameters: tuple = ()


def monotone_path(v, x):
    """The measured x made to move with the input: isotonic along each stroke of v.

    Within every run of constant direction of v, x is replaced by its
    least-squares projection on the sequences that move in that direction
    (and not back past the run's start).  Noise that moves a measured x
    against the input stroke is averaged out instead of driving the
    stroke integration backwards.

    Parameters
    ----------
    v, x : ndarray
        Input and measured output, 1-D, same length.

    Returns
    -------
    ndarray
        The projected output [x-unit].

    Examples
    --------
    Noise that moves x against the input stroke is averaged out:

    >>> v = np.array([0.0, 1.0, 2.0, 3.0, 2.0, 1.0])
    >>> monotone_path(v, np.array([0.0, 1.2, 1.0, 3.0, 2.1, 2.3]))
    array([0. , 1.1, 1.1, 3. , 2.2, 2.2])
    """
    v, x = check_signals(2, v=v, x=x)
    out = x.copy()
    for start, stop, s in strokes(v):
        seg = opt.isotonic_regression(out[start + 1:stop + 1], increasing=s > 0).x
        out[start + 1:stop + 1] = (np.maximum(seg, out[start]) if s > 0
                                   else np.minimum(seg, out[start]))
    return out


def _unit_model(form, alpha1, alpha2, start):
    """Model whose H is z1 for gamma_a = 1: H of a general model is beta2*gamma_a*z1."""
    return DahlModel(alpha1, alpha2, 0.0, 1.0, 1.0, 1.0, form=form, start=start)


#: Fit bounds of alpha1 * R and alpha2 * R^2 (R: output range).  The upper
#: bounds reach the first-order limit: for alpha1 R >> 1 the fast mode of
#: the stroke dynamics (path length 1/alpha1) is negligible and the model
#: acts as a first-order Dahl model, H -> +-b/alpha2 at the rate
#: alpha2/alpha1 per x-unit; at alpha1 R = 1e5 the fast mode lasts 1e-5 of
#: the range.  Below alpha2 R^2 = 1e-4 the steady state b/alpha2 becomes so
#: large that H is the small difference of huge terms.
ALPHA1_BOUNDS = (1e-3, 1e5)
ALPHA2_BOUNDS = (1e-4, 1e8)
#: Fit bounds of g_a relative to the loops' mean slope: H stays a deviation
#: from g_a v.  Without them the Bliman-Sorine fit drifts to g_a -> 0 with H
#: carrying the whole transduction (a degenerate, ill-conditioned limit).
G_A_BOUNDS = (0.5, 2.0)
_GRID_CELL = 1.5   # e-folds per grid cell of the starting-point search
_ON_BOUND = 1e-6   # a fitted parameter this close to a bound (relative to its range) is on it


def _mean_slope(data):
    """Least-squares slope of x on v over all loops (each loop about its own mean).

    Independent of the first sample (a record may start at a step, at rest
    or mid-stroke).
    """
    num = den = 0.0
    for v, x, used in data:
        dv, dx = v[used] - np.mean(v[used]), x[used] - np.mean(x[used])
        num += float(dv @ dx)
        den += float(dv @ dv)
    if not num > 0 or not den > 0:
        raise ValueError("the loops must show x increasing with v (positive mean slope): "
                         "the data cannot support a hysteresis model x = g_a v - H")
    return num / den


def _loop_weights(data):
    """Residual weight per loop: 1 / (output range * sqrt(samples used))."""
    return [1.0 / (np.ptp(x[used]) * math.sqrt(used.size)) for v, x, used in data]


def _equation_error(form, data, paths, log_a1, log_a2, g_bounds, offset, start):
    """Residual and (g_a, b[, x0]) of the linear problem x = g_a v - b z1(x) [+ x0].

    z1 is driven by the measured x (``paths``: :func:`monotone_path`), which
    makes the problem linear in g_a,
    b = beta2 gamma_a and the offset x0.  g_a is held inside ``g_bounds``
    (clipped, the other parameters then refitted).
    """
    unit = _unit_model(form, math.exp(log_a1), math.exp(log_a2), start)
    rows, rhs = [], []
    z1s = _z1_driven(unit, [(v, path) for (v, x, used), path in zip(data, paths)])
    for (v, x, used), z1, w in zip(data, z1s, _loop_weights(data)):
        columns = [v[used], -z1[used]] + ([np.ones(used.size)] if offset else [])
        rows.append(w * np.column_stack(columns))
        rhs.append(w * x[used])
    M, y = np.vstack(rows), np.concatenate(rhs)
    theta = np.linalg.lstsq(M, y, rcond=None)[0]
    if not g_bounds[0] <= theta[0] <= g_bounds[1]:
        theta[0] = min(max(theta[0], g_bounds[0]), g_bounds[1])
        theta[1:] = np.linalg.lstsq(M[:, 1:], y - theta[0] * M[:, 0], rcond=None)[0]
    return M @ theta - y, theta


def _alpha_bounds(R):
    """Lower and upper bounds of (log alpha1, log alpha2) for output range R."""
    lo = [math.log(ALPHA1_BOUNDS[0] / R), math.log(ALPHA2_BOUNDS[0] / R ** 2)]
    hi = [math.log(ALPHA1_BOUNDS[1] / R), math.log(ALPHA2_BOUNDS[1] / R ** 2)]
    return lo, hi


def _initial_guesses(form, data, gamma_a, g_bounds, starts, offset, start):
    """Equation-error starting points, best first.

    For fixed (alpha1, alpha2), x = g_a v - b z1(x) [+ x0] is linear in
    (g_a, b = beta2 gamma_a[, x0]) when z1 is driven by the measured x.  On a
    log grid over (alpha1, alpha2) with cells 1.5 e-folds wide (about the
    size of a basin) the ``starts`` best local minima are taken (distinct
    valleys, not one valley's neighbours), and each is refined with the
    linear parameters projected out.
    """
    R = max(float(np.ptp(x[used])) for v, x, used in data)
    lo, hi = _alpha_bounds(R)
    la1 = np.linspace(lo[0], hi[0], int((hi[0] - lo[0]) / _GRID_CELL) + 1)
    la2 = np.linspace(lo[1], hi[1], int((hi[1] - lo[1]) / _GRID_CELL) + 1)

    paths = [monotone_path(v, x) for v, x, used in data]

    def error(p):
        return _equation_error(form, data, paths, p[0], p[1], g_bounds, offset, start)

    cost = np.array([[float(np.sum(error((p, q))[0] ** 2)) for q in la2] for p in la1])
    padded = np.pad(cost, 1, constant_values=np.inf)
    neighbours = np.min([padded[1 + i:1 + i + cost.shape[0], 1 + j:1 + j + cost.shape[1]]
                         for i in (-1, 0, 1) for j in (-1, 0, 1) if i or j], axis=0)
    minima = np.argwhere(cost <= neighbours)
    minima = minima[np.argsort(cost[tuple(minima.T)])][:starts]
    found = []
    for i, j in minima:
        res = opt.least_squares(lambda p: error(p)[0], [la1[i], la2[j]], bounds=(lo, hi),
                                xtol=1e-10, ftol=1e-10)
        g, b, *x0 = error(res.x)[1]
        found.append((res.cost, DahlModel(math.exp(res.x[0]), math.exp(res.x[1]), 0.0,
                                          b / gamma_a, gamma_a, g, form=form,
                                          x0=x0[0] if offset else 0.0, start=start)))
    return [m for c, m in sorted(found, key=lambda item: item[0])]


def _to_theta(model):
    """Fit parameters: g_a, log alpha1, log alpha2, b = beta2 gamma_a."""
    return np.array([model.g_a, math.log(model.alpha1), math.log(model.alpha2),
                     model.beta2 * model.gamma_a])


def _from_theta(theta, form, gamma_a, start, x0=0.0):
    g, log_a1, log_a2, b = theta
    return DahlModel(math.exp(log_a1), math.exp(log_a2), 0.0, b / gamma_a, gamma_a, g,
                     form=form, x0=x0, start=start)


def _project_offset(r, wv):
    """x0 minimising |r + x0 wv|^2 (weighted residuals r, weights wv)."""
    return -float(wv @ r) / float(wv @ wv)


def check_fit_options(form, offset, start):
    """Validated (form, offset, start) of a fit, offset as a plain bool.

    Raises
    ------
    ValueError
        ``form`` not in :data:`~piezolib.hysteresis.dahl.FORMS` or ``start``
        not in :data:`~piezolib.hysteresis.dahl.DAHL_STARTS`.
    TypeError
        ``offset`` not a bool.

    Examples
    --------
    >>> check_fit_options("printed", np.True_, "rest")
    ('printed', True, 'rest')
    >>> check_fit_options("dahl", False, "virgin")
    Traceback (most recent call last):
    ...
    ValueError: form must be one of ('printed', 'bliman_sorine'), got 'dahl'
    """
    if form not in FORMS:
        raise ValueError(f"form must be one of {FORMS}, got {form!r}")
    if not isinstance(offset, (bool, np.bool_)):
        raise TypeError(f"offset must be True or False, got {offset!r}")
    if start not in DAHL_STARTS:
        raise ValueError(f"start must be one of {DAHL_STARTS}, got {start!r}")
    return form, bool(offset), start


#: Most samples per record :func:`fit_dahl` fits by default (``stride=None``): the model is
#: rate independent, so its output at the kept samples (every turning point included) is
#: exact; more samples only average noise, at a cost proportional to their number.
MAX_FIT_SAMPLES = 1000


def fit_dahl(loops, gamma_a, form="bliman_sorine", offset=False, start="virgin",
             discard=0, stride=None, initial=None, starts=3):
    """Least-squares fit of the Dahl parameters to one or several loops jointly.

    The fitted model is the voltage-driven model (:func:`simulate_dahl`,
    output error on x).  The free parameters are g_a, log alpha1, log alpha2
    and b = beta2 gamma_a (Jacobian scaling; bounds relative to the largest
    output range R: :data:`ALPHA1_BOUNDS` / R and :data:`ALPHA2_BOUNDS` / R^2,
    g_a within :data:`G_A_BOUNDS` times the loops' mean slope), and with
    ``offset`` the output offset x0 (one for all loops), which enters
    linearly and is solved exactly at every evaluation (variable projection),
    so it costs no extra simulation.  beta1 is held at 0 (the published
    value) and ``gamma_a`` is fixed (only beta2*gamma_a is identifiable).
    Candidate models whose voltage-driven form is not invertible get a large
    constant residual.  Each loop's residual is divided by its output range
    and by sqrt(samples used), so that every loop weighs the same.  The
    output-error problem is solved from ``starts`` starting points: the best
    local minima of a log grid over (alpha1, alpha2) on which g_a,
    beta2*gamma_a (and x0) solve the linear equation-error problem
    x = g_a v - beta2 gamma_a z1(x) [+ x0] (z1 driven by the measured x).
    Each start is solved to a loose tolerance and the best one polished;
    a transient progress bar counts these solves
    (:func:`piezolib.progress.progress`; ``PIEZOLIB_PROGRESS=0`` hides it).
    The work is bounded by counts (``starts`` solves of scipy's
    ``least_squares`` with its default evaluation limit), not by time.

    Parameters
    ----------
    loops : sequence of (v, x)
        Input [v-unit] and measured displacement [x-unit] records, each with
        at least one ascending and one descending stroke of v.
    gamma_a : float
        Input weight of eq. 10, > 0, held fixed: only beta2*gamma_a enters H
        (the paper's model has 30).
    form : {"bliman_sorine", "printed"}
    offset : bool, optional
        Fit the output offset x0 of :class:`DahlModel` (workbook extension).
        Default False: the paper's eq. 13 exactly (x0 = 0).
    start : {"virgin", "rest", "maximum", "auto"}, optional
        The fitted model's ``start``: the state it is in at the first sample
        of every record (default "virgin": z = 0; "rest": after a long
        descending stroke, as at rest or at a cut at an input minimum;
        "maximum": after a long ascending stroke, a cut at an input
        maximum).  "auto" fits from each of
        :data:`~piezolib.hysteresis.dahl.DAHL_STARTS` and keeps the smallest
        residual (three fits; the warnings are the kept fit's).
    discard : int, optional
        Samples at the start of each record left out of the residuals (the
        model still runs through them), e.g. one period to skip the virgin
        curve.
    stride : int, optional
        Use every ``stride``-th sample (and every turning point of v) in the
        fit; the model output there is exact regardless, so this only trades
        noise averaging for speed.  The reported residuals use all samples.
        Default: the smallest stride that leaves at most
        :data:`MAX_FIT_SAMPLES` samples of the longest record (a 51 000-sample
        raw record at 5 kHz is fitted on every 52nd sample).
    initial : DahlModel, optional
        Single starting point instead of the grid search (its x0 is ignored:
        x0 is solved exactly).
    starts : int, optional
        Number of grid starting points (ignored with ``initial``).

    Returns
    -------
    DahlFit
        With :meth:`DahlFit.parameter_table`; a
        :class:`~piezolib.hysteresis.common.FitWarning` is issued when a
        parameter ends on a bound or is not identifiable.

    Raises
    ------
    ValueError
        Where the data cannot support the model: no ascending and
        descending stroke of v after ``discard``, x not increasing with v,
        or no invertible model of this form near the data.

    Examples
    --------
    >>> from piezolib.signals import triangle
    >>> true = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                  form="bliman_sorine")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)        # a 0-4 V triangle, 81 samples
    >>> fit = fit_dahl([(v, true.simulate(v))], gamma_a=0.5, starts=1)
    >>> round(fit.model.alpha1, 3), round(fit.model.alpha2, 3), round(fit.model.g_a, 3)
    (3.0, 2.0, 1.0)
    >>> bool(fit.pooled_rms_percent < 1e-6)
    True
    """
    if isinstance(start, str) and start == "auto":
        return _best_start(loops, gamma_a, form=form, offset=offset, discard=discard,
                           stride=stride, initial=initial, starts=starts)
    form, offset, start = check_fit_options(form, offset, start)
    gamma_a = check_positive("gamma_a", gamma_a)
    if stride is None:
        longest = max(len(pair[1]) for pair in check_loops(loops, discard, 1))
        stride = max(1, math.ceil(longest / MAX_FIT_SAMPLES))
    data = check_loops(loops, discard, stride)
    slope = _mean_slope(data)
    g_bounds = (slope * G_A_BOUNDS[0], slope * G_A_BOUNDS[1])
    if initial is None:
        starts = check_integer("starts", starts, minimum=1)
    elif not isinstance(initial, DahlModel):
        raise TypeError(f"initial must be a DahlModel, got {type(initial).__name__}")
    R = max(float(np.ptp(x[used])) for v, x, used in data)
    weights = _loop_weights(data)
    wv = np.concatenate([np.full(used.size, w) for (v, x, used), w in zip(data, weights)])
    lo, hi = _alpha_bounds(R)
    lower = np.array([g_bounds[0], *lo, -1e8 / R])
    upper = np.array([g_bounds[1], *hi, 1e8 / R])
    n_res = sum(used.size for v, x, used in data)

    def output_error(theta):
        """Weighted residuals with x0 = 0 (the offset is added by the caller)."""
        model = _from_theta(theta, form, gamma_a, start)
        try:
            sims = simulate_dahl_records(model, [v for v, x, used in data])
        except NotInvertibleError:
            return None
        return np.concatenate([w * (sim.x[used] - x[used])
                               for sim, (v, x, used), w in zip(sims, data, weights)])

    def residuals(theta):
        r = output_error(theta)
        if r is None:
            return np.full(n_res, 10.0 / math.sqrt(n_res))  # far worse than any loop fit
        return r + _project_offset(r, wv) * wv if offset else r

    def solve(theta0, tol):
        theta0 = np.clip(theta0, lower + 1e-9 * (upper - lower), upper - 1e-9 * (upper - lower))
        return opt.least_squares(residuals, theta0, bounds=(lower, upper), x_scale="jac",
                                 method="trf", xtol=tol, ftol=tol, gtol=tol)

    with progress(desc=f"fit_dahl {form}", unit="solve") as bar:
        if initial is None:
            postfix(bar, "grid search for starting points", refresh=True)
            candidates = _initial_guesses(form, data, gamma_a, g_bounds, starts, offset, start)
        else:
            candidates = [replace(initial, form=form, beta1=0.0, start=start,
                                  beta2=initial.beta2 * initial.gamma_a / gamma_a,
                                  gamma_a=gamma_a)]
        result, initial = _multistart(solve, candidates, len(data), bar)
    r0 = output_error(result.x)
    if r0 is None:
        raise ValueError(f"no invertible {form} Dahl model fits these loops (every candidate "
                         "overshoots: x + H(x) decreases along a stroke); the data cannot "
                         "support this form")
    x0 = _project_offset(r0, wv) if offset else 0.0
    model = _from_theta(result.x, form, gamma_a, start, x0)
    parameters = _parameter_estimates(output_error, result, r0, wv, offset, model, lower, upper)
    warn_about(parameters, f"fit_dahl ({form}, offset={offset}, start={start})")
    return _scored(DahlFit(model=model, x_model=[], residuals=[], rms=np.zeros(0),
                           rms_percent=np.zeros(0), max_percent=np.zeros(0), initial=initial,
                           result=result, offset=offset, parameters=tuple(parameters)),
                   loops, discard)


def _best_start(loops, gamma_a, **options):
    """:func:`fit_dahl` from each start of DAHL_STARTS; the fit of least cost, its warnings."""
    fits, caught, failure = {}, {}, None
    for start in DAHL_STARTS:
        with warnings.catch_warnings(record=True) as caught[start]:
            warnings.simplefilter("always")
            try:
                fits[start] = fit_dahl(loops, gamma_a, start=start, **options)
            except ValueError as exc:      # no invertible model from this start
                failure = exc
    if not fits:
        raise failure
    best = min(fits, key=lambda s: fits[s].result.cost)     # ties: the first listed
    for w in caught[best]:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return fits[best]


def _scored(fit, loops, discard):
    """``fit`` with its loop outputs and errors computed for ``fit.model`` on every sample."""
    full = check_loops(loops, discard, 1)
    x_model = [simulate_dahl(fit.model, v).x for v, x, used in full]
    first = [int(used[0]) for v, x, used in full]
    res, rms, rms_pct, max_pct = loop_errors(
        x_model, [(v, x) for v, x, used in full], first[0])
    return replace(fit, x_model=x_model, residuals=res, rms=rms, rms_percent=rms_pct,
                   max_percent=max_pct)


def rescore_dahl(fit, model, loops, discard=0):
    """``fit`` (a :class:`DahlFit` of ``loops``) moved to another model of the same optimum.

    Where the cost has a flat valley (parameters identifiable only in
    combination), the end point of the optimisation depends on rounding; a
    model stored from an earlier run of the same fit can then stand in for
    it.  Its loop outputs and errors are recomputed on ``loops``; the
    identifiability analysis (``parameters``) and ``result`` stay the fit's.

    Parameters
    ----------
    fit : DahlFit
    model : DahlModel
        Of the same form and start as ``fit.model``.
    loops, discard
        As given to :func:`fit_dahl`.

    Returns
    -------
    DahlFit

    Examples
    --------
    >>> from piezolib.signals import triangle
    >>> true = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                  form="bliman_sorine")
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)        # a 0-4 V triangle, 81 samples
    >>> fit = fit_dahl([(v, true.simulate(v))], gamma_a=0.5, starts=1)
    >>> moved = rescore_dahl(fit, true, [(v, true.simulate(v))])   # the exact model instead
    >>> moved.model is true, bool(moved.pooled_rms_percent < 1e-9)
    (True, True)
    """
    if not isinstance(fit, DahlFit):
        raise TypeError(f"fit must be a DahlFit, got {type(fit).__name__}")
    if not isinstance(model, DahlModel):
        raise TypeError(f"model must be a DahlModel, got {type(model).__name__}")
    if (model.form, model.start) != (fit.model.form, fit.model.start):
        raise ValueError(f"model must have the fit's form and start {fit.model.form!r}, "
                         f"{fit.model.start!r}, got {model.form!r}, {model.start!r}")
    return _scored(replace(fit, model=model), loops, discard)


def _multistart(solve, candidates, n_loops, bar):
    """Every start solved to a loose tolerance, the best one polished; (result, its start).

    One step of ``bar`` per least-squares solve; its status names the solve
    running and the best RMS error so far in % of the output range (each
    loop's weighted residuals sum to its squared relative RMS error, so the
    pooled value is sqrt(2 cost / n_loops)).
    """
    bar.reset(total=len(candidates) + (len(candidates) > 1))   # known once the grid is searched
    result = initial = None

    def status(text):
        if result is not None:
            text += f", best rms {100 * math.sqrt(2 * result.cost / n_loops):.3g} % of range"
        postfix(bar, text, refresh=True)      # shown while the solve runs

    for k, candidate in enumerate(candidates):
        status(f"start {k + 1}/{len(candidates)}")
        trial = solve(_to_theta(candidate), 1e-4 if len(candidates) > 1 else 1e-10)
        if result is None or trial.cost < result.cost:
            result, initial = trial, candidate
        bar.update()
    if len(candidates) > 1:
        status("polishing the best start")
        result = solve(result.x, 1e-10)
        bar.update()
    return result, initial


def _parameter_estimates(output_error, result, r0, wv, offset, model, lower, upper):
    """95 % intervals of (g_a, alpha1, alpha2, beta2[, x0]) and the derived H_ss, rate.

    Central differences of the weighted residuals in the fit coordinates
    (g_a, log alpha1, log alpha2, b), plus the offset column ``wv``; a
    coordinate whose step makes the model non-invertible gets a one-sided
    difference, or NaN (interval unknown, not identifiable).
    """
    theta = result.x
    cols = []
    for i in range(theta.size):
        h = 1e-6 * max(abs(theta[i]), 1.0) if i in (0, 3) else 1e-5
        up, dn = theta.copy(), theta.copy()
        up[i] = min(theta[i] + h, upper[i])
        dn[i] = max(theta[i] - h, lower[i])
        r_up, r_dn = output_error(up), output_error(dn)
        if r_up is not None and r_dn is not None and up[i] > dn[i]:
            cols.append((r_up - r_dn) / (up[i] - dn[i]))
        elif r_up is not None and up[i] > theta[i]:
            cols.append((r_up - r0) / (up[i] - theta[i]))
        elif r_dn is not None and dn[i] < theta[i]:
            cols.append((r0 - r_dn) / (theta[i] - dn[i]))
        else:
            cols.append(np.full(r0.size, np.nan))
    if offset:
        cols.append(wv)
    J = np.column_stack(cols)
    r = r0 + (_project_offset(r0, wv) * wv if offset else 0.0)
    cov = covariance(J, r, J.shape[1])
    g, b = theta[0], theta[3]
    a1, a2 = model.alpha1, model.alpha2
    values = [g, a1, a2, model.beta2] + ([model.x0] if offset else [])
    # scipy marks a bound active only within its own tolerance of it, which the rounding
    # path decides (straight data: g_a 8e-7 inside its bound, active under one BLAS kernel,
    # not under another); a parameter that close to a bound is on it
    near = np.minimum(theta - lower, upper - theta) <= _ON_BOUND * (upper - lower)
    bound = list((np.asarray(result.active_mask) != 0) | near) + ([False] if offset else [])
    natural = cov.copy()                                # b -> beta2 = b / gamma_a
    natural[3, :] /= model.gamma_a
    natural[:, 3] /= model.gamma_a
    names = ["g_a", "alpha1", "alpha2", "beta2"] + (["x0"] if offset else [])
    units = ["x/v", "1/x", "1/x^2", "-"] + (["x"] if offset else [])
    logs = [False, True, True, False] + ([False] if offset else [])
    out = estimates(names, units, values, logs, natural, bound)
    # derived: steady state b / alpha2 (linear) and rate alpha2 / alpha1 (log)
    grad_h = np.zeros(J.shape[1])
    grad_h[2], grad_h[3] = -b / a2, 1.0 / a2
    grad_l = np.zeros(J.shape[1])
    grad_l[1], grad_l[2] = -1.0, 1.0
    derived = np.array([grad_h, grad_l])
    with np.errstate(invalid="ignore"):
        dcov = derived @ np.where(np.isinf(cov), 1e300, cov) @ derived.T
    dcov[~np.isfinite(dcov) | (dcov > 1e299)] = np.inf
    out += estimates(["H_ss = beta2 gamma_a / alpha2", "rate alpha2 / alpha1"], ["x", "1/x"],
                     [b / a2, a2 / a1], [False, True], dcov,
                     [bool(bound[2] or bound[3]), bool(bound[1] or bound[2])])
    return out


def choose_fit(fits):
    """The workbook's selection rule: the fit with the smallest pooled RMS error.

    Parameters
    ----------
    fits : dict
        {key: DahlFit}, all fitted to the same loops.

    Returns
    -------
    key
        The key of the fit with the smallest :attr:`DahlFit.pooled_rms_percent`
        (the criterion every fit minimises; first key on a tie).

    Examples
    --------
    >>> from types import SimpleNamespace as Fit              # anything with pooled_rms_percent
    >>> choose_fit({"printed": Fit(pooled_rms_percent=2.4),
    ...             "bliman_sorine": Fit(pooled_rms_percent=0.9)})
    'bliman_sorine'
    """
    if not isinstance(fits, Mapping):
        raise TypeError(f"fits must be a dict {{key: DahlFit}}, got {type(fits).__name__}")
    if not fits:
        raise ValueError("fits must hold at least one DahlFit")
    for key, fit in fits.items():
        if not isinstance(getattr(fit, "pooled_rms_percent", None), numbers.Real):
            raise TypeError(f"fits[{key!r}] must be a fit with a pooled_rms_percent (a DahlFit), "
                            f"got {type(fit).__name__}")
    return min(fits, key=lambda key: fits[key].pooled_rms_percent)
