"""Virtual stand-in for the paper's stage, amplifier, sensor and DAQ (Sec. II): one stage, one run.

:class:`VirtualStage` takes the control input u_c [V] at 10 kHz and returns
what the DAQ would measure: DAC (16 bit, ZOH) -> amplifier (x10, limits) ->
Prandtl-Ishlinskii hysteresis of unit small-signal gain -> G(s) of eq. 4
(exact ZOH) -> sensor noise -> ADC (16 bit).  Out-of-range signals are limited
and reported (:class:`StageSaturationWarning`, :class:`Saturation`).  The
hysteresis (:mod:`piezolib.problem.stage_hysteresis`) is calibrated on Table 4
Case I only (:func:`piezolib.problem.stage_calibration.calibrate_hysteresis`).

This module holds what a single run needs: the settings, the record and its
saturation summary, the stage with its whole-record run (:meth:`VirtualStage.run`)
and its sample-by-sample run (:class:`StageSimulation`), and the converters
and plant filter they share.  N stages run at once (one state array per
state, :class:`~piezolib.problem.stage_batch.StageBatch`) are the concern of
:mod:`piezolib.problem.stage_batch`, which builds on this module; the Case I
experiment and the calibration on it, which run stages, are
:mod:`piezolib.problem.stage_calibration`.

Signal path, assumptions table and calibration rule: ``docs/stage.md``.  The
experiment files recorded on this stage: :mod:`piezolib.problem.stage_data`.
"""

import math
import warnings
from dataclasses import dataclass, field, fields, replace

import control as ct
import numpy as np
import scipy.signal as sg

from piezolib._checks import (check_finite_array, check_integer, check_nonnegative,
                              check_positive, check_siso, check_stable, check_type)
from piezolib.identification import zoh_coefficients
from piezolib.problem import paper
from piezolib.problem.stage_hysteresis import (CALIBRATED_HYSTERESIS, HysteresisLaw,
                                               PlayHysteresis)
from piezolib.robust.lti import realize

__all__ = [
    "ADC_RANGE_V", "StageSettings", "Saturation", "RECORD_COLUMNS", "StageRecord",
    "StageSaturationWarning", "VirtualStage", "StageSimulation",
]



# --- settings, records, saturation --------------------------------------------
#: ADC input range [V]: the PXIe-6361's +-10 V range, the smallest that holds
#: the sensor's 0 ... 10 V output (paper.SENSOR_OUTPUT_RANGE_V) with margin, so
#: that noise and the small dynamic undershoot around 0 um are measured, not
#: rectified.  An assumption: the paper does not state the DAQ input range.
ADC_RANGE_V = (-10.0, 10.0)

@dataclass(frozen=True)
class StageSettings:
    """Everything :class:`VirtualStage` assumes (table in ``docs/stage.md``).

    Attributes
    ----------
    plant : control.LTI
        Linear dynamics from u_c [V] to v_y [V] (strictly proper; stable
        unless ``unstable_plant_ok``).
    sample_rate_Hz : float
    amplifier_gain : float
        v_a / u_c [V/V].
    dac_range_V, dac_bits
        DAC (= amplifier input) range [V] and resolution.
    amplifier_output_range_V : tuple
        Amplifier output limits [V].
    adc_range_V, adc_bits
        ADC range for v_y [V] and resolution.
    noise_rms_V : float
        White Gaussian sensor noise on v_y [V rms].
    hysteresis : HysteresisLaw, PlayHysteresis or None
        Hysteresis truth; ``None`` gives a linear stage (H = identity).
    unstable_plant_ok : bool
        Accept an unstable ``plant`` (default False: refused).  For closed-loop
        studies over a model set, some of whose members are unstable on their
        own and only a controller stabilises; run open loop, such a stage
        diverges (its output leaves the ADC range at once).
    """

    plant: object = field(default_factory=paper.plant)
    sample_rate_Hz: float = paper.SAMPLING_FREQUENCY_HZ
    amplifier_gain: float = paper.AMPLIFIER_GAIN
    dac_range_V: tuple = paper.AMPLIFIER_INPUT_RANGE_V
    dac_bits: int = paper.DAQ_BITS
    amplifier_output_range_V: tuple = paper.AMPLIFIER_OUTPUT_RANGE_V
    adc_range_V: tuple = ADC_RANGE_V
    adc_bits: int = paper.DAQ_BITS
    noise_rms_V: float = 0.5e-3
    hysteresis: object = CALIBRATED_HYSTERESIS
    unstable_plant_ok: bool = False


