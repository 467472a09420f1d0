"""The 10 kHz control loop of Fig. 1 on the virtual stage.

u_c[k] = u_f[k] + u_b[k - d]: the feedforward u_f of the whole reference
first, then the discrete controller on v_e[k] = v_r[k] - v_y[k] sample by
sample, its output applied ``d`` samples later (the computation delay,
default :data:`COMPUTATION_DELAY_SAMPLES` = 1), each u_c held for one DAQ
period.  :func:`run_loop` with ``seeds`` (or a
:class:`~piezolib.problem.stage_batch.StageBatch`) runs N copies of the loop at
once, one per noise seed, with one state array of shape (N,) per state:
member i is identical, float for float, to the single run with seed i, and
N = 32 seeds cost about four single runs
(``benchmarks/bench_loop_seeds.py``).  Timing, signal flow and start-up are
described in ``docs/controller_design.md``; the experiments of Sec. V (Cases I-III,
Tables 4-5) are in :mod:`piezolib.workbook.experiments`.
"""

import math
from collections import deque
from dataclasses import dataclass, field
from numbers import Real

import control as ct
import numpy as np

from piezolib.problem import paper
from piezolib._checks import check_finite_array, check_integer, check_positive, check_proper, check_siso
from piezolib.hysteresis.common import MODEL_REQUIREMENT, HysteresisModel
from piezolib.hysteresis.dahl import DahlModel
from piezolib.metrics import (peak_to_peak_error_percent, tracking_error_percent,
                              tracking_errors_percent)
from piezolib.robust.discrete import DiscreteController, discretize
from piezolib.robust.export import SectionFilter, SectionFilterBatch, SOSController

__all__ = ["LoopResult", "discrete_controller", "run_loop", "batch_tracking_errors",
           "DISCARD_PERIODS",
           "COMPUTATION_DELAY_SAMPLES", "SECTION_DTYPES"]

#: Whole samples between reading v_y[k] and applying the u_b computed from it.
#: A real-time loop reads the ADC at tick k, computes u_b, and can write the
#: DAC at tick k + 1 at the earliest (the DAC update of tick k has already
#: happened when the computation ends), so the loop's own delay is one sample;
#: 0 reproduces the idealised loop that applies u_b[k] at once.
COMPUTATION_DELAY_SAMPLES = 1

#: Arithmetic of the controller's sections in the loop.
SECTION_DTYPES = ("float32", "float64")

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
        :func:`piezolib.robust.discrete.discretize` (pre-warped at its sharpest
        feature).  A discrete-time SISO model: used as it is; its sample time
        must be 1/fs.  A :class:`~piezolib.robust.DiscreteController`:
        its ``K``.
    fs : float
        Loop rate [Hz].

    Returns
    -------
    control.StateSpace or None

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> Kd = discrete_controller(paper.controller())        # Tustin at 10 kHz
    >>> Kd.dt, Kd.nstates
    (0.0001, 6)
    >>> discrete_controller(None) is None, discrete_controller(0.5).D.tolist()
    (True, [[0.5]])
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
    controller : control.StateSpace, SOSController or None
        The discrete controller used.
    delay_samples : int
        Computation delay of the run [samples]: u_b_V[k] reached the DAC at
        tick k + delay_samples.

    Examples
    --------
    >>> import numpy as np
    >>> r = LoopResult(v_r_V=np.full(3, 1.0), u_f_V=np.full(3, 1.0), u_b_V=np.zeros(3),
    ...                record=None, feedforward="none", delay_samples=0)
    >>> len(r), r.x_r_um.tolist(), r.u_c_requested_V.tolist()
    (3, [3.0, 3.0, 3.0], [1.0, 1.0, 1.0])
    """

    v_r_V: np.ndarray
    u_f_V: np.ndarray
    u_b_V: np.ndarray
    record: object
    feedforward: str
    controller: object = field(default=None, repr=False)
    delay_samples: int = COMPUTATION_DELAY_SAMPLES

    def __len__(self):
        return len(self.v_r_V)

    @property
    def t_s(self):
        """Time [s]."""
        return self.record.t_s

    @property
    def u_c_requested_V(self):
        """u_f[k] + u_b[k - delay_samples] as sent to the DAC, before it limits and quantises [V]."""
        d = self.delay_samples
        applied = np.r_[np.zeros(d), self.u_b_V[:len(self.u_b_V) - d]] if d else self.u_b_V
        return self.u_f_V + applied

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

    def steady_state(self, frequency_Hz, discard_periods=DISCARD_PERIODS):
        """Slice of the samples after the first ``discard_periods`` periods."""
        return _steady_state(len(self), self.t_s[1] - self.t_s[0], frequency_Hz,
                             discard_periods)

    def tracking_error_percent(self, frequency_Hz, discard_periods=DISCARD_PERIODS,
                               range_um=None):
        """Tracking error % (:func:`piezolib.metrics.tracking_error_percent`)
        over the steady state; ``range_um`` defaults to the reference's range."""
        s = self.steady_state(frequency_Hz, discard_periods)
        return tracking_error_percent(self.x_r_um[s], self.x_um[s], range_um)

    def peak_to_peak_error_percent(self, frequency_Hz, discard_periods=DISCARD_PERIODS,
                                   range_um=None):
        """The literal reading, (max e - min e) / range % over the steady state
        (:func:`piezolib.metrics.peak_to_peak_error_percent`); ``range_um`` as in
        :meth:`tracking_error_percent`."""
        s = self.steady_state(frequency_Hz, discard_periods)
        return peak_to_peak_error_percent(self.x_r_um[s], self.x_um[s], range_um)


