"""Virtual stand-in for the paper's stage, amplifier, sensor and DAQ (Sec. II).

:class:`VirtualStage` takes the control input u_c [V] at 10 kHz and returns
what the DAQ would measure: DAC (16 bit, ZOH) -> amplifier (x10, limits) ->
Prandtl-Ishlinskii hysteresis of unit small-signal gain -> G(s) of eq. 4
(exact ZOH) -> sensor noise -> ADC (16 bit).  Out-of-range signals are limited
and reported (:class:`StageSaturationWarning`, :class:`Saturation`).  The
hysteresis (:mod:`piezolib.problem.stage_hysteresis`) is calibrated on Table 4
Case I only (:func:`calibrate_hysteresis`).

Signal path, assumptions table and calibration rule: ``docs/stage.md``.  The
experiment files recorded on this stage: :mod:`piezolib.problem.stage_data`.
"""

import math
import numbers
import warnings
from collections.abc import Iterable
from dataclasses import dataclass, field, fields, replace

import control as ct
import numpy as np
import scipy.optimize as opt
import scipy.signal as sg

from piezolib import signals
from piezolib._checks import (check_finite_array, check_integer, check_nonnegative,
                              check_positive, check_siso, check_stable, check_type)
from piezolib.identification import zoh_coefficients
from piezolib.hysteresis.measure import hysteresis_percent
from piezolib.problem import paper
from piezolib.problem.stage_hysteresis import (CALIBRATED_HYSTERESIS, HysteresisLaw,
                                               PlayHysteresis)
from piezolib.robust.lti import realize

