"""Raw records of a stage whose hysteresis comes from a family no fit here has: Bouc-Wen, a
Preisach operator with a smooth density, a Duhem model; and the best error a fit can reach.

The virtual stage's hysteresis is a sum of plays, the structure of every
Prandtl-Ishlinskii-type model the library fits, so a fit to its records
proves little about a real stage.  The records here have the form of a real
raw record (rest with an output offset, a step to -87 V that rings a lightly
damped resonance for about 12 ms, then a +-150 V sine at 1 Hz for 6.7
periods, V in and um out, white sensor noise of 0.1 % of the stroke) and a
hysteresis of about 15 % from a model of another family:

=========  ==============================================================
family     hysteresis operator h[v] [um] (rate independent, exact per stroke)
=========  ==============================================================
bouc_wen   k (v - z), dz = A dv - beta |dv| z - gamma dv |z| (n = 1,
           closed form along each stroke)
preisach   w_lin v + sum of relays on a 90-level grid, density
           exp(-r / r0) exp(-(c - c0)^2 / 2 s^2) in half-width r and centre c
           (asymmetric loops: not a sum of plays)
duhem      Coleman-Hodgdon dz/dv = alpha sgn(dv) (f(v) - z) + g, f(v) = a v +
           b tanh(v / v_s) (integrated on a 0.05 V grid along each stroke)
=========  ==============================================================

Each starts in the state a decaying alternation 150, -135, 120, ... -> 0 V
leaves (the stage's unrecorded history), then x = x_offset + G[h[v]] +
noise, with G a resonance of unit DC gain (1.2 kHz, damping 0.06, ZOH at the
record's rate).  :func:`best_achievable` states the error no fit of the
record can be expected to beat: the noise floor, and a fit of a finely
discretised Preisach operator (ramped relays on a 16 x 16 grid of half-widths
and centres, a Krasnosel'skii-Pokrovskii discretisation: smooth loops of any
shape, symmetric or not) through the true dynamics.
"""

import math
from dataclasses import dataclass

import control as ct
import numpy as np
import scipy.optimize as opt
import scipy.signal as sg

from piezolib import records
from piezolib._checks import check_integer, check_positive, check_real, check_type
from piezolib.hysteresis.dahl import strokes
from piezolib.hysteresis.pi import play_outputs
from piezolib.hysteresis.select import split_record
from piezolib.identification.continuous import zoh_coefficients

__all__ = ["FAMILIES", "MIN_SAMPLES", "MAX_SAMPLES", "MAX_REGRESSOR_ENTRIES", "BoucWen",
           "SmoothPreisach", "Duhem", "foreign_operator", "RawForeignRecord",
           "foreign_raw_record", "BestAchievable", "best_achievable"]

FAMILIES = ("bouc_wen", "preisach", "duhem")

#: Fewest and most samples of a raw record (:func:`foreign_raw_record`; the most is 200 s
#: at 5 kHz).
MIN_SAMPLES, MAX_SAMPLES = 100, 2_000_000

#: Most entries (samples x columns) of the regressor of :func:`best_achievable` (240 MB of
#: float64, held three times: the default 16 levels on a 7.2 s record at 5 kHz is 5.5e6).
MAX_REGRESSOR_ENTRIES = 30_000_000

#: Resonance of the generating dynamics: natural frequency [Hz] and damping ratio.
RESONANCE = (1200.0, 0.06)

# the unrecorded history every operator starts from: a decaying alternation to 0 V
_HISTORY_V = np.r_[150.0 * (-0.9) ** np.arange(30), 0.0]


def _path_with_history(v):
    return np.r_[_HISTORY_V, v]


