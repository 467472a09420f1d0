"""Fixed-pole basis models: causal nonlinear MIMO models that are linear in their parameters.

A model of this family is a sum of branches.  Branch b takes a static
function phi_b of the input (the input itself, u|u| or u^3, channel by
channel), filters each channel through a bank of first-order filters with
fixed poles p_i (one complex filter per conjugate pair, its real and
imaginary parts two regressors; a real pole one regressor), adds the
channel itself (a feedthrough), and multiplies the lot by a^j(k), a power of
a causal amplitude of the input:

    y(k) = sum_b a(k)^{j_b} [ sum_i sum_c Theta_{b,i,c} x_{b,i,c}(k) + sum_c D_{b,c} phi_b(u_c(k)) ],
    x_{b,i,c}(k + 1) = p_i x_{b,i,c}(k) + phi_b(u_c(k)),    x(0) = 0.

The poles fix the dynamics that can be represented (e.g. the union of the
poles of linear models fitted at several excitation levels, so that the
resonances of every level are in the basis); the coefficients Theta, D are
found by one linear least-squares solve.  The branches with j > 0 make it a
linear-parameter-varying (LPV) model scheduled by the input's amplitude: a
resonance that moves with the level is, to first order, a term a dG/da u,
and the union of the levels' poles holds each level's model, so that a
quadratic schedule (j = 0, 1, 2) contains the per-level models blended by a
quadratic interpolation in a.  The static branches (u|u|, u^3) describe
distortions within a level (a Hammerstein part with fixed poles).

The amplitude a(k) (:func:`running_rms`) is the RMS over the input channels
of the past inputs, over a window that grows from the first sample up to
``window_samples`` and then slides exponentially: it uses the inputs up to
k only, so the model is causal, starts from rest and cannot go unstable (it
has no output feedback: every filter is stable).

The fit (:func:`fit_basis_model`) accumulates the normal equations record by
record, each record simulated from rest and its first ``n_init`` samples
dropped, each output of each record weighted by the inverse of its variance:
the cost is the sum of squared NRMSEs, the quantity a benchmark metric such as
:func:`piezolib.metrics.simulation_error` averages.  :func:`select_basis_model`
chooses the branches and the window on held-out records, sharing one
accumulation per window between the candidates.

Inputs in any unit (``input_scale`` in the same unit makes a dimensionless);
time in samples.

Examples
--------
A static u|u| term ahead of a known filter, recovered from 4 records:

>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> poles = np.array([0.9, 0.5 + 0.5j])
>>> truth = BasisModel(poles, (("u", 0), ("u|u|", 0)), 50.0, 1.0,
...                    theta=rng.standard_normal((1, 2 * (3 + 1))), n_inputs=1)
>>> u = [rng.standard_normal((500, 1)) for _ in range(4)]
>>> y = [truth.simulate(ur) for ur in u]
>>> model = fit_basis_model(u, y, poles, (("u", 0), ("u|u|", 0)), 50.0, 1.0)
>>> bool(np.allclose(model.theta, truth.theta, atol=1e-6))
True
"""

from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.linalg
import scipy.linalg.blas
import scipy.signal

from piezolib._checks import (check_finite_array, check_integer, check_nonnegative,
                              check_positive, check_type)

__all__ = ["BRANCH_FUNCTIONS", "BasisModel", "BasisStepper", "BasisSelection", "basis_poles", "running_rms",
           "basis_regressors", "fit_basis_model", "select_basis_model"]

#: The static functions a branch may apply to each input channel (``scale``: ``input_scale``).
BRANCH_FUNCTIONS = {
    "u": lambda u, scale: u,
    "u|u|": lambda u, scale: u * np.abs(u) / scale,
    "u^3": lambda u, scale: u ** 3 / scale ** 2,
}
#: Largest pole radius accepted (a pole on the unit circle integrates: no rest to return to).
MAX_POLE_RADIUS = 0.99999