def _steady_state(n, dt, frequency_Hz, discard_periods):
    """:meth:`LoopResult.steady_state` of an ``n``-sample run at sample time ``dt`` [s]."""
    frequency_Hz = check_positive("frequency_Hz", frequency_Hz)
    discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
    start = int(round(discard_periods * (1.0 / dt) / frequency_Hz))
    if start >= n - 2:
        raise ValueError(f"discard_periods = {discard_periods} period(s) of {frequency_Hz:g} Hz "
                         f"leaves no samples of the {n}-sample run")
    return slice(start, None)


def _feedforward_signal(feedforward, v_r):
    if feedforward is None:
        return np.zeros_like(v_r), "none"
    if isinstance(feedforward, HysteresisModel):
        name = f"{type(feedforward).__name__}.feedforward"
        # a model of the user's own is held to what the loop needs: one finite u_f per sample
        u_f = check_finite_array(f"{name}(v_r)", feedforward.feedforward(v_r), shape=v_r.shape,
                                 real=True)
        if isinstance(feedforward, DahlModel):
            return u_f, f"Dahl eq. 14 (g_a = {feedforward.g_a:.4g})"
        return u_f, name
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
                    f"(g, x0) (u_f = (v_r - x0) / g) or {MODEL_REQUIREMENT}, got "
                    f"{type(feedforward).__name__}")


