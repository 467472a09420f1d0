"""Dahl hysteresis model, its fit and the inverse-free feedforward (Sec. III-C, IV-A).

The model (eq. 10-13)
---------------------
Two forms are implemented, both rate independent (they depend on the path of
the displacement x, not on time):

``"printed"``  eq. 10-12 exactly as printed::

    dz/dt = A_H(sgn x') z x' + B_H x',   A_H = [[0, 1], [-a2, -a1 sgn x']]
    H     = [b2, b1 sgn x'] z,            B_H = [0, g]

``"bliman_sorine"``  the sign moved onto the state term (second-order
Bliman-Sorine / Dahl model)::

    dz/dt = A_0 z |x'| + B_H x',          A_0 = [[0, 1], [-a2, -a1]]

with ``a1 = alpha1``, ``a2 = alpha2``, ``b1 = beta1``, ``b2 = beta2``,
``g = gamma_a``.  The displacement obeys eq. 13, x = g_a v - H, where H
depends on the history of x itself: an implicit relation, solved exactly here.

Workbook extension: an output offset x0 (default 0 = eq. 13 exactly),

    x = g_a v - H + x0,

the displacement (sensor) zero of the model, which eq. 13 lacks.  Both forms
give loops symmetric about x = g_a v (H swings between -h and +h), so a loop
of v from 0 up to A and back bottoms out at x = +h at v = 0, whereas a stage
that starts at rest returns to its zero there.  The offset lets one
parameter set put the loops where the stage's are.  H depends only on
increments of x, so x0 changes nothing else: H is the same function of the
path, and the feedforward becomes u_f = (x_r - x0 + H(x_r)) / g_a.

Along one monotone stroke (direction s = sgn x', path length sigma = |x - x_start|)
both forms are a *linear* system in sigma,

    dz/dsigma = N_s z + s B_H,   so   z(sigma) = z_ss + expm(N_s sigma) (z0 - z_ss),

with N_+ = A_0 for both forms, N_- = A_0 (Bliman-Sorine) or
[[0, -1], [a2, -a1]] (printed), and z_ss = -s N_s^-1 B_H.  Every N_s has the
characteristic polynomial lambda^2 + a1 lambda + a2, so it is stable for
a1, a2 > 0.  The 2x2 exponential is evaluated in closed form, which makes
the integration exact for any step size.

What the two forms predict (see notebook 03):

* printed: z_ss = (g/a2, 0) in *both* directions, so after a long stroke H
  settles to the same b2 g / a2 whichever way x moves: no loop.  Loops only
  exist while strokes are short compared with the transient length 1/(a1/2).
* Bliman-Sorine: z_ss = s (g/a2, 0), H tends to +-b2 g / a2: a loop of full
  height 2 b2 g / a2 in H.  For a1 >> a2 (a1^2 >> 4 a2) the fast mode of the
  stroke dynamics dies out within 1/a1 and the model acts as a first-order
  Dahl model, dH/dsigma = (a2/a1) (s b2 g / a2 - H) (the first-order limit,
  reachable within the fit bounds :data:`ALPHA1_BOUNDS`).

Only the products b1 g and b2 g enter H (z is proportional to g), so
``gamma_a`` and the betas cannot be identified separately; fits keep
``gamma_a`` at its published value.

Units (workbook convention)
---------------------------
The model is unit agnostic: x and H share one unit, v another, ``alpha1``
is per x-unit, ``alpha2`` per x-unit squared, ``g_a`` in x-unit per v-unit.
The workbook takes **v = u_c, the amplifier input [V], and x = v_y, the
displacement in sensor volts [V] (x [um] = 3 um/V * v_y)**.  This is the only
natural convention in which the published g_a = 0.925 is close to the static
gain of the chain (0.8976 V/V, the DC gain of G), and it is the one eq. 14
needs: u_f is added to the controller output u_b (amplifier-input volts) and
x_r is compared with v_y in volts.  Hence g_a [V/V], alpha1 [1/V],
alpha2 [1/V^2], H [V].  Multiply v by 10 for actuator volts and x by 3 for um.

Contents
--------
* :class:`DahlModel` (parameters and form), :func:`dahl_hysteresis` (H driven
  by a displacement record), :func:`simulate_dahl` (x driven by the input v,
  eq. 13 solved exactly);
* :func:`feedforward` and :class:`DahlFeedforward`: eq. 14 on arrays and
  sample by sample;
* :func:`fit_dahl`: least-squares fit to one or several loops, with or
  without the offset x0;
* :func:`fit_case_I_loops`, :func:`choose_fit`, :func:`workbook_dahl_fit`:
  the candidate fits to the virtual stage's Case I loops, the selection rule
  and the one shared feedforward model of notebooks 03 and 06 (cached);
* :func:`table4_reference`, :func:`table4_measure`: how the Table 4 loops are
  produced and measured (shared by Cases I-III; the cases themselves are run
  by :func:`piezolib.workbook.loop.run_case`);
* :func:`hysteresis_percent` / :func:`hysteresis_measure` (eq. 25-26),
  re-exported from :mod:`piezolib.metrics`.

Conventions of this implementation
----------------------------------
* sgn(x') at rest (x' = 0) keeps the last direction, so H does not change at
  rest; the first direction is +1 unless given.
* The initial state is the model's ``start`` unless given: z = 0 (virgin
  actuator, the default) or "rest", the state after a long descending
  stroke (the virtual stage starts at rest after being lowered).
* The voltage-driven model (:func:`simulate_dahl`) needs beta1 = 0 (the
  published value): with beta1 != 0, H jumps by 2 beta1 z2 at every reversal,
  and so would x = g_a v - H with the input at rest.
"""

