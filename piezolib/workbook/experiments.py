"""Cases I–III of Sec. V: the Table 4 hysteresis test and the Table 5 tracking test.

:func:`table4_reference` is the 10 Hz triangle of the Table 4 test and
:func:`table4_measure` how every Table 4 loop is measured (shared by Cases
I–III; the cases themselves are run by :func:`run_case` on the loop of
:mod:`piezolib.workbook.loop`).  :func:`hysteresis_test` and
:func:`tracking_test` run the three cases on references built once and give
the tables in the paper's layout.  What each case applies and why:
``docs/controller_design.md``.

The feedforward of Cases II-III is any hysteresis model the loop can use
(:class:`~piezolib.hysteresis.common.HysteresisModel`: the workbook's
:class:`~piezolib.hysteresis.DahlModel` of eq. 14, or a
:class:`~piezolib.hysteresis.PIModel` with its exact inverse); Case I
applies the reference through the model's ``static_part``, the line
x = g v + x0 without the hysteresis (Dahl: g_a and x0; PI: the sum of the
play weights and x0), or through ``case_I_gain``.

Case III's figures sit at the sensor-noise and ADC floor of the stage, so one
noise draw moves them by 5-50 % between machines; with ``seeds`` both tests
run every case for N noise seeds at once (the batched loop of
:mod:`piezolib.workbook.loop`) and report the mean over the seeds with its
95 % Student-t interval (:func:`piezolib.metrics.mean_interval`) and the
noise-free table beside it.  :class:`ExperimentResult` gives those
statistics row by row and over columns (:meth:`ExperimentResult.over_seeds`),
:func:`add_table_claims` turns a result into claims on the published table,
one per cell, and :func:`design_goal_table` judges the goals of Sec. IV-B.
"""

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from piezolib import signals
from piezolib._checks import (check_finite_array, check_integer, check_positive,
                              check_same_length, check_type)
from piezolib.hysteresis.common import check_hysteresis_model
from piezolib.hysteresis.measure import hysteresis_measure
from piezolib.metrics import improvement_percent, mean_interval
from piezolib.problem import paper
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_batch import StageBatch, check_seeds
from piezolib.robust.export import SOSController
from piezolib.workbook.loop import (COMPUTATION_DELAY_SAMPLES, DISCARD_PERIODS,
                                    discrete_controller, run_loop)
from piezolib.workbook.report import ClaimTable, goal_verdict

__all__ = ["table4_reference", "table4_measure",
           "CASES", "MIN_MEASURED_S", "run_case", "case_table", "ExperimentResult",
           "hysteresis_test", "tracking_periods", "tracking_reference", "tracking_test",
           "CLAIM_TOLERANCES", "add_table_claims", "design_goal_table"]


def table4_reference(amplitude_V, periods=3, frequency_Hz=None, fs=paper.SAMPLING_FREQUENCY_HZ,
                     amplifier_gain=paper.AMPLIFIER_GAIN):
    """Reference of the Table 4 experiments for one actuator amplitude.

    A triangle from 0 to ``amplitude_V / AMPLIFIER_GAIN`` [V] at 10 Hz: the
    amplifier-input voltage that Case I applies directly (actuator voltage
    0 ... amplitude_V) and, read as x_r = v_r in sensor volts, the desired
    displacement of Cases II and III (0 ... 0.3 um/V x amplitude_V).

    Parameters
    ----------
    amplitude_V : float
        Actuator amplitude A [V] (Table 4: 10, 20, 30, 40 V).
    periods : int, optional
        Number of periods.
    frequency_Hz, fs : float, optional
        Triangle frequency (default 10 Hz) and sampling rate [Hz] (default
        the paper's 10 kHz).
    amplifier_gain : float, optional
        Actuator volts per amplifier-input volt (default the paper's 10).

    Returns
    -------
    t : ndarray
        Time [s].
    v_r : ndarray
        Reference [V].

    Examples
    --------
    >>> t, v_r = table4_reference(20.0)          # 20 V actuator amplitude, 3 periods at 10 Hz
    >>> t.shape, float(v_r.max()), float(t[-1])
    ((3001,), 2.0, 0.3)
    """
    amplitude_V = check_positive("amplitude_V", amplitude_V)
    gain = check_positive("amplifier_gain", amplifier_gain)
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_Hz is None else frequency_Hz
    return signals.triangle(amplitude_V / gain, f, periods=periods, fs=fs)