def run_loop(stage, v_r, *, feedforward=None, controller=None,
             delay_samples=COMPUTATION_DELAY_SAMPLES, sections_dtype="float32", seeds=None):
    """Run the loop of Fig. 1 on a stage at its sample rate.

    Parameters
    ----------
    stage : piezolib.problem.stage.VirtualStage or StageBatch
        Each run starts from the stage's rest state with its noise seed.  A
        :class:`~piezolib.problem.stage_batch.StageBatch` runs the loop on every
        member at once (as ``seeds`` does).
    v_r : array_like
        Reference voltage [V] at the stage's rate, 1-D (x_r = 3 um/V * v_r).
    feedforward : None, float, (float, float) or HysteresisModel
        ``None``: u_f = 0.  A positive number g: u_f = v_r / g (static map,
        no hysteresis compensation; g = 1 applies v_r itself).  A pair
        (g, x0): u_f = (v_r - x0) / g.  A hysteresis model
        (:class:`~piezolib.hysteresis.common.HysteresisModel`) in the
        workbook convention (v = u_c, x = v_y, both in V): u_f =
        ``model.feedforward(x_r)`` with x_r = v_r in sensor volts, from the
        model's start state; for a :class:`~piezolib.hysteresis.DahlModel`
        u_f = (x_r - x0 + H(x_r)) / g_a (eq. 14, x0 = the model's offset),
        for a :class:`~piezolib.hysteresis.PIModel` its exact inverse.
    controller : None, float, control.LTI, DiscreteController or SOSController
        Feedback K on v_e = v_r - v_y (see :func:`discrete_controller`);
        ``None`` runs open loop.  An exported
        :class:`~piezolib.robust.export.SOSController` (its ``fs`` must be
        the stage's) runs through the reference section filter in
        ``sections_dtype`` arithmetic: what a real-time target would run.
    delay_samples : int
        Computation delay d >= 0 [samples]: u_b computed from v_y[k] reaches
        the DAC at tick k + d (u_b = 0 before).  The feedforward, computed
        ahead from the reference, is not delayed.
    sections_dtype : {'float32', 'float64'}
        Arithmetic of an SOSController.
    seeds : sequence of int, optional
        Noise seeds (distinct, non-negative): run the loop once per seed,
        all seeds at once, on ``StageBatch.of_seeds(stage, seeds)`` (the stage with only
        its seed changed).  ``None``: one run with the stage's seed.

    Returns
    -------
    LoopResult or list of LoopResult
        A list (one result per member, in order) when ``seeds`` is given or
        ``stage`` is a StageBatch.  Result i is identical, float for float,
        to ``run_loop(stage.replace(seed=seeds[i]), ...)``; limited samples
        are counted per result and warned once per place of the chain.

    Raises
    ------
    ValueError
        Bad reference or seeds, a controller at another sample time, or a
        controller output that stops being finite (an unstable loop).

    Examples
    --------
    >>> import numpy as np
    >>> from piezolib.problem import paper
    >>> from piezolib.problem.stage import VirtualStage
    >>> result = run_loop(VirtualStage(seed=0), np.full(300, 2.0), feedforward=0.9,
    ...                   controller=paper.controller())      # 30 ms step to 6 um
    >>> len(result), result.feedforward, result.delay_samples, result.saturation_count
    (300, 'static v_r / 0.9', 1, 0)
    >>> bool(np.abs(result.error_um[-100:]).max() < 0.05)     # settled [um]
    True
    """
    from piezolib.problem.stage import VirtualStage               # imported lazily by the package
    from piezolib.problem.stage_batch import StageBatch
    # the reference and the arithmetic first: both paths below would otherwise name an
    # internal signal (u_c) or fail deep in the section filter
    v_r = check_finite_array("v_r", v_r, ndim=1, min_length=2, real=True)
    _check_sections_dtype(sections_dtype)
    if isinstance(stage, StageBatch):
        if seeds is not None:
            raise ValueError("seeds must be None when stage is a StageBatch (its members "
                             "carry their seeds)")
        return _run_batch(stage, v_r, feedforward, controller, delay_samples, sections_dtype)
    if not isinstance(stage, VirtualStage):
        raise TypeError(f"stage must be a VirtualStage or a StageBatch, got "
                        f"{type(stage).__name__}")
    if seeds is not None:
        return _run_batch(StageBatch.of_seeds(stage, seeds), v_r, feedforward, controller,
                          delay_samples, sections_dtype)
    delay = check_integer("delay_samples", delay_samples, minimum=0)
    u_f, ff_text = _feedforward_signal(feedforward, v_r)
    if isinstance(controller, SOSController):
        if not math.isclose(controller.fs, stage.fs, rel_tol=1e-9):
            raise ValueError(f"controller sections run at {controller.fs:g} Hz, the stage at "
                             f"{stage.fs:g} Hz")
        filt = SectionFilter(controller, sections_dtype)
        u_b, record = _closed_loop(stage, v_r, u_f, filt.step, delay)
        return LoopResult(v_r, u_f, u_b, record, ff_text, controller, delay)
    Kd = discrete_controller(controller, stage.fs)
    if Kd is None:
        record = stage.run(u_f)
        return LoopResult(v_r, u_f, np.zeros_like(v_r), record, ff_text, None, delay)
    u_b, record = _closed_loop(stage, v_r, u_f, _state_space_step(Kd), delay)
    return LoopResult(v_r, u_f, u_b, record, ff_text, Kd, delay)


def _check_sections_dtype(sections_dtype):
    if sections_dtype not in SECTION_DTYPES:
        raise ValueError(f"sections_dtype must be one of {SECTION_DTYPES}, "
                         f"got {sections_dtype!r}")


def _state_space_step(Kd):
    """One-sample step function x -> u_b of the discrete state-space controller."""
    M = _augmented(Kd)
    n = M.shape[0] - 1
    w = np.zeros(n + 1)

    def step(e):
        nonlocal w
        w[n] = e
        w = M @ w
        return float(w[n])
    return step


def _closed_loop(stage, v_r, u_f, controller_step, delay):
    """Sample-by-sample loop with ``delay`` samples of computation delay; (u_b, StageRecord).

    ``u_b[k]`` is the controller output computed at tick k; the DAC receives
    u_f[k] + u_b[k - delay].
    """
    sim = stage.start()
    step = sim.step
    u_b = np.empty(len(v_r))
    pending = [0.0] * delay          # outputs computed but not yet applied, oldest first
    v_y = sim.v_y_V
    for k, (r, f) in enumerate(zip(v_r.tolist(), u_f.tolist())):
        ub = controller_step(r - v_y)
        # the DAC limits any finite request, so only a growing controller
        # state can get here; stop long before it overflows (NaN fails too)
        if not abs(ub) < _DIVERGED_V:
            raise ValueError(f"the controller output diverged at sample {k} "
                             f"(t = {k / stage.fs:.4f} s): is the closed loop stable?")
        u_b[k] = ub
        if delay:
            pending.append(ub)
            ub = pending.pop(0)
        v_y = step(f + ub)
    return u_b, sim.record()