import functools
import math
from dataclasses import dataclass, fields, replace

import numpy as np
import scipy.optimize as opt

from piezolib import paper, signals
from piezolib._checks import check_finite_array, check_integer, check_positive, check_same_length
from piezolib.metrics import HysteresisMeasure, hysteresis_measure, hysteresis_percent

__all__ = [
    "FORMS", "STARTS", "DahlModel", "DahlResponse", "NotInvertibleError",
    "dahl_hysteresis", "simulate_dahl", "feedforward", "DahlFeedforward",
    "DahlFit", "fit_dahl", "CASE_I_CANDIDATES", "WORKBOOK_DAHL", "fit_case_I_loops",
    "choose_fit", "workbook_dahl_fit", "ALPHA1_BOUNDS", "ALPHA2_BOUNDS", "G_A_BOUNDS", "strokes",
    "table4_reference", "table4_measure",
    "HysteresisMeasure", "hysteresis_measure", "hysteresis_percent",
]

#: The two model forms: eq. 10 as printed, and the Bliman-Sorine placement.
FORMS = ("printed", "bliman_sorine")
#: Initial states: "virgin" z = 0 (moving up), "rest" the state after a long
#: descending stroke (moving down), i.e. at rest after being lowered.
STARTS = ("virgin", "rest")


class NotInvertibleError(ValueError):
    """x + H(x) is not monotone along a stroke, so x = g_a v - H has no unique solution."""


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
        Where the sign of the velocity enters (see the module docstring).
    x0 : float, optional
        Output offset [x-unit], x = g_a v - H + x0: the model's displacement
        (sensor) zero, a workbook extension that eq. 13 lacks.  Default 0:
        the paper's model exactly.
    start : {"virgin", "rest"}, optional
        State every simulation and feedforward starts from unless told
        otherwise (:meth:`initial_state`): "virgin" (default) z = 0, "rest"
        the state reached after a long descending stroke, i.e. at rest after
        the actuator was lowered.
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
        if self.start not in STARTS:
            raise ValueError(f"start must be one of {STARTS}, got {self.start!r}")

    @classmethod
    def published(cls, form="printed", params=paper.DAHL):
        """The paper's identified parameters (Sec. III-C) in the given form."""
        if not isinstance(params, paper.DahlParameters):
            raise TypeError("params must be a paper.DahlParameters instance")
        return cls(**{f.name: getattr(params, f.name) for f in fields(params)}, form=form)

    def steady_state(self, direction=1):
        """H reached after a long stroke in ``direction`` (+1 or -1) [x-unit].

        ``beta2 gamma_a / alpha2`` for both directions in the printed form,
        ``direction * beta2 gamma_a / alpha2`` in the Bliman-Sorine form.
        """
        s = _direction(direction)
        dyn = _Dynamics(self)
        return float(dyn.C[s] @ dyn.z_ss[s])

    @property
    def damping(self):
        """zeta = a1 / (2 sqrt(a2)) of the stroke dynamics (dimensionless)."""
        return self.alpha1 / (2.0 * math.sqrt(self.alpha2))

    @property
    def transient_length(self):
        """1 / (a1/2): path length over which a transient decays by e [x-unit]."""
        return 2.0 / self.alpha1

    def with_form(self, form):
        """The same parameters in another form."""
        return replace(self, form=form)

    def initial_state(self):
        """(z0, direction0) of the model's ``start``.

        "virgin": z = 0, direction +1.  "rest": z = z_ss of a descending
        stroke, direction -1; in the Bliman-Sorine form H = -b2 gamma_a / a2
        there, in the printed form the common steady state (no loop).
        """
        if self.start == "virgin":
            return np.zeros(2), 1
        return _Dynamics(self).z_ss[-1].copy(), -1

    def with_offset(self, x0):
        """The same model with output offset ``x0`` [x-unit] (0: the paper's eq. 13)."""
        return replace(self, x0=x0)