@dataclass(frozen=True)
class BoucWen:
    """Bouc-Wen operator (n = 1): h = k (v - z), dz = A dv - beta |dv| z - gamma dv |z|.

    Along a stroke of direction s and path length sigma, w = s z obeys
    dw/dsigma = A - beta w - gamma |w|: linear on each side of w = 0, solved in
    closed form.

    Examples
    --------
    >>> h = BoucWen().simulate(np.r_[np.linspace(0, 150, 40), np.linspace(150, -150, 80)])
    >>> bool(np.all(np.isfinite(h))), round(float(np.ptp(h)), 1)
    (True, 33.9)
    """

    k: float = 0.13
    A: float = 0.40
    beta: float = 0.016
    gamma: float = 0.004

    def _stroke(self, w0, sigma):
        A, b, g = self.A, self.beta, self.gamma
        w = np.empty_like(sigma)
        if w0 < 0:            # rising towards 0 with rate A - (b - g) w
            k1 = b - g
            wf = A / k1
            s_zero = math.log((wf - w0) / wf) / k1
        else:
            s_zero = 0.0
        first = sigma < s_zero
        if w0 < 0:
            w[first] = wf + (w0 - wf) * np.exp(-k1 * sigma[first])
        k2 = b + g
        w_inf = A / k2
        start = 0.0 if w0 < 0 else w0
        w[~first] = w_inf + (start - w_inf) * np.exp(-k2 * (sigma[~first] - s_zero))
        return w

    def simulate(self, v):
        """h[v] [um] for the input ``v`` [V], after the history of the module docstring."""
        path = _path_with_history(np.asarray(v, dtype=float))
        z = np.zeros(path.size)
        for start, stop, s in strokes(path):
            sigma = s * (path[start + 1:stop + 1] - path[start])
            z[start + 1:stop + 1] = s * self._stroke(s * z[start], sigma)
        return (self.k * (path - z))[_HISTORY_V.size:]


@dataclass(frozen=True)
class SmoothPreisach:
    """Preisach operator: a linear part and relays of a smooth density on a fine grid.

    Relay (alpha, beta), alpha >= beta, on a ``levels``-level grid over
    [-v_max, v_max]; its weight exp(-r / r0) exp(-(c - c0)^2 / (2 s^2)) with
    half-width r = (alpha - beta) / 2 and centre c = (alpha + beta) / 2,
    scaled so that the relays give ``relay_share`` of the slope.  A density
    that depends on c is not a sum of plays (those depend on r only).

    Examples
    --------
    >>> h = SmoothPreisach().simulate(np.r_[np.linspace(0, 150, 40), np.linspace(150, -150, 80)])
    >>> round(float(np.ptp(h)), 1)
    37.7
    """

    slope: float = 0.127
    relay_share: float = 0.5
    v_max: float = 160.0
    r0: float = 50.0
    c0: float = 10.0
    s: float = 200.0
    levels: int = 90

    def relays(self):
        """(alpha, beta, weight) of every relay [V, V, um per relay step]."""
        grid = np.linspace(-self.v_max, self.v_max, self.levels)
        a, b = np.meshgrid(grid, grid, indexing="ij")
        keep = a >= b
        a, b = a[keep], b[keep]
        r, c = (a - b) / 2, (a + b) / 2
        mu = np.exp(-r / self.r0) * np.exp(-(c - self.c0) ** 2 / (2 * self.s ** 2))
        # a relay steps by 2 w: the relays' slope, summed over a full stroke, is relay_share
        mu *= self.relay_share * self.slope * 2 * self.v_max / (2 * mu.sum())
        return a, b, mu

    def simulate(self, v):
        """h[v] [um] for the input ``v`` [V], after the history of the module docstring."""
        path = _path_with_history(np.asarray(v, dtype=float))
        a, b, mu = self.relays()
        state = np.where(a + b < 0, 1.0, -1.0)        # before the history: demagnetised
        out = np.empty(path.size)
        out[0] = mu @ state
        for start, stop, s in strokes(path):
            seg = path[start + 1:stop + 1]
            if s > 0:
                free = np.flatnonzero(state < 0)
                order = free[np.argsort(a[free])]
                gain = np.r_[0.0, np.cumsum(2 * mu[order])]
                out[start + 1:stop + 1] = out[start] + gain[
                    np.searchsorted(a[order], seg, side="right")]
                state[order[a[order] <= seg[-1]]] = 1.0
            else:
                free = np.flatnonzero(state > 0)
                order = free[np.argsort(-b[free])]
                gain = np.r_[0.0, np.cumsum(2 * mu[order])]
                out[start + 1:stop + 1] = out[start] - gain[
                    np.searchsorted(-b[order], -seg, side="right")]
                state[order[b[order] >= seg[-1]]] = -1.0
        h = self.slope * (1 - self.relay_share) * path + out
        return h[_HISTORY_V.size:]