# --------------------------------------------------------------------------- checks
def _check_poles(poles):
    p = check_finite_array("poles", poles, ndim=1, min_length=1)
    p = p.astype(complex)
    if np.any(np.abs(p) >= MAX_POLE_RADIUS):
        raise ValueError(f"poles must lie inside the unit circle (|p| < {MAX_POLE_RADIUS}), "
                         f"largest |p| = {np.abs(p).max():.6g}")
    if np.any(p.imag < 0):
        raise ValueError("poles must be given once per conjugate pair, with Im(p) >= 0 "
                         "(basis_poles does that)")
    return p


def _check_branches(branches):
    if isinstance(branches, (str, bytes)) or not hasattr(branches, "__len__") or not branches:
        raise TypeError(f"branches must be a non-empty sequence of (function, power) pairs, "
                        f"got {branches!r}")
    out = []
    for i, b in enumerate(branches):
        if isinstance(b, (str, bytes)) or not hasattr(b, "__len__") or len(b) != 2:
            raise TypeError(f"branches[{i}] must be a (function, power) pair, got {b!r}")
        name, power = b
        if name not in BRANCH_FUNCTIONS:
            raise ValueError(f"branches[{i}]: function must be one of "
                             f"{tuple(BRANCH_FUNCTIONS)}, got {name!r}")
        out.append((str(name), check_integer(f"branches[{i}] power", power, minimum=0)))
    if len(set(out)) != len(out):
        raise ValueError(f"branches must not repeat a (function, power) pair, got {out}")
    return tuple(out)


def _check_window(window_samples):
    window = check_positive("window_samples", window_samples)
    if window < 1:
        raise ValueError(f"window_samples must be at least 1 sample, got {window!r}")
    return window


def _record(name, u, n_channels=None, min_length=2):
    u = check_finite_array(name, u, real=True)
    if u.ndim != 2 or u.shape[0] < min_length or u.shape[1] < 1:
        raise ValueError(f"{name} must have shape (N >= {min_length}, n_channels), got "
                         f"{u.shape}")
    if n_channels is not None and u.shape[1] != n_channels:
        raise ValueError(f"{name} must have {n_channels} channels on axis 1, got {u.shape[1]}")
    return u


def _records(name, x, min_length=2):
    """A list of 2-D records from a list of arrays or one array (N, n, ...) (records on the
    trailing axes)."""
    if isinstance(x, (list, tuple)):
        if not x:
            raise ValueError(f"{name} must hold at least one record")
        return [_record(f"{name}[{i}]", xi, min_length=min_length) for i, xi in enumerate(x)]
    x = check_finite_array(name, x, real=True)
    if x.ndim < 2:
        raise ValueError(f"{name} must have shape (N, n_channels, ...) or be a list of "
                         f"(N, n_channels) records, got {x.shape}")
    flat = x.reshape(x.shape[0], x.shape[1], -1)
    return [_record(name, flat[..., i], min_length=min_length) for i in range(flat.shape[2])]


def _pairs(u, y, n_init, names=("u", "y")):
    nu, ny = names
    us, ys = _records(nu, u), _records(ny, y)
    shortest = min(ur.shape[0] for ur in us)
    if shortest < n_init + 3:
        raise ValueError(f"n_init = {n_init} leaves fewer than 3 samples of the shortest record "
                         f"of {nu} ({shortest} samples)")
    if len(us) != len(ys):
        raise ValueError(f"{ny} must hold as many records as {nu} ({len(us)}), got {len(ys)}")
    for i, (ur, yr) in enumerate(zip(us, ys)):
        if yr.shape[0] != ur.shape[0] or ur.shape[1] != us[0].shape[1] \
                or yr.shape[1] != ys[0].shape[1]:
            raise ValueError(f"{ny}: record {i} has shape {yr.shape}, {nu}'s {ur.shape}: every record "
                             f"needs as many samples as its input and the channels of the first")
        if np.any(np.std(yr[n_init:], axis=0) <= 0):
            raise ValueError(f"{ny}: record {i} has a constant output channel")
    return us, ys