def _direction(direction):
    if direction not in (1, -1):
        raise ValueError(f"direction must be +1 or -1, got {direction!r}")
    return int(direction)


class _Dynamics:
    """Per-direction constants of the stroke dynamics dz/dsigma = N_s z + s B."""

    def __init__(self, model):
        a1, a2 = model.alpha1, model.alpha2
        B = np.array([0.0, model.gamma_a])
        A0 = np.array([[0.0, 1.0], [-a2, -a1]])
        self.m = -a1 / 2.0                 # real part of the eigenvalues
        self.disc = a1 * a1 / 4.0 - a2     # > 0 overdamped, < 0 oscillatory
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
        m, disc = self.m, self.disc
        if disc < 0:
            w = math.sqrt(-disc)
            em = np.exp(m * sigma)
            return em * np.cos(w * sigma), em * sigma * np.sinc(w * sigma / np.pi)
        q = math.sqrt(disc)
        y = q * sigma
        ep, en = np.exp((m + q) * sigma), np.exp((m - q) * sigma)
        ec = 0.5 * (ep + en)
        small = y < 1e-3
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
    """
    d = np.sign(np.diff(u))
    idx = np.where(d != 0, np.arange(d.size), -1)
    idx = np.maximum.accumulate(idx)
    s = np.where(idx >= 0, d[np.maximum(idx, 0)], direction0).astype(int)
    if s.size == 0:
        return []
    change = np.flatnonzero(np.diff(s)) + 1
    starts = np.r_[0, change]
    stops = np.r_[change, s.size]
    return [(int(a), int(b), int(s[a])) for a, b in zip(starts, stops)]


def _initial_state(model, z0, direction0):
    """(z0, direction0) given, or the model's start (:meth:`DahlModel.initial_state`)."""
    z_start, s_start = model.initial_state()
    z = z_start if z0 is None else check_finite_array("z0", z0, shape=(2,))
    return z, s_start if direction0 is None else _direction(direction0)


def _check_model(model):
    if not isinstance(model, DahlModel):
        raise TypeError(f"model must be a DahlModel, got {type(model).__name__}")
    return model


# --------------------------------------------------------------------------- driven by x
def dahl_hysteresis(model, x, z0=None, direction0=None, return_state=False):
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

    Returns
    -------
    H : ndarray
        H at every sample [x-unit]; ``(H, z)`` with ``return_state``.
    """
    _check_model(model)
    x = check_finite_array("x", x, ndim=1, min_length=2)
    z_init, s0 = _initial_state(model, z0, direction0)
    dyn = _Dynamics(model)
    z = np.empty((x.size, 2))
    z[0] = z_init
    H = np.empty(x.size)
    H[0] = dyn.C[s0] @ z[0]
    for start, stop, s in strokes(x, s0):
        sigma = s * (x[start + 1:stop + 1] - x[start])
        z[start + 1:stop + 1] = dyn.propagate(s, sigma, z[start])
        H[start + 1:stop + 1] = z[start + 1:stop + 1] @ dyn.C[s]
    return (H, z) if return_state else H


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
    """
    _check_model(model)
    x_r = check_finite_array("x_r", x_r, ndim=1, min_length=2)
    H = dahl_hysteresis(model, x_r, z0=z0, direction0=direction0)
    return (x_r - model.x0 + H) / model.g_a