def table4_measure(reference_V, v_y_V, discard_periods=1, frequency_Hz=None,
                   fs=paper.SAMPLING_FREQUENCY_HZ, amplifier_gain=paper.AMPLIFIER_GAIN,
                   um_per_volt=paper.UM_PER_VOLT):
    """Hysteresis of one Table 4 loop, measured the same way in every case.

    The loop is the measured displacement x = 3 um/V * v_y [um] against the
    reference expressed as actuator voltage, AMPLIFIER_GAIN * reference [V]
    (Case I: the reference is the applied u_c, so the input axis is the
    actuator voltage v_a itself; Cases II-III: the reference v_r that the
    feedforward / closed loop receives).  The first ``discard_periods``
    periods (compensator and loop start-up) are left out, and eq. 25-26 are
    applied to the rest (:func:`piezolib.hysteresis.hysteresis_measure`).

    Parameters
    ----------
    reference_V : array_like
        u_c (Case I) or v_r (Cases II, III) [V] at the DAQ rate.
    v_y_V : array_like
        Measured sensor output [V], same length.
    discard_periods : int, optional
    frequency_Hz, fs : float, optional
        Triangle frequency (default 10 Hz) and sampling rate [Hz] (default
        the paper's 10 kHz).
    amplifier_gain : float, optional
        Actuator volts per reference volt (default the paper's 10).
    um_per_volt : float, optional
        Sensor scale [um/V] (default the paper's 3).

    Returns
    -------
    HysteresisMeasure
        In actuator volts and micrometres.

    Examples
    --------
    >>> from piezolib.problem.stage_data import load_hysteresis_loops
    >>> loop = load_hysteresis_loops()[20.0]      # Case I: the reference is u_c itself
    >>> round(table4_measure(loop.u_c_V, loop.v_y_V).percent, 1)   # Table 4: 9.08 %
    9.2
    """
    reference_V = check_finite_array("reference_V", reference_V, ndim=1, min_length=8)
    v_y_V = check_finite_array("v_y_V", v_y_V, ndim=1, min_length=8)
    check_same_length(reference_V=reference_V, v_y_V=v_y_V)
    discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
    f = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_Hz is None else frequency_Hz
    start = int(round(discard_periods * check_positive("fs", fs) / check_positive("frequency_Hz", f)))
    if start >= reference_V.size - 8:
        raise ValueError(f"discarding {discard_periods} period(s) leaves no record "
                         f"({reference_V.size} samples)")
    gain = check_positive("amplifier_gain", amplifier_gain)
    scale = check_positive("um_per_volt", um_per_volt)
    return hysteresis_measure(gain * reference_V[start:], scale * v_y_V[start:])


# --------------------------------------------------------------------------- the cases
#: The cases of Sec. V (Tables 4-5, Fig. 14-15).
CASES = {
    "I": "open loop without compensator",
    "II": "open loop with Dahl feedforward",
    "III": "Dahl feedforward + feedback controller",
}

#: Shortest steady-state record of the tracking test [s] (whole periods).
MIN_MEASURED_S = 0.1