# --------------------------------------------------------------------------- N seeds at once
def _run_batch(batch, v_r, feedforward, controller, delay_samples, sections_dtype):
    """:func:`run_loop` on every member of a StageBatch; a list of LoopResult."""
    delay = check_integer("delay_samples", delay_samples, minimum=0)
    u_f, ff_text = _feedforward_signal(feedforward, v_r)
    n = batch.size
    if isinstance(controller, SOSController):
        if not math.isclose(controller.fs, batch.fs, rel_tol=1e-9):
            raise ValueError(f"controller sections run at {controller.fs:g} Hz, the stage at "
                             f"{batch.fs:g} Hz")
        used = controller
        sections = SectionFilterBatch(controller, sections_dtype, n)
        u_b, records = _closed_loop_sections(batch, v_r, u_f, sections, delay)
    else:
        used = discrete_controller(controller, batch.fs)
        if used is None:
            return [LoopResult(v_r, u_f, np.zeros_like(v_r), record, ff_text, None, delay)
                    for record in batch.run(u_f)]
        u_b, records = _closed_loop_batch(batch, v_r, u_f, _state_space_batch_step(used, n),
                                          delay)
    return [LoopResult(v_r, u_f, u_b[i], record, ff_text, used, delay)
            for i, record in enumerate(records)]


def batch_tracking_errors(batch, v_r, frequency_Hz, *, feedforward=None, controller=None,
                          delay_samples=COMPUTATION_DELAY_SAMPLES, sections_dtype="float32",
                          discard_periods=DISCARD_PERIODS, range_um=None, workspace=None):
    """The tracking error % and the limited samples of every member of a batch, without
    a :class:`LoopResult` per member.

    Entry i equals, float for float, what ``run_loop(batch, v_r, ...)[i]`` gives with
    :meth:`LoopResult.tracking_error_percent` ``(frequency_Hz, discard_periods,
    range_um)`` and :attr:`LoopResult.saturation_count`; with an SOSController the
    compiled loop's signals are read in place (no record per member: a set of hundreds
    of members saves their copies).  No :class:`StageSaturationWarning` is issued: the
    counts say which members were limited.

    Parameters
    ----------
    batch : piezolib.problem.stage_batch.StageBatch
    v_r : array_like
        Reference [V], 1-D.
    frequency_Hz : float
        The reference's frequency [Hz] (the steady state starts after
        ``discard_periods`` of its periods).
    feedforward, controller, delay_samples, sections_dtype
        As in :func:`run_loop`.
    discard_periods : int
    range_um : float, optional
        As in :meth:`LoopResult.tracking_error_percent`.
    workspace : ndarray, optional
        A 1-D float64 array the compiled loop keeps its signals in when it is large
        enough (:meth:`~piezolib.problem.stage_batch.StageBatchSimulation.run_sections_loop`):
        pass the same one to a series of calls.

    Returns
    -------
    errors : ndarray, shape (N,)
        Tracking error [%] of each member (:func:`piezolib.metrics.tracking_error_percent`).
    saturation_counts : ndarray of int, shape (N,)

    Examples
    --------
    >>> from piezolib.problem.stage import VirtualStage
    >>> from piezolib.problem.stage_batch import StageBatch
    >>> batch = StageBatch.of_seeds(VirtualStage(), [0, 1])
    >>> v_r = 2.0 + np.sin(2 * np.pi * 50.0 * np.arange(600) / 1e4)   # 3 periods of 50 Hz
    >>> errors, counts = batch_tracking_errors(batch, v_r, 50.0, feedforward=0.9,
    ...                                        controller=paper.controller())
    >>> errors.shape, counts.tolist()
    ((2,), [0, 0])
    """
    from piezolib.problem.stage_batch import StageBatch           # imported lazily by the package
    if not isinstance(batch, StageBatch):
        raise TypeError(f"batch must be a StageBatch, got {type(batch).__name__}")
    v_r = check_finite_array("v_r", v_r, ndim=1, min_length=2, real=True)
    steady = _steady_state(len(v_r), 1.0 / batch.fs, frequency_Hz, discard_periods)
    _check_sections_dtype(sections_dtype)
    range_um = None if range_um is None else check_positive("range_um", range_um)
    if isinstance(controller, SOSController):
        delay = check_integer("delay_samples", delay_samples, minimum=0)
        if not math.isclose(controller.fs, batch.fs, rel_tol=1e-9):
            raise ValueError(f"controller sections run at {controller.fs:g} Hz, the stage at "
                             f"{batch.fs:g} Hz")
        u_f, _ = _feedforward_signal(feedforward, v_r)
        sim = _run_sections(batch, v_r, u_f, SectionFilterBatch(controller, sections_dtype,
                                                                batch.size), delay,
                            workspace)[0]
        v_y, counts = sim.samples("v_y"), sim.saturation_counts()
    else:
        results = _run_batch(batch, v_r, feedforward, controller, delay_samples,
                             sections_dtype)
        v_y = np.stack([r.v_y_V for r in results], axis=1)
        counts = np.array([r.saturation_count for r in results])
    # x = 3 um/V v_y and x_r = 3 um/V v_r, the products LoopResult forms
    errors = tracking_errors_percent(paper.UM_PER_VOLT * v_r[steady],
                                     paper.UM_PER_VOLT * v_y[steady], range_um)
    return errors, counts


