"""The 10 kHz control loop of Fig. 1 on the virtual stage, and the experiments of Sec. V.

Signal flow, one DAQ period T = 0.1 ms (paper Fig. 1 and Sec. II)::

    v_r[k] --feedforward (eq. 14)--------------------------> u_f[k] --+
    v_r[k] - v_y[k] = v_e[k] --discrete controller K_d-----> u_b[k] --+--> u_c[k] --> stage
    v_y[k+1] <-- stage (DAC, amplifier, hysteresis, G, sensor, ADC)

At sample k the DAQ reads v_y[k] (which depends on u_c[0..k-1] only), the
controller computes u_b[k] from v_e[k] without further delay (the Tustin
controller's direct feedthrough acts within the sample, i.e. the computation
time is taken as negligible against 100 us), and u_c[k] = u_f[k] + u_b[k] is
written to the DAC and held for one period.  The desired displacement is
x_r = 3 um/V * v_r and the error is e[k] = x_r[k] - 3 um/V * v_y[k] = 3 um/V *
v_e[k], the error the loop itself sees.

The feedforward path depends on the reference only, so u_f is computed for
the whole record first (:func:`piezolib.hysteresis.feedforward`, equal to the
stateful :class:`~piezolib.hysteresis.DahlFeedforward` to rounding); only the
feedback needs a sample-by-sample loop: for an n-state controller one
(n+1) x (n+1) matrix-vector product [x_{k+1}; u_b[k]] = [[A, B], [C, D]]
[x_k; v_e[k]] and one :meth:`StageSimulation.step
<piezolib.problem.stage.StageSimulation.step>` per sample, 5-10 us.  Without
feedback the stage runs vectorised (:meth:`VirtualStage.run
<piezolib.problem.stage.VirtualStage.run>`).

The three cases of Sec. V
-------------------------

====  =========================================  ===================================
case  paper                                      here (``run_case``)
====  =========================================  ===================================
I     open loop without compensator              u_c = (v_r - x0) / g, no feedback
II    open loop with Dahl feedforward            u_c = u_f = (x_r - x0 + H(x_r)) / g_a
III   Dahl feedforward + mu feedback controller  u_c = u_f + K_d v_e
====  =========================================  ===================================

x0 is the Dahl model's output offset (its displacement zero, a workbook
extension of eq. 13; 0 for the paper's model, see :mod:`piezolib.hysteresis`).
What Case I applies is not stated for the tracking test.  The workbook reads
"without compensator" as eq. 14 with the hysteresis term removed: the
reference mapped to the amplifier input through the static part of the same
model, (v_r - x0) / g_a, with g_a and x0 of the Dahl model used in Case II.
Then Case I and Case II differ by exactly the Dahl term H(x_r) / g_a, which
is what the paper's "Case II w.r.t. Case I" rows credit to the compensator;
and Sec. IV-A says that besides the hysteresis model only "the inverse of the
piezoelectric coefficient" is needed.  (The paper's g_a = 0.925 V/V is within 3 % of
G(0) = 0.8976, so on its hardware 1/g_a and 1/G(0) are nearly the same map.)
In the hysteresis test (Table 4) the paper applies the actuator voltage
itself ("input voltages of 10 V ... 40 V to the piezoelectric actuator"), so
there Case I uses g = 1: u_c is the triangle from 0 to A/10 V, exactly the
experiment the virtual stage is calibrated on.

Saturation is never hidden: every :class:`LoopResult` carries the stage's
:class:`~piezolib.problem.stage.Saturation` summaries (DAC/amplifier input,
amplifier output, ADC) and the experiments tabulate the counts.
"""

import math
from dataclasses import dataclass, field
from numbers import Real

import control as ct
import numpy as np
import pandas as pd