def run_case(case, stage, v_r, model, controller=None, case_I_gain=None,
             delay_samples=COMPUTATION_DELAY_SAMPLES):
    """Run Case I, II or III of Sec. V on one reference.

    Parameters
    ----------
    case : {"I", "II", "III"}
    stage : piezolib.problem.stage.VirtualStage or StageBatch
        A StageBatch runs the case on every member at once.
    v_r : array_like
        Reference [V].
    model : HysteresisModel or None
        The feedforward model of Cases II and III, u_f = ``model.feedforward(v_r)``
        (:class:`~piezolib.hysteresis.DahlModel`: eq. 14;
        :class:`~piezolib.hysteresis.PIModel`: its exact inverse; any
        :class:`~piezolib.hysteresis.common.HysteresisModel`).  None: the
        workbook's shared Dahl model,
        :func:`piezolib.problem.hysteresis_fits.workbook_dahl_fit`.
    controller : see :func:`piezolib.workbook.loop.discrete_controller`
        Required for Case III, ignored otherwise.
    case_I_gain : float, optional
        g of Case I, applied without offset (u_c = v_r / g); default: the
        model's ``static_part`` (g, x0), u_c = (v_r - x0) / g (Dahl: g_a and
        x0; PI: the sum of its weights and x0).  A model without a
        ``static_part`` needs it.
    delay_samples : int
        Computation delay of the feedback [samples] (Case III; default 1,
        :data:`piezolib.workbook.loop.COMPUTATION_DELAY_SAMPLES`).

    Returns
    -------
    piezolib.workbook.loop.LoopResult or list of LoopResult
        A list (one per member) for a StageBatch.

    Raises
    ------
    TypeError
        ``model`` is not a hysteresis model (no ``simulate`` and ``feedforward``).
    ValueError
        An unknown case, Case III without a controller, or Case I without
        ``case_I_gain`` for a model without a ``static_part``.

    Examples
    --------
    >>> from piezolib.problem.hysteresis_fits import read_dahl_model, workbook_dahl_path
    >>> from piezolib.problem.stage import VirtualStage
    >>> model = read_dahl_model(workbook_dahl_path())
    >>> _, v_r = table4_reference(20.0, periods=1)
    >>> run_case("II", VirtualStage(seed=0), v_r, model).feedforward
    'Dahl eq. 14 (g_a = ...)'
    >>> len(run_case("I", VirtualStage(seed=0), v_r, model))
    1001
    """
    if not isinstance(case, str) or case not in CASES:
        raise ValueError(f"case must be one of {sorted(CASES)}, got {case!r}")
    delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
    if model is None:
        model = workbook_dahl_fit().model
    check_hysteresis_model("model", model)
    if case == "I":
        if case_I_gain is not None:
            return run_loop(stage, v_r, feedforward=check_positive("case_I_gain", case_I_gain))
        if not hasattr(model, "static_part"):
            raise ValueError(f"case I needs case_I_gain: a {type(model).__name__} has no "
                             "static_part (g, x0)")
        return run_loop(stage, v_r, feedforward=tuple(model.static_part))
    if case == "II":
        return run_loop(stage, v_r, feedforward=model)
    if controller is None:
        raise ValueError("case III needs a controller")
    return run_loop(stage, v_r, feedforward=model, controller=controller,
                    delay_samples=delay_samples)


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
        Rows as in :func:`piezolib.problem.paper.table4` (its row index).

    Examples
    --------
    >>> import pandas as pd
    >>> table = case_table({"I": [10.0, 12.0], "II": [5.0, 6.0], "III": [1.0, 1.5]},
    ...                    pd.Index([1.0, 10.0], name="frequency_Hz"))
    >>> table.loc["improvement_III_vs_I"].tolist()      # % of Case I's error removed
    [90.0, 87.5]
    """
    check_type("case_values", case_values, dict, 'a dict {"I": ..., "II": ..., "III": ...}')
    missing = [c for c in CASES if c not in case_values]
    if missing:
        raise ValueError(f"case_values lacks the case(s) {missing}")
    if isinstance(columns, (str, bytes)) or not hasattr(columns, "__len__"):
        raise TypeError(f"columns must be a sequence of column labels, got {columns!r}")
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
        Same layout as :func:`piezolib.problem.paper.table4` /
        :func:`~piezolib.problem.paper.table5` [%].  With seeds: the mean over the
        seeds (each improvement row is computed seed by seed, then averaged).
    runs : dict
        {(case, column value): LoopResult}; with seeds, the runs of the first
        seed.
    saturation : pandas.DataFrame
        Limited samples per case (rows) and column: DAC/amplifier input +
        amplifier output + ADC; with seeds, the largest count over the seeds
        and the noise-free run.
    low, high : pandas.DataFrame or None
        With seeds: the two-sided 95 % confidence interval of the mean
        (Student t, N - 1 degrees of freedom), same layout as ``table`` [%].
    noise_free : pandas.DataFrame or None
        With seeds: the table of one run on the stage without sensor noise
        (``noise_rms_V=0``; the DAC and ADC quantisation kept) [%].
    per_seed : pandas.DataFrame or None
        With seeds: every seed's table, rows indexed by (seed, row) [%].
    seeds : tuple of int or None
        The seeds used (None: one run with the stage's own seed).
    """

    table: pd.DataFrame
    runs: dict = field(repr=False)
    saturation: pd.DataFrame
    low: object = field(default=None, repr=False)
    high: object = field(default=None, repr=False)
    noise_free: object = field(default=None, repr=False)
    per_seed: object = field(default=None, repr=False)
    seeds: object = None

    def _seeded(self, what):
        if self.seeds is None:
            raise ValueError(f"{what} needs a result run with seeds (N >= 2 noise seeds)")

    def statistics(self, row):
        """Mean over the seeds, its 95 % interval and the noise-free value of one row.

        Parameters
        ----------
        row : str
            A row of :attr:`table`, e.g. ``"case_III"``.

        Returns
        -------
        pandas.DataFrame
            Rows ``mean``, ``95 % low``, ``95 % high``, ``noise-free``; the
            table's columns [%].
        """
        self._seeded("statistics")
        return pd.DataFrame({"mean": self.table.loc[row], "95 % low": self.low.loc[row],
                             "95 % high": self.high.loc[row],
                             "noise-free": self.noise_free.loc[row]}).T

    def interval(self, row, column):
        """(low, high): the 95 % interval of the mean of one cell [%]."""
        self._seeded("interval")
        return float(self.low.loc[row, column]), float(self.high.loc[row, column])

    def over_seeds(self, row, columns=None, how="max"):
        """Mean over the seeds of one row reduced over columns seed by seed, with its interval.

        Each seed's row is reduced first (its largest value, or its mean, over
        ``columns``) and the N reduced values are then averaged: the largest
        error over 1-10 Hz of one seed is a draw of its own, and the mean of
        the per-column means would not be its mean.

        Parameters
        ----------
        row : str
            A row of :attr:`table`.
        columns : sequence, optional
            Columns to reduce over (default: all).
        how : {"max", "mean"}
            The reduction.

        Returns
        -------
        mean, low, high : float
            [%]; the interval of :func:`piezolib.metrics.mean_interval`.
        """
        self._seeded("over_seeds")
        if how not in ("max", "mean"):
            raise ValueError(f"how must be 'max' or 'mean', got {how!r}")
        per_seed = self.per_seed.xs(row, level="row")
        if columns is not None:
            per_seed = per_seed[list(columns)]
        return mean_interval(getattr(per_seed, how)(axis=1))