def _state_space_batch_step(Kd, size):
    """:func:`_state_space_step` for ``size`` members: e and u_b of shape (size,).

    ``np.matmul`` of M with a stack of column vectors runs numpy's
    matrix-vector kernel once per member, the call ``M @ w`` makes in the
    single run, so each member's arithmetic is the single run's (a matrix
    product ``W @ M.T`` would sum in another order).
    """
    M = _augmented(Kd)
    n = M.shape[0] - 1
    W = np.zeros((size, n + 1, 1))

    def step(e):
        nonlocal W
        W[:, n, 0] = e
        W = np.matmul(M, W)
        return W[:, n, 0].copy()
    return step


def _run_sections(batch, v_r, u_f, sections, delay, workspace=None):
    """The compiled loop of a section controller on a batch (:meth:`StageBatchSimulation.
    run_sections_loop`: :func:`_closed_loop_batch`'s arithmetic); (simulation, u_b of
    shape (n, N)), a ValueError when the loop diverged."""
    sim = batch.start()
    u_b, diverged = sim.run_sections_loop(v_r, u_f, sections, delay, _DIVERGED_V, workspace)
    if diverged >= 0:
        ub = u_b[diverged]
        bad = [batch.seeds[i] for i in np.flatnonzero(~(np.abs(ub) < _DIVERGED_V))]
        raise ValueError(f"the controller output diverged at sample {diverged} "
                         f"(t = {diverged / batch.fs:.4f} s) for seed(s) "
                         f"{bad or list(batch.seeds)}: is the closed loop stable?")
    return sim, u_b


def _closed_loop_sections(batch, v_r, u_f, sections, delay):
    """:func:`_closed_loop_batch` with a section controller, as one compiled loop."""
    sim, u_b = _run_sections(batch, v_r, u_f, sections, delay)
    return u_b.T.copy(), sim.records()


def _closed_loop_batch(batch, v_r, u_f, controller_step, delay):
    """:func:`_closed_loop` on every member of ``batch`` at once.

    Returns
    -------
    u_b : ndarray, shape (N, n)
        Row i: the controller output of member i [V].
    records : list of StageRecord
    """
    sim = batch.start()
    advance = sim._advance           # step without re-checking: u_f and u_b are finite here
    ubs = []
    pending = deque(np.zeros(batch.size) for _ in range(delay))   # oldest first
    v_y = sim.v_y_V
    for k, (r, f) in enumerate(zip(v_r.tolist(), u_f.tolist())):
        ub = controller_step(r - v_y)
        # as in _closed_loop, stop long before an output overflows; the root sum
        # of squares over the members is one cheap call (NaN fails too)
        if not ub.dot(ub) < _DIVERGED_V ** 2:
            bad = [batch.seeds[i] for i in np.flatnonzero(~(np.abs(ub) < _DIVERGED_V))]
            raise ValueError(f"the controller output diverged at sample {k} "
                             f"(t = {k / batch.fs:.4f} s) for seed(s) {bad or list(batch.seeds)}"
                             ": is the closed loop stable?")
        ubs.append(ub)
        if delay:
            pending.append(ub)
            ub = pending.popleft()
        v_y = advance(f, ub)             # u_c = f + ub
    return np.array(ubs).T.copy(), sim.records()