# --------------------------------------------------------------------------- building blocks
def basis_poles(models, merge_tolerance=1e-9):
    """The poles of discrete linear models as a basis: one per conjugate pair, duplicates merged.

    Parameters
    ----------
    models : sequence of control.StateSpace
        Discrete, stable models (e.g. linear models fitted at several
        excitation levels).
    merge_tolerance : float, optional
        Poles closer than this (absolute distance in the z-plane) count once.

    Returns
    -------
    ndarray of complex, shape (n_p,)
        Sorted by angle, Im(p) >= 0.

    Examples
    --------
    >>> import control as ct
    >>> a = ct.ss(ct.tf([1.0], [1.0, -1.0, 0.5], 1.0))      # poles 0.5 +- 0.5j
    >>> b = ct.ss(ct.tf([1.0], [1.0, -0.2], 1.0))
    >>> basis_poles([a, b, a]).round(3).tolist()
    [(0.2+0j), (0.5+0.5j)]
    """
    if isinstance(models, ct.StateSpace) or not isinstance(models, (list, tuple)) or not models:
        raise TypeError("models must be a non-empty list of discrete StateSpace models")
    tol = check_nonnegative("merge_tolerance", merge_tolerance)
    found = []
    for i, m in enumerate(models):
        check_type(f"models[{i}]", m, ct.StateSpace, "a discrete StateSpace")
        if not m.isdtime(strict=True):
            raise ValueError(f"models[{i}] must be discrete-time (dt > 0)")
        lam = np.linalg.eigvals(m.A) if m.nstates else np.array([])
        if lam.size and np.abs(lam).max() >= MAX_POLE_RADIUS:
            raise ValueError(f"models[{i}] must be stable (a pole at |p| = "
                             f"{np.abs(lam).max():.6g})")
        for p in lam:
            p = complex(p.real, abs(p.imag)) if abs(p.imag) > 1e-12 else complex(p.real, 0.0)
            if not any(abs(p - q) <= tol for q in found):
                found.append(p)
    if not found:
        raise ValueError("models must have at least one pole (static models give no basis)")
    found = np.array(found)
    return found[np.lexsort((np.abs(found), np.angle(found)))]


def _amplitude_sq(u, window):
    """Mean square over channels, averaged over a window growing to ``window`` then
    sliding exponentially: (N, ...)."""
    m = np.mean(u ** 2, axis=1)
    N = m.shape[0]
    k0 = min(N, int(np.floor(window)))           # 1/(k+1) >= 1/window for k < k0
    out = np.empty_like(m)
    out[:k0] = np.cumsum(m[:k0], axis=0) / np.arange(1, k0 + 1).reshape((-1,) + (1,) * (m.ndim - 1))
    if k0 < N:
        g = 1.0 / window
        zi = ((1 - g) * out[k0 - 1])[None]
        out[k0:] = scipy.signal.lfilter([g], [1.0, -(1 - g)], m[k0:], axis=0, zi=zi)[0]
    return out


def running_rms(u, window_samples):
    """Causal amplitude of an input: the RMS over channels and over the past window.

    a(k)^2 = mean over channels of u^2, averaged over samples 0..k while
    k + 1 <= ``window_samples``, then by an exponential window of that time
    constant: a(k) uses the inputs up to k only.

    Parameters
    ----------
    u : array_like, shape (N, n_u, ...)
        Input samples; axis 0 time, axis 1 channels, further axes records.
    window_samples : float
        Time constant of the window [samples], >= 1.

    Returns
    -------
    ndarray, shape (N, ...)
        [unit of ``u``].

    Examples
    --------
    >>> import numpy as np
    >>> u = np.array([[2.0], [-2.0], [0.0], [0.0]])
    >>> running_rms(u, 2.0).round(4).tolist()            # mean square 4, 4, then halves
    [2.0, 2.0, 1.4142, 1.0]
    """
    u = check_finite_array("u", u, real=True)
    if u.ndim < 2 or u.shape[0] < 1:
        raise ValueError(f"u must have shape (N, n_u, ...), got {u.shape}")
    return np.sqrt(_amplitude_sq(u, _check_window(window_samples)))