# --------------------------------------------------------------------------- claims
#: (atol, rtol) of a claim on one cell of Table 4 or 5: a case row agrees within
#: max(0.1 points, 20 %), an improvement row (a ratio of two noisy rows) within 5 points.
CLAIM_TOLERANCES = {"case": (0.1, 0.2), "improvement": (5.0, 0.0)}

#: Note of an improvement row that ``notes`` leaves out.
_IMPROVEMENT_NOTE = "from the case rows above"


def add_table_claims(claims, section, published, result, quantity, *, rows=None, notes="",
                     reason="virtual stage"):
    """One claim per cell of a published Table 4/5 that a seeded result has.

    Each claim is the mean over the noise seeds, judged on its 95 % interval
    (:meth:`piezolib.workbook.report.ClaimTable.add`) with the tolerances of
    :data:`CLAIM_TOLERANCES`; the claims are added row by row, column by
    column, in the published table's order.

    Parameters
    ----------
    claims : piezolib.workbook.report.ClaimTable
    section : str
        Paper location, e.g. ``"Table 4"``.
    published : pandas.DataFrame
        :func:`piezolib.problem.paper.table4` or ``table5``; only the
        columns the result also has are claimed.
    result : ExperimentResult
        Run with seeds.
    quantity : str
        Format of the quantity with fields ``row`` and ``col``, e.g.
        ``"hysteresis {row} at {col:g} V"``.
    rows : sequence of str, optional
        Rows to claim (default: all of ``published``).
    notes : str or dict, optional
        The note of every row, or {row: note}; an improvement row missing
        from the dict gets "from the case rows above".
    reason : str, optional
        Why a row may differ (:data:`piezolib.workbook.report.REASONS`).
    """
    check_type("claims", claims, ClaimTable, "a ClaimTable")
    check_type("published", published, pd.DataFrame, "a pandas DataFrame (paper.table4/5)")
    check_type("result", result, ExperimentResult, "an ExperimentResult")
    result._seeded("add_table_claims")
    for row in published.index if rows is None else rows:
        improvement = row.startswith("improvement")
        atol, rtol = CLAIM_TOLERANCES["improvement" if improvement else "case"]
        note = notes if isinstance(notes, str) else \
            notes.get(row, _IMPROVEMENT_NOTE if improvement else "")
        for col in published.columns.intersection(result.table.columns):
            claims.add(section, quantity.format(row=row, col=col),
                       float(published.loc[row, col]), float(result.table.loc[row, col]),
                       interval=result.interval(row, col), unit="%", atol=atol, rtol=rtol,
                       reason=reason, note=note)