@dataclass(frozen=True)
class Duhem:
    """Coleman-Hodgdon (Duhem) operator dz/dv = alpha sgn(dv) (f(v) - z) + g.

    f(v) = a v + b tanh(v / v_s) with b < 0: the branches steepen at large |v|.  Along each
    stroke the linear ODE in v is solved with its integrating factor on a
    0.05 V grid (exact for f linear between grid points).

    Examples
    --------
    >>> h = Duhem().simulate(np.r_[np.linspace(0, 150, 40), np.linspace(150, -150, 80)])
    >>> round(float(np.ptp(h)), 1)
    31.9
    """

    alpha: float = 0.025
    a: float = 0.14
    b: float = -3.0
    v_s: float = 100.0
    g: float = 0.07
    grid_V: float = 0.05

    def _f(self, v):
        return self.a * v + self.b * np.tanh(v / self.v_s)

    def simulate(self, v):
        """h[v] [um] for the input ``v`` [V], after the history of the module docstring."""
        path = _path_with_history(np.asarray(v, dtype=float))
        z = np.empty(path.size)
        z[0] = self._f(path[0])
        for start, stop, s in strokes(path):
            v0, v1 = path[start], path[stop]
            n = max(2, int(math.ceil(abs(v1 - v0) / self.grid_V)) + 1)
            u = np.linspace(v0, v1, n)
            # d/du (e^{alpha s (u - v0)} z) = e^{alpha s (u - v0)} (alpha s f(u) + g)
            e = np.exp(self.alpha * s * (u - v0))
            rate = e * (self.alpha * s * self._f(u) + self.g)
            integral = np.r_[0.0, np.cumsum((rate[1:] + rate[:-1]) / 2 * np.diff(u))]
            zu = (z[start] + integral) / e
            seg = path[start + 1:stop + 1]
            z[start + 1:stop + 1] = np.interp(s * seg, s * u, zu)
        return z[_HISTORY_V.size:]


def foreign_operator(family):
    """The hysteresis operator of one family with the defaults above.

    Examples
    --------
    >>> type(foreign_operator("duhem")).__name__
    'Duhem'
    """
    ops = {"bouc_wen": BoucWen, "preisach": SmoothPreisach, "duhem": Duhem}
    if not isinstance(family, str) or family not in ops:
        raise ValueError(f"family must be one of {FAMILIES}, got {family!r}")
    return ops[family]()


def resonance_dynamics(fs):
    """(b, a) of the unit-DC-gain resonance of :data:`RESONANCE`, ZOH at ``fs`` [Hz]."""
    f_n, zeta = RESONANCE
    w = 2 * math.pi * f_n
    b, a = zoh_coefficients(ct.tf([w * w], [1, 2 * zeta * w, w * w]), 1.0 / fs)
    return b / (b.sum() / a.sum()), a