def _bank(s, poles):
    """(N, C) signal through every pole's filter z^-1 / (1 - p z^-1), then s itself:
    (N, n_bank C + C) real regressors."""
    cols = []
    for p in poles:
        if p.imag == 0:
            cols.append(scipy.signal.lfilter([0.0, 1.0], [1.0, -p.real], s, axis=0))
        else:
            x = scipy.signal.lfilter([0.0, 1.0], [1.0, -p], s.astype(complex), axis=0)
            cols += [x.real, x.imag]
    cols.append(s)
    return np.concatenate(cols, axis=1)


def _n_bank(poles):
    return int(np.sum(np.where(poles.imag == 0, 1, 2)))


def _regressors(u, poles, branches, window, scale):
    """Regressor matrix of one 2-D record: (N, n_reg), branches in order."""
    a = np.sqrt(_amplitude_sq(u, window)) / scale if any(j for _, j in branches) else None
    filtered, out = {}, []
    for name, j in branches:
        if name not in filtered:
            filtered[name] = _bank(BRANCH_FUNCTIONS[name](u, scale), poles)
        out.append(filtered[name] if j == 0 else filtered[name] * (a ** j)[:, None])
    return np.concatenate(out, axis=1)


def basis_regressors(u, poles, branches, window_samples, input_scale):
    """The regressors of a basis model on one record, each simulated from rest.

    Parameters
    ----------
    u : array_like, shape (N, n_u)
        Input samples [any unit].
    poles : array_like of complex, shape (n_p,)
        Inside the unit circle, one per conjugate pair (Im >= 0), e.g.
        :func:`basis_poles`.
    branches : sequence of (str, int)
        (static function of :data:`BRANCH_FUNCTIONS`, power of the amplitude).
    window_samples : float
        Time constant of the amplitude :func:`running_rms` [samples].
    input_scale : float
        The amplitude's and the static functions' scale [unit of ``u``].

    Returns
    -------
    ndarray, shape (N, n_branches (n_bank + 1) n_u)
        Per branch, per pole (real and imaginary part of a complex one) and
        channel the filtered signal, then the channels themselves;
        n_bank = number of real poles + 2 x number of complex ones.

    Examples
    --------
    >>> import numpy as np
    >>> X = basis_regressors(np.ones((3, 1)), [0.5], [("u", 0)], 10.0, 1.0)
    >>> X.tolist()                                 # filter 1/(z - 0.5) from rest, then u
    [[0.0, 1.0], [1.0, 1.0], [1.5, 1.0]]
    """
    u = _record("u", u)
    return _regressors(u, _check_poles(poles), _check_branches(branches),
                       _check_window(window_samples), check_positive("input_scale", input_scale))