class StageSaturationWarning(UserWarning):
    """A signal of the virtual stage left its range and was limited."""


@dataclass(frozen=True)
class Saturation:
    """Summary of how often one stage of the chain was driven out of range.

    Attributes
    ----------
    where : str
        ``"DAC/amplifier input"``, ``"amplifier output"`` or ``"ADC"``.
    limits_V : tuple
        The allowed range [V].
    count : int
        Number of samples outside the range (they were limited to it).
    first_index : int or None
        First offending sample.
    requested_min_V, requested_max_V : float or None
        Extremes of the signal that was asked for (before limiting).
    """

    where: str
    limits_V: tuple
    count: int = 0
    first_index: object = None
    requested_min_V: object = None
    requested_max_V: object = None

    @property
    def occurred(self):
        """True when at least one sample was limited."""
        return self.count > 0

    def message(self, fs=paper.SAMPLING_FREQUENCY_HZ):
        """One sentence naming the range and the offending values."""
        if not self.occurred:
            return f"{self.where}: within {self.limits_V[0]:g} ... {self.limits_V[1]:g} V"
        return (f"{self.where}: requested {self.requested_min_V:.6g} ... "
                f"{self.requested_max_V:.6g} V exceeds the range {self.limits_V[0]:g} ... "
                f"{self.limits_V[1]:g} V in {self.count} sample(s), first at sample "
                f"{self.first_index} (t = {self.first_index / fs:.4f} s); the output "
                "was held at the range limit")

    @classmethod
    def of(cls, where, limits, requested, first_index_offset=0):
        """Summarise the samples of ``requested`` outside ``limits``."""
        requested = np.asarray(requested, dtype=float)
        bad = np.flatnonzero((requested < limits[0]) | (requested > limits[1]))
        if bad.size == 0:
            return cls(where, tuple(limits))
        return cls(where, tuple(limits), int(bad.size), int(bad[0]) + first_index_offset,
                   float(requested.min()), float(requested.max()))


#: Signals of a :class:`StageRecord`, in the column order of the experiment files.
RECORD_COLUMNS = ("t_s", "u_c_V", "v_a_V", "x_um", "v_y_V")


@dataclass(frozen=True, eq=False)
class StageRecord:
    """One run of the virtual stage, sample k at t = k T.

    Attributes
    ----------
    t_s : ndarray
        Time [s].
    u_c_V : ndarray
        Control input as the DAC produced it (quantised, limited) [V].
    v_a_V : ndarray
        Amplifier output = actuator voltage [V].
    x_um : ndarray
        True displacement [um] (3 um/V x noise-free output of G).
    v_y_V : ndarray
        Measured sensor output [V]: noise and ADC quantisation included;
        v_y[k] depends on u_c[0..k-1] only.
    input_saturation, output_saturation, adc_saturation : Saturation
        What was limited at the DAC/amplifier input, the amplifier output and
        the ADC (whole run).
    seed : int or None
        Noise seed of the run.
    """

    t_s: np.ndarray
    u_c_V: np.ndarray
    v_a_V: np.ndarray
    x_um: np.ndarray
    v_y_V: np.ndarray
    input_saturation: Saturation
    output_saturation: Saturation
    adc_saturation: Saturation
    seed: object = None

    def __post_init__(self):
        n = None
        for name in RECORD_COLUMNS:
            arr = np.array(getattr(self, name), dtype=float)
            if arr.ndim != 1 or (n is not None and len(arr) != n):
                raise ValueError(f"{name} must be 1-D with the length of t_s")
            n = len(arr)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def __len__(self):
        return len(self.t_s)

    @property
    def x_measured_um(self):
        """Displacement as measured: 3 um/V x v_y [um]."""
        return paper.UM_PER_VOLT * self.v_y_V

    @property
    def saturated(self):
        """True when any part of the chain was driven out of range."""
        return any(s.occurred for s in
                   (self.input_saturation, self.output_saturation, self.adc_saturation))

    def segment(self, start=None, stop=None):
        """Samples start:stop as a record (saturation info of the whole run)."""
        cut = slice(start, stop)
        return replace(self, **{name: getattr(self, name)[cut] for name in RECORD_COLUMNS})

    def columns(self):
        """The signals as a dict of arrays, in file column order."""
        return {name: getattr(self, name) for name in RECORD_COLUMNS}