def design_goal_table(results, goals=None):
    """The tracking goals of Sec. IV-B for seeded Table 5 results, judged on 95 % intervals.

    Per result: the mean over the seeds of the largest Case III error over
    the frequencies up to 10 Hz (each seed's largest, then averaged) and of
    the error at 50 Hz (NaN without a 50 Hz column), their 95 % intervals,
    and the verdict on each goal (:func:`piezolib.workbook.report.goal_verdict`:
    met when the interval lies below the goal).

    Parameters
    ----------
    results : dict
        {name: ExperimentResult} of :func:`tracking_test` with seeds.
    goals : dict, optional
        ``peak_to_peak_error_pct_up_to_10Hz`` and
        ``peak_to_peak_error_pct_at_50Hz`` [%]; default the paper's
        :data:`piezolib.problem.paper.DESIGN_GOALS`.

    Returns
    -------
    pandas.DataFrame
        One row per result; columns the errors [%], their intervals and the two verdicts.
    """
    check_type("results", results, dict, "a dict {name: ExperimentResult}")
    for name, result in results.items():
        check_type(f"results[{name!r}]", result, ExperimentResult, "an ExperimentResult")
    goals = paper.DESIGN_GOALS if goals is None else goals
    goal_10 = goals["peak_to_peak_error_pct_up_to_10Hz"]
    goal_50 = goals["peak_to_peak_error_pct_at_50Hz"]
    rows = {}
    for name, result in results.items():
        columns = result.table.columns
        m10, lo10, hi10 = result.over_seeds("case_III", [f for f in columns if f <= 10.0])
        m50, lo50, hi50 = (result.over_seeds("case_III", [50.0]) if 50.0 in columns
                           else (np.nan,) * 3)
        rows[name] = {"max error up to 10 Hz [%]": m10, "up to 10 Hz, 95 % low": lo10,
                      "up to 10 Hz, 95 % high": hi10,
                      f"goal < {goal_10:g} % up to 10 Hz": goal_verdict(lo10, hi10, goal_10),
                      "error at 50 Hz [%]": m50, "50 Hz, 95 % low": lo50,
                      "50 Hz, 95 % high": hi50,
                      f"goal < {goal_50:g} % at 50 Hz": goal_verdict(lo50, hi50, goal_50)}
    return pd.DataFrame(rows).T


# --------------------------------------------------------------------------- references
def _read_only(t, v_r):
    t.flags.writeable = False
    v_r.flags.writeable = False
    return t, v_r


@functools.lru_cache(maxsize=64)
def _table4_triangle(amplitude_V, periods, fs, amplifier_gain):
    return _read_only(*table4_reference(amplitude_V, periods=periods, fs=fs,
                                        amplifier_gain=amplifier_gain))


@functools.lru_cache(maxsize=64)
def _table5_triangle(frequency_Hz, periods, amplitude_um, fs):
    return _read_only(*signals.triangle(amplitude_um / paper.UM_PER_VOLT, frequency_Hz,
                                        periods=periods, fs=fs))


def tracking_periods(frequency_Hz, discard_periods=DISCARD_PERIODS,
                     min_measured_s=MIN_MEASURED_S):
    """Periods to simulate: ``discard_periods`` plus whole periods covering
    at least ``min_measured_s`` [s] (one period at least).

    Examples
    --------
    >>> tracking_periods(1.0), tracking_periods(50.0)   # 2 discarded + at least 0.1 s measured
    (3, 7)
    """
    frequency_Hz = check_positive("frequency_Hz", frequency_Hz)
    discard_periods = check_integer("discard_periods", discard_periods, minimum=0)
    min_measured_s = check_positive("min_measured_s", min_measured_s)
    return discard_periods + max(1, math.ceil(min_measured_s * frequency_Hz - 1e-9))


