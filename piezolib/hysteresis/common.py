"""What every hysteresis model and fit of this package shares.

A model (:class:`~piezolib.hysteresis.dahl.DahlModel`,
:class:`~piezolib.hysteresis.pi.PIModel`) satisfies :class:`HysteresisModel`:
``simulate(v) -> x`` and ``feedforward(x_r) -> v``.  A fit
(:class:`~piezolib.hysteresis.fit.DahlFit`, :class:`~piezolib.hysteresis.pi.PIFit`)
carries the model, its output and errors per loop, and a parameter table with
95 % confidence intervals from the Jacobian (:class:`ParameterEstimate`).
:func:`check_loops` validates measured loops for every fit.
"""

import math
import warnings
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from piezolib._checks import check_integer, check_signals

# The functions below the classes (estimates, covariance, parameter_frame, warn_about,
# check_loops, loop_errors) are the fits' shared plumbing, imported by name by fit.py and
# pi.py; they take inputs those fits have already checked and are not part of the API.
__all__ = ["HysteresisModel", "MODEL_REQUIREMENT", "check_hysteresis_model", "FitScores",
           "FitWarning", "ParameterEstimate", "Z95"]

#: Two-sided 95 % quantile of the normal distribution.
Z95 = 1.959963984540054


@runtime_checkable
class HysteresisModel(Protocol):
    """A rate-independent hysteresis model with a feedforward.

    ``simulate(v)`` returns the displacement [x-unit] for an input record
    [v-unit], ``feedforward(x_r)`` the input that makes the model follow the
    desired displacement x_r (exactly, for the models of this package).

    Examples
    --------
    >>> from piezolib.hysteresis import PIModel
    >>> isinstance(PIModel(thresholds=(0.0,), weights=(2.0,)), HysteresisModel)
    True
    >>> isinstance(lambda v: 2.0 * v, HysteresisModel)       # no feedforward
    False
    """

    def simulate(self, v): ...

    def feedforward(self, x_r): ...


#: How an error message names what a model must be (the protocol, not a list of classes).
MODEL_REQUIREMENT = ("a hysteresis model: an object with simulate(v) and feedforward(x_r) "
                     "(piezolib.hysteresis.HysteresisModel; DahlModel, PIModel and "
                     "HammersteinModel are three)")


def check_hysteresis_model(name, model):
    """``model`` when it follows :class:`HysteresisModel`, else a TypeError naming ``name``.

    Any class with ``simulate(v)`` and ``feedforward(x_r)`` qualifies: the
    experiments, the loop and model selection take a model of one's own
    without edits elsewhere.

    Examples
    --------
    >>> class Linear:
    ...     def simulate(self, v): return 2.0 * v
    ...     def feedforward(self, x_r): return x_r / 2.0
    >>> isinstance(check_hysteresis_model("model", Linear()), Linear)
    True
    >>> check_hysteresis_model("model", 2.0)
    Traceback (most recent call last):
    ...
    TypeError: model must be a hysteresis model: an object with simulate(v) and feedforward(x_r) (piezolib.hysteresis.HysteresisModel; DahlModel, PIModel and HammersteinModel are three), got float
    """
    if isinstance(model, type):          # the class passes the protocol check: its methods
        raise TypeError(f"{name} must be {MODEL_REQUIREMENT}, got the class "
                        f"{model.__name__} itself: pass an instance (a fitted model)")
    if not isinstance(model, HysteresisModel):
        raise TypeError(f"{name} must be {MODEL_REQUIREMENT}, got {type(model).__name__}")
    return model


class FitScores:
    """Scores shared by every hysteresis fit result (needs ``rms_percent`` and ``parameters``).

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass
    ... class Scores(FitScores):
    ...     rms_percent: np.ndarray
    ...     parameters: tuple = ()
    >>> s = Scores(np.array([3.0, 4.0]))
    >>> s.worst_rms_percent, round(s.pooled_rms_percent, 4)     # sqrt((9 + 16) / 2)
    (4.0, 3.5355)
    """

    def parameter_table(self):
        """pandas DataFrame of :attr:`parameters`: value, unit, 95 % CI, at_bound, identifiable."""
        return parameter_frame(self.parameters)

    @property
    def worst_rms_percent(self):
        """Largest per-loop RMS error [% of range]."""
        return float(np.max(self.rms_percent))

    @property
    def pooled_rms_percent(self):
        """RMS over the loops of the per-loop RMS errors [% of range]: every loop weighs the
        same (the criterion each fit minimises, and the workbook's selection rule)."""
        return float(np.sqrt(np.mean(self.rms_percent ** 2)))