# --- the stage --------------------------------------------------------------------
class VirtualStage:
    """Virtual P-752.21 stage with amplifier, sensor and DAQ (``docs/stage.md``).

    Parameters
    ----------
    seed : int, optional
        Seed of the sensor noise.  Every :meth:`run` and :meth:`start`
        begins from the same state with a fresh generator of this seed, so a
        stage is deterministic.
    **overrides
        Any field of :class:`StageSettings`, e.g. ``noise_rms_V=0`` or
        ``hysteresis=None`` (linear stage).

    Attributes
    ----------
    settings : StageSettings
        Everything assumed (defaults plus overrides).
    fs, gain : float
        Sample rate [Hz] and amplifier gain [V/V].
    hysteresis : PlayHysteresis or None
        The hysteresis operator in use.
    b, a : ndarray
        Direct-form coefficients of the ZOH-discretised plant (b[0] = 0).

    Examples
    --------
    >>> stage = VirtualStage(seed=0)
    >>> rec = stage.run(np.full(1000, 1.0))        # 0.1 s at u_c = 1 V
    >>> sim = stage.start()                        # closed-loop use
    >>> v_y = sim.v_y_V                            # measurement at k = 0
    >>> for k in range(1000):
    ...     u_c = 1.0 + 0.5 * (1.0 - v_y)          # any causal controller
    ...     v_y = sim.step(u_c)                    # measurement at k + 1
    """

    def __init__(self, seed=0, **overrides):
        self.seed = check_integer("seed", seed, minimum=0)
        names = {f.name for f in fields(StageSettings)}
        unknown = set(overrides) - names
        if unknown:
            raise TypeError(f"unknown stage setting(s) {sorted(unknown)}; "
                            f"expected some of {sorted(names)}")
        self.settings = s = StageSettings(**overrides)
        self.fs = check_positive("sample_rate_Hz", s.sample_rate_Hz)
        self.gain = check_positive("amplifier_gain", s.amplifier_gain)
        self.dac = _Converter("dac_range_V", s.dac_range_V, s.dac_bits)
        self.adc = _Converter("adc_range_V", s.adc_range_V, s.adc_bits)
        self.out_lo, self.out_hi = _range("amplifier_output_range_V",
                                          s.amplifier_output_range_V)
        self.noise_rms = check_nonnegative("noise_rms_V", s.noise_rms_V)
        if isinstance(s.hysteresis, HysteresisLaw):
            self.hysteresis = s.hysteresis.operator()
        elif isinstance(s.hysteresis, PlayHysteresis) or s.hysteresis is None:
            self.hysteresis = s.hysteresis
        else:
            raise TypeError("hysteresis must be a HysteresisLaw, a PlayHysteresis or "
                            f"None, got {type(s.hysteresis).__name__}")
        check_type("unstable_plant_ok", s.unstable_plant_ok, bool, "True or False")
        self.b, self.a = _zoh_filter(s.plant, 1.0 / self.fs, s.unstable_plant_ok)

    def __repr__(self):
        return f"VirtualStage(seed={self.seed})"

    # -- models of the truth -------------------------------------------------------
    def small_signal_model(self):
        """The stage's exact model for small signals: w0 G(s), u_c -> v_y.

        Valid for any input that, after its last reversal, oscillates with a
        peak-to-peak size below :attr:`small_signal_limit_V` at the amplifier
        input: then no play moves and H is v_a plus a constant.
        """
        w0 = 1.0 if self.hysteresis is None else self.hysteresis.linear_weight
        G = ct.tf(self.settings.plant)
        return ct.tf(w0 * G.num[0][0], G.den[0][0], inputs="u_c", outputs="v_y",
                     name="G_small_signal")

    @property
    def small_signal_limit_V(self):
        """Largest peak-to-peak u_c [V] of the exactly linear zone (2 r_1 / gain)."""
        if self.hysteresis is None:
            return float("inf")
        return 2 * self.hysteresis.thresholds_V[0] / self.gain

    def assumptions(self):
        """The stage's assumptions, as used, in a table (see ``docs/stage.md``).

        Returns
        -------
        pandas.DataFrame
            Columns ``quantity``, ``value``, ``source / reason``.
        """
        import pandas as pd
        s, h = self.settings, self.hysteresis
        if h is None:
            hyst = ("none (linear stage)", "override")
        else:
            law = s.hysteresis if isinstance(s.hysteresis, HysteresisLaw) else None
            hyst = (f"Prandtl-Ishlinskii, {len(h.thresholds_V)} plays, r = "
                    f"{h.thresholds_V[0]:g} ... {h.thresholds_V[-1]:.3g} V, w0 = "
                    f"{h.linear_weight:g}" + (f", c = {law.density_per_V:g} /V, rho = "
                                              f"{law.decay_V:g} V" if law else ""),
                    "calibrated on Table 4 Case I only (calibrate_hysteresis)")
        rows = [
            ("sampling / control rate", f"{self.fs:g} Hz", "paper Sec. V"),
            ("DAC", f"{s.dac_bits} bit, {self.dac.lo:g} ... {self.dac.hi:g} V, ZOH, "
                    f"LSB {self.dac.lsb * 1e3:.3g} mV",
             "PXIe-6361 16 bit; range = E-505 input range (Sec. II)"),
            ("amplifier", f"static gain {self.gain:g}, output {self.out_lo:g} ... "
                          f"{self.out_hi:g} V", "E-505 (Sec. II)"),
            ("amplifier bandwidth", f"{paper.AMPLIFIER_BANDWIDTH_HZ:g} Hz: not added",
             "inside G, which was identified from u_c to v_y"),
            ("hysteresis", *hyst),
            ("hysteresis placement", "on v_a, small-signal gain 1, before G/10",
             "G is the small-signal model: counted once"),
            ("initial state", "rest, v_a = 0 V, plays on the descending branch",
             "as if last lowered to 0 V"),
            ("linear dynamics", "G(s) of eq. 4 on v_h / 10, exact ZOH discretisation",
             "paper eq. 4"),
            ("sensor noise", f"{s.noise_rms_V * 1e3:g} mV rms white Gaussian "
                             f"({s.noise_rms_V * paper.UM_PER_VOLT * 1e3:.3g} nm)",
             "assumed: a few LSB of a 16-bit DAQ input plus sensor electronics"),
            ("ADC", f"{s.adc_bits} bit, {self.adc.lo:g} ... {self.adc.hi:g} V, "
                    f"LSB {self.adc.lsb * 1e3:.3g} mV", "PXIe-6361 +-10 V range (assumed)"),
            ("sensor", f"ideal inside G, x = {paper.UM_PER_VOLT:g} um/V x y",
             "paper's 3 um/V scale"),
            ("causality", "v_y[k] depends on u_c[0 .. k-1]", "ZOH DAC, sampling ADC"),
            ("not modelled", "creep, drift, temperature, load", "paper neglects creep (Sec. I)"),
        ]
        return pd.DataFrame(rows, columns=["quantity", "value", "source / reason"])

    # -- batch run ------------------------------------------------------------------
    def run(self, u_c):
        """Apply a sampled control input and return the record.

        Parameters
        ----------
        u_c : array_like
            Control input [V] at the stage's sample rate, 1-D; held constant
            over each sample period.  Values outside the DAC/amplifier input
            range are limited with a :class:`StageSaturationWarning`.

        Returns
        -------
        StageRecord
            Identical, float for float, to stepping a :meth:`start`
            simulation through the same input.
        """
        u = check_finite_array("u_c", u_c, ndim=1, min_length=1, real=True)
        n = len(u)
        u_dac, v_a, y, sat_in, sat_out = self._noise_free(u)
        noise = self.noise_rms * np.random.default_rng(self.seed).standard_normal(n)
        analog = y + noise
        v_y = self.adc.convert(analog)
        sat_adc = Saturation.of("ADC", self.adc.limits, analog)
        record = StageRecord(np.arange(n) / self.fs, u_dac, v_a, paper.UM_PER_VOLT * y,
                             v_y, sat_in, sat_out, sat_adc, self.seed)
        self._warn(record)
        return record

    def _noise_free(self, u):
        """(u_dac, v_a, y, input saturation, output saturation) of the input u [V]:
        everything of :meth:`run` before the sensor noise and the ADC."""
        u_dac, v_a, v_h, sat_in, sat_out = self._before_plant(u)
        return u_dac, v_a, self._plant_output(v_h), sat_in, sat_out

    def _before_plant(self, u):
        """(u_dac, v_a, v_h, input saturation, output saturation): DAC, amplifier, hysteresis."""
        u_dac = self.dac.convert(u)
        sat_in = Saturation.of("DAC/amplifier input", self.dac.limits, u)
        v_cmd = self.gain * u_dac
        v_a = np.minimum(np.maximum(v_cmd, self.out_lo), self.out_hi)
        sat_out = Saturation.of("amplifier output", (self.out_lo, self.out_hi), v_cmd)
        v_h = v_a if self.hysteresis is None else self.hysteresis.apply(v_a)[0]
        return u_dac, v_a, v_h, sat_in, sat_out

    def _plant_output(self, v_h):
        """y [V]: the linear dynamics G on v_h / gain (noise-free sensor output)."""
        return sg.lfilter(self.b, self.a, v_h / self.gain)

    def start(self):
        """Begin a sample-by-sample simulation (for closed loops); see
        :class:`StageSimulation`."""
        return StageSimulation(self)

    # -- variants -------------------------------------------------------------------
    def replace(self, seed=None, **overrides):
        """This stage with another noise seed and/or other settings.

        Parameters
        ----------
        seed : int, optional
            Noise seed of the new stage; default this stage's.
        **overrides
            Fields of :class:`StageSettings` to change, e.g. ``noise_rms_V=0``
            for the noise-free stage (quantisation kept).

        Returns
        -------
        VirtualStage
            A new stage; ``self`` is not changed.  With only a new seed it
            shares this stage's (read-only) models, so it is cheap.
        """
        seed = self.seed if seed is None else check_integer("seed", seed, minimum=0)
        if not overrides:
            new = object.__new__(VirtualStage)
            new.__dict__.update(self.__dict__)
            new.seed = seed
            return new
        settings = {f.name: getattr(self.settings, f.name) for f in fields(StageSettings)}
        unknown = set(overrides) - set(settings)
        if unknown:
            raise TypeError(f"unknown stage setting(s) {sorted(unknown)}; "
                            f"expected some of {sorted(settings)}")
        settings.update(overrides)
        return VirtualStage(seed, **settings)

    def _warn(self, record):
        for sat in (record.input_saturation, record.output_saturation,
                    record.adc_saturation):
            if sat.occurred:
                warnings.warn(sat.message(self.fs), StageSaturationWarning, stacklevel=3)