class DahlFeedforward:
    """Stateful, sample-by-sample Dahl feedforward (eq. 14) for a 10 kHz loop.

    Each :meth:`step` costs a few dozen floating-point operations on Python
    floats (closed-form 2x2 matrix exponential), and the sequence of steps
    equals :func:`feedforward` on the whole record to rounding.

    Parameters
    ----------
    model : DahlModel
    z0 : array_like of shape (2,), optional
        Initial state (default: the model's ``start``).
    direction0 : {1, -1}, optional
        Direction assumed until the reference first moves (default: the
        model's ``start``).

    Examples
    --------
    >>> ff = DahlFeedforward(DahlModel(2.0, 1.0, 0.0, 0.1, 1.0, 0.9))
    >>> u = [ff.step(r) for r in (0.0, 0.1, 0.2)]
    """

    def __init__(self, model, z0=None, direction0=None):
        self.model = _check_model(model)
        z_init, self._s_init = _initial_state(model, z0, direction0)
        self._z_init = tuple(float(v) for v in z_init)
        dyn = _Dynamics(model)
        self._m = dyn.m
        self._disc = dyn.disc
        self._root = math.sqrt(abs(dyn.disc))
        # per direction: P = N - mI (4 floats), z_ss (2), C (2)
        self._P = {s: tuple(float(v) for v in dyn.P[s].ravel()) for s in (1, -1)}
        self._zss = {s: tuple(float(v) for v in dyn.z_ss[s]) for s in (1, -1)}
        self._C = {s: tuple(float(v) for v in dyn.C[s]) for s in (1, -1)}
        self._inv_g = 1.0 / model.g_a
        self._x0 = model.x0
        self.reset()

    def reset(self):
        """Return to the initial state (before the first sample)."""
        self._z1, self._z2 = self._z_init
        self._s = self._s_init
        self._x = None

    @property
    def state(self):
        """Current (z1, z2)."""
        return (self._z1, self._z2)

    @property
    def H(self):
        """Current hysteretic term H [x-unit]."""
        c1, c2 = self._C[self._s]
        return c1 * self._z1 + c2 * self._z2

    def step(self, x_r):
        """Advance to the desired displacement ``x_r`` and return u_f [v-unit]."""
        x_r = float(x_r)
        if not math.isfinite(x_r):
            raise ValueError(f"x_r must be finite, got {x_r!r}")
        if self._x is not None and x_r != self._x:
            dx = x_r - self._x
            s = 1 if dx > 0 else -1
            sigma = abs(dx)
            ec, es = self._parts(sigma)
            zs1, zs2 = self._zss[s]
            p11, p12, p21, p22 = self._P[s]
            w1, w2 = self._z1 - zs1, self._z2 - zs2
            self._z1 = zs1 + ec * w1 + es * (p11 * w1 + p12 * w2)
            self._z2 = zs2 + ec * w2 + es * (p21 * w1 + p22 * w2)
            self._s = s
        self._x = x_r
        c1, c2 = self._C[self._s]
        return (x_r - self._x0 + c1 * self._z1 + c2 * self._z2) * self._inv_g

    def _parts(self, sigma):
        """Scalar version of :meth:`_Dynamics.parts`."""
        m, q = self._m, self._root
        if self._disc < 0:
            em = math.exp(m * sigma)
            y = q * sigma
            return em * math.cos(y), em * (math.sin(y) / q if y > 1e-8 else sigma)
        y = q * sigma
        ep, en = math.exp((m + q) * sigma), math.exp((m - q) * sigma)
        if y < 1e-3:
            return 0.5 * (ep + en), math.exp(m * sigma) * sigma * (1 + y * y / 6 + y ** 4 / 120)
        return 0.5 * (ep + en), (ep - en) / (2 * q)

    def run(self, x_r):
        """Feed a whole record sample by sample (continuing from the current state)."""
        x_r = check_finite_array("x_r", x_r, ndim=1)
        return np.array([self.step(v) for v in x_r])


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
    """

    v: np.ndarray
    x: np.ndarray
    H: np.ndarray
    z: np.ndarray


def simulate_dahl(model, v, z0=None, direction0=None):
    """Displacement of the Dahl model driven by the input voltage v (eq. 10-13).

    The implicit relation x = g_a v - H(x) + x0 (eq. 13 for x0 = 0) is
    solved exactly: along a run of constant input direction s the
    displacement moves the same way, and x_k = x_start + s sigma_k where
    sigma_k >= 0 is the root of

        psi(sigma) = sigma + s [C z(sigma) + x_start - x0 - g_a v_k],

    with z(sigma) in closed form.  All samples of a run are solved together
    by a safeguarded (bracketed) Newton iteration to machine precision.

    Parameters
    ----------
    model : DahlModel
        With ``beta1 == 0`` (see the module docstring).
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
    """
    _check_model(model)
    v = check_finite_array("v", v, ndim=1, min_length=2)
    if model.beta1 != 0:
        raise ValueError(
            "simulate_dahl needs beta1 = 0: with beta1 != 0 H (eq. 12) jumps by "
            "2*beta1*z2 at every reversal, so x = g_a v - H would jump with the input "
            f"at rest (got beta1={model.beta1}); the published value is 0")
    x, H, z = _simulate_records(model, [v], *_initial_state(model, z0, direction0))[0]
    return DahlResponse(v=v, x=x, H=H, z=z)


def _simulate_records(model, records, z0=None, s0=None):
    """(x, H, z) of the voltage-driven model for several input records.

    Each record starts from ``z0``, ``s0`` (default: the model's start).  The
    k-th strokes of all records are solved together (they are independent),
    so fitting several loops costs little more than one.  ``model.beta1`` must
    be 0 (checked by :func:`simulate_dahl`; :func:`fit_dahl` fits with beta1 = 0).
    """
    dyn = _Dynamics(model)
    z_start, s_start = model.initial_state()
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
        runs.append(strokes(v, s0))
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
            om = math.sqrt(-disc)
            theta = np.arctan2(-(m * a + b), m * b / om - om * a) % math.pi
            cand += [theta / om, (theta + math.pi) / om]
        else:
            q = math.sqrt(disc)
            K = (b + a * m) / ((b + a * q) * (m + q))
            if q == 0:
                cand.append(-K)
            else:
                cand.append(np.log1p(np.where(-2 * q * K > -1, -2 * q * K, 0.0)) / (2 * q))
    sig = np.column_stack(cand)
    sig = np.where(np.isfinite(sig) & (sig >= 0) & (sig <= sigma_max[:, None]), sig, 0.0)
    ec, es = dyn.parts(sig)
    return np.min(1.0 + ec * a[:, None] + es * b[:, None], axis=1)


def _min_slope(dyn, s, w, sigma_max):
    """:func:`_min_slopes` for one stroke in direction s from z = z_ss + w."""
    cw, cpw, cnw, cnpw, C = _stroke_constants(dyn, np.array([s]), np.array([w]))
    return float(_min_slopes(dyn, s * cnw, s * cnpw, np.array([float(sigma_max)]))[0])


def _solve_strokes(dyn, s, Z, x_start, targets, n_grid=48):
    """Path lengths sigma >= 0 of several strokes: x_start + s sigma + C z(sigma) = target.

    With Phi(sigma) = sigma + s C z(sigma) (x + H along the stroke, signed),
    every sample solves Phi(sigma) = s (target - x_start).  Phi is tabulated
    once per stroke to bracket and start each root, a bracketed Newton
    iteration finishes all samples of all strokes together, and the exact
    monotonicity check (:func:`_min_slopes`) proves the roots unique.

    Parameters
    ----------
    s : ndarray of int, shape (K,)
        Stroke directions.
    Z, x_start : ndarray, shapes (K, 2) and (K,)
        State and displacement at the start of each stroke.
    targets : list of K ndarray
        g_a v + x0 at the samples of each stroke.

    Returns
    -------
    list of K ndarray
    """
    K = s.size
    z_ss = np.array([dyn.z_ss[k] for k in s])
    cw, cpw, cnw, cnpw, C = _stroke_constants(dyn, s, Z - z_ss)
    counts = np.array([tg.size for tg in targets])
    seg = np.repeat(np.arange(K), counts)
    offsets = np.r_[0, np.cumsum(counts)[:-1]]
    base = x_start + np.einsum("ki,ki->k", C, z_ss)
    y = s[seg] * (np.concatenate(targets) - base[seg])
    scale = np.max(np.abs(np.column_stack([np.ones(K), x_start, base, cw, cpw])), axis=1)
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
    if np.any(_min_slopes(dyn, sn, snp, np.maximum.reduceat(sigma, offsets)) <= 0):
        raise NotInvertibleError(
            "x + H(x) is not increasing along a stroke (dH/dx <= -1: the Dahl transient "
            "overshoots), so x = g_a v - H has no unique solution; use a better damped "
            "model or drive the model by displacement (dahl_hysteresis)")
    return np.split(sigma, offsets[1:])


# --------------------------------------------------------------------------- fit
@dataclass(frozen=True)
class DahlFit:
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

    @property
    def worst_rms_percent(self):
        """Largest per-loop RMS error [% of range]."""
        return float(np.max(self.rms_percent))

    @property
    def pooled_rms_percent(self):
        """RMS over the loops of the per-loop RMS errors [% of range].

        The fit's own criterion (every loop weighs the same), evaluated on
        all samples: the workbook's model selection rule (:func:`choose_fit`).
        """
        return float(np.sqrt(np.mean(self.rms_percent ** 2)))


def _check_loops(loops, discard, stride):
    """Validated loops as (v, x, used) with ``used`` the residual samples.

    ``used`` holds every ``stride``-th sample from ``discard`` on plus every
    turning point of v: the model output at these samples is exactly that of
    the full record, because a rate-independent model only sees the path.
    """
    if isinstance(loops, tuple) and len(loops) == 2 and np.ndim(loops[0]) == 1 \
            and np.size(loops[0]) > 2:
        loops = [loops]                       # a single (v, x) pair
    try:
        loops = list(loops)
    except TypeError:
        raise TypeError("loops must be a sequence of (v, x) pairs of 1-D arrays") from None
    if not loops:
        raise ValueError("loops must hold at least one (v, x) pair")
    discard = check_integer("discard", discard, minimum=0)
    stride = check_integer("stride", stride, minimum=1)
    out = []
    for i, pair in enumerate(loops):
        if not isinstance(pair, (tuple, list)) or len(pair) != 2:
            raise TypeError(f"loops[{i}] must be a (v, x) pair of arrays, "
                            f"got {type(pair).__name__}")
        v = check_finite_array(f"loops[{i}] v", pair[0], ndim=1, min_length=8)
        x = check_finite_array(f"loops[{i}] x", pair[1], ndim=1, min_length=8)
        if v.size != x.size:
            raise ValueError(f"loops[{i}]: v and x must have equal lengths "
                             f"({v.size} and {x.size})")
        runs = strokes(v)
        late = [r for r in runs if r[1] > discard]
        if not any(r[2] > 0 for r in late) or not any(r[2] < 0 for r in late) \
                or np.ptp(x[discard:]) == 0:
            raise ValueError(f"loops[{i}] has no full cycle after discarding {discard} "
                             "samples: need an ascending and a descending stroke of v")
        keep = np.union1d(np.arange(0, v.size, stride), [r[1] for r in runs] + [0])
        out.append((v[keep], x[keep], np.flatnonzero(keep >= discard)))
    return out


def _unit_model(form, alpha1, alpha2, start):
    """Model whose H is z1 for gamma_a = 1: H of a general model is beta2*gamma_a*z1."""
    return DahlModel(alpha1, alpha2, 0.0, 1.0, 1.0, 1.0, form=form, start=start)


def _z1_on_input_strokes(model, v, x):
    """z1 driven by a (noisy) measured x, with directions taken from the input v."""
    dyn = _Dynamics(model)
    z, s0 = model.initial_state()
    z1 = np.full(x.size, z[0])
    for start, stop, s in strokes(v, s0):
        zk = dyn.propagate(s, s * (x[start + 1:stop + 1] - x[start]), z)
        z1[start + 1:stop + 1] = zk[:, 0]
        z = zk[-1]
    return z1


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


def _mean_slope(data):
    """Least-squares slope of x on v over all loops (through the records' start)."""
    num = sum(float(np.dot(v[used] - v[0], x[used] - x[0])) for v, x, used in data)
    den = sum(float(np.dot(v[used] - v[0], v[used] - v[0])) for v, x, used in data)
    if not num > 0 or not den > 0:
        raise ValueError("the loops must show x increasing with v (positive mean slope)")
    return num / den


def _loop_weights(data):
    """Residual weight per loop: 1 / (output range * sqrt(samples used))."""
    return [1.0 / (np.ptp(x[used]) * math.sqrt(used.size)) for v, x, used in data]


def _equation_error(form, data, log_a1, log_a2, g_bounds, offset, start):
    """Residual and (g_a, b[, x0]) of the linear problem x = g_a v - b z1(x) [+ x0].

    z1 is driven by the measured x, which makes the problem linear in g_a,
    b = beta2 gamma_a and the offset x0.  g_a is held inside ``g_bounds``
    (clipped, the other parameters then refitted).
    """
    unit = _unit_model(form, math.exp(log_a1), math.exp(log_a2), start)
    rows, rhs = [], []
    for (v, x, used), w in zip(data, _loop_weights(data)):
        z1 = _z1_on_input_strokes(unit, v, x)
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

    def error(p):
        return _equation_error(form, data, p[0], p[1], g_bounds, offset, start)

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


def _check_fit_options(form, offset, start):
    """Validated (form, offset, start) of a fit, offset as a plain bool."""
    if form not in FORMS:
        raise ValueError(f"form must be one of {FORMS}, got {form!r}")
    if not isinstance(offset, (bool, np.bool_)):
        raise TypeError(f"offset must be True or False, got {offset!r}")
    if start not in STARTS:
        raise ValueError(f"start must be one of {STARTS}, got {start!r}")
    return form, bool(offset), start


def fit_dahl(loops, form="bliman_sorine", offset=False, start="virgin",
             gamma_a=paper.DAHL.gamma_a, discard=0, stride=1, initial=None, starts=3):
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
    Each start is solved to a loose tolerance and the best one polished.

    Parameters
    ----------
    loops : sequence of (v, x)
        Input [v-unit] and measured displacement [x-unit] records, each with
        at least one ascending and one descending stroke of v.
    form : {"bliman_sorine", "printed"}
    offset : bool, optional
        Fit the output offset x0 of :class:`DahlModel` (workbook extension).
        Default False: the paper's eq. 13 exactly (x0 = 0).
    start : {"virgin", "rest"}, optional
        The fitted model's ``start``: the state it is in at the first sample
        of every record (default "virgin": z = 0; "rest": after a long
        descending stroke).
    gamma_a : float, optional
        Fixed input weight (default: the published 30).
    discard : int, optional
        Samples at the start of each record left out of the residuals (the
        model still runs through them), e.g. one period to skip the virgin
        curve.
    stride : int, optional
        Use every ``stride``-th sample (and every turning point of v) in the
        fit; the model output there is exact regardless, so this only trades
        noise averaging for speed.  The reported residuals use all samples.
    initial : DahlModel, optional
        Single starting point instead of the grid search (its x0 is ignored:
        x0 is solved exactly).
    starts : int, optional
        Number of grid starting points (ignored with ``initial``).

    Returns
    -------
    DahlFit
    """
    form, offset, start = _check_fit_options(form, offset, start)
    gamma_a = check_positive("gamma_a", gamma_a)
    data = _check_loops(loops, discard, stride)
    slope = _mean_slope(data)
    g_bounds = (slope * G_A_BOUNDS[0], slope * G_A_BOUNDS[1])
    if initial is None:
        candidates = _initial_guesses(form, data, gamma_a, g_bounds,
                                      check_integer("starts", starts, minimum=1), offset,
                                      start)
    else:
        _check_model(initial)
        candidates = [replace(initial, form=form, beta1=0.0, start=start,
                              beta2=initial.beta2 * initial.gamma_a / gamma_a, gamma_a=gamma_a)]
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
            sims = _simulate_records(model, [v for v, x, used in data])
        except NotInvertibleError:
            return None
        return np.concatenate([w * (xm[used] - x[used])
                               for (xm, H, z), (v, x, used), w in zip(sims, data, weights)])

    def residuals(theta):
        r = output_error(theta)
        if r is None:
            return np.full(n_res, 10.0 / math.sqrt(n_res))  # far worse than any loop fit
        return r + _project_offset(r, wv) * wv if offset else r

    result, initial = None, None
    def solve(theta0, tol):
        theta0 = np.clip(theta0, lower + 1e-9 * (upper - lower), upper - 1e-9 * (upper - lower))
        return opt.least_squares(residuals, theta0, bounds=(lower, upper), x_scale="jac",
                                 method="trf", xtol=tol, ftol=tol, gtol=tol)

    # every start to a loose tolerance, the best one polished
    for candidate in candidates:
        trial = solve(_to_theta(candidate), 1e-4 if len(candidates) > 1 else 1e-10)
        if result is None or trial.cost < result.cost:
            result, initial = trial, candidate
    if len(candidates) > 1:
        result = solve(result.x, 1e-10)
    x0 = _project_offset(output_error(result.x), wv) if offset else 0.0
    model = _from_theta(result.x, form, gamma_a, start, x0)
    x_model, res, rms, rms_pct, max_pct = [], [], [], [], []
    for v, x, used in _check_loops(loops, discard, 1):
        xm = simulate_dahl(model, v).x
        r = xm[used] - x[used]
        span = np.ptp(x[used])
        x_model.append(xm)
        res.append(r)
        rms.append(math.sqrt(float(np.mean(r ** 2))))
        rms_pct.append(100 * rms[-1] / span)
        max_pct.append(100 * float(np.max(np.abs(r))) / span)
    return DahlFit(model=model, x_model=x_model, residuals=res, rms=np.array(rms),
                   rms_percent=np.array(rms_pct), max_percent=np.array(max_pct),
                   initial=initial, result=result, offset=offset)


# --------------------------------------------------------------------------- workbook model
#: Candidate (form, offset, start) fits to the Case I loops.  From rest the
#: printed form's H is constant (both directions share one steady state), so
#: that form is fitted from the virgin state only.
CASE_I_CANDIDATES = tuple((form, offset, start) for form in FORMS for offset in (False, True)
                          for start in STARTS if not (form == "printed" and start == "rest"))
#: The candidate that :func:`choose_fit` selects on the virtual stage's Case I
#: loops (checked in notebook 03); the model behind :func:`workbook_dahl_fit`.
WORKBOOK_DAHL = ("bliman_sorine", True, "rest")


def fit_case_I_loops(form, offset, start, directory=None, stride=10):
    """Joint fit of one candidate to the Table 4 Case I loops (cached in-process).

    The four 10 Hz loops of :func:`piezolib.problem.stage.load_hysteresis_loops`
    (v = u_c [V], x = v_y [V]), the first period left out of the residuals
    (the model still runs through it), every ``stride``-th sample used in the
    fit.  The result is cached per argument set: treat it as read-only.

    Parameters
    ----------
    form : {"printed", "bliman_sorine"}
    offset : bool
        Fit the output offset x0.
    start : {"virgin", "rest"}
        The model's initial state.
    directory : str or Path, optional
        Where the experiment files are (default: the workbook's ``data/``).
    stride : int, optional

    Returns
    -------
    DahlFit
    """
    form, offset, start = _check_fit_options(form, offset, start)
    directory = None if directory is None else str(directory)
    return _fit_case_I_loops(form, offset, start, directory,
                             check_integer("stride", stride, minimum=1))


@functools.lru_cache(maxsize=None)
def _fit_case_I_loops(form, offset, start, directory, stride):
    """:func:`fit_case_I_loops` with normalised arguments (one cache entry per fit)."""
    from piezolib.problem import stage as _stage     # lazy: the stage module is heavier than this one
    loops = _stage.load_hysteresis_loops(directory)
    period = int(round(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"]))
    return fit_dahl([(rec.u_c_V, rec.v_y_V) for rec in loops.values()], form=form,
                    offset=offset, start=start, discard=period, stride=stride)


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
    """
    if not fits:
        raise ValueError("fits must hold at least one DahlFit")
    return min(fits, key=lambda key: fits[key].pooled_rms_percent)


def workbook_dahl_fit(directory=None):
    """The workbook's feedforward model: :data:`WORKBOOK_DAHL` fitted to the Case I loops.

    One shared, cached fit for notebooks 03 and 06 and :mod:`piezolib.workbook.loop`,
    so that they cannot diverge.  Notebook 03 checks that :func:`choose_fit`
    picks :data:`WORKBOOK_DAHL` among :data:`CASE_I_CANDIDATES`.

    Returns
    -------
    DahlFit
    """
    return fit_case_I_loops(*WORKBOOK_DAHL, directory=directory)


# --------------------------------------------------------------------------- Table 4
def table4_reference(amplitude_V, periods=3, frequency_hz=None, fs=paper.SAMPLING_FREQUENCY_HZ):
    """Reference of the Table 4 experiments for one actuator amplitude.

    A triangle from 0 to ``amplitude_V / AMPLIFIER_GAIN`` [V] at 10 Hz: the
    amplifier-input voltage that Case I applies directly (actuator voltage
    0 ... amplitude_V) and, read as x_r = v_r in sensor volts, the desired
    displacement of Cases II and III (0 ... 0.3 um/V x amplitude_V).

    Returns
    -------
    t : ndarray
        Time [s].
    v_r : ndarray
        Reference [V].
    """
    amplitude_V = check_positive("amplitude_V", amplitude_V)
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_hz is None else frequency_hz
    return signals.triangle(amplitude_V / paper.AMPLIFIER_GAIN, f, periods=periods, fs=fs)


def table4_measure(reference_V, v_y_V, discard_periods=1, frequency_hz=None,
                   fs=paper.SAMPLING_FREQUENCY_HZ):
    """Hysteresis of one Table 4 loop, measured the same way in every case.

    The loop is the measured displacement x = 3 um/V * v_y [um] against the
    reference expressed as actuator voltage, AMPLIFIER_GAIN * reference [V]
    (Case I: the reference is the applied u_c, so the input axis is the
    actuator voltage v_a itself; Cases II-III: the reference v_r that the
    feedforward / closed loop receives).  The first ``discard_periods``
    periods (compensator and loop start-up) are left out, and eq. 25-26 are
    applied to the rest (:func:`hysteresis_measure`).

    Parameters
    ----------
    reference_V : array_like
        u_c (Case I) or v_r (Cases II, III) [V] at the DAQ rate.
    v_y_V : array_like
        Measured sensor output [V], same length.
    discard_periods : int, optional
    frequency_hz, fs : float, optional
        Triangle frequency (default 10 Hz) and sampling rate [Hz].

    Returns
    -------
    HysteresisMeasure
        In actuator volts and micrometres.
    """
    reference_V = check_finite_array("reference_V", reference_V, ndim=1, min_length=8)
    v_y_V = check_finite_array("v_y_V", v_y_V, ndim=1, min_length=8)
    check_same_length(reference_V=reference_V, v_y_V=v_y_V)
    discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_hz is None else frequency_hz
    start = int(round(discard_periods * check_positive("fs", fs) / check_positive("frequency_hz", f)))
    if start >= reference_V.size - 8:
        raise ValueError(f"discarding {discard_periods} period(s) leaves no record "
                         f"({reference_V.size} samples)")
    return hysteresis_measure(paper.AMPLIFIER_GAIN * reference_V[start:],
                              paper.UM_PER_VOLT * v_y_V[start:])