from piezolib import paper, signals
from piezolib._checks import check_finite_array, check_integer, check_positive, check_proper, check_siso
from piezolib.robust.discrete import DiscreteController, discretize
from piezolib.hysteresis.dahl import (DahlModel, feedforward as dahl_feedforward, table4_measure,
                         table4_reference, workbook_dahl_fit)
from piezolib.metrics import improvement_percent, tracking_error_percent

__all__ = [
    "CASES", "LoopResult", "discrete_controller", "run_loop", "run_case",
    "ExperimentResult", "hysteresis_test", "tracking_test", "tracking_reference",
    "tracking_periods", "case_table", "MIN_MEASURED_S", "DISCARD_PERIODS",
]

#: The cases of Sec. V (Tables 4-5, Fig. 14-15).
CASES = {
    "I": "open loop without compensator",
    "II": "open loop with Dahl feedforward",
    "III": "Dahl feedforward + feedback controller",
}

#: Shortest steady-state record of the tracking test [s] (whole periods).
MIN_MEASURED_S = 0.1

#: Periods left out before measuring: the loop starts from rest and its
#: start-up lasts into the second period (the first lower reversal of the
#: closed loop has a visibly larger error); from the third period on the
#: error repeats period after period to within the sensor noise.
DISCARD_PERIODS = 2

#: A controller output beyond this [V] means an unstable loop (the DAC range is -2 ... 12 V).
_DIVERGED_V = 1e9

# --------------------------------------------------------------------------- controller
def discrete_controller(K, fs=paper.SAMPLING_FREQUENCY_HZ):
    """The controller as a discrete state-space model at ``fs``, or None.

    Parameters
    ----------
    K : None, float, control.LTI or DiscreteController
        ``None``: no feedback.  A real number: a static gain [V/V].  A
        continuous-time SISO model (v_e -> u_b): discretised by Tustin with
        :func:`piezolib.discretize.discretize` (pre-warped at its sharpest
        feature).  A discrete-time SISO model: used as it is; its sample time
        must be 1/fs.  A :class:`~piezolib.robust.DiscreteController`:
        its ``K``.
    fs : float
        Loop rate [Hz].

    Returns
    -------
    control.StateSpace or None
    """
    fs = check_positive("fs", fs)
    if K is None:
        return None
    if isinstance(K, DiscreteController):
        K = K.K
    if isinstance(K, Real) and not isinstance(K, bool):
        if not math.isfinite(K):
            raise ValueError(f"controller must be finite, got {K!r}")
        return ct.ss([], [], [], [[float(K)]], 1.0 / fs, inputs="v_e", outputs="u_b",
                     name="K_static")
    if not isinstance(K, ct.LTI):
        raise TypeError("controller must be None, a real gain, a control.StateSpace / "
                        f"TransferFunction or a DiscreteController, got {type(K).__name__}")
    check_siso("controller", K)
    check_proper("controller", K)
    if K.isctime(strict=True):
        return discretize(K, fs).K
    if K.dt is True or not math.isclose(float(K.dt), 1.0 / fs, rel_tol=1e-9):
        raise ValueError(f"controller must have sample time 1/fs = {1.0 / fs:g} s, "
                         f"got dt = {K.dt!r}")
    Kd = ct.ss(K)
    if not np.all(np.isfinite(Kd.A)) or not np.all(np.isfinite(Kd.D)):
        raise ValueError("controller has non-finite matrices")
    return Kd


def _augmented(Kd):
    """M = [[A, B], [C, D]]: [x_{k+1}; u_b[k]] = M [x_k; v_e[k]]."""
    n = Kd.nstates
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:], M[n:, :n], M[n:, n:] = Kd.A, Kd.B, Kd.C, Kd.D
    return M


