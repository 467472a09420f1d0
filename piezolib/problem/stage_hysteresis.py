"""The hysteresis "truth" of the virtual stage: Prandtl-Ishlinskii play operators.

:class:`PlayHysteresis` is the operator the stage applies to the actuator
voltage, :class:`HysteresisLaw` the two-parameter family it is chosen from,
:data:`CALIBRATED_HYSTERESIS` the law calibrated on Table 4 Case I only.
Calibrating runs the stage, so :func:`piezolib.problem.stage_calibration.calibrate_hysteresis`
lives above the stage, which imports this module (never the other way).

Operator definition and calibration rule: ``docs/stage.md``.
"""

from dataclasses import dataclass

import numpy as np

from piezolib._checks import check_finite_array, check_integer, check_positive, check_same_length

__all__ = ["PlayHysteresis", "HysteresisLaw", "CALIBRATED_HYSTERESIS"]


# --- hysteresis truth: Prandtl-Ishlinskii play operators ----------------------
@dataclass(frozen=True)
class PlayHysteresis:
    """Prandtl-Ishlinskii operator H[v] = w0 v + sum_i w_i (F_{r_i}[v] - r_i).

    F_r is the play (backlash) operator of threshold r:
    y_k = min(max(y_{k-1}, v_k - r), v_k + r).  Subtracting r_i makes H
    return to 0 whenever v comes back down to 0 from above.

    Attributes
    ----------
    thresholds_V : tuple of float
        Play thresholds r_i [V of v_a], positive and increasing.
    weights : tuple of float
        Play weights w_i >= 0 (dimensionless).
    linear_weight : float
        w0, the slope right after a reversal: the small-signal gain.
    """

    thresholds_V: tuple
    weights: tuple
    linear_weight: float = 1.0

    def __post_init__(self):
        r = check_finite_array("thresholds_V", self.thresholds_V, ndim=1, min_length=1)
        w = check_finite_array("weights", self.weights, ndim=1)
        check_same_length(thresholds_V=r, weights=w)
        if r[0] <= 0 or np.any(np.diff(r) <= 0):
            raise ValueError("thresholds_V must be positive and strictly increasing")
        if np.any(w < 0):
            raise ValueError("weights must be non-negative")
        check_positive("linear_weight", self.linear_weight)
        object.__setattr__(self, "thresholds_V", tuple(float(x) for x in r))
        object.__setattr__(self, "weights", tuple(float(x) for x in w))
        object.__setattr__(self, "linear_weight", float(self.linear_weight))

    def initial_state(self, v0=0.0):
        """Play outputs on the descending branch at v0 (as if lowered to v0)."""
        return tuple(v0 + r for r in self.thresholds_V)

    def apply(self, v, state=None):
        """Evaluate H on a sampled input, one monotone stroke at a time.

        Within a stroke in which v does not decrease, every play output is
        max(y_start, v_k - r) (and min(y_start, v_k + r) when v does not
        increase), so each stroke is one numpy operation over samples and
        plays.  The arithmetic is the same as the sample-by-sample recursion
        of :class:`StageSimulation`, so both give identical floats.

        Parameters
        ----------
        v : array_like
            Input samples [V], 1-D.
        state : sequence of float, optional
            Play outputs before the first sample; default
            :meth:`initial_state` at 0 V (at rest).

        Returns
        -------
        v_h : ndarray
            Operator output [V], same length as ``v``.
        state : tuple of float
            Play outputs after the last sample.
        """
        v = check_finite_array("v", v, ndim=1, min_length=1)
        r = np.asarray(self.thresholds_V)
        y = np.asarray(self.initial_state(0.0) if state is None else state, dtype=float)
        if y.shape != r.shape:
            raise ValueError(f"state must hold {len(r)} play outputs, got {y.shape}")
        Y = np.empty((len(v), len(r)))
        Y[0] = y = np.minimum(np.maximum(y, v[0] - r), v[0] + r)
        # direction of each later sample; a repeated value changes nothing,
        # so it joins the stroke it is in
        d = np.sign(np.diff(v))
        idx = np.maximum.accumulate(np.where(d != 0, np.arange(len(d)), 0))
        d = d[idx]
        d[d == 0] = 1
        bounds = np.concatenate(([1], np.flatnonzero(np.diff(d)) + 2, [len(v)]))
        for a, b in zip(bounds[:-1], bounds[1:]):
            if b <= a:
                continue
            seg = v[a:b, None]
            if d[a - 1] > 0:
                Y[a:b] = np.maximum(y, seg - r)
            else:
                Y[a:b] = np.minimum(y, seg + r)
            y = Y[b - 1]
        out = self.linear_weight * v
        for i, (ri, wi) in enumerate(zip(self.thresholds_V, self.weights)):
            out = out + wi * (Y[:, i] - ri)
        return out, tuple(float(x) for x in y)

    def chord_gain(self, stroke_V):
        """Gain (H change)/(v change) of a monotone stroke of ``stroke_V``
        volts that starts at a reversal of a periodic loop (or from rest):
        w0 + sum_i w_i max(0, 1 - 2 r_i / stroke)."""
        stroke_V = check_positive("stroke_V", stroke_V)
        r = np.asarray(self.thresholds_V)
        return float(self.linear_weight
                     + np.sum(np.asarray(self.weights) * np.maximum(0.0, 1 - 2 * r / stroke_V)))


@dataclass(frozen=True)
class HysteresisLaw:
    """Two-parameter family of :class:`PlayHysteresis` operators.

    Thresholds r_i = r_1 q^(i-1), i = 1..n, and weights
    w_i = c (r_i - r_{i-1}) exp(-r_i / rho) with r_0 = 0: a play density
    that decays exponentially with the threshold.  w0 = 1 (small-signal gain
    1).  Only ``density_per_V`` (c) and ``decay_V`` (rho) are calibrated.
    """

    density_per_V: float
    decay_V: float
    first_threshold_V: float = 1.0
    threshold_ratio: float = 1.25
    count: int = 20

    def __post_init__(self):
        check_positive("density_per_V", self.density_per_V)
        check_positive("decay_V", self.decay_V)
        check_positive("first_threshold_V", self.first_threshold_V)
        if not self.threshold_ratio > 1:
            raise ValueError(f"threshold_ratio must exceed 1, got {self.threshold_ratio}")
        check_integer("count", self.count, minimum=1)

    def operator(self):
        """The :class:`PlayHysteresis` operator of this law."""
        r = self.first_threshold_V * self.threshold_ratio ** np.arange(self.count)
        cell = np.diff(np.concatenate(([0.0], r)))
        w = self.density_per_V * cell * np.exp(-r / self.decay_V)
        return PlayHysteresis(tuple(r), tuple(w), 1.0)


#: Calibrated on Table 4 Case I only; re-derive with
#: :func:`piezolib.problem.stage_calibration.calibrate_hysteresis`.
CALIBRATED_HYSTERESIS = HysteresisLaw(density_per_V=0.0553682, decay_V=20.9598)