class FitWarning(UserWarning):
    """A fitted parameter sits on a bound or is not identifiable from the data.

    Examples
    --------
    >>> import warnings
    >>> from piezolib.hysteresis import PIModel, fit_pi
    >>> v = np.r_[np.linspace(0, 4, 21), np.linspace(3.8, 0, 20)]
    >>> x = PIModel((0.0, 0.5), (1.0, 0.3), start="virgin").simulate(v)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     fit = fit_pi([(v, x)], offset=False, start="virgin", thresholds=(0.0, 0.5, 1.5))
    >>> caught[0].category is FitWarning, str(caught[0].message)     # a play not needed
    (True, "fit_pi (start 'virgin'): w_2 (r = 1.5) = 0 on a bound")
    """


@dataclass(frozen=True)
class ParameterEstimate:
    """One fitted (or derived) parameter with its 95 % confidence interval.

    Attributes
    ----------
    name : str
    value : float
    unit : str
        In the units of the records (``x`` the output, ``v`` the input unit).
    low, high : float
        95 % confidence interval from the Jacobian at the optimum, assuming
        white residuals (with model error in the residuals, an optimistic
        interval; NaN where the Jacobian is singular).  For a parameter
        fitted on a log scale the interval is exp(log value +- 1.96 se).
    at_bound : bool
        The optimum lies on a bound of this parameter.
    identifiable : bool
        The relative standard error is below 1/1.96 (the 95 % interval stays
        within a factor e of the value for a log parameter, excludes 0 for a
        linear one) and the parameter is not on a bound.

    Examples
    --------
    >>> p = ParameterEstimate("g_a", 1.02, "x/v", low=0.98, high=1.06, at_bound=False,
    ...                       identifiable=True)
    >>> p.low < p.value < p.high, p.identifiable
    (True, True)
    >>> from piezolib.hysteresis.common import parameter_frame
    >>> float(parameter_frame([p]).loc["g_a", "value"])
    1.02
    """

    name: str
    value: float
    unit: str
    low: float
    high: float
    at_bound: bool
    identifiable: bool


def estimates(names, units, values, log_scale, cov, at_bound):
    """:class:`ParameterEstimate` list from values and the covariance of the fit coordinates.

    Parameters
    ----------
    names, units : sequence of str
    values : array_like
        Parameter values (natural scale).
    log_scale : sequence of bool
        Whether the fit coordinate of each parameter is its logarithm.
    cov : ndarray
        Covariance of the fit coordinates (log for ``log_scale`` ones).
    at_bound : sequence of bool
    """
    out = []
    se = np.sqrt(np.abs(np.diag(cov)))       # inf: not seen by the data, NaN: unknown
    for name, unit, value, log, s, bound in zip(names, units, values, log_scale, se, at_bound):
        value = float(value)
        if log:
            spread = math.exp(min(Z95 * s, 700.0)) if np.isfinite(s) else s
            low, high = value / spread, value * spread
            rel = s
        else:
            low, high = value - Z95 * s, value + Z95 * s
            rel = s / abs(value) if value != 0 else math.inf
        ok = bool(np.isfinite(rel) and Z95 * rel < 1.0 and not bound)
        out.append(ParameterEstimate(name, value, unit, float(low), float(high), bool(bound), ok))
    return out


def covariance(J, r, dof_used):
    """Least-squares covariance s^2 (J^T J)^+ with s^2 = |r|^2 / (n - p).

    Columns that do not change the residual at all give an infinite variance.
    """
    n, p = J.shape
    s2 = float(r @ r) / max(n - dof_used, 1)
    if not np.all(np.isfinite(J)):
        return np.full((p, p), np.nan)
    U, sv, Vt = np.linalg.svd(J, full_matrices=False)
    tiny = sv <= sv[0] * 1e-12 if sv.size and sv[0] > 0 else np.ones_like(sv, dtype=bool)
    inv = np.where(tiny, 0.0, 1.0 / np.where(tiny, 1.0, sv) ** 2)
    cov = (Vt.T * inv) @ Vt * s2
    # a direction the data do not see: infinite variance for every parameter in it
    for k in np.flatnonzero(tiny):
        cov[np.abs(Vt[k]) > 1e-8, np.abs(Vt[k]) > 1e-8] = np.inf
    return cov