# --------------------------------------------------------------------------- one run
@dataclass(frozen=True, eq=False)
class LoopResult:
    """One run of the loop of Fig. 1 (sample k at t = k T).

    Attributes
    ----------
    v_r_V : ndarray
        Reference voltage [V]; x_r = 3 um/V * v_r.
    u_f_V : ndarray
        Feedforward part of the control input [V].
    u_b_V : ndarray
        Feedback part [V] (zeros without a controller).
    record : piezolib.problem.stage.StageRecord
        What the stage applied (``u_c_V`` as the DAC produced it) and measured.
    feedforward : str
        Description of the feedforward path.
    controller : control.StateSpace or None
        The discrete controller used.
    """

    v_r_V: np.ndarray
    u_f_V: np.ndarray
    u_b_V: np.ndarray
    record: object
    feedforward: str
    controller: object = field(default=None, repr=False)

    def __len__(self):
        return len(self.v_r_V)

    @property
    def t_s(self):
        """Time [s]."""
        return self.record.t_s

    @property
    def u_c_requested_V(self):
        """u_f + u_b as computed, before the DAC limits and quantises it [V]."""
        return self.u_f_V + self.u_b_V

    @property
    def v_y_V(self):
        """Measured sensor output [V]."""
        return self.record.v_y_V

    @property
    def x_r_um(self):
        """Desired displacement 3 um/V * v_r [um]."""
        return paper.UM_PER_VOLT * self.v_r_V

    @property
    def x_um(self):
        """Measured displacement 3 um/V * v_y [um]."""
        return self.record.x_measured_um

    @property
    def error_um(self):
        """Tracking error e = x_r - 3 um/V * v_y [um] (= 3 um/V * v_e)."""
        return self.x_r_um - self.x_um

    @property
    def saturation(self):
        """(DAC/amplifier input, amplifier output, ADC) Saturation summaries."""
        r = self.record
        return (r.input_saturation, r.output_saturation, r.adc_saturation)

    @property
    def saturation_count(self):
        """Samples limited anywhere in the chain (sum over the three places)."""
        return sum(s.count for s in self.saturation)

    def steady_state(self, frequency_hz, discard_periods=DISCARD_PERIODS):
        """Slice of the samples after the first ``discard_periods`` periods."""
        frequency_hz = check_positive("frequency_hz", frequency_hz)
        discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
        fs = 1.0 / (self.t_s[1] - self.t_s[0])
        start = int(round(discard_periods * fs / frequency_hz))
        if start >= len(self) - 2:
            raise ValueError(f"discarding {discard_periods} period(s) of {frequency_hz:g} Hz "
                             f"leaves no samples of the {len(self)}-sample run")
        return slice(start, None)

    def tracking_error_percent(self, frequency_hz, discard_periods=DISCARD_PERIODS,
                               range_um=None):
        """Tracking error % (:func:`piezolib.metrics.tracking_error_percent`)
        over the steady state; ``range_um`` defaults to the reference's range."""
        s = self.steady_state(frequency_hz, discard_periods)
        return tracking_error_percent(self.x_r_um[s], self.x_um[s], range_um)


def _feedforward_signal(feedforward, v_r):
    if feedforward is None:
        return np.zeros_like(v_r), "none"
    if isinstance(feedforward, DahlModel):
        return dahl_feedforward(feedforward, v_r), f"Dahl eq. 14 (g_a = {feedforward.g_a:.4g})"
    if isinstance(feedforward, Real) and not isinstance(feedforward, bool):
        g = check_positive("feedforward", feedforward)
        return v_r / g, f"static v_r / {g:.4g}"
    if isinstance(feedforward, tuple) and len(feedforward) == 2 \
            and all(isinstance(p, Real) and not isinstance(p, bool) for p in feedforward):
        g = check_positive("feedforward gain", feedforward[0])
        x0 = float(feedforward[1])
        if not math.isfinite(x0):
            raise ValueError(f"feedforward offset must be finite, got {x0!r}")
        return (v_r - x0) / g, f"static (v_r - {x0:.4g}) / {g:.4g}"
    raise TypeError("feedforward must be None, a positive gain g (u_f = v_r / g), a pair "
                    "(g, x0) (u_f = (v_r - x0) / g) or a hysteresis.DahlModel (eq. 14), "
                    f"got {type(feedforward).__name__}")