# --------------------------------------------------------------------------- the model
@dataclass(frozen=True)
class BasisModel:
    """A fixed-pole basis model (module docstring): branches, poles, schedule, coefficients.

    Attributes
    ----------
    poles : ndarray of complex, shape (n_p,)
    branches : tuple of (str, int)
    window_samples : float
        Time constant of the amplitude [samples].
    input_scale : float
        [unit of the input].
    theta : ndarray, shape (n_y, n_reg)
        Coefficients of the regressors (:func:`basis_regressors`' columns).
    n_inputs : int
    """

    poles: np.ndarray
    branches: tuple
    window_samples: float
    input_scale: float
    theta: np.ndarray
    n_inputs: int

    def __post_init__(self):
        object.__setattr__(self, "poles", _check_poles(self.poles))
        object.__setattr__(self, "branches", _check_branches(self.branches))
        object.__setattr__(self, "window_samples", _check_window(self.window_samples))
        object.__setattr__(self, "input_scale", check_positive("input_scale", self.input_scale))
        object.__setattr__(self, "n_inputs", check_integer("n_inputs", self.n_inputs, minimum=1))
        theta = check_finite_array("theta", self.theta, ndim=2, real=True)
        if theta.shape[1] != self.n_regressors:
            raise ValueError(f"theta must have {self.n_regressors} columns (the regressors), "
                             f"got {theta.shape}")
        object.__setattr__(self, "theta", theta)

    @property
    def n_regressors(self):
        """Number of regressors (coefficients per output)."""
        return len(self.branches) * (_n_bank(self.poles) + 1) * self.n_inputs

    @property
    def n_outputs(self):
        """Number of outputs."""
        return int(self.theta.shape[0])

    def simulate(self, u):
        """Output from rest, shape (N, n_y, ...), for inputs (N, n_u, ...): each record (the
        trailing axes) on its own."""
        u = check_finite_array("u", u, real=True)
        if u.ndim < 2 or u.shape[1] != self.n_inputs or u.shape[0] < 2:
            raise ValueError(f"u must have shape (N >= 2, {self.n_inputs}, ...), got {u.shape}")
        flat = u.reshape(u.shape[0], u.shape[1], -1)
        y = np.empty((u.shape[0], self.n_outputs, flat.shape[2]))
        block = (_n_bank(self.poles) + 1) * self.n_inputs
        for r in range(flat.shape[2]):
            y[:, :, r] = self._simulate_record(flat[:, :, r], block)
        return y.reshape((u.shape[0], self.n_outputs) + u.shape[2:])

    def _simulate_record(self, u, block):
        """One record: each function's filter bank once, times each power's coefficients,
        then scaled by a^j (the regressor matrix of :func:`basis_regressors` is never formed)."""
        scale = self.input_scale
        a = (np.sqrt(_amplitude_sq(u, self.window_samples)) / scale
             if any(j for _, j in self.branches) else None)
        banks, y = {}, np.zeros((u.shape[0], self.n_outputs))
        for b, (name, j) in enumerate(self.branches):
            if name not in banks:
                banks[name] = _bank(BRANCH_FUNCTIONS[name](u, scale), self.poles)
            part = banks[name] @ self.theta[:, b * block:(b + 1) * block].T
            y += part if j == 0 else part * (a ** j)[:, None]
        return y

    def stepper(self):
        """The model one sample at a time, e.g. inside a feedback loop: :class:`BasisStepper`.

        Its outputs equal :meth:`simulate`'s on the same input from rest (the same
        recursions, the filters' states and the amplitude's window carried from sample to
        sample).

        Examples
        --------
        >>> import numpy as np
        >>> model = BasisModel(np.array([0.9, 0.5 + 0.5j]), (("u", 0), ("u", 1)), 20.0, 1.0,
        ...                    theta=np.ones((1, 2 * (3 + 1))), n_inputs=1)
        >>> u = np.sin(np.arange(50.0))[:, None]
        >>> run = model.stepper()
        >>> bool(np.allclose([run.step(x) for x in u], model.simulate(u), rtol=1e-12))
        True
        """
        return BasisStepper(self)

    def to_arrays(self):
        """The model as a dict of arrays (for ``numpy.savez``; :meth:`from_arrays` reads it)."""
        return {"poles": self.poles, "branch_functions": np.array([b[0] for b in self.branches]),
                "branch_powers": np.array([b[1] for b in self.branches]),
                "window_samples": np.float64(self.window_samples),
                "input_scale": np.float64(self.input_scale), "theta": self.theta,
                "n_inputs": np.int64(self.n_inputs)}

    @classmethod
    def from_arrays(cls, arrays):
        """The model from :meth:`to_arrays`' dict (or an ``numpy.load`` of its file)."""
        branches = tuple((str(f), int(j)) for f, j in zip(arrays["branch_functions"],
                                                          arrays["branch_powers"]))
        return cls(np.asarray(arrays["poles"]), branches, float(arrays["window_samples"]),
                   float(arrays["input_scale"]), np.asarray(arrays["theta"]),
                   int(arrays["n_inputs"]))