def parameter_frame(parameters):
    """pandas DataFrame of :class:`ParameterEstimate` rows, indexed by name."""
    import pandas as pd
    return pd.DataFrame([{"value": p.value, "unit": p.unit, "95% CI low": p.low,
                          "95% CI high": p.high, "at_bound": p.at_bound,
                          "identifiable": p.identifiable} for p in parameters],
                        index=pd.Index([p.name for p in parameters], name="parameter"))


def warn_about(parameters, what, stacklevel=3):
    """Warn (:class:`FitWarning`) about every parameter on a bound or not identifiable."""
    bad = [p for p in parameters if p.at_bound or not p.identifiable]
    if bad:
        text = "; ".join(f"{p.name} = {p.value:.4g} " + (
            "on a bound" if p.at_bound else f"not identifiable (95% CI {p.low:.3g} ... "
                                            f"{p.high:.3g})") for p in bad)
        warnings.warn(f"{what}: {text}", FitWarning, stacklevel=stacklevel)
    return bad


def loop_pairs(loops):
    """The (v, x) pairs of ``loops`` as a list (a single (v, x) pair allowed)."""
    if isinstance(loops, tuple) and len(loops) == 2 and np.ndim(loops[0]) == 1 \
            and np.size(loops[0]) > 2:
        return [loops]
    return list(loops)


def check_loops(loops, discard=0, stride=1, what="loops"):
    """Validated loops as a list of (v, x, used), ``used`` the residual samples.

    ``used`` holds every ``stride``-th sample from ``discard`` on plus every
    turning point of v; ``v`` and ``x`` are thinned the same way (a rate-
    independent model only sees the path, so its output there is exact).

    Raises
    ------
    TypeError, ValueError
        Naming the loop: not (v, x) pairs, NaN, unequal lengths, fewer than
        8 samples, or no ascending and descending stroke of v after
        ``discard`` (the data cannot show a loop).
    """
    from piezolib.hysteresis.dahl import strokes
    try:
        loops = loop_pairs(loops)
    except TypeError:
        raise TypeError(f"{what} must be a sequence of (v, x) pairs of 1-D arrays") from None
    if not loops:
        raise ValueError(f"{what} must hold at least one (v, x) pair")
    discard = check_integer("discard", discard, minimum=0)
    stride = check_integer("stride", stride, minimum=1)
    out = []
    for i, pair in enumerate(loops):
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise TypeError(f"{what}[{i}] must be a (v, x) pair of arrays, "
                            f"got {type(pair).__name__}")
        v, x = check_signals(8, **{f"{what}[{i}] v": pair[0], f"{what}[{i}] x": pair[1]})
        if np.iscomplexobj(v) or np.iscomplexobj(x):
            raise TypeError(f"{what}[{i}]: v and x must be real")
        runs = strokes(v)
        late = [r for r in runs if r[1] > discard]
        if not any(r[2] > 0 for r in late) or not any(r[2] < 0 for r in late) \
                or np.ptp(x[discard:]) == 0:
            raise ValueError(f"{what}[{i}] has no full cycle after discard={discard} "
                             "samples: need an ascending and a descending stroke of v")
        keep = np.union1d(np.arange(0, v.size, stride), [r[1] for r in runs] + [0])
        out.append((v[keep], x[keep], np.flatnonzero(keep >= discard)))
    return out


def loop_errors(x_models, loops, discard):
    """Residuals and (rms, rms %, max %) per loop on the samples from ``discard`` on.

    Percentages are of each loop's output range on those samples.
    """
    res, rms, rms_pct, max_pct = [], [], [], []
    for xm, (v, x) in zip(x_models, loops):
        x = np.asarray(x, dtype=float)
        r = xm[discard:] - x[discard:]
        span = float(np.ptp(x[discard:]))
        res.append(r)
        rms.append(math.sqrt(float(np.mean(r ** 2))))
        rms_pct.append(100 * rms[-1] / span)
        max_pct.append(100 * float(np.max(np.abs(r))) / span)
    return res, np.array(rms), np.array(rms_pct), np.array(max_pct)