def run_loop(stage, v_r, *, feedforward=None, controller=None):
    """Run the loop of Fig. 1 on a stage at its sample rate.

    Parameters
    ----------
    stage : piezolib.problem.stage.VirtualStage
        Each run starts from the stage's rest state with its noise seed.
    v_r : array_like
        Reference voltage [V] at the stage's rate, 1-D (x_r = 3 um/V * v_r).
    feedforward : None, float, (float, float) or DahlModel
        ``None``: u_f = 0.  A positive number g: u_f = v_r / g (static map,
        no hysteresis compensation; g = 1 applies v_r itself).  A pair
        (g, x0): u_f = (v_r - x0) / g.  A
        :class:`~piezolib.hysteresis.DahlModel` in the workbook convention
        (v = u_c, x = v_y, both in V): u_f = (x_r - x0 + H(x_r)) / g_a
        (eq. 14, x0 = the model's offset) with x_r = v_r in sensor volts,
        H from the model's start state.
    controller : None, float, control.LTI or DiscreteController
        Feedback K on v_e = v_r - v_y (see :func:`discrete_controller`);
        ``None`` runs open loop.

    Returns
    -------
    LoopResult

    Raises
    ------
    ValueError
        Bad reference, a controller at another sample time, or a controller
        output that stops being finite (an unstable loop).
    """
    from piezolib.problem.stage import VirtualStage     # stage is imported lazily by the package
    if not isinstance(stage, VirtualStage):
        raise TypeError(f"stage must be a VirtualStage, got {type(stage).__name__}")
    v_r = check_finite_array("v_r", v_r, ndim=1, min_length=2)
    u_f, ff_text = _feedforward_signal(feedforward, v_r)
    Kd = discrete_controller(controller, stage.fs)
    if Kd is None:
        record = stage.run(u_f)
        return LoopResult(v_r, u_f, np.zeros_like(v_r), record, ff_text, None)
    u_b, record = _closed_loop(stage, v_r, u_f, _augmented(Kd))
    return LoopResult(v_r, u_f, u_b, record, ff_text, Kd)


def _closed_loop(stage, v_r, u_f, M):
    """Sample-by-sample loop; returns (u_b, StageRecord)."""
    n = M.shape[0] - 1
    sim = stage.start()
    step = sim.step
    w = np.zeros(n + 1)
    u_b = np.empty(len(v_r))
    v_y = sim.v_y_V
    for k, (r, f) in enumerate(zip(v_r.tolist(), u_f.tolist())):
        w[n] = r - v_y
        w = M @ w
        ub = float(w[n])
        # the DAC limits any finite request, so only a growing controller
        # state can get here; stop long before it overflows (NaN fails too)
        if not abs(ub) < _DIVERGED_V:
            raise ValueError(f"the controller output diverged at sample {k} "
                             f"(t = {k / stage.fs:.4f} s): is the closed loop stable?")
        u_b[k] = ub
        v_y = step(f + ub)
    return u_b, sim.record()