def tracking_reference(frequency_Hz, periods, amplitude_um=None, fs=paper.SAMPLING_FREQUENCY_HZ):
    """v_r [V] of the tracking test: a triangle from 0 to amplitude_um / (3 um/V).

    Built once per argument set and shared (the arrays are read-only).

    Parameters
    ----------
    frequency_Hz : float
        Triangle frequency [Hz].
    periods : int
        Number of periods.
    amplitude_um : float, optional
        Peak displacement [um]; default the paper's 12 um.
    fs : float
        Sampling rate [Hz].

    Returns
    -------
    t : ndarray
        Time [s].
    v_r : ndarray
        Reference [V].

    Examples
    --------
    >>> t, v_r = tracking_reference(10.0, periods=3)    # 12 um triangle = 4 V of v_r
    >>> t.shape, float(v_r.max()), v_r.flags.writeable
    ((3001,), 4.0, False)
    """
    amplitude_um = paper.TRACKING_TEST["amplitude_um"] if amplitude_um is None else amplitude_um
    return _table5_triangle(check_positive("frequency_Hz", frequency_Hz),
                            check_integer("periods", periods, minimum=1),
                            check_positive("amplitude_um", amplitude_um),
                            check_positive("fs", fs))


# --------------------------------------------------------------------------- the tests
def _positive_values(name, values, default):
    values = default if values is None else values
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise TypeError(f"{name} must be a sequence of numbers, got {values!r}")
    values = [check_positive(name, v) for v in values]
    if not values:
        raise ValueError(f"{name} must hold at least one value")
    return values


def _check_stage_and_model(stage, model):
    """Raise unless ``stage`` is a VirtualStage and ``model`` a hysteresis model (or None)."""
    check_type("stage", stage, VirtualStage, "a VirtualStage")
    if model is not None:
        check_hysteresis_model("model", model)


def _case_III_controller(controller, stage):
    if controller is None:
        raise ValueError("controller must be given (Case III)")
    if isinstance(controller, SOSController):
        return controller
    return discrete_controller(controller, stage.fs)


def _seeded_stages(stage, seeds):
    """None, or the StageBatch of the seeds plus the noise-free stage (last)."""
    if seeds is None:
        return None
    seeds = check_seeds(seeds, min_count=2,
                        why="N >= 2 seeds are needed for a confidence interval")
    if not isinstance(stage, VirtualStage):
        raise TypeError(f"stage must be a VirtualStage to run seeds, got {type(stage).__name__}")
    return StageBatch([stage.replace(seed=s) for s in seeds]
                      + [stage.replace(noise_rms_V=0.0)])


def _experiment(columns, run, measure, batch=None):
    if batch is not None:
        return _seeded_experiment(columns, run, measure, batch)
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


def _seeded_experiment(columns, run, measure, batch):
    """:func:`_experiment` on a batch whose last member is the noise-free stage."""
    seeds = batch.seeds[:-1]
    values = {c: np.empty((batch.size, len(columns))) for c in CASES}
    runs, sat = {}, {c: [] for c in CASES}
    for j, col in enumerate(columns):
        for case in CASES:
            results = run(case, col)
            runs[(case, float(col))] = results[0]
            for m, result in enumerate(results):
                values[case][m, j] = measure(result, col)
            sat[case].append(max(r.saturation_count for r in results))
    tables = [case_table({c: values[c][m] for c in CASES}, columns)
              for m in range(batch.size)]
    mean, low, high = mean_interval(np.stack([t.to_numpy() for t in tables[:-1]]), axis=0)

    def like(data):
        return pd.DataFrame(data, index=tables[0].index, columns=columns)

    per_seed = pd.concat(dict(zip(seeds, tables[:-1])), names=["seed"])
    saturation = pd.DataFrame([sat[c] for c in CASES], index=pd.Index(
        [f"case_{c}" for c in CASES], name="row"), columns=columns)
    return ExperimentResult(like(mean), runs, saturation, like(low), like(high), tables[-1],
                            per_seed, tuple(seeds))