@dataclass(frozen=True)
class RawForeignRecord:
    """A raw record of a stage with foreign hysteresis, and what made it.

    Attributes
    ----------
    record : piezolib.records.Record
        Input [V] and measured displacement [um] at ``fs``.
    family : str
    x_true : ndarray
        The noise-free displacement [um].
    noise_rms : float
        Sensor noise RMS [um].
    b, a : ndarray
        The generating dynamics (unit DC gain) at ``fs``.
    operator : object
        The hysteresis operator (``simulate(v)``).
    x_offset : float
        Output offset [um].
    """

    record: object
    family: str
    x_true: np.ndarray
    noise_rms: float
    b: np.ndarray
    a: np.ndarray
    operator: object
    x_offset: float

    def plant(self, v):
        """The noise-free stage: displacement [um] for any input ``v`` [V] from its history."""
        h = self.operator.simulate(v)
        return self.x_offset + h[0] + sg.lfilter(self.b, self.a, h - h[0])

    @property
    def noise_floor_percent(self):
        """Noise RMS [% of the measured stroke]."""
        return 100 * self.noise_rms / float(np.ptp(self.record.output))


def foreign_raw_record(family, fs=5000.0, seed=0, *, rest_s=0.5, periods=6.7,
                       noise_percent=0.1, x_offset=12.3):
    """A raw record (rest, a step to -87 V, a +-150 V 1 Hz sine) of foreign hysteresis.

    Parameters
    ----------
    family : {"bouc_wen", "preisach", "duhem"}
    fs : float, optional
        Sampling rate [Hz]; with ``rest_s`` and ``periods`` it gives
        :data:`MIN_SAMPLES` to :data:`MAX_SAMPLES` samples.
    seed : int, optional
        Seed of the sensor noise.
    rest_s : float, optional
        Rest at 0 V before the step [s].
    periods : float, optional
        Periods of the 1 Hz sine after the step.
    noise_percent : float, optional
        Sensor noise RMS [% of the noise-free stroke].
    x_offset : float, optional
        Output offset [um].

    Returns
    -------
    RawForeignRecord

    Examples
    --------
    >>> raw = foreign_raw_record("bouc_wen", fs=2000.0, periods=1.2)
    >>> raw.record
    Record(3400 samples at 2000 Hz, v [V] -> x [um])
    >>> float(raw.record.input[1000]), round(raw.noise_floor_percent, 2)     # the step
    (-87.0, 0.1)
    """
    operator = foreign_operator(family)
    fs = check_positive("fs", fs)
    seed = check_integer("seed", seed, minimum=0)
    n_rest = int(round(check_positive("rest_s", rest_s) * fs))
    n_sine = int(round(check_positive("periods", periods) * fs))
    noise_percent = check_positive("noise_percent", noise_percent)
    x_offset = check_real("x_offset", x_offset)
    if not MIN_SAMPLES <= n_rest + n_sine <= MAX_SAMPLES:
        raise ValueError(f"fs, rest_s and periods give {n_rest + n_sine:,} samples "
                         f"(fs * (rest_s + periods)); a record has {MIN_SAMPLES} to "
                         f"{MAX_SAMPLES:,}")
    t = np.arange(n_sine) / fs
    phase = math.asin(-87.0 / 150.0)
    v = np.r_[np.zeros(n_rest), 150.0 * np.sin(2 * math.pi * t + phase)]
    b, a = resonance_dynamics(fs)
    h = operator.simulate(v)
    x_true = x_offset + h[0] + sg.lfilter(b, a, h - h[0])
    noise_rms = noise_percent / 100 * float(np.ptp(x_true))
    x = x_true + noise_rms * np.random.default_rng(seed).standard_normal(v.size)
    rec = records.Record(v, x, fs, input_unit="V", output_unit="um", input_name="v",
                         output_name="x", metadata={"family": family})
    return RawForeignRecord(rec, family, x_true, noise_rms, b, a, operator, x_offset)