# --------------------------------------------------------------------------- the cases
def run_case(case, stage, v_r, dahl, controller=None, case_I_gain=None):
    """Run Case I, II or III of Sec. V on one reference.

    Parameters
    ----------
    case : {"I", "II", "III"}
    stage : VirtualStage
    v_r : array_like
        Reference [V].
    dahl : DahlModel or None
        The feedforward model (Cases II, III) whose g_a and x0 also map the
        reference in Case I.  None: the workbook's shared model,
        :func:`piezolib.hysteresis.workbook_dahl_fit`.
    controller : see :func:`discrete_controller`
        Required for Case III, ignored otherwise.
    case_I_gain : float, optional
        g of Case I, applied without offset (u_c = v_r / g); default: the
        static part of the Dahl model, u_c = (v_r - x0) / g_a (module
        docstring).

    Returns
    -------
    LoopResult
    """
    if case not in CASES:
        raise ValueError(f"case must be one of {sorted(CASES)}, got {case!r}")
    if dahl is None:
        dahl = workbook_dahl_fit().model
    if not isinstance(dahl, DahlModel):
        raise TypeError(f"dahl must be a hysteresis.DahlModel, got {type(dahl).__name__}")
    if case == "I":
        static = ((dahl.g_a, dahl.x0) if case_I_gain is None
                  else check_positive("case_I_gain", case_I_gain))
        return run_loop(stage, v_r, feedforward=static)
    if case == "II":
        return run_loop(stage, v_r, feedforward=dahl)
    if controller is None:
        raise ValueError("case III needs a controller")
    return run_loop(stage, v_r, feedforward=dahl, controller=controller)


def case_table(case_values, columns):
    """Table 4/5 layout: the three case rows and the three improvement rows.

    Parameters
    ----------
    case_values : dict
        {"I": values, "II": values, "III": values}, one value per column.
    columns : pandas.Index
        Column index (amplitudes [V] or frequencies [Hz]).

    Returns
    -------
    pandas.DataFrame
        Rows as in :func:`piezolib.paper.table4` (its row index).
    """
    I, II, III = (np.asarray(case_values[c], dtype=float) for c in ("I", "II", "III"))
    data = [I, II, III, improvement_percent(I, II), improvement_percent(I, III),
            improvement_percent(II, III)]
    return pd.DataFrame(data, index=paper.case_rows_index(), columns=columns)


@dataclass(frozen=True, eq=False)
class ExperimentResult:
    """A Table 4 or Table 5 experiment.

    Attributes
    ----------
    table : pandas.DataFrame
        Same layout as :func:`piezolib.paper.table4` / :func:`~piezolib.paper.table5`.
    runs : dict
        {(case, column value): LoopResult}.
    saturation : pandas.DataFrame
        Limited samples per case (rows) and column: DAC/amplifier input +
        amplifier output + ADC.
    """

    table: pd.DataFrame
    runs: dict = field(repr=False)
    saturation: pd.DataFrame


def _positive_values(name, values, default):
    return [check_positive(name, v) for v in (default if values is None else values)]


def _case_III_controller(controller, stage):
    if controller is None:
        raise ValueError("controller must be given (Case III)")
    return discrete_controller(controller, stage.fs)


def _experiment(columns, run, measure):
    values, runs, sat = {c: [] for c in CASES}, {}, {c: [] for c in CASES}
    for col in columns:
        for case in CASES:
            result = run(case, col)
            runs[(case, float(col))] = result
            values[case].append(measure(result, col))
            sat[case].append(result.saturation_count)
    table = case_table(values, columns)
    saturation = pd.DataFrame([sat[c] for c in CASES], index=pd.Index(
        [f"case_{c}" for c in CASES], name="row"), columns=columns)
    return ExperimentResult(table, runs, saturation)


def hysteresis_test(stage, dahl, controller, amplitudes_V=None, periods=4,
                    discard_periods=DISCARD_PERIODS):
    """Table 4: hysteresis % of 10 Hz triangles, Cases I-III.

    The reference of each amplitude A is :func:`piezolib.hysteresis.table4_reference`
    (0 ... A/10 V); Case I applies it directly (g = 1, the actuator voltage
    triangle of the paper), Cases II-III read it as x_r = v_r.  Each loop is
    measured by :func:`piezolib.hysteresis.table4_measure` (x = 3 um/V v_y
    against 10 v_r, first ``discard_periods`` left out).

    Parameters
    ----------
    stage : VirtualStage
    dahl : DahlModel or None
        None: the workbook's shared model (:func:`run_case`).
    controller : see :func:`discrete_controller`
        Case III's feedback (not None).
    amplitudes_V : sequence of float, optional
        Actuator amplitudes; default 10, 20, 30, 40 V.
    periods, discard_periods : int

    Returns
    -------
    ExperimentResult
    """
    amplitudes_V = _positive_values("amplitudes_V", amplitudes_V,
                                    paper.HYSTERESIS_TEST["actuator_amplitudes_V"])
    periods = check_integer("periods", periods, minimum=discard_periods + 1)
    Kd = _case_III_controller(controller, stage)
    refs = {A: table4_reference(A, periods=periods, fs=stage.fs)[1] for A in amplitudes_V}

    def run(case, A):
        return run_case(case, stage, refs[A], dahl, Kd, case_I_gain=1.0)

    def measure(result, A):
        return table4_measure(result.v_r_V, result.v_y_V, discard_periods=discard_periods,
                              fs=stage.fs).percent

    return _experiment(pd.Index(amplitudes_V, name="amplitude_V"), run, measure)