class StageSimulation:
    """Sample-by-sample run of a :class:`VirtualStage` in plain Python floats.

    Causality: at sample k the DAQ first reads v_y[k] (:attr:`v_y_V`), which
    depends on u_c[0..k-1] only; then u_c[k] is written to the DAC and held
    for one period.  :meth:`step` applies u_c[k] and returns v_y[k+1], the
    measurement the controller uses for u_c[k+1]:

    >>> def controller(v_e):            # any causal controller: here proportional
    ...     return 1.0 + 0.5 * v_e
    >>> reference = np.full(1000, 1.0)  # v_r [V], 0.1 s
    >>> sim = VirtualStage().start()
    >>> v_y = sim.v_y_V
    >>> for r_k in reference:
    ...     v_y = sim.step(controller(r_k - v_y))
    >>> record = sim.record()          # == stage.run(all u_c applied)
    >>> len(record.t_s)
    1000

    One step costs about 10-20 us.
    """

    _BLOCK = 4096

    def __init__(self, stage):
        self._stage = stage
        self._rng = np.random.default_rng(stage.seed)
        self._noise = []
        self._noise_start = 0
        self._z = [0.0] * (len(stage.a) - 1)
        self._b = [float(x) for x in stage.b]
        self._a = [float(x) for x in stage.a]
        hyst = stage.hysteresis
        if hyst is None:
            self._plays = None
        else:
            self._plays = list(hyst.initial_state(0.0))
            self._r = list(hyst.thresholds_V)
            self._w = list(hyst.weights)
            self._w0 = hyst.linear_weight
        self._k = 0
        self._u, self._u_dac, self._v_cmd, self._v_a, self._y, self._analog, self._v_y = (
            [], [], [], [], [], [], [])
        self._warned = set()
        self._current = self._measure(0.0)

    @property
    def k(self):
        """Number of samples applied so far (index of the current measurement)."""
        return self._k

    @property
    def v_y_V(self):
        """Measurement v_y[k] at the current sample [V]."""
        return self._current[1]

    @property
    def state(self):
        """Internal state after :attr:`k` samples, as plain Python floats.

        Returns
        -------
        filter_state : tuple of float
            State of the direct-form II transposed filter of the discretised
            plant (its input is v_h / gain [V]).
        play_outputs_V : tuple of float
            Outputs of the play operators [V] (empty for a linear stage):
            the ``state`` that :meth:`PlayHysteresis.apply` returns after the
            same actuator voltages.
        """
        return tuple(self._z), (() if self._plays is None else tuple(self._plays))

    def _noise_at(self, k):
        while k >= self._noise_start + len(self._noise):
            self._noise_start += len(self._noise)
            self._noise = (self._stage.noise_rms
                           * self._rng.standard_normal(self._BLOCK)).tolist()
        return self._noise[k - self._noise_start]

    def _measure(self, y):
        analog = y + self._noise_at(self._k)
        return analog, self._stage.adc.convert_scalar(analog)

    def step(self, u_c):
        """Apply u_c[k] [V] for one period; return the next measurement v_y[k+1] [V]."""
        u = float(u_c)
        if not math.isfinite(u):
            raise ValueError(f"u_c must be finite, got {u_c!r} at sample {self._k}")
        st = self._stage
        u_dac = st.dac.convert_scalar(u)
        if (u < st.dac.lo or u > st.dac.hi) and "in" not in self._warned:
            self._warned.add("in")
            warnings.warn(Saturation.of("DAC/amplifier input", st.dac.limits, [u],
                                        self._k).message(st.fs),
                          StageSaturationWarning, stacklevel=2)
        v_cmd = st.gain * u_dac
        v_a = min(max(v_cmd, st.out_lo), st.out_hi)
        if v_a != v_cmd and "out" not in self._warned:
            self._warned.add("out")
            warnings.warn(Saturation.of("amplifier output", (st.out_lo, st.out_hi), [v_cmd],
                                        self._k).message(st.fs),
                          StageSaturationWarning, stacklevel=2)
        if self._plays is None:
            v_h = v_a
        else:
            plays, r = self._plays, self._r
            v_h = self._w0 * v_a
            for i in range(len(plays)):
                y = plays[i]
                lo = v_a - r[i]
                if y < lo:
                    y = lo
                else:
                    hi = v_a + r[i]
                    if y > hi:
                        y = hi
                plays[i] = y
                v_h = v_h + self._w[i] * (y - r[i])
        x_in = v_h / st.gain
        # direct form II transposed, the same arithmetic as scipy.signal.lfilter
        z, b, a = self._z, self._b, self._a
        y_k = z[0] + b[0] * x_in
        last = len(z) - 1
        for i in range(last):
            z[i] = z[i + 1] + x_in * b[i + 1] - y_k * a[i + 1]
        z[last] = x_in * b[last + 1] - y_k * a[last + 1]
        analog, v_y = self._current
        self._u.append(u)
        self._u_dac.append(u_dac)
        self._v_cmd.append(v_cmd)
        self._v_a.append(v_a)
        self._y.append(y_k)
        self._analog.append(analog)
        self._v_y.append(v_y)
        self._k += 1
        self._current = self._measure(z[0])
        analog = self._current[0]
        if not st.adc.lo <= analog <= st.adc.hi and "adc" not in self._warned:
            self._warned.add("adc")
            warnings.warn(Saturation.of("ADC", st.adc.limits, [analog], self._k).message(st.fs),
                          StageSaturationWarning, stacklevel=2)
        return self._current[1]

    def record(self):
        """The samples applied so far as a :class:`StageRecord`."""
        st = self._stage
        u = np.array(self._u)
        y = np.array(self._y)
        return StageRecord(
            np.arange(len(u)) / st.fs, np.array(self._u_dac), np.array(self._v_a),
            paper.UM_PER_VOLT * y,
            np.array(self._v_y),
            Saturation.of("DAC/amplifier input", st.dac.limits, u),
            Saturation.of("amplifier output", (st.out_lo, st.out_hi), np.array(self._v_cmd)),
            Saturation.of("ADC", st.adc.limits, np.array(self._analog)), st.seed)