class BasisStepper:
    """A :class:`BasisModel` run one sample at a time from rest (:meth:`BasisModel.stepper`).

    Each static function's filter bank keeps its states (one complex state per pole and
    channel), the amplitude its running mean square; :meth:`step` takes u(k) and returns
    y(k), which uses the inputs up to k only.
    """

    def __init__(self, model):
        check_type("model", model, BasisModel, "a BasisModel")
        self.model = model
        self._names = list(dict.fromkeys(name for name, _ in model.branches))
        self._x = {name: np.zeros((model.poles.size, model.n_inputs), complex)
                   for name in self._names}
        self._complex = model.poles.imag != 0
        self._k, self._mean_sq = 0, 0.0
        block = (_n_bank(model.poles) + 1) * model.n_inputs
        self._theta = [model.theta[:, b * block:(b + 1) * block].T
                       for b in range(len(model.branches))]

    def _row(self, x, s):
        """The regressors of one branch at this sample, in :func:`_bank`'s column order."""
        parts = []
        for i, cplx in enumerate(self._complex):
            parts += [x[i].real, x[i].imag] if cplx else [x[i].real]
        parts.append(s)
        return np.concatenate(parts)

    def step(self, u):
        """Output y(k) [unit of the model's outputs] for the input u(k), shape (n_inputs,)."""
        m = self.model
        u = check_finite_array("u", u, shape=(m.n_inputs,), real=True)
        scale, window = m.input_scale, m.window_samples
        # the amplitude of _amplitude_sq: a growing mean, then an exponential window
        ms = float(np.mean(u ** 2))
        k0 = int(np.floor(window))
        if self._k < k0:
            self._mean_sq = (self._mean_sq * self._k + ms) / (self._k + 1)
        else:
            g = 1.0 / window
            self._mean_sq = g * ms + (1 - g) * self._mean_sq
        a = np.sqrt(self._mean_sq) / scale
        rows, signals = {}, {}
        for name in self._names:
            signals[name] = BRANCH_FUNCTIONS[name](u, scale)
            rows[name] = self._row(self._x[name], signals[name])
        y = np.zeros(m.n_outputs)
        for (name, j), theta in zip(m.branches, self._theta):
            part = rows[name] @ theta
            y += part if j == 0 else part * a ** j
        for name in self._names:              # x(k + 1) = p x(k) + phi(u(k))
            self._x[name] = m.poles[:, None] * self._x[name] + signals[name][None, :]
        self._k += 1
        return y


# --------------------------------------------------------------------------- fitting
def _gram(X):
    """X^T X by a symmetric rank-k update (half the flops of X.T @ X)."""
    G = scipy.linalg.blas.dsyrk(1.0, np.asfortranarray(X.T), trans=0, lower=0)
    return np.triu(G) + np.triu(G, 1).T


class _Normal:
    """Normal equations of every output, weighted per record and output by 1/var(y)."""

    def __init__(self):
        self.A = self.b = None
        self.count = 0

    def add(self, X, Y):
        w = 1.0 / np.var(Y, axis=0)                                    # (n_y,)
        G, XtY = _gram(X), X.T @ Y
        if self.A is None:
            self.A = np.zeros((Y.shape[1],) + G.shape)
            self.b = np.zeros((Y.shape[1], G.shape[0]))
        for o in range(Y.shape[1]):
            self.A[o] += w[o] * G
            self.b[o] += w[o] * XtY[:, o]
        self.count += 1

    def solve(self, ridge, columns=None):
        n_y = self.A.shape[0]
        idx = np.arange(self.A.shape[1]) if columns is None else columns
        theta = np.zeros((n_y, idx.size))
        for o in range(n_y):
            A = self.A[o][np.ix_(idx, idx)]
            d = np.sqrt(np.diag(A))
            d = np.where(d > 0, d, 1.0)
            An = A / d[:, None] / d[None, :]
            rhs = self.b[o][idx] / d
            try:
                t = scipy.linalg.solve(An + ridge * np.eye(idx.size), rhs, assume_a="pos")
            except (np.linalg.LinAlgError, scipy.linalg.LinAlgError):
                t = np.linalg.lstsq(An + ridge * np.eye(idx.size), rhs, rcond=None)[0]
            theta[o] = t / d
        return theta