def tracking_periods(frequency_hz, discard_periods=DISCARD_PERIODS,
                     min_measured_s=MIN_MEASURED_S):
    """Periods to simulate: ``discard_periods`` plus whole periods covering
    at least ``min_measured_s`` (one period at least)."""
    frequency_hz = check_positive("frequency_hz", frequency_hz)
    discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
    min_measured_s = check_positive("min_measured_s", min_measured_s)
    return discard_periods + max(1, math.ceil(min_measured_s * frequency_hz - 1e-9))


def tracking_reference(frequency_hz, periods, amplitude_um=None, fs=paper.SAMPLING_FREQUENCY_HZ):
    """v_r [V] of the tracking test: a triangle from 0 to amplitude_um / (3 um/V).

    Returns
    -------
    t : ndarray
        Time [s].
    v_r : ndarray
        Reference [V].
    """
    amplitude_um = paper.TRACKING_TEST["amplitude_um"] if amplitude_um is None else amplitude_um
    amplitude_um = check_positive("amplitude_um", amplitude_um)
    return signals.triangle(amplitude_um / paper.UM_PER_VOLT, frequency_hz, periods=periods,
                            fs=fs)


def tracking_test(stage, dahl, controller, frequencies_Hz=None, amplitude_um=None,
                  discard_periods=DISCARD_PERIODS, min_measured_s=MIN_MEASURED_S):
    """Table 5: tracking error % of 12 um triangles, Cases I-III.

    Each frequency runs :func:`tracking_periods` periods; the first
    ``discard_periods`` (start-up from rest) are left out and the tracking
    error % (:func:`piezolib.metrics.tracking_error_percent`, range = the
    commanded amplitude) is taken over the rest.

    Parameters
    ----------
    stage : VirtualStage
    dahl : DahlModel or None
        None: the workbook's shared model (:func:`run_case`).
    controller : see :func:`discrete_controller`
        Case III's feedback (not None).
    frequencies_Hz : sequence of float, optional
        Default 1, 10, 20, 30, 40, 50 Hz.
    amplitude_um : float, optional
        Default 12 um.
    discard_periods : int
    min_measured_s : float

    Returns
    -------
    ExperimentResult
    """
    frequencies_Hz = _positive_values("frequencies_Hz", frequencies_Hz,
                                      paper.TRACKING_TEST["frequencies_Hz"])
    amplitude_um = check_positive("amplitude_um", paper.TRACKING_TEST["amplitude_um"]
                                  if amplitude_um is None else amplitude_um)
    Kd = _case_III_controller(controller, stage)
    refs = {f: tracking_reference(f, tracking_periods(f, discard_periods, min_measured_s),
                                  amplitude_um, stage.fs)[1] for f in frequencies_Hz}

    def run(case, f):
        return run_case(case, stage, refs[f], dahl, Kd)

    def measure(result, f):
        return result.tracking_error_percent(f, discard_periods, range_um=amplitude_um)

    return _experiment(pd.Index(frequencies_Hz, name="frequency_Hz"), run, measure)