@dataclass(frozen=True)
class BestAchievable:
    """The error a fit of a raw foreign record can be expected to reach [% of stroke].

    Attributes
    ----------
    noise_floor_percent : float
        The sensor noise: no model beats it on the whole record.
    whole_percent, out_of_sample_percent : float
        A fine Preisach fit through the true dynamics: on the whole record
        (fitted to it all) and on the samples after the turning point nearest
        the middle (fitted before it, run through the whole record).
    """

    noise_floor_percent: float
    whole_percent: float
    out_of_sample_percent: float


def _ramped_relays(v, levels, v_max):
    """Ramped-relay outputs (N, levels^2 / 2 + ...) along v, after the stage's history.

    Element (r, c) is the play of threshold r, shifted by c and clipped to
    +-1 over a ramp of one grid step: a relay at (c + r, c - r) that switches
    linearly, so that the sum is continuous in v.
    """
    path = _path_with_history(v)
    step = 2 * v_max / levels
    r = step * np.arange(levels // 2 + 1)
    plays = play_outputs(path, r, np.zeros(r.size))[_HISTORY_V.size:]
    centres = np.linspace(-v_max, v_max, levels + 1)
    cols = [np.clip((plays[:, i:i + 1] - centres[np.abs(centres) + ri <= v_max + step])
                    / (step / 2), -1, 1) for i, ri in enumerate(r)]
    return np.hstack(cols)


def best_achievable(raw, levels=16, rows=12000):
    """:class:`BestAchievable` of a :class:`RawForeignRecord`.

    The reference fit: a linear term, an offset and ramped relays on a
    ``levels`` grid over the input's range (weights >= 0 by bounded least
    squares, the elements run through the stage's history), through the
    generating dynamics, on about ``rows`` samples spread over the record
    (every sample of the step and its ringing kept).  The regressor holds every
    sample: ``levels`` is bounded so that it has at most
    :data:`MAX_REGRESSOR_ENTRIES` entries.

    Examples
    --------
    >>> raw = foreign_raw_record("duhem", fs=2000.0, periods=2.7)
    >>> best = best_achievable(raw, levels=8)
    >>> best.noise_floor_percent <= best.whole_percent < 1.0
    True
    """
    check_type("raw", raw, RawForeignRecord, "a RawForeignRecord (foreign_raw_record)")
    levels = check_integer("levels", levels, minimum=2)
    rows = check_integer("rows", rows, minimum=100)
    v, x = raw.record.input, raw.record.output
    columns = (levels // 2 + 1) * (levels + 1) + 2     # at most: relays, slope and offset
    if columns * v.size > MAX_REGRESSOR_ENTRIES:
        raise ValueError(f"levels = {levels} on a record of {v.size:,} samples needs a "
                         f"regressor of up to {columns * v.size:,} entries, at most "
                         f"{MAX_REGRESSOR_ENTRIES:,}: fewer levels or a shorter record")
    v_max = float(np.max(np.abs(v))) * 1.001
    cols = np.column_stack([v, _ramped_relays(v, levels, v_max)])
    filtered = cols[0] + sg.lfilter(raw.b, raw.a, cols - cols[0], axis=0)
    design = np.column_stack([filtered, np.ones(v.size)])
    lower = np.r_[np.zeros(design.shape[1] - 1), -np.inf]
    step = int(np.argmax(np.abs(np.diff(v)))) + 1
    every = np.union1d(np.arange(0, v.size, max(1, v.size // rows)),
                       np.arange(step, min(v.size, step + int(0.03 * raw.record.fs))))

    def fit(used):
        return opt.lsq_linear(design[used], x[used], bounds=(lower, np.inf),
                              method="bvls").x

    def rms_percent(theta, used):
        r = design[used] @ theta - x[used]
        return 100 * math.sqrt(float(np.mean(r ** 2))) / float(np.ptp(x))

    whole = rms_percent(fit(every), np.arange(v.size))
    (_, _), (_, _, first) = split_record(v, x, 0.5)
    out = rms_percent(fit(every[every <= first]), np.arange(first, v.size))
    return BestAchievable(raw.noise_floor_percent, whole, out)