class _Converter:
    """Uniform quantiser on the grid k * lsb (0 V is a code, as on a bipolar
    converter), lsb = (hi - lo) / (2**bits - 1), limited to [lo, hi]."""

    def __init__(self, name, limits, bits):
        self.lo, self.hi = _range(name, limits)
        bits = check_integer(f"{name.split('_')[0]}_bits", bits, minimum=1)
        self.lsb = (self.hi - self.lo) / (2 ** bits - 1)
        self.code_lo = math.ceil(self.lo / self.lsb)
        self.code_hi = math.floor(self.hi / self.lsb)
        self.limits = (self.lo, self.hi)

    def convert(self, v):
        return np.clip(np.rint(v / self.lsb), self.code_lo, self.code_hi) * self.lsb

    def convert_scalar(self, v):
        # round() is round-half-even like np.rint, so both paths agree exactly;
        # limiting first keeps round() away from overflow for huge inputs
        v = min(max(v, self.lo - self.lsb), self.hi + self.lsb)
        return min(max(round(v / self.lsb), self.code_lo), self.code_hi) * self.lsb


def _range(name, limits):
    try:
        lo, hi = (float(x) for x in limits)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a pair (low, high) of volts, got {limits!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be finite with low < high, got {limits!r}")
    return lo, hi


def _zoh_filter(plant, dt, unstable_ok=False):
    """Exact ZOH discretisation of a strictly proper (stable, unless
    ``unstable_ok``) plant as (b, a) of a direct-form filter with b[0] = 0
    (no direct feedthrough)."""
    check_siso("plant", plant)
    if not plant.isctime(strict=True):
        raise ValueError("plant must be a continuous-time model")
    if not unstable_ok:
        check_stable("plant", plant)
    sys = realize(plant)
    if sys.nstates == 0 or np.any(sys.D != 0):
        raise ValueError("plant must be strictly proper (no direct feedthrough), so "
                         "that v_y[k] depends on u_c up to sample k-1")
    return zoh_coefficients(plant, dt)

