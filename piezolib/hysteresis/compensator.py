"""Dahl feedforward compensator (eq. 14, inverse-free), sample by sample for a real-time loop.

u_f = (x_r - x0 + H(x_r)) / g_a with H of :mod:`piezolib.hysteresis.dahl`
driven by the desired displacement x_r; fed to the voltage-driven model it
gives x = x_r exactly.  The same on a whole record is
:func:`piezolib.hysteresis.dahl.feedforward` (the model's own inverse, so it
lives with the model and this module imports it, never the other way).
Equations: ``docs/hysteresis.md``.
"""

import math

import numpy as np

from piezolib._checks import check_finite_array
from piezolib.hysteresis.dahl import StrokeDynamics, check_dahl_model, initial_state_of

__all__ = ["DahlFeedforward"]


class DahlFeedforward:
    """Stateful, sample-by-sample Dahl feedforward (eq. 14) for a 10 kHz loop.

    Each :meth:`step` costs a few dozen floating-point operations on Python
    floats (closed-form 2x2 matrix exponential), and the sequence of steps
    equals :func:`~piezolib.hysteresis.dahl.feedforward` on the whole record
    to rounding.

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
    >>> from piezolib.hysteresis import DahlModel
    >>> ff = DahlFeedforward(DahlModel(2.0, 1.0, 0.0, 0.1, 1.0, 0.9))
    >>> [round(ff.step(r), 4) for r in (0.0, 0.1, 0.2)]
    [0.0, 0.1116, 0.2242]
    """

    def __init__(self, model, z0=None, direction0=None):
        self.model = check_dahl_model(model)
        z_init, self._s_init = initial_state_of(model, z0, direction0)
        self._z_init = tuple(float(v) for v in z_init)
        dyn = StrokeDynamics(model)
        self._m = dyn.m
        self._disc = dyn.disc
        self._root = dyn.q
        self._slow, self._fast = dyn.slow, dyn.fast
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
        # float('1') would take text (and a complex reference loses its imaginary part);
        # checked cheaply: step runs once per sample
        if isinstance(x_r, (str, bytes, complex, bool)):
            raise TypeError(f"x_r must be a real number, got {x_r!r}")
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
        """Scalar version of :meth:`~piezolib.hysteresis.dahl.StrokeDynamics.parts`."""
        m, q = self._m, self._root
        if self._disc < 0:
            em = math.exp(m * sigma)
            y = q * sigma
            return em * math.cos(y), em * (math.sin(y) / q if y > 1e-8 else sigma)
        y = q * sigma
        ep, en = math.exp(self._slow * sigma), math.exp(self._fast * sigma)
        if y < 1e-3:
            return 0.5 * (ep + en), math.exp(m * sigma) * sigma * (1 + y * y / 6 + y ** 4 / 120)
        return 0.5 * (ep + en), (ep - en) / (2 * q)

    def run(self, x_r):
        """Feed a whole record sample by sample (continuing from the current state)."""
        x_r = check_finite_array("x_r", x_r, ndim=1)
        return np.array([self.step(v) for v in x_r])