def hysteresis_test(stage, model, controller, amplitudes_V=None, periods=4,
                    discard_periods=DISCARD_PERIODS, delay_samples=COMPUTATION_DELAY_SAMPLES,
                    seeds=None):
    """Table 4: hysteresis % of 10 Hz triangles, Cases I-III.

    The reference of each amplitude A is :func:`table4_reference` (0 ...
    A/g V with g the stage's amplifier gain, built once); Case I applies it
    directly (the actuator voltage triangle of the paper), Cases II-III read
    it as x_r = v_r.  Each loop is measured by :func:`table4_measure`
    (x = 3 um/V v_y against g v_r, first ``discard_periods`` left out).

    Parameters
    ----------
    stage : piezolib.problem.stage.VirtualStage
    model : HysteresisModel or None
        The feedforward of Cases II-III (:func:`run_case`); None: the
        workbook's shared Dahl model.
    controller : see :func:`piezolib.workbook.loop.run_loop`
        Case III's feedback (not None); an exported SOSController runs in float32.
    amplitudes_V : sequence of float, optional
        Actuator amplitudes [V]; default 10, 20, 30, 40 V.
    periods, discard_periods : int
    delay_samples : int
        Computation delay of Case III's feedback [samples] (default 1).
    seeds : sequence of int, optional
        N >= 2 distinct non-negative noise seeds: every case runs for every
        seed (all seeds at once) and once without sensor noise, and the
        result holds the mean, its 95 % interval, the noise-free table and
        the per-seed tables (:class:`ExperimentResult`).  ``None``: one run
        with the stage's seed.

    Returns
    -------
    ExperimentResult
    """
    amplitudes_V = _positive_values("amplitudes_V", amplitudes_V,
                                    paper.HYSTERESIS_TEST["actuator_amplitudes_V"])
    periods = check_integer("periods", periods, minimum=discard_periods + 1)
    _check_stage_and_model(stage, model)
    Kd = _case_III_controller(controller, stage)
    batch = _seeded_stages(stage, seeds)
    target = stage if batch is None else batch

    def run(case, A):
        v_r = _table4_triangle(A, periods, stage.fs, stage.gain)[1]
        return run_case(case, target, v_r, model, Kd, case_I_gain=1.0,
                        delay_samples=delay_samples)

    def measure(result, A):
        return table4_measure(result.v_r_V, result.v_y_V, discard_periods=discard_periods,
                              fs=stage.fs, amplifier_gain=stage.gain).percent

    return _experiment(pd.Index(amplitudes_V, name="amplitude_V"), run, measure, batch)


def tracking_test(stage, model, controller, frequencies_Hz=None, amplitude_um=None,
                  discard_periods=DISCARD_PERIODS, min_measured_s=MIN_MEASURED_S,
                  delay_samples=COMPUTATION_DELAY_SAMPLES, seeds=None):
    """Table 5: tracking error % of 12 um triangles, Cases I-III.

    Each frequency runs :func:`tracking_periods` periods of
    :func:`tracking_reference`; the first ``discard_periods`` (start-up from
    rest) are left out and the tracking error %
    (:func:`piezolib.metrics.tracking_error_percent`, range = the commanded
    amplitude) is taken over the rest.

    Parameters
    ----------
    stage : piezolib.problem.stage.VirtualStage
    model : HysteresisModel or None
        The feedforward of Cases II-III (:func:`run_case`); None: the
        workbook's shared Dahl model.
    controller : see :func:`piezolib.workbook.loop.run_loop`
        Case III's feedback (not None); an exported SOSController runs in float32.
    frequencies_Hz : sequence of float, optional
        Default 1, 10, 20, 30, 40, 50 Hz.
    amplitude_um : float, optional
        Default 12 um.
    discard_periods : int
    min_measured_s : float
        [s]
    delay_samples : int
        Computation delay of Case III's feedback [samples] (default 1).
    seeds : sequence of int, optional
        As in :func:`hysteresis_test`: N >= 2 seeds give the mean over the
        seeds, its 95 % interval, the noise-free and the per-seed tables.

    Returns
    -------
    ExperimentResult
    """
    frequencies_Hz = _positive_values("frequencies_Hz", frequencies_Hz,
                                      paper.TRACKING_TEST["frequencies_Hz"])
    amplitude_um = check_positive("amplitude_um", paper.TRACKING_TEST["amplitude_um"]
                                  if amplitude_um is None else amplitude_um)
    _check_stage_and_model(stage, model)
    Kd = _case_III_controller(controller, stage)
    batch = _seeded_stages(stage, seeds)
    target = stage if batch is None else batch

    def run(case, f):
        periods = tracking_periods(f, discard_periods, min_measured_s)
        v_r = tracking_reference(f, periods, amplitude_um, stage.fs)[1]
        return run_case(case, target, v_r, model, Kd, delay_samples=delay_samples)

    def measure(result, f):
        return result.tracking_error_percent(f, discard_periods, range_um=amplitude_um)

    return _experiment(pd.Index(frequencies_Hz, name="frequency_Hz"), run, measure, batch)