def fit_basis_model(u, y, poles, branches, window_samples, input_scale, *, n_init=0,
                    ridge=1e-9):
    """Least-squares coefficients of a basis model on records simulated from rest.

    Parameters
    ----------
    u : list of array_like (N_r, n_u), or array_like (N, n_u, ...)
        Input records (a list may mix lengths; an array holds records on its
        trailing axes).
    y : like ``u``, with n_y channels
        Measured outputs of the same records.
    poles : array_like of complex, shape (n_p,)
        :func:`basis_poles`.
    branches : sequence of (str, int)
        (static function of :data:`BRANCH_FUNCTIONS`, power of the amplitude).
    window_samples : float
        Time constant of the amplitude [samples].
    input_scale : float
        [unit of ``u``] (e.g. the inputs' RMS).
    n_init : int, optional
        Samples dropped at the start of every record (the metric's transient).
    ridge : float, optional
        Ridge on the normal equations scaled to unit diagonal (>= 0).

    Returns
    -------
    BasisModel
        Minimising sum over records and outputs of
        sum_k (y_model - y)^2 / var(y) over samples k >= n_init.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(1)
    >>> u = rng.standard_normal((400, 1))
    >>> y = np.convolve(u[:, 0], 0.8 ** np.arange(60))[:400, None]   # 1/(1 - 0.8 z^-1)
    >>> model = fit_basis_model([u], [y], [0.8], [("u", 0)], 20.0, 1.0)
    >>> model.theta.round(6).tolist()                 # 0.8 x (the filter's state) + u
    [[0.8, 1.0]]
    """
    n_init = check_integer("n_init", n_init, minimum=0)
    us, ys = _pairs(u, y, n_init)
    poles, branches = _check_poles(poles), _check_branches(branches)
    window = _check_window(window_samples)
    scale = check_positive("input_scale", input_scale)
    ridge = check_nonnegative("ridge", ridge)
    normal = _Normal()
    for ur, yr in zip(us, ys):
        normal.add(_regressors(ur, poles, branches, window, scale)[n_init:], yr[n_init:])
    return BasisModel(poles, branches, window, scale, normal.solve(ridge), us[0].shape[1])


@dataclass(frozen=True)
class BasisSelection:
    """Result of :func:`select_basis_model`.

    Attributes
    ----------
    candidates : tuple of tuple
        The candidate branch sets.
    windows_samples : tuple of float
        The candidate windows [samples].
    validation_nrmse : ndarray, shape (n_windows, n_candidates, n_val_records)
        NRMSE (fraction, averaged over outputs) of each candidate on each
        validation record.
    fit_nrmse : ndarray, shape (n_windows, n_candidates)
        The same averaged over the fitting records.
    branches : tuple
        The chosen branch set.
    window_samples : float
        The chosen window.
    model : BasisModel
        The chosen candidate (fitted on the fitting records).
    """

    candidates: tuple
    windows_samples: tuple
    validation_nrmse: np.ndarray
    fit_nrmse: np.ndarray
    branches: tuple
    window_samples: float
    model: BasisModel

    @property
    def mean_validation_nrmse(self):
        """Validation NRMSE averaged over the records, (n_windows, n_candidates)."""
        return self.validation_nrmse.mean(axis=2)


def _nrmse(y_model, y, n_init):
    e = y_model[n_init:] - y[n_init:]
    return float(np.mean(np.sqrt(np.mean(e ** 2, axis=0)) / np.std(y[n_init:], axis=0)))