__all__ = [
    "ADC_RANGE_V", "StageSettings", "Saturation", "RECORD_COLUMNS", "StageRecord",
    "StageSaturationWarning", "VirtualStage", "StageSimulation", "StageBatch",
    "StageBatchSimulation", "check_seeds", "case_I_input", "run_case_I", "case_I_hysteresis",
    "calibrate_hysteresis",
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

    # -- variants and batches -------------------------------------------------------
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

    def batch(self, seeds):
        """N copies of this stage that differ only in the noise seed.

        Parameters
        ----------
        seeds : sequence of int
            Distinct non-negative noise seeds, one per member (N >= 1).

        Returns
        -------
        StageBatch
            Member i is ``self.replace(seed=seeds[i])``.
        """
        return StageBatch([self.replace(seed=s) for s in check_seeds(seeds)])

    def over_model_set(self, mset, seeds=None):
        """One copy of this stage per member of a model set, as a batch.

        Member k has the exact ZOH model of ``mset``'s member k as its linear
        dynamics (:func:`piezolib.uncertainty.sampled.member_zoh_coefficients`,
        all members in one batched call) and everything else of this stage:
        hysteresis, amplifier, converters, noise level.  Members may be
        unstable on their own (``unstable_plant_ok``): run them in a loop
        that stabilises them.

        Parameters
        ----------
        mset : piezolib.uncertainty.ModelSet
            Perturbations of this stage's plant (``mset.plant`` is normally
            ``settings.plant``; any plant of the same order works).
        seeds : sequence of int, optional
            One noise seed per member; default: this stage's seed for every
            member (the same noise, so that members differ by their plant
            only).

        Returns
        -------
        StageBatch
        """
        from piezolib.uncertainty.modelset import check_model_set
        from piezolib.uncertainty.sampled import member_zoh_coefficients

        check_model_set(mset)
        if seeds is None:
            seeds = [self.seed] * mset.size
        else:
            seeds = [check_integer("seeds[i]", s, minimum=0) for s in seeds]
            if len(seeds) != mset.size:
                raise ValueError(f"seeds must hold one seed per member ({mset.size}), got "
                                 f"{len(seeds)}")
        b, a = member_zoh_coefficients(mset, 1.0 / self.fs)
        members = []
        for k, seed in enumerate(seeds):
            new = object.__new__(VirtualStage)
            new.__dict__.update(self.__dict__)
            new.settings = replace(self.settings, plant=mset.member(k), unstable_plant_ok=True)
            new.seed, new.b, new.a = seed, b[k], a[k]
            members.append(new)
        return StageBatch(members)

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


def check_seeds(seeds, min_count=1, name="seeds", why=None):
    """Return ``seeds`` as a tuple of distinct non-negative ints.

    Parameters
    ----------
    seeds : sequence of int
        Noise seeds (Python or numpy integers; not bool).
    min_count : int
        Fewest seeds accepted.
    name : str
        Argument name used in the error messages.
    why : str, optional
        Reason for ``min_count``, appended to its error message.

    Returns
    -------
    tuple of int

    Raises
    ------
    ValueError
        ``seeds`` is not a sequence, holds fewer than ``min_count`` seeds, a
        non-integer, a negative or a repeated seed.
    """
    if isinstance(seeds, (str, bytes)) or not isinstance(seeds, Iterable):
        raise ValueError(f"{name} must be a sequence of non-negative integers, got {seeds!r}")
    seeds = list(seeds)
    if len(seeds) < min_count:
        raise ValueError(f"{name} must hold at least {min_count} seed(s), got {len(seeds)}"
                         + (f": {why}" if why else ""))
    out = []
    for s in seeds:
        if isinstance(s, bool) or not isinstance(s, numbers.Integral):
            raise ValueError(f"{name} must be integers, got {s!r}")
        if s < 0:
            raise ValueError(f"{name} must be non-negative, got {int(s)}")
        out.append(int(s))
    repeated = sorted({s for s in out if out.count(s) > 1})
    if repeated:
        raise ValueError(f"{name} must be distinct, got {repeated} more than once")
    return tuple(out)


class StageBatch:
    """N virtual stages run side by side: one state array of shape (N,) per state.

    Each member is a :class:`VirtualStage`; the batch runs them with the
    arithmetic of :meth:`VirtualStage.run` (:meth:`run`) and of
    :class:`StageSimulation` (:meth:`start`) applied elementwise, so member i
    of a batch gives, float for float, the record that ``stages[i]`` gives
    alone.  Typical use: one stage with N noise seeds
    (:meth:`VirtualStage.batch`), or those plus the noise-free stage.

    Parameters
    ----------
    stages : sequence of VirtualStage
        The members, N >= 1.  They may differ in the seed, the sensor noise,
        the plant (of one order) and the hysteresis (the same number of plays,
        or none in every member); they must share the sample rate, the
        amplifier (gain, output limits) and the converters.

    Attributes
    ----------
    stages : tuple of VirtualStage
    size : int
        N.
    seeds : tuple of int
        The members' noise seeds.
    fs, gain : float
        Sample rate [Hz] and amplifier gain [V/V] (shared).
    b, a : ndarray, shape (N, order + 1)
        The members' direct-form plant coefficients (rows, read-only).
    noise_rms_V : ndarray, shape (N,)
        The members' sensor noise [V rms].
    thresholds_V, weights : ndarray, shape (N, n_plays) or None
        The members' play thresholds [V] and weights (None: linear stages).
    linear_weight : ndarray, shape (N,) or None
        The members' w0.

    Examples
    --------
    >>> batch = VirtualStage().batch([0, 1, 2])
    >>> records = batch.run(np.full(1000, 1.0))    # one StageRecord per member
    >>> sim = batch.start()
    >>> v_y = sim.v_y_V                            # shape (3,)
    >>> for k in range(1000):
    ...     v_y = sim.step(1.0 + 0.5 * (1.0 - v_y))
    >>> records = sim.records()
    >>> len(records), len(records[0].t_s)
    (3, 1000)
    """

    def __init__(self, stages):
        if isinstance(stages, VirtualStage) or not isinstance(stages, Iterable):
            raise TypeError("stages must be a sequence of VirtualStage, got "
                            f"{type(stages).__name__}")
        stages = tuple(stages)
        if not stages:
            raise ValueError("stages must hold at least one VirtualStage")
        for i, st in enumerate(stages):
            if not isinstance(st, VirtualStage):
                raise TypeError(f"stages[{i}] must be a VirtualStage, got {type(st).__name__}")
        first = stages[0]

        def shared(st):
            return (st.fs, st.gain, st.out_lo, st.out_hi, st.dac.lo, st.dac.hi, st.dac.lsb,
                    st.adc.lo, st.adc.hi, st.adc.lsb)

        for i, st in enumerate(stages[1:], 1):
            if shared(st) != shared(first):
                raise ValueError(f"stages must share the sample rate, the amplifier and the "
                                 f"converters; stages[{i}] differs from stages[0]")
            if len(st.a) != len(first.a):
                raise ValueError(f"stages must have plants of one order; stages[{i}] has "
                                 f"order {len(st.a) - 1}, stages[0] {len(first.a) - 1}")
            if (st.hysteresis is None) != (first.hysteresis is None) or (
                    st.hysteresis is not None
                    and len(st.hysteresis.thresholds_V) != len(first.hysteresis.thresholds_V)):
                raise ValueError(f"stages must all have hysteresis with the same number of "
                                 f"plays, or none; stages[{i}] differs from stages[0]")
        self.stages = stages
        self.size = len(stages)
        self.seeds = tuple(st.seed for st in stages)
        self.fs, self.gain = first.fs, first.gain
        self.dac, self.adc = first.dac, first.adc
        self.out_lo, self.out_hi = first.out_lo, first.out_hi
        self.b = _read_only(np.array([st.b for st in stages], dtype=float))
        self.a = _read_only(np.array([st.a for st in stages], dtype=float))
        self.noise_rms_V = _read_only(np.array([st.noise_rms for st in stages], dtype=float))
        if first.hysteresis is None:
            self.thresholds_V = self.weights = self.linear_weight = None
        else:
            hs = [st.hysteresis for st in stages]
            self.thresholds_V = _read_only(np.array([h.thresholds_V for h in hs]))
            self.weights = _read_only(np.array([h.weights for h in hs]))
            self.linear_weight = _read_only(np.array([h.linear_weight for h in hs]))

    def __len__(self):
        return self.size

    def __repr__(self):
        return f"StageBatch(size={self.size}, seeds={list(self.seeds)})"

    def run(self, u_c):
        """Apply one sampled control input to every member (open loop).

        The noise-free part (DAC, amplifier, hysteresis, G) is computed once
        for members that share the plant and the hysteresis; each member
        then adds its own noise and is converted by the ADC.

        Parameters
        ----------
        u_c : array_like
            Control input [V] at the sample rate, 1-D (the same for every
            member).

        Returns
        -------
        list of StageRecord
            Record i is identical, float for float, to ``stages[i].run(u_c)``.
            Limited samples give one :class:`StageSaturationWarning` per
            place of the chain, naming the members concerned.
        """
        u = check_finite_array("u_c", u_c, ndim=1, min_length=1, real=True)
        n = len(u)
        t = np.arange(n) / self.fs
        records, fronts, truths = [], {}, {}
        for st in self.stages:
            # the hysteresis is shared by members that differ only in the plant (a model set)
            front_key, plant_key = self._truth_key(st)
            if front_key not in fronts:
                fronts[front_key] = st._before_plant(u)
            u_dac, v_a, v_h, sat_in, sat_out = fronts[front_key]
            if (front_key, plant_key) not in truths:
                truths[front_key, plant_key] = st._plant_output(v_h)
            y = truths[front_key, plant_key]
            # the arithmetic of VirtualStage.run, member by member
            noise = st.noise_rms * np.random.default_rng(st.seed).standard_normal(n)
            analog = y + noise
            v_y = st.adc.convert(analog)
            sat_adc = Saturation.of("ADC", st.adc.limits, analog)
            records.append(StageRecord(t, u_dac, v_a, paper.UM_PER_VOLT * y, v_y, sat_in,
                                       sat_out, sat_adc, st.seed))
        _warn_members(records, self.fs)
        return records

    @staticmethod
    def _truth_key(st):
        """(hysteresis key, plant key) of a member's noise-free output."""
        h = st.hysteresis
        return (None if h is None else (h.thresholds_V, h.weights, h.linear_weight),
                (st.b.tobytes(), st.a.tobytes()))


    def start(self):
        """Begin a sample-by-sample simulation of all members (for closed
        loops); see :class:`StageBatchSimulation`."""
        return StageBatchSimulation(self)


def _clip(x, lo, hi, out):
    """min(max(x, lo), hi) elementwise into ``out`` (two ufunc calls: np.clip's Python
    wrapper costs more than both)."""
    np.maximum(x, lo, out=out)
    return np.minimum(out, hi, out=out)


def _read_only(arr):
    arr.setflags(write=False)
    return arr


def _warn_members(records, fs, stacklevel=4):
    """One StageSaturationWarning per place of the chain that limited any member."""
    for place in ("input_saturation", "output_saturation", "adc_saturation"):
        hit = [r for r in records if getattr(r, place).occurred]
        if not hit:
            continue
        seeds = ", ".join(str(r.seed) for r in hit[:8]) + (", ..." if len(hit) > 8 else "")
        prefix = (f"{len(hit)} of {len(records)} batch members (seeds {seeds}); seed "
                  f"{hit[0].seed}: ") if len(records) > 1 else ""
        warnings.warn(prefix + getattr(hit[0], place).message(fs), StageSaturationWarning,
                      stacklevel=stacklevel)


class StageBatchSimulation:
    """Sample-by-sample run of a :class:`StageBatch`, all members at once.

    The arithmetic of :meth:`StageSimulation.step` on arrays of shape (N,):
    the DAC and ADC quantisers (round half to even), the amplifier limits,
    the play operators, the direct-form II transposed plant filter and each
    member's noise stream (its own generator, drawn in the same blocks).
    Member i is therefore identical, float for float, to a
    :class:`StageSimulation` of ``batch.stages[i]`` driven by the same inputs.

    Causality as in :class:`StageSimulation`: :attr:`v_y_V` is v_y[k];
    :meth:`step` applies u_c[k] and returns v_y[k+1].

    Saturation is recorded per member; the warnings are issued by
    :meth:`records` (one per place of the chain, naming the members), not
    while stepping, which keeps a step cheap: about 20 us for N = 32
    (``benchmarks/bench_loop_seeds.py``), against 6 us for one
    :class:`StageSimulation` step.  The signals are kept in blocks of
    4096 samples: about 56 N bytes per sample.
    """

    _BLOCK = StageSimulation._BLOCK
    #: rows of a block of the signal log
    _SIGNALS = ("u", "u_dac", "v_cmd", "v_a", "y", "analog", "v_y")

    def __init__(self, batch):
        if not isinstance(batch, StageBatch):
            raise TypeError(f"batch must be a StageBatch, got {type(batch).__name__}")
        self._batch = bt = batch
        n = bt.size
        self._rngs = [np.random.default_rng(st.seed) for st in bt.stages]
        # states and coefficients are held transposed, (order or n_plays, N): row j is
        # one state of every member.  Constants are 0-d arrays: a ufunc takes them
        # faster than Python floats, with the same values.
        order = bt.a.shape[1] - 1
        self._z, self._z_next = np.zeros((order, n)), np.empty((order, n))
        self._z_tmp = np.empty((order, n))
        self._b0, self._b1 = bt.b[:, 0].copy(), np.ascontiguousarray(bt.b[:, 1:].T)
        self._a1 = np.ascontiguousarray(bt.a[:, 1:].T)
        self._x = np.empty(n)
        self._gain = np.array(bt.gain)
        self._out = (np.array(bt.out_lo), np.array(bt.out_hi))
        # the amplifier limits cannot act when the DAC's extreme codes stay inside them
        # (gain * u_dac is monotone in u_dac): then v_a = v_cmd exactly, as in the
        # single run, and the limits are skipped
        dac, adc = bt.dac, bt.adc
        self._amp_limits = not (bt.out_lo <= bt.gain * (dac.code_lo * dac.lsb)
                                and bt.gain * (dac.code_hi * dac.lsb) <= bt.out_hi)
        self._dac = tuple(np.array(float(x)) for x in (dac.lsb, dac.code_lo, dac.code_hi))
        self._adc = tuple(np.array(float(x)) for x in (adc.lsb, adc.code_lo, adc.code_hi))
        if bt.thresholds_V is None:
            self._plays = None
        else:
            r = np.ascontiguousarray(bt.thresholds_V.T)
            self._r, self._w = r, np.ascontiguousarray(bt.weights.T)
            self._w0 = bt.linear_weight
            self._plays = 0.0 + r                   # initial_state(0.0): 0.0 + r
            self._pm_r = np.stack([-r, r])          # v_a + (-r) is v_a - r exactly
            self._bounds = np.empty_like(self._pm_r)
            self._h = np.empty((r.shape[0] + 1, n))
            self._h_sum = np.empty(n)
            self._h_rows = list(self._h[2:])
        self._blocks = []               # (7, BLOCK, N): the signals of _SIGNALS by sample
        self._k = 0
        self._j = 0                     # row of sample k in the last block
        self._new_block()
        self._measure(np.zeros(n))

    def _new_block(self):
        bt = self._batch
        noise = np.empty((self._BLOCK, bt.size))
        for i, (rng, st) in enumerate(zip(self._rngs, bt.stages)):
            noise[:, i] = st.noise_rms * rng.standard_normal(self._BLOCK)
        self._noise = noise
        self._log = np.empty((len(self._SIGNALS), self._BLOCK, bt.size))
        self._blocks.append(self._log)

    @staticmethod
    def _convert(v, out, lsb, code_lo, code_hi):
        # _Converter.convert_scalar elementwise: round half to even, limit the code (its
        # limiting of v first only keeps round() from overflowing; the code is the same)
        np.divide(v, lsb, out)
        np.rint(out, out)
        _clip(out, code_lo, code_hi, out)
        return np.multiply(out, lsb, out)

    def _measure(self, y):
        """Measurement v_y[k] from the noise-free output y[k] (k = self._k)."""
        log, j = self._log, self._j
        analog = np.add(y, self._noise[j], log[5, j])
        self._v_y = self._convert(analog, log[6, j], *self._adc)

    @property
    def size(self):
        """Number of members N."""
        return self._batch.size

    @property
    def seeds(self):
        """The members' noise seeds."""
        return self._batch.seeds

    @property
    def k(self):
        """Number of samples applied so far (index of the current measurement)."""
        return self._k

    @property
    def v_y_V(self):
        """Measurements v_y[k] of the members at the current sample [V], shape (N,)."""
        return self._v_y.copy()

    @property
    def state(self):
        """Internal state after :attr:`k` samples (copies).

        Returns
        -------
        filter_state : ndarray, shape (N, order)
            Row i: ``StageSimulation.state[0]`` of member i.
        play_outputs_V : ndarray, shape (N, n_plays)
            Row i: ``StageSimulation.state[1]`` of member i ((N, 0) for
            linear stages).
        """
        plays = (np.empty((self.size, 0)) if self._plays is None else self._plays.T.copy())
        return self._z.T.copy(), plays

    def step(self, u_c):
        """Apply u_c[k] to every member for one period; return v_y[k+1].

        Parameters
        ----------
        u_c : float or array_like, shape (N,)
            Control input of each member [V] (a scalar is applied to all).

        Returns
        -------
        ndarray, shape (N,)
            The next measurement of each member [V] (a new array).
        """
        n = self._batch.size
        u = np.asarray(u_c, dtype=float)
        if u.shape != (n,):
            if u.ndim > 1 or (u.ndim == 1 and u.shape[0] != n):
                raise ValueError(f"u_c must be a scalar or of shape ({n},), got shape "
                                 f"{u.shape} at sample {self._k}")
            u = np.full(n, float(u))
        if not np.isfinite(u).all():
            raise ValueError(f"u_c must be finite, got {u!r} at sample {self._k}")
        return self._advance(u).copy()

    def _advance(self, u, u_b=None):
        """:meth:`step` with u_c = u (+ u_b) for finite arrays of shape (N,) (or u a
        float); returns v_y[k+1] as a view that later steps do not change."""
        log, j = self._log, self._j
        u_c = log[0, j]
        if u_b is None:
            u_c[...] = u
        else:
            np.add(u, u_b, u_c)
        u_dac = self._convert(u_c, log[1, j], *self._dac)
        v_a = v_cmd = np.multiply(u_dac, self._gain, log[2, j])
        if self._amp_limits:
            v_a = _clip(v_cmd, *self._out, log[3, j])
        if self._plays is not None:
            # the plays: y_i <- min(max(y_i, v_a - r_i), v_a + r_i)
            plays, bounds, h = self._plays, self._bounds, self._h
            np.add(v_a, self._pm_r, bounds)
            _clip(plays, bounds[0], bounds[1], plays)
            # v_h = w0 v_a, then + w_i (y_i - r_i) play by play, in that order as
            # StageSimulation.step adds them (row by row: cheaper than a cumulative sum
            # over axis 0 for N in the hundreds)
            np.multiply(self._w0, v_a, h[0])
            np.subtract(plays, self._r, h[1:])
            np.multiply(h[1:], self._w, h[1:])
            v_h = np.add(h[0], h[1], self._h_sum)
            for row in self._h_rows:
                np.add(v_h, row, v_h)
        else:
            v_h = v_a
        x_in = np.divide(v_h, self._gain, self._x)
        # direct form II transposed, StageSimulation.step's arithmetic per member:
        # y = z0 + b0 x;  z_i = (z_{i+1} + x b_{i+1}) - y a_{i+1};  z_last = x b - y a
        z, z_new = self._z, self._z_next
        y_k = np.multiply(self._b0, x_in, log[4, j])
        np.add(z[0], y_k, y_k)
        np.multiply(x_in, self._b1, z_new)
        np.add(z_new[:-1], z[1:], z_new[:-1])
        np.multiply(y_k, self._a1, self._z_tmp)
        np.subtract(z_new, self._z_tmp, z_new)
        self._z, self._z_next = z_new, z
        self._k += 1
        self._j = j + 1
        if self._j == self._BLOCK:
            self._new_block()
            self._j = 0
        self._measure(z_new[0])
        return self._v_y

    def record(self, i):
        """The samples applied so far to member ``i`` as a :class:`StageRecord`
        (no warning; see :meth:`records`)."""
        i = check_integer("i", i, minimum=0)
        if i >= self.size:
            raise ValueError(f"i must be below the batch size {self.size}, got {i}")
        return self._records([i])[0]

    def records(self):
        """The samples applied so far, one :class:`StageRecord` per member.

        Issues one :class:`StageSaturationWarning` per place of the chain
        (DAC/amplifier input, amplifier output, ADC) where any member was
        limited, naming the members.

        Returns
        -------
        list of StageRecord
            Record i is identical, float for float, to
            ``StageSimulation.record()`` of member i.
        """
        records = self._records(range(self.size))
        _warn_members(records, self._batch.fs, stacklevel=3)
        return records

    def _records(self, members):
        bt = self._batch
        n = self._k
        members = list(members)

        def signal(name):
            # blocks of (BLOCK, N) by sample -> (len(members), n): a row per member
            row = self._SIGNALS.index(name)
            out = np.empty((len(members), n))
            for start, blk in zip(range(0, n, self._BLOCK), self._blocks):
                stop = min(start + self._BLOCK, n)
                out[:, start:stop] = blk[row][:stop - start][:, members].T
            return out

        u_dac, v_cmd, y, v_y = (signal(name) for name in ("u_dac", "v_cmd", "y", "v_y"))
        v_a = signal("v_a") if self._amp_limits else v_cmd
        sat_in = _saturations("DAC/amplifier input", bt.dac.limits, signal("u"))
        sat_out = _saturations("amplifier output", (bt.out_lo, bt.out_hi), v_cmd)
        sat_adc = _saturations("ADC", bt.adc.limits, signal("analog"))
        t = np.arange(n) / bt.fs
        return [StageRecord(t, u_dac[m], v_a[m], paper.UM_PER_VOLT * y[m], v_y[m], sat_in[m],
                            sat_out[m], sat_adc[m], bt.stages[i].seed)
                for m, i in enumerate(members)]


def _saturations(where, limits, requested):
    """:meth:`Saturation.of` of each row of ``requested``, shape (M, n)."""
    outside = ((requested < limits[0]) | (requested > limits[1])).any(axis=1)
    return [Saturation.of(where, limits, row) if out else Saturation(where, tuple(limits))
            for row, out in zip(requested, outside)]


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


# --- Table 4 Case I experiment and calibration --------------------------------
def case_I_input(amplitude_V, stage=None, periods=3, frequency_Hz=None):
    """u_c [V] of the Table 4 experiment: a triangle of the actuator voltage
    from 0 to ``amplitude_V`` [V] (u_c from 0 to amplitude/gain)."""
    gain = paper.AMPLIFIER_GAIN if stage is None else stage.gain
    fs = paper.SAMPLING_FREQUENCY_HZ if stage is None else stage.fs
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_Hz is None else frequency_Hz
    return signals.triangle(check_positive("amplitude_V", amplitude_V) / gain, f,
                            periods=periods, fs=fs)[1]


def run_case_I(stage, amplitudes_V=None, periods=3):
    """Run the Table 4 Case I experiment (open loop, no compensator).

    Parameters
    ----------
    stage : VirtualStage
    amplitudes_V : sequence of float, optional
        Actuator amplitudes [V], each positive; default Table 4's 10 ... 40 V.
    periods : int, optional
        Periods of the triangle per amplitude.

    Returns
    -------
    dict
        {actuator amplitude [V]: StageRecord}.

    Raises
    ------
    TypeError, ValueError
        Naming the argument, before any run: ``stage`` not a :class:`VirtualStage`,
        ``amplitudes_V`` empty or with an amplitude that is not positive, ``periods``
        not a positive integer.
    """
    check_type("stage", stage, VirtualStage, "a VirtualStage")
    amplitudes_V = _check_amplitudes(
        paper.HYSTERESIS_TEST["actuator_amplitudes_V"] if amplitudes_V is None
        else amplitudes_V)
    check_integer("periods", periods, minimum=1)
    return {A: stage.run(case_I_input(A, stage, periods)) for A in amplitudes_V}


def _check_amplitudes(amplitudes_V):
    """The amplitudes as floats, all checked before the first (slow) run."""
    if isinstance(amplitudes_V, (str, bytes)) or not isinstance(amplitudes_V, Iterable):
        raise TypeError("amplitudes_V must be a sequence of amplitudes [V], got "
                        f"{type(amplitudes_V).__name__}")
    amplitudes_V = [check_positive(f"amplitudes_V[{i}]", A) for i, A in enumerate(amplitudes_V)]
    if not amplitudes_V:
        raise ValueError("amplitudes_V must hold at least one amplitude, got none")
    return amplitudes_V


def case_I_hysteresis(records):
    """Hysteresis % (eq. 25-26) of each loop: measured displacement
    (3 um/V x v_y) against actuator voltage v_a, as an experimenter sees it.

    Parameters
    ----------
    records : dict
        {amplitude: StageRecord}, e.g. from :func:`run_case_I` or
        :func:`piezolib.problem.stage_data.load_hysteresis_loops`.

    Returns
    -------
    dict
        {amplitude [V]: hysteresis %}.

    Raises
    ------
    TypeError, ValueError
        ``records`` is not a non-empty dict of :class:`StageRecord`.
    """
    check_type("records", records, dict, "a dict {amplitude [V]: StageRecord}")
    if not records:
        raise ValueError("records must hold at least one StageRecord, got an empty dict")
    for A, rec in records.items():
        check_type(f"records[{A!r}]", rec, StageRecord, "a StageRecord")
    return {A: hysteresis_percent(rec.v_a_V, rec.x_measured_um) for A, rec in records.items()}


def _check_targets(targets):
    """{amplitude [V]: hysteresis [%]} with both positive and finite (log-parameter fit)."""
    if not isinstance(targets, dict) or not targets:
        raise TypeError(f"targets must be a non-empty dict {{amplitude [V]: %}}, got {targets!r}")
    return {check_positive("targets (amplitude)", A):
            check_positive(f"targets[{A!r}] (hysteresis %)", value)
            for A, value in targets.items()}


def calibrate_hysteresis(law=CALIBRATED_HYSTERESIS, targets=None):
    """Re-derive the hysteresis parameters from Table 4 Case I only.

    Least squares on (log c, log rho) of :class:`HysteresisLaw` so that the
    noise-free stage's Case I hysteresis % matches Table 4's first row.  The
    noise is switched off so that the parameters do not depend on one noise
    realisation; everything else (DAC, ADC, dynamics of G) is as in the
    experiment files.

    Parameters
    ----------
    law : HysteresisLaw, optional
        Starting point; its fixed fields (threshold grid) are kept.
    targets : dict, optional
        {amplitude [V]: %}; default Table 4 Case I.

    Returns
    -------
    law : HysteresisLaw
        Calibrated law (c and rho rounded to 6 significant digits).
    achieved : dict
        {amplitude: %} of the noise-free stage with that law.

    Raises
    ------
    TypeError, ValueError
        ``law`` not a :class:`HysteresisLaw`; ``targets`` not a dict of positive, finite
        amplitudes and percentages.
    """
    check_type("law", law, HysteresisLaw, "a HysteresisLaw")
    if targets is None:
        targets = paper.table4().loc["case_I"].to_dict()
    targets = _check_targets(targets)
    amplitudes = sorted(targets)
    want = np.array([targets[A] for A in amplitudes])

    def percents(law_):
        stage = VirtualStage(seed=0, noise_rms_V=0.0, hysteresis=law_)
        got = case_I_hysteresis(run_case_I(stage, amplitudes))
        return np.array([got[A] for A in amplitudes])

    def residual(p):
        return percents(replace(law, density_per_V=math.exp(p[0]), decay_V=math.exp(p[1]))) - want

    sol = opt.least_squares(residual, [math.log(law.density_per_V), math.log(law.decay_V)],
                            diff_step=1e-4, xtol=1e-10, ftol=1e-10)
    fitted = replace(law, density_per_V=float(f"{math.exp(sol.x[0]):.6g}"),
                     decay_V=float(f"{math.exp(sol.x[1]):.6g}"))
    return fitted, dict(zip(amplitudes, percents(fitted).tolist()))
