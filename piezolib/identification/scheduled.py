"""Amplitude-scheduled models: linear models blended by the input's measured level.

A system whose linear behaviour changes with the excitation level (a piezo's
stiffness and gain move with the drive amplitude) is described by linear
models identified at a few levels s_1 < ... < s_L.  The scheduled model
computes the schedule variable of a record from its input signal - the RMS
over time and channels - and blends the outputs of the two neighbouring
models linearly in it: y = (1 - a) y_l + a y_{l+1}, a = (s - s_l) / (s_{l+1} -
s_l), clamped to the end models outside [s_1, s_L].  Each record (axes 2 and
beyond of the input) gets its own schedule value; within a record the model
is linear time-invariant.  It is not linear in the amplitude: scaling the
input moves the schedule.

Examples
--------
Two gains (one fast pole each, D the gain) at levels 1 and 3; a record of RMS 2
gets the mean gain:

>>> import control as ct, numpy as np
>>> gain = lambda k: ct.ss([[0.0]], [[0.0]], [[0.0]], [[k]], 1.0)
>>> m = ScheduledModel((gain(1.0), gain(3.0)), (1.0, 3.0))
>>> u = np.array([[2.0], [-2.0], [2.0], [-2.0]])
>>> float(m.schedule(u)), m.simulate(u)[:2, 0].tolist()
(2.0, [4.0, -4.0])
"""

from dataclasses import dataclass

import control as ct
import numpy as np

from piezolib._checks import check_finite_array, check_type
from piezolib.identification.freqfit import simulate_discrete

__all__ = ["ScheduledModel", "input_rms"]


def input_rms(u):
    """Schedule variable of each record: RMS of the input over time and channels.

    Parameters
    ----------
    u : array_like, shape (N, n_u, ...)

    Returns
    -------
    ndarray, shape u.shape[2:]
        [unit of ``u``].
    """
    u = check_finite_array("u", u, real=True)
    if u.ndim < 2:
        raise ValueError(f"u must have shape (N, n_u, ...), got {u.shape}")
    return np.sqrt(np.mean(u ** 2, axis=(0, 1)))


@dataclass(frozen=True)
class ScheduledModel:
    """Discrete linear models at increasing schedule levels, blended by the input's RMS.

    Parameters
    ----------
    models : sequence of control.StateSpace
        Discrete models with one sample time and one signal shape.
    levels : sequence of float
        Schedule value (input RMS) of each model, strictly increasing [unit
        of the input].
    """

    models: tuple
    levels: tuple

    def __post_init__(self):
        models = tuple(self.models) if isinstance(self.models, (list, tuple)) else None
        if not models:
            raise ValueError("models must be a non-empty sequence of discrete StateSpace")
        for i, m in enumerate(models):
            check_type(f"models[{i}]", m, ct.StateSpace, "a discrete StateSpace")
            if not m.isdtime(strict=True) or m.dt != models[0].dt:
                raise ValueError(f"models[{i}] must be discrete with dt = {models[0].dt}")
            if (m.ninputs, m.noutputs) != (models[0].ninputs, models[0].noutputs):
                raise ValueError(f"models[{i}] must have the inputs and outputs of models[0]")
        levels = check_finite_array("levels", self.levels, ndim=1, min_length=1, real=True)
        if levels.size != len(models) or np.any(np.diff(levels) <= 0) or levels[0] < 0:
            raise ValueError(f"levels must be {len(models)} non-negative, strictly increasing "
                             f"values, got {levels}")
        object.__setattr__(self, "models", models)
        object.__setattr__(self, "levels", tuple(float(x) for x in levels))

    def schedule(self, u):
        """Schedule value of each record (:func:`input_rms`)."""
        return input_rms(u)

    def blend_weights(self, u):
        """Weight of each model per record, shape (L, ...): two neighbours, summing to 1."""
        s = self.schedule(u)
        lv = np.asarray(self.levels)
        eye = np.eye(lv.size)
        return np.stack([np.interp(s, lv, eye[i]) for i in range(lv.size)])

    def simulate(self, u):
        """Output, shape (N, n_y, ...), for inputs (N, n_u, ...), each record from rest."""
        u = check_finite_array("u", u, real=True)
        if u.ndim < 2 or u.shape[1] != self.models[0].ninputs:
            raise ValueError(f"u must have shape (N, {self.models[0].ninputs}, ...), got "
                             f"{u.shape}")
        a = self.blend_weights(u)
        y = np.zeros((u.shape[0], self.models[0].noutputs) + u.shape[2:])
        for i, m in enumerate(self.models):
            if np.any(a[i] > 0):
                y += a[i][None, None] * simulate_discrete(m, u)
        return y
