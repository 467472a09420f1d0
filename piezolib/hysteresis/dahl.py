"""Dahl hysteresis model (eq. 10-13): strokes, exact integration, simulation.

Two forms: ``"printed"`` (eq. 10-12 as printed) and ``"bliman_sorine"`` (the
sign of the velocity on the state term), both with an optional output offset
x0 (x = g_a v - H + x0; 0 is eq. 13) and an initial state ("virgin",
"rest" or "maximum").  Along each monotone stroke the model is linear in the path length
and is integrated exactly (closed-form 2x2 matrix exponential); the implicit
relation of the voltage-driven model is solved exactly too.  The model is
unit agnostic.  Its inverse-free feedforward (eq. 14) on a record is
:func:`feedforward`; sample by sample for a real-time loop it is
:class:`piezolib.hysteresis.compensator.DahlFeedforward`.  Equations, the
workbook's unit convention and why the published parameters give no loop:
``docs/hysteresis.md``.
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from piezolib._checks import check_finite_array, check_positive, check_same_length

__all__ = [
    "FORMS", "STARTS", "DAHL_STARTS", "DahlModel", "DahlResponse", "NotInvertibleError", "strokes",
    "dahl_hysteresis", "simulate_dahl", "simulate_dahl_records", "min_stroke_slope",
    "StrokeDynamics", "check_dahl_model", "feedforward",
]   # initial_state_of: shared with compensator.py, not part of the API

#: The two model forms: eq. 10 as printed, and the Bliman-Sorine placement.
FORMS = ("printed", "bliman_sorine")
#: Initial states of a record that begins with the stage's history: "virgin" z = 0 (moving
#: up, a freshly powered actuator), "rest" the state after a long descending stroke (moving
#: down), i.e. at rest after being lowered, or a record cut at an input minimum.
STARTS = ("virgin", "rest")
#: Every initial state a record can have: :data:`STARTS` and "maximum", the state after a
#: long ascending stroke (moving up), i.e. a record cut at an input maximum.
DAHL_STARTS = STARTS + ("maximum",)


_EPS = np.finfo(float).eps
#: Largest scale (and inverse of the smallest) of alpha1, alpha2 and the steady
#: state gamma_a / alpha2 whose products stay inside double precision.
_SCALE_LIMIT = 1e150


class NotInvertibleError(ValueError):
    """x + H(x) is not monotone along a stroke, so x = g_a v - H has no unique solution.

    Examples
    --------
    A strongly underdamped model overshoots along a stroke, so x(v) is not unique:

    >>> bad = DahlModel(alpha1=0.2, alpha2=25.0, beta1=0.0, beta2=40.0, gamma_a=1.0, g_a=1.0,
    ...                 form="bliman_sorine")
    >>> simulate_dahl(bad, np.linspace(0.0, 4.0, 41))
    Traceback (most recent call last):
    ...
    piezolib.hysteresis.dahl.NotInvertibleError: x + H(x) is not increasing along a stroke ...
    """


# --------------------------------------------------------------------------- model
@dataclass(frozen=True)
class DahlModel:
    """Parameters and form of the second-order Dahl model (eq. 10-13).

    Attributes
    ----------
    alpha1 : float
        Damping coefficient a1 > 0 [1/x-unit].
    alpha2 : float
        Stiffness coefficient a2 > 0 [1/x-unit^2].
    beta1, beta2 : float
        Output weights of eq. 12 (b1 multiplies sgn(x') z2).
    gamma_a : float
        Input weight of eq. 10.
    g_a : float
        Piezoelectric coefficient of eq. 13, > 0 [x-unit per v-unit].
    form : {"printed", "bliman_sorine"}
        Where the sign of the velocity enters (``docs/hysteresis.md``).
    x0 : float, optional
        Output offset [x-unit], x = g_a v - H + x0: the model's displacement
        (sensor) zero, a workbook extension that eq. 13 lacks.  Default 0:
        the paper's model exactly.
    start : {"virgin", "rest", "maximum"}, optional
        State every simulation and feedforward starts from unless told
        otherwise (:meth:`initial_state`): "virgin" (default) z = 0, "rest"
        the state reached after a long descending stroke, i.e. at rest after
        the actuator was lowered (or a record cut at an input minimum),
        "maximum" the state after a long ascending stroke (a record cut at
        an input maximum).

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> m.steady_state(+1), m.steady_state(-1)        # +-beta2 gamma_a / alpha2
    (0.25, -0.25)
    >>> round(m.damping, 3), round(m.transient_length, 3)
    (1.061, 0.667)
    >>> m.with_offset(0.1).static_part                      # (g_a, x0)
    (1.0, 0.1)
    """

    alpha1: float
    alpha2: float
    beta1: float
    beta2: float
    gamma_a: float
    g_a: float
    form: str = "printed"
    x0: float = 0.0
    start: str = "virgin"

    def __post_init__(self):
        for name in ("alpha1", "alpha2", "g_a"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        for name in ("beta1", "beta2", "gamma_a", "x0"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise TypeError(f"{name} must be a real number, got {value!r}")
            if not np.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {self.form!r}")
        if self.start not in DAHL_STARTS:
            raise ValueError(f"start must be one of {DAHL_STARTS}, got {self.start!r}")
        self._check_range()

    def _check_range(self):
        # the closed-form strokes multiply the state matrices (entries up to
        # alpha1, alpha2) by states of the size of the steady state
        # gamma_a / alpha2; beyond _SCALE_LIMIT those products overflow
        # and the simulation returns infinities or zeros instead of the model
        scales = {"alpha1": self.alpha1, "alpha2": self.alpha2,
                  "gamma_a / alpha2 (the steady state)": abs(self.gamma_a) / self.alpha2}
        for what, value in scales.items():
            # a tiny steady state is only a weak hysteresis: no lower limit for it
            low = 0.0 if what.startswith("gamma_a") else 1 / _SCALE_LIMIT
            if not low <= value <= _SCALE_LIMIT:
                raise ValueError(
                    f"{what} = {value:.3g} is outside [{low:g}, {_SCALE_LIMIT:g}]: the stroke "
                    "integration "
                    "would overflow double precision; rescale the displacement unit "
                    f"(alpha1={self.alpha1!r}, alpha2={self.alpha2!r}, gamma_a={self.gamma_a!r})")

    def steady_state(self, direction=1):
        """H reached after a long stroke in ``direction`` (+1 or -1) [x-unit].

        ``beta2 gamma_a / alpha2`` for both directions in the printed form,
        ``direction * beta2 gamma_a / alpha2`` in the Bliman-Sorine form.
        """
        s = _direction(direction)
        dyn = StrokeDynamics(self)
        return float(dyn.C[s] @ dyn.z_ss[s])

    @property
    def damping(self):
        """zeta = a1 / (2 sqrt(a2)) of the stroke dynamics (dimensionless)."""
        return self.alpha1 / (2.0 * math.sqrt(self.alpha2))

    @property
    def transient_length(self):
        """1 / (a1/2): path length over which a transient decays by e [x-unit]."""
        return 2.0 / self.alpha1

    @property
    def static_part(self):
        """(g_a, x0): the line x = g_a v + x0 of eq. 13 without its hysteretic term H.

        The map a feedforward without hysteresis compensation inverts,
        v = (x_r - x0) / g_a (Case I of the tracking test).
        """
        return self.g_a, self.x0

    def with_form(self, form):
        """The same parameters in another form."""
        return replace(self, form=form)

    def initial_state(self):
        """(z0, direction0) of the model's ``start``.

        "virgin": z = 0, direction +1.  "rest": z = z_ss of a descending
        stroke, direction -1; in the Bliman-Sorine form H = -b2 gamma_a / a2
        there, in the printed form the common steady state (no loop).
        "maximum": z = z_ss of an ascending stroke, direction +1 (H = +b2
        gamma_a / a2 in the Bliman-Sorine form).

        Examples
        --------
        >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
        ...               form="bliman_sorine", start="maximum")
        >>> z, s = m.initial_state()
        >>> z.round(3) + 0.0, s
        (array([0.25, 0.  ]), 1)
        """
        if self.start == "virgin":
            return np.zeros(2), 1
        s = 1 if self.start == "maximum" else -1
        return StrokeDynamics(self).z_ss[s].copy(), s

    def with_offset(self, x0):
        """The same model with output offset ``x0`` [x-unit] (0: the paper's eq. 13)."""
        return replace(self, x0=x0)

    def simulate(self, v):
        """Displacement [x-unit] for the input record ``v`` [v-unit] (:func:`simulate_dahl`)."""
        return simulate_dahl(self, v).x

    def feedforward(self, x_r):
        """Input [v-unit] for the desired displacement ``x_r`` [x-unit] (eq. 14).

        :func:`feedforward` from the model's start.
        """
        return feedforward(self, x_r)


def _direction(direction):
    if direction not in (1, -1):
        raise ValueError(f"direction must be +1 or -1, got {direction!r}")
    return int(direction)


class StrokeDynamics:
    """Per-direction constants of the stroke dynamics dz/dsigma = N_s z + s B.

    Parameters
    ----------
    model : DahlModel

    Attributes
    ----------
    m : float
        Real part of the eigenvalues of N_s, -alpha1 / 2.
    disc : float
        alpha1^2 / 4 - alpha2: > 0 overdamped, < 0 oscillatory (its sign
        is exact; its value may overflow to inf for alpha1 > 1e154).
    q : float
        sqrt(|disc|), evaluated without overflow.
    slow, fast : float
        For disc >= 0 the two real eigenvalues m + q and m - q, the slow one
        evaluated without cancellation (-alpha2 / (alpha1/2 + q)), so that
        the first-order limit alpha1^2 >> alpha2 (even alpha1 = 1e30) keeps
        its rate alpha2 / alpha1; NaN for disc < 0.
    N, P, z_ss, C : dict
        For s = +1 and -1: N_s, N_s - m I, the steady state -s N_s^-1 B and
        the output row of eq. 12 (H = C_s z).

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> d = StrokeDynamics(m)           # overdamped: eigenvalues -1 and -2
    >>> round(d.disc, 3), round(d.slow, 3), round(d.fast, 3), d.z_ss[1].round(3) + 0.0
    (0.25, -1.0, -2.0, array([0.25, 0.  ]))
    """

    def __init__(self, model):
        a1, a2 = model.alpha1, model.alpha2
        B = np.array([0.0, model.gamma_a])
        A0 = np.array([[0.0, 1.0], [-a2, -a1]])
        half, root = a1 / 2.0, math.sqrt(a2)
        self.m = -half                     # real part of the eigenvalues
        self.disc = (half - root) * (half + root)   # > 0 overdamped, < 0 oscillatory
        self.q = math.sqrt(abs(half - root)) * math.sqrt(half + root)
        if self.disc >= 0:                 # m + q without cancellation: (m+q)(m-q) = a2
            self.slow, self.fast = -a2 / (half + self.q), -(half + self.q)
        else:
            self.slow = self.fast = math.nan
        self.N, self.P, self.z_ss, self.C = {}, {}, {}, {}
        for s in (1, -1):
            if model.form == "printed" and s == -1:
                N = np.array([[0.0, -1.0], [a2, -a1]])
            else:
                N = A0
            self.N[s] = N
            self.P[s] = N - self.m * np.eye(2)
            self.z_ss[s] = -s * np.linalg.solve(N, B)
            self.C[s] = np.array([model.beta2, model.beta1 * s])

    def parts(self, sigma):
        """e^{m sigma} cosh-like and sinh-like parts of expm(N sigma), sigma >= 0.

        expm(N sigma) = ec I + es (N - m I), evaluated without overflow or
        cancellation for any sign of the discriminant.
        """
        sigma = np.asarray(sigma, dtype=float)
        m, q = self.m, self.q
        if self.disc < 0:
            em = np.exp(m * sigma)
            # np.sinc(q sigma / pi), its operations inlined (this runs in every fit's
            # innermost loop): sin(y) / y with y = pi (q sigma / pi), eps where y = 0
            t = np.pi * (q * sigma / np.pi)
            t = np.where(t, t, _EPS)
            return em * np.cos(q * sigma), em * sigma * (np.sin(t) / t)
        y = q * sigma
        ep, en = np.exp(self.slow * sigma), np.exp(self.fast * sigma)
        ec = 0.5 * (ep + en)
        small = y < 1e-3
        if q > 0 and not small.any():           # the series is not used anywhere
            return ec, (ep - en) / (2.0 * q)
        series = np.exp(m * sigma) * sigma * (1.0 + y * y / 6.0 + y ** 4 / 120.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            direct = (ep - en) / (2.0 * q) if q > 0 else series
        return ec, np.where(small, series, direct)

    def propagate(self, s, sigma, z0):
        """States z(sigma) (shape (n, 2)) along a stroke in direction s from z0."""
        w = z0 - self.z_ss[s]
        ec, es = self.parts(sigma)
        return self.z_ss[s] + ec[:, None] * w + es[:, None] * (self.P[s] @ w)


# --------------------------------------------------------------------------- strokes
def strokes(u, direction0=1):
    """Split a record into runs of constant direction of motion.

    Parameters
    ----------
    u : ndarray
        1-D record (displacement or input).
    direction0 : {1, -1}
        Direction assumed before the first change.

    Returns
    -------
    list of (start, stop, s)
        Sample k in ``start < k <= stop`` moves from sample k-1 in direction
        ``s``; samples at rest keep the previous direction.  ``start`` is the
        index of the sample the run starts from.

    Examples
    --------
    >>> strokes(np.array([0.0, 1.0, 2.0, 2.0, 1.0, 0.0, 1.0]))   # the rest at 2 keeps "up"
    [(0, 3, 1), (3, 5, -1), (5, 6, 1)]
    """
    u = check_finite_array("u", u, ndim=1, min_length=1, real=True)
    d = np.sign(np.diff(u))
    idx = np.where(d != 0, np.arange(d.size), -1)
    idx = np.maximum.accumulate(idx)
    s = np.where(idx >= 0, d[np.maximum(idx, 0)], direction0).astype(int)
    if s.size == 0:
        return []
    change = (np.flatnonzero(np.diff(s)) + 1).tolist()
    return [(int(a), int(b), int(s[a])) for a, b in zip([0] + change, change + [s.size])]


#: Stroke lists of recent records (:func:`_runs`): a fit simulates the same records with
#: hundreds of parameter sets.
_RUNS_CACHE = {}
_RUNS_CACHE_SIZE = 64


def _runs(u, direction0):
    """:func:`strokes` of a record already checked, remembered by its bytes."""
    key = (u.tobytes(), u.dtype.str, u.shape, int(direction0))
    runs = _RUNS_CACHE.get(key)
    if runs is None:
        runs = tuple(strokes(u, direction0))
        if len(_RUNS_CACHE) >= _RUNS_CACHE_SIZE:
            _RUNS_CACHE.pop(next(iter(_RUNS_CACHE)))
        _RUNS_CACHE[key] = runs
    return runs


def _start(model, dyn):
    """:meth:`DahlModel.initial_state` from the model's dynamics ``dyn`` (not built again)."""
    if model.start == "virgin":
        return np.zeros(2), 1
    s = 1 if model.start == "maximum" else -1
    return dyn.z_ss[s].copy(), s


def initial_state_of(model, z0=None, direction0=None):
    """(z0, direction0) given, or the model's start (:meth:`DahlModel.initial_state`).

    Returns
    -------
    z : ndarray, shape (2,)
        Initial state.
    direction : {1, -1}
        Direction of motion assumed until the input first changes.
    """
    z_start, s_start = model.initial_state()
    z = z_start if z0 is None else check_finite_array("z0", z0, shape=(2,))
    return z, s_start if direction0 is None else _direction(direction0)


def check_dahl_model(model):
    """Return ``model`` if it is a :class:`DahlModel`; raise TypeError otherwise.

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> check_dahl_model(m) is m
    True
    >>> check_dahl_model("dahl")
    Traceback (most recent call last):
    ...
    TypeError: model must be a DahlModel, got str
    """
    if not isinstance(model, DahlModel):
        raise TypeError(f"model must be a DahlModel, got {type(model).__name__}")
    return model


# --------------------------------------------------------------------------- driven by x
def dahl_hysteresis(model, x, z0=None, direction0=None, return_state=False, directions=None):
    """Hysteretic term H(t) of eq. 11-12 driven by the displacement record x.

    Exact for any sampling: along each run of constant direction the state is
    propagated in closed form from the run's start.

    Parameters
    ----------
    model : DahlModel
    x : array_like
        Displacement record [x-unit], 1-D, at least 2 samples.
    z0 : array_like of shape (2,), optional
        State at the first sample (default: the model's ``start``, z = 0
        for a virgin actuator).
    direction0 : {1, -1}, optional
        Direction of motion assumed until x first changes (default: the
        model's ``start``, +1 for a virgin actuator).
    return_state : bool, optional
        Also return the states z, shape (n, 2).
    directions : array_like, optional
        Record whose direction of motion gives sgn(x'), same length as ``x``
        (default: ``x`` itself).  For a noisy measured x, the input v that
        produced it gives clean stroke directions.  The state depends only
        on x[k] - x[stroke start]; where noise carries x back behind the
        stroke's start, the path length is taken as 0, so the closed-form
        integration never runs backwards (it would overflow).

    Returns
    -------
    H : ndarray
        H at every sample [x-unit]; ``(H, z)`` with ``return_state``.

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> dahl_hysteresis(m, np.array([0.0, 1.0, 2.0, 1.0, 0.0])).round(3)  # H up, then down
    array([ 0.   ,  0.1  ,  0.187,  0.026, -0.133])
    """
    check_dahl_model(model)
    x = check_finite_array("x", x, ndim=1, min_length=2, real=True)
    guided = directions is not None
    if not guided:
        directions = x
    else:
        directions = check_finite_array("directions", directions, ndim=1)
        check_same_length(x=x, directions=directions)
    z_init, s0 = initial_state_of(model, z0, direction0)
    H, z = _driven(StrokeDynamics(model), x, strokes(directions, s0), z_init, s0, guided)
    return (H, z) if return_state else H


def _driven(dyn, x, runs, z_init, s0, guided):
    """(H, z) of :func:`dahl_hysteresis` for checked input, the strokes ``runs`` given."""
    z = np.empty((x.size, 2))
    z[0] = z_init
    H = np.empty(x.size)
    H[0] = dyn.C[s0] @ z[0]
    for start, stop, s in runs:
        sigma = s * (x[start + 1:stop + 1] - x[start])
        if guided:          # noise may carry x back behind the stroke's start
            sigma = np.maximum(sigma, 0.0)
        z[start + 1:stop + 1] = dyn.propagate(s, sigma, z[start])
        H[start + 1:stop + 1] = z[start + 1:stop + 1] @ dyn.C[s]
    return H, z


def _z1_driven(model, pairs):
    """z1 of one model driven by each measured (noisy) x, the directions from its input v:
    ``dahl_hysteresis(model, x, return_state=True, directions=v)[1][:, 0]`` per (v, x) of
    ``pairs`` (checked records), the model's dynamics built once."""
    dyn = StrokeDynamics(model)
    z_init, s0 = _start(model, dyn)
    return [_driven(dyn, x, _runs(v, s0), z_init, s0, True)[1][:, 0] for v, x in pairs]


def feedforward(model, x_r, z0=None, direction0=None):
    """Inverse-free Dahl feedforward of eq. 14 on a whole record.

    u_f = (x_r - x0 + H(x_r)) / g_a, with H driven by the desired
    displacement (x0 = ``model.x0``, 0 for the paper's model: eq. 14 as
    printed).  Fed to the voltage-driven model, it gives x = x_r exactly.

    Parameters
    ----------
    model : DahlModel
    x_r : array_like
        Desired displacement [x-unit] (workbook: reference v_r [V]).
    z0, direction0
        Initial state and direction, as in :func:`dahl_hysteresis`.

    Returns
    -------
    ndarray
        Feedforward input u_f [v-unit] (workbook: amplifier input [V]).

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> x_r = np.r_[np.linspace(0.0, 3.0, 31), np.linspace(2.9, 0.0, 30)]
    >>> u = feedforward(m, x_r)                   # eq. 14: no inversion needed
    >>> bool(np.allclose(simulate_dahl(m, u).x, x_r))
    True
    """
    check_dahl_model(model)
    x_r = check_finite_array("x_r", x_r, ndim=1, min_length=2, real=True)
    H = dahl_hysteresis(model, x_r, z0=z0, direction0=direction0)
    return (x_r - model.x0 + H) / model.g_a


# --------------------------------------------------------------------------- driven by v
@dataclass(frozen=True)
class DahlResponse:
    """Response of the voltage-driven model: x = g_a v - H(x) + x0 (eq. 13, x0 = 0).

    Attributes
    ----------
    v : ndarray
        Input [v-unit].
    x : ndarray
        Displacement [x-unit].
    H : ndarray
        Hysteretic term [x-unit].
    z : ndarray
        States, shape (n, 2).

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> r = simulate_dahl(m, np.array([0.0, 1.0, 2.0, 1.0, 0.0]))
    >>> r.x.shape, r.z.shape, bool(np.allclose(r.x, m.g_a * r.v - r.H))
    ((5,), (5, 2), True)
    """

    v: np.ndarray
    x: np.ndarray
    H: np.ndarray
    z: np.ndarray


def simulate_dahl(model, v, z0=None, direction0=None):
    """Displacement of the Dahl model driven by the input voltage v (eq. 10-13).

    The implicit relation x = g_a v - H(x) + x0 (eq. 13 for x0 = 0) is
    solved exactly, stroke by stroke, by a bracketed Newton iteration on the
    closed-form state (``docs/hysteresis.md``).

    Parameters
    ----------
    model : DahlModel
        With ``beta1 == 0`` (with beta1 != 0, H jumps at every reversal).
    v : array_like
        Input record [v-unit], 1-D.
    z0 : array_like of shape (2,), optional
        Initial state (default: the model's ``start``).
    direction0 : {1, -1}, optional
        Direction assumed until v first changes (default: the model's
        ``start``).

    Returns
    -------
    DahlResponse

    Raises
    ------
    NotInvertibleError
        When x + H(x) decreases somewhere along a stroke (a strongly
        underdamped model), so that x(v) is not unique.

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> from piezolib.signals import triangle
    >>> t, v = triangle(4.0, 1.0, fs=40.0, periods=2)
    >>> r = simulate_dahl(m, v)
    >>> round(float(r.x.max()), 3), round(float(r.H.min()), 3)
    (3.777, -0.223)
    """
    check_dahl_model(model)
    v = check_finite_array("v", v, ndim=1, min_length=2, real=True)
    _check_beta1(model)
    x, H, z = _simulate_records(model, [v], *initial_state_of(model, z0, direction0))[0]
    return DahlResponse(v=v, x=x, H=H, z=z)


def simulate_dahl_records(model, records):
    """:func:`simulate_dahl` of several input records [v-unit], each from the model's ``start``.

    The k-th strokes of all records are solved together, so several loops
    cost little more than one; each response equals that of
    :func:`simulate_dahl`.  Returns a list of :class:`DahlResponse`; raises
    as :func:`simulate_dahl`.

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> v1, v2 = np.linspace(0.0, 4.0, 41), np.linspace(4.0, 0.0, 21)
    >>> r1, r2 = simulate_dahl_records(m, [v1, v2])
    >>> bool(np.allclose(r2.x, simulate_dahl(m, v2).x)), len(r1.x), len(r2.x)
    (True, 41, 21)
    """
    check_dahl_model(model)
    _check_beta1(model)
    records = [check_finite_array(f"records[{i}]", v, ndim=1, min_length=2, real=True)
               for i, v in enumerate(records)]
    if not records:
        raise ValueError("records must hold at least one input record")
    return [DahlResponse(v=v, x=x, H=H, z=z)
            for v, (x, H, z) in zip(records, _simulate_records(model, records))]


def _check_beta1(model):
    if model.beta1 != 0:
        raise ValueError(
            "simulate_dahl needs beta1 = 0: with beta1 != 0 H (eq. 12) jumps by "
            "2*beta1*z2 at every reversal, so x = g_a v - H would jump with the input "
            f"at rest (got beta1={model.beta1}); the published value is 0")


def _simulate_records(model, records, z0=None, s0=None):
    """(x, H, z) of the voltage-driven model for several input records.

    Each record starts from ``z0``, ``s0`` (default: the model's start).  The
    k-th strokes of all records are solved together (they are independent),
    so fitting several loops costs little more than one.  ``model.beta1`` must
    be 0 (checked by the public callers).
    """
    dyn = StrokeDynamics(model)
    z_start, s_start = _start(model, dyn)
    z0 = z_start if z0 is None else z0
    s0 = s_start if s0 is None else s0
    g = model.g_a
    out, runs = [], []
    for v in records:
        z = np.empty((v.size, 2))
        z[0] = z0
        H = np.empty(v.size)
        H[0] = dyn.C[s0] @ z0
        x = np.empty(v.size)
        x[0] = g * v[0] - H[0] + model.x0
        out.append((x, H, z))
        runs.append(_runs(v, s0))
    for rank in range(max(len(r) for r in runs)):
        batch = [(i, runs[i][rank]) for i in range(len(records)) if rank < len(runs[i])]
        s = np.array([run[2] for i, run in batch])
        starts = [(out[i][2][run[0]], out[i][0][run[0]]) for i, run in batch]
        sigmas = _solve_strokes(dyn, s, np.array([zs for zs, xs in starts]),
                                np.array([xs for zs, xs in starts]),
                                [g * records[i][run[0] + 1:run[1] + 1] + model.x0
                                 for i, run in batch])
        for (i, (start, stop, sk)), sigma in zip(batch, sigmas):
            x, H, z = out[i]
            zk = dyn.propagate(sk, sigma, z[start])
            z[start + 1:stop + 1] = zk
            H[start + 1:stop + 1] = zk @ dyn.C[sk]
            x[start + 1:stop + 1] = x[start] + sk * sigma
    return out


def _stroke_constants(dyn, s, W):
    """Per stroke: C expm(N sigma) w = ec*cw + es*cpw, its derivative ec*cnw + es*cnpw."""
    C = np.array([dyn.C[k] for k in s])
    N = np.array([dyn.N[k] for k in s])
    P = np.array([dyn.P[k] for k in s])
    PW = np.einsum("kij,kj->ki", P, W)
    return (np.einsum("ki,ki->k", C, W), np.einsum("ki,ki->k", C, PW),
            np.einsum("ki,kij,kj->k", C, N, W), np.einsum("ki,kij,kj->k", C, N, PW), C)


def _min_slopes(dyn, a, b, sigma_max):
    """Minimum over 0 <= sigma <= sigma_max of 1 + ec(sigma) a + es(sigma) b, per stroke.

    This is d(x + H)/dsigma along a stroke (a = s C N w, b = s C N P w).  The
    function is a damped sinusoid or a sum of two exponentials in sigma, so it
    is evaluated at both ends and at its stationary points, found in closed
    form: the check is exact.
    """
    m, disc = dyn.m, dyn.disc
    cand = [np.zeros_like(sigma_max), sigma_max]
    with np.errstate(divide="ignore", invalid="ignore"):
        if disc < 0:
            om = dyn.q
            theta = np.arctan2(-(m * a + b), m * b / om - om * a) % math.pi
            cand += [theta / om, (theta + math.pi) / om]
        else:
            q = dyn.q
            K = (b + a * m) / ((b + a * q) * dyn.slow)
            if q == 0:
                cand.append(-K)
            else:
                cand.append(np.log1p(np.where(-2 * q * K > -1, -2 * q * K, 0.0)) / (2 * q))
    sig = np.column_stack(cand)
    sig = np.where(np.isfinite(sig) & (sig >= 0) & (sig <= sigma_max[:, None]), sig, 0.0)
    ec, es = dyn.parts(sig)
    return np.min(1.0 + ec * a[:, None] + es * b[:, None], axis=1)


def min_stroke_slope(model, z0, direction, length):
    """Smallest slope d(x + H)/dx along one stroke, found exactly.

    Where it is positive, x = g_a v - H(x) + x0 has one solution along the
    stroke (:func:`simulate_dahl` raises :class:`NotInvertibleError`
    otherwise).  The minimum lies at an end or at a stationary point of the
    slope, found in closed form.

    Parameters
    ----------
    model : DahlModel
        With ``beta1 == 0`` (H continuous at the start of the stroke).
    z0 : array_like of shape (2,)
        State at the start of the stroke.
    direction : {1, -1}
        Direction of the stroke.
    length : float
        Path length of the stroke, > 0 [x-unit].

    Returns
    -------
    float
        min over 0 <= sigma <= ``length`` of d(x + H)/dx (dimensionless).

    Examples
    --------
    >>> m = DahlModel(alpha1=3.0, alpha2=2.0, beta1=0.0, beta2=1.0, gamma_a=0.5, g_a=1.0,
    ...                form="bliman_sorine")
    >>> min_stroke_slope(m, np.zeros(2), direction=1, length=4.0)   # > 0: invertible
    1.0
    >>> bad = DahlModel(0.2, 25.0, 0.0, 40.0, 1.0, 1.0, form="bliman_sorine")
    >>> round(min_stroke_slope(bad, np.zeros(2), 1, 4.0), 2)          # < 0: overshoot
    -6.28
    """
    check_dahl_model(model)
    s = _direction(direction)
    z0 = check_finite_array("z0", z0, shape=(2,))
    length = check_positive("length", length)
    dyn = StrokeDynamics(model)
    cw, cpw, cnw, cnpw, C = _stroke_constants(dyn, np.array([s]), (z0 - dyn.z_ss[s])[None])
    return float(_min_slopes(dyn, s * cnw, s * cnpw, np.array([length]))[0])


def _solve_strokes(dyn, s, Z, x_start, targets, n_grid=48):
    """Path lengths sigma >= 0 of several strokes: x_start + s sigma + C z(sigma) = target.

    With Phi(sigma) = sigma + s C z(sigma) (x + H along the stroke, signed),
    every sample solves Phi(sigma) = s (target - x_start): Phi tabulated per
    stroke brackets each root, a bracketed Newton iteration finishes all
    samples together, and :func:`_min_slopes` proves the roots unique.
    s: directions (K,); Z, x_start: state (K, 2) and displacement (K,) at the
    start of each stroke; targets: K arrays of g_a v + x0.
    """
    K = s.size
    z_ss = np.array([dyn.z_ss[k] for k in s])
    cw, cpw, cnw, cnpw, C = _stroke_constants(dyn, s, Z - z_ss)
    counts = np.array([tg.size for tg in targets])
    seg = np.repeat(np.arange(K), counts)
    offsets = np.concatenate(([0], np.cumsum(counts)[:-1]))
    base = x_start + np.einsum("ki,ki->k", C, z_ss)
    y = s[seg] * (np.concatenate(targets) - base[seg])
    # magnitudes of the terms of Phi: es(sigma) <= 2 / max(q, |m|) for every sigma, so the
    # sinh-like term never exceeds 2 |cpw| / max(q, |m|) (cpw alone can be 1e27 while the
    # term it multiplies is a few x-units: alpha1 = 1e30)
    es_max = 2.0 / max(dyn.q, abs(dyn.m))
    scale = np.max(np.abs(np.column_stack([np.ones(K), x_start, base, cw, es_max * cpw])),
                   axis=1)
    scale = np.maximum(scale, np.maximum.reduceat(np.abs(np.concatenate(targets)), offsets))
    tol = 16 * np.finfo(float).eps * scale
    sc, sp, sn, snp = s * cw, s * cpw, s * cnw, s * cnpw     # signed stroke constants

    def phi(sig, k):
        ec, es = dyn.parts(sig)
        return sig + ec * sc[k] + es * sp[k], 1.0 + ec * sn[k] + es * snp[k]

    y_max = np.maximum.reduceat(y, offsets)
    top = np.maximum(y_max - sc, tol)
    every = np.arange(K)
    for _ in range(200):                     # Phi grows like sigma: double until Phi >= y
        low = phi(top, every)[0] < y_max
        if not low.any():
            break
        top = np.where(low, 2.0 * top, top)
    else:
        raise NotInvertibleError("no root of x + H(x) = g_a v along a stroke")
    grid = top[:, None] * np.linspace(0.0, 1.0, n_grid)
    envelope = np.maximum.accumulate(phi(grid, every[:, None])[0], axis=1)
    k = np.clip(np.argmax(envelope[seg] >= y[:, None], axis=1), 1, n_grid - 1)
    lo, hi = grid[seg, k - 1], grid[seg, k]          # the first crossing lies in [lo, hi]
    e_lo, e_hi = envelope[seg, k - 1], envelope[seg, k]
    frac = np.clip((y - e_lo) / np.maximum(e_hi - e_lo, np.finfo(float).tiny), 0.0, 1.0)
    done = y <= sc[seg] + tol[seg]           # the input did not move (or rounding)
    sigma = np.where(done, 0.0, lo + (hi - lo) * frac)
    tol_e = tol[seg]
    for _ in range(100):                     # Newton, bisection when a step leaves the bracket
        f, df = phi(sigma, seg)
        f -= y
        done |= np.abs(f) <= tol_e
        lo = np.where(f < 0, sigma, lo)
        hi = np.where(f > 0, sigma, hi)
        done |= hi - lo <= 4 * np.finfo(float).eps * hi
        if done.all():
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = sigma - f / df
        inside = (df > 0) & (newton >= lo) & (newton <= hi)
        sigma = np.where(done, sigma, np.where(inside, newton, 0.5 * (lo + hi)))
    else:
        raise NotInvertibleError("the implicit relation x = g_a v - H did not converge")
    slopes = _min_slopes(dyn, sn, snp, np.maximum.reduceat(sigma, offsets))
    if np.any(slopes <= 0):
        a2 = dyn.m ** 2 - dyn.disc                    # alpha2 (nan/inf for alpha1 > 1e154)
        zeta = -dyn.m / math.sqrt(a2) if math.isfinite(a2) and a2 > 0 else math.inf
        raise NotInvertibleError(
            f"x + H(x) is not increasing along a stroke (smallest slope {slopes.min():.3g}: "
            f"dH/dx <= -1, the Dahl transient overshoots; damping alpha1/(2 sqrt(alpha2)) = "
            f"{zeta:.3g}), so x = g_a v - H has no unique solution for this input.  A Dahl "
            "model fitted to a raw record that starts at rest and steps has learnt the "
            "stage's ringing after the step as hysteresis: refit it on the record without "
            "its start-up (piezolib.records.cut_at_turning_points(record, "
            "skip_transient=True)), or fit the linear dynamics with the hysteresis "
            "(piezolib.hysteresis.fit_hammerstein).  To evaluate this model anyway, drive it "
            "by displacement (dahl_hysteresis), which needs no inversion")
    return np.split(sigma, offsets[1:])