def select_basis_model(u_fit, y_fit, u_validation, y_validation, poles, candidates,
                       windows_samples, input_scale, *, n_init=0, ridge=1e-9):
    """Branches and window of a basis model chosen by the NRMSE on held-out records.

    Every candidate branch set is fitted (:func:`fit_basis_model`) on the
    fitting records at every window, from one accumulation of the normal
    equations of all candidates' branches per window, and simulated from rest
    on the validation records; the pair with the smallest mean validation
    NRMSE wins (a window only matters to branches with a power > 0).

    Parameters
    ----------
    u_fit, y_fit : records as in :func:`fit_basis_model`
    u_validation, y_validation : records
        Held-out records of the same channels.
    poles : array_like of complex
    candidates : sequence of branch sets
        Each a sequence of (str, int) as in :func:`fit_basis_model`.
    windows_samples : sequence of float
        Candidate time constants of the amplitude [samples].
    input_scale : float
    n_init : int, optional
    ridge : float, optional

    Returns
    -------
    BasisSelection

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(2)
    >>> u = [rng.standard_normal((300, 1)) for _ in range(3)]
    >>> y = [np.convolve(x[:, 0] + 0.3 * x[:, 0] * abs(x[:, 0]), 0.5 ** np.arange(40))[:300, None]
    ...      + 1e-3 * rng.standard_normal((300, 1)) for x in u]
    >>> sel = select_basis_model(u[:2], y[:2], u[2:], y[2:], [0.5],
    ...                          [[("u", 0)], [("u", 0), ("u|u|", 0)]], [10.0], 1.0)
    >>> sel.branches                                   # the static term is needed
    (('u', 0), ('u|u|', 0))
    """
    n_init = check_integer("n_init", n_init, minimum=0)
    us, ys = _pairs(u_fit, y_fit, n_init, ("u_fit", "y_fit"))
    uv, yv = _pairs(u_validation, y_validation, n_init, ("u_validation", "y_validation"))
    if uv[0].shape[1] != us[0].shape[1] or yv[0].shape[1] != ys[0].shape[1]:
        raise ValueError("u_validation, y_validation must have the channels of u_fit, y_fit")
    poles = _check_poles(poles)
    if isinstance(candidates, (str, bytes)) or not hasattr(candidates, "__len__") \
            or not candidates:
        raise TypeError("candidates must be a non-empty sequence of branch sets")
    cands = []
    for i, c in enumerate(candidates):
        try:
            cands.append(_check_branches(c))
        except (ValueError, TypeError) as exc:
            raise type(exc)(f"candidates[{i}]: {exc}") from None
    windows = check_finite_array("windows_samples", windows_samples, ndim=1, min_length=1,
                                 real=True)
    for i, w in enumerate(windows):
        if not w >= 1:
            raise ValueError(f"windows_samples[{i}] must be at least 1 sample, got {w!r}")
    windows = tuple(float(w) for w in windows)
    scale = check_positive("input_scale", input_scale)
    ridge = check_nonnegative("ridge", ridge)
    union = tuple(dict.fromkeys(b for c in cands for b in c))
    block = (_n_bank(poles) + 1) * us[0].shape[1]
    cols = [np.concatenate([np.arange(union.index(b) * block, (union.index(b) + 1) * block)
                            for b in c]) for c in cands]
    val = np.zeros((len(windows), len(cands), len(uv)))
    fit = np.zeros((len(windows), len(cands)))
    thetas = {}
    for w, window in enumerate(windows):
        normal = _Normal()
        for ur, yr in zip(us, ys):
            normal.add(_regressors(ur, poles, union, window, scale)[n_init:], yr[n_init:])
        th = [normal.solve(ridge, c) for c in cols]
        thetas[w] = th
        for ur, yr in zip(us, ys):
            X = _regressors(ur, poles, union, window, scale)
            fit[w] += [_nrmse(X[:, c] @ t.T, yr, n_init) / len(us) for c, t in zip(cols, th)]
        for r, (ur, yr) in enumerate(zip(uv, yv)):
            X = _regressors(ur, poles, union, window, scale)
            val[w, :, r] = [_nrmse(X[:, c] @ t.T, yr, n_init) for c, t in zip(cols, th)]
    w, c = np.unravel_index(int(np.argmin(val.mean(axis=2))), val.shape[:2])
    model = BasisModel(poles, cands[c], windows[w], scale, thetas[w][c], us[0].shape[1])
    return BasisSelection(candidates=tuple(cands), windows_samples=windows,
                          validation_nrmse=val, fit_nrmse=fit, branches=cands[c],
                          window_samples=windows[w], model=model)
