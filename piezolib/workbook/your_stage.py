"""The pipeline of notebook 08 on a user's own records, one call per stage, with its checks.

Notebook 08 runs the workbook's pipeline on records in whatever form an
acquisition wrote them (columns, units, sampling rate: the notebook's
parameters).  Each stage here is one call that returns a result object: what
the stage computed, the lines a reader sees under the cell (its display, with
any table in the one number format of :func:`piezolib.workbook.tables.readable`)
and ``checks``, a dict {what it states: bool} that the notebook asserts at its
end (:func:`stage_checks`)::

    records = load_records(folder, "chirp.csv", {"sine": "loop_sine.csv"}, columns=..., fs=5e3)
    data = prepare_identification(records, (0.15, 0.29), um_per_volt=3.0, hold_out=0.1,
                                  band_Hz=(5.0, 2000.0))       # operating point, cut, split
    model = identify(data, 6, 3, nb=6, nk=1, floor_percent=70.0)
    weight = uncertainty_weight(model, 0.015, 3, 4, omega)
    loops = prepare_loops(records, um_per_volt=3.0, decimation=5, skip_transient=True)
    choice = fit_hysteresis(loops, ("sine",), ("triangle",), gamma_a=30.0, plays=10,
                            ceiling_percent=5.0)
    design = design_for_loop(model, weight, error_weight, output_weight, rolloff, ...)
    verification = verify_design(design, model, weight)
    feedforward = feedforward_cross_check(choice)
    experiments = run_experiments(design, choice, seed=7, ...)   # on the virtual stage

A folder with hysteresis records only (no identification record) has no
plant: the stages that need one return :class:`Skipped`, which says why,
passes through the later stages and has no checks.  :func:`known_truth` is
the plant of the virtual stage the example records come from; on real data it
is left out (``truth=None`` everywhere) together with
:func:`known_truth_checks`.
"""

import html
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import control as ct
import numpy as np
import pandas as pd
import scipy.signal as sg

from piezolib import hysteresis as hy
from piezolib import identification as ident
from piezolib import records as recs
from piezolib import robust
from piezolib import uncertainty as unc
from piezolib._checks import check_integer, check_positive, check_type
from piezolib.problem import analysis, genplant
from piezolib.problem.design import design_controller
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments as exps
from piezolib.workbook import tables
from piezolib.workbook.loop import DISCARD_PERIODS
from piezolib.workbook.outputs import data_dir

__all__ = ["NO_PLANT_NOTE", "Skipped", "OwnRecords", "IdentificationData", "Identification",
           "KnownTruth", "UncertaintyWeight", "HysteresisLoops", "HysteresisChoice",
           "LoopDesign", "Verification", "FeedforwardCheck", "Experiments",
           "analysis_grid", "load_records", "prepare_identification", "identify", "known_truth",
           "uncertainty_weight", "prepare_loops", "fit_hysteresis", "design_for_loop",
           "verify_design", "feedforward_cross_check", "run_experiments", "record_claims",
           "stage_checks", "known_truth_checks", "summary_lines", "ran"]

#: What a stage that needs the plant says when there is no identification record.
NO_PLANT_NOTE = ("skipped: no identification record (CHIRP_FILE = None), so no plant model; "
                 "the hysteresis models are fitted and validated, the steps that need the "
                 "plant (weight, controller, experiments) are not run")

#: Largest variation of the input over the operating window, as a share of its range.
REST_WOBBLE = 1e-3
#: Frequency below which the identified model is compared with the true plant [rad/s].
TRUTH_TOP_RAD_S = 2 * np.pi * 1000.0
#: Grid of the design's verification: mu bounds and the roll-off [rad/s].
VERIFICATION_GRID = (-2, 7, 1200)
#: Section of the claims this notebook writes.
SECTION = "own stage"


class _Shown:
    """Display of a stage result: its lines, then its tables in the one number format."""

    def _tables(self):
        return ()               # (frame, show the index) pairs

    def __str__(self):
        text = list(self.lines)
        text += [frame.map(tables.format_number).to_string() for frame, _ in self._tables()]
        return "\n".join(text)

    __repr__ = __str__

    def _repr_pretty_(self, printer, cycle):
        printer.text(str(self))

    def _repr_html_(self):
        parts = [f"<pre>{html.escape(line)}</pre>" for line in self.lines]
        parts += [tables.readable(frame, index=index).to_html()
                  for frame, index in self._tables()]
        return "\n".join(parts)


@dataclass(frozen=True, repr=False)
class Skipped(_Shown):
    """A stage not run, and why; it passes through the stages after it.

    Attributes
    ----------
    reason : str
    """

    reason: str

    @property
    def lines(self):
        return (self.reason,)

    @property
    def checks(self):
        """No checks: a stage not run states nothing."""
        return {}


def ran(result):
    """True when ``result`` is a stage's result (not None and not :class:`Skipped`)."""
    return result is not None and not isinstance(result, Skipped)


def analysis_grid(low_rad_s, high_rad_s, points=1000):
    """The logarithmic analysis grid of the notebook [rad/s]
    (:func:`piezolib.robust.frequency_grid`).

    Examples
    --------
    >>> w = analysis_grid(1.0, 1e6)
    >>> w.size, float(w[0]), float(w[-1])
    (1000, 1.0, 1000000.0)
    """
    return robust.frequency_grid(low_rad_s, high_rad_s, points)


# -- 1. records -------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class OwnRecords(_Shown):
    """The loaded records: the identification run (or None) and the hysteresis loops.

    Attributes
    ----------
    chirp : piezolib.records.Record or None
        The identification run; None for a folder of hysteresis records only.
    loops : dict
        {label: Record}: the large-signal hysteresis runs.
    fs : float
        The sampling rate the records are stated to have [Hz].
    chirp_file : str or None
        The identification run's file name (for messages).
    """

    chirp: object
    loops: dict
    fs: float
    chirp_file: object = None

    @property
    def have_plant(self):
        """True when there is an identification record (a plant can be identified)."""
        return self.chirp is not None

    @property
    def all(self):
        """{label: Record} of every record, the identification run first as ``"chirp"``."""
        return {**({"chirp": self.chirp} if self.have_plant else {}), **self.loops}

    @property
    def lines(self):
        out = [] if self.have_plant else [
            "No identification record: identification is skipped, and with it the uncertainty "
            "weight, the controller and the experiments. A hysteresis record (a slow sine or "
            "triangle, a step from rest) has no broadband excitation to identify the stage's "
            "dynamics from; add a chirp record (CHIRP_FILE) for those steps."]
        return tuple(out + [f"{label:9s} {rec}, {rec.duration:.2f} s, input "
                            f"{rec.input.min():.3f} ... {rec.input.max():.3f} {rec.input_unit}"
                            for label, rec in self.all.items()])

    @property
    def checks(self):
        return {"every record is sampled at the stated rate (0.1 %)":
                all(abs(rec.fs - self.fs) < 1e-3 * self.fs for rec in self.all.values())}


def load_records(folder, chirp_file, loop_files, *, columns, fs, header=False, delimiter=",",
                 time_scale=1.0, input=("u", "V", 1.0), output=("y", "V", 1.0)):
    """Load a stage's records with one column mapping (:func:`piezolib.records.load_csv`).

    Parameters
    ----------
    folder : str, pathlib.Path or None
        Folder of the runs; None: the example records ``data/own_stage/``.
    chirp_file : str or None
        The identification run (broadband, from rest); None for a folder of
        hysteresis records only.
    loop_files : dict
        {label: file name} of the large-signal hysteresis runs (at least one).
    columns : dict
        {"time": ..., "input": ..., "output": ...}: 0-based column numbers,
        or names with ``header=True``.
    fs : float
        The records' sampling rate [Hz], checked against the time column.
    header, delimiter, time_scale
        As :func:`~piezolib.records.load_csv` (``time_scale``: file time unit -> s).
    input, output : (name, unit, scale)
        Each signal's name, unit and the factor from the file's numbers to that unit.

    Returns
    -------
    OwnRecords

    Raises
    ------
    piezolib.records.RecordError
        A malformed file, naming the file and the line.
    """
    folder = data_dir() / "own_stage" if folder is None else Path(folder)
    check_type("loop_files", loop_files, dict, "a dict {label: file name}")
    if not loop_files:
        raise ValueError("loop_files must name at least one hysteresis record")
    check_type("columns", columns, dict, "a dict with keys 'time', 'input', 'output'")
    if set(columns) != {"time", "input", "output"}:
        raise ValueError(f"columns must have the keys 'time', 'input', 'output', got "
                         f"{sorted(columns)}")
    for name, spec in (("input", input), ("output", output)):
        if not (isinstance(spec, tuple) and len(spec) == 3):
            raise TypeError(f"{name} must be (name, unit, scale), got {spec!r}")
    fs = check_positive("fs", fs)

    def load(name):
        return recs.load_csv(folder / name, time=columns["time"], input=columns["input"],
                             output=columns["output"], fs=fs, header=header,
                             delimiter=delimiter, time_scale=time_scale,
                             input_unit=input[1], output_unit=output[1],
                             input_scale=input[2], output_scale=output[2],
                             input_name=input[0], output_name=output[0])

    chirp = None if chirp_file is None else load(chirp_file)
    return OwnRecords(chirp, {label: load(name) for label, name in loop_files.items()}, fs,
                      chirp_file)


# -- 2. operating point, cut and split ---------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class IdentificationData(_Shown):
    """The identification run about its operating point, cut and split.

    Attributes
    ----------
    chirp : piezolib.records.Record
        The run as loaded.
    window_s : (float, float)
        The operating window [s].
    u_op, x_op : float
        Input and output averaged over the window (the records' units).
    input_wobble : float
        Peak-to-peak input in the window over its peak-to-peak in the run.
    record : piezolib.records.Record
        Deviations from the operating point from the window on, the output in
        sensor volts (``v_y``).
    band_Hz : (float, float)
        The band the run excites [Hz] (as stated).
    excitation_Hz : float
        Frequency below which 99 % of the input's power lies [Hz].
    estimation, held_out : piezolib.records.Record
        The record's first part and its held-out end.
    """

    chirp: object
    window_s: tuple
    u_op: float
    x_op: float
    input_wobble: float
    record: object
    band_Hz: tuple
    excitation_Hz: float
    estimation: object
    held_out: object

    @property
    def lines(self):
        c, h = self.chirp, self.held_out
        return (f"operating point: {c.input_name} = {self.u_op:.4f} {c.input_unit}, "
                f"{c.output_name} = {self.x_op:.4f} {c.output_unit}; input varies by "
                f"{100 * self.input_wobble:.3f} % of its range in the window",
                f"excitation: 99 % of the input's power below {self.excitation_Hz:.0f} Hz",
                f"estimation {self.estimation}, held out {len(h)} samples "
                f"({h.t0:.3f} ... {h.time[-1]:.3f} s)")

    @property
    def checks(self):
        return {"the operating window is at rest (input within 0.1 % of its range)":
                self.input_wobble < REST_WOBBLE}


def prepare_identification(records, window_s, um_per_volt, hold_out, band_Hz):
    """The identification run as deviations from its operating point, cut and split.

    Parameters
    ----------
    records : OwnRecords
    window_s : (float, float)
        A stretch of the run where the input is steady at the operating point [s].
    um_per_volt : float
        Sensor: output unit per sensor volt (the output becomes ``v_y`` [V]).
    hold_out : float
        Share of the run held out for validation (its end), 0 < hold_out < 1.
    band_Hz : (float, float)
        Band the run is meant to excite [Hz].

    Returns
    -------
    IdentificationData or Skipped
        Skipped without an identification record.

    Raises
    ------
    ValueError
        When the run has no broadband excitation (99 % of its input's power
        below a tenth of ``band_Hz[1]``: e.g. a hysteresis record given as the
        identification run).
    """
    check_type("records", records, OwnRecords, "the OwnRecords of load_records")
    if not records.have_plant:
        return Skipped(NO_PLANT_NOTE)
    um_per_volt = check_positive("um_per_volt", um_per_volt)
    if not 0 < hold_out < 1:
        raise ValueError(f"hold_out must lie between 0 and 1, got {hold_out!r}")
    chirp = records.chirp
    k0, k1 = (int(round((t - chirp.t0) * chirp.fs)) for t in window_s)
    window = chirp.segment(k0, k1)
    u_op, x_op = float(window.input.mean()), float(window.output.mean())
    input_wobble = float(np.ptp(window.input)) / float(np.ptp(chirp.input))
    record = chirp.segment(k0).with_signals(
        chirp.input[k0:] - u_op, (chirp.output[k0:] - x_op) / um_per_volt,
        output_unit="V", output_name="v_y")
    excitation = ident.excitation_band(record.input, record.fs)
    if excitation < band_Hz[1] / 10:
        raise ValueError(f"{records.chirp_file}: 99 % of the input's power lies below "
                         f"{excitation:.3g} Hz, far below the band to identify "
                         f"({band_Hz[1]:g} Hz): no broadband excitation to identify the "
                         "dynamics from. Give a chirp record, or set CHIRP_FILE = None to fit "
                         "the hysteresis models only")
    estimation, held_out = recs.split(record, 1.0 - hold_out)
    return IdentificationData(chirp, tuple(window_s), u_op, x_op, input_wobble, record,
                              tuple(band_Hz), excitation, estimation, held_out)


# -- 3. identification -------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class Identification(_Shown):
    """The identified model, validated on the held-out part.

    Attributes
    ----------
    data : IdentificationData
    identified : piezolib.identification.IdentifiedModel
        What :func:`~piezolib.identification.identify_record` returned.
    model : control.TransferFunction
        G_id, u_c [V] -> v_y [V].
    y_sim : ndarray
        The model's output simulated over the whole record [V].
    fit_estimation, fit_held_out : float
        Normalised fit on either part [%].
    floor_percent : float
        The least acceptable held-out fit [%].
    seconds : float
        Time taken by the identification.
    measured : (ndarray, ndarray)
        Empirical response (omega [rad/s], complex) where the coherence exceeds 0.9.
    """

    data: object
    identified: object
    model: object
    y_sim: np.ndarray
    fit_estimation: float
    fit_held_out: float
    floor_percent: float
    seconds: float
    measured: tuple

    @property
    def n_estimation(self):
        """Samples of the estimation part (the held-out part starts there)."""
        return len(self.data.estimation)

    @property
    def pole_pairs(self):
        """The model's complex pole pairs: natural frequency [rad/s] and damping ratio."""
        wn, zeta = ident.pole_pairs(self.model)
        return pd.DataFrame({"natural frequency [rad/s]": wn, "damping ratio": zeta})

    @property
    def lines(self):
        i = self.identified
        return (f"identified in {self.seconds:.2f} s; gain in {i.output_unit}/{i.input_unit}; "
                f"fit: estimation {self.fit_estimation:.1f} %, held out "
                f"{self.fit_held_out:.1f} %",)

    def _tables(self):
        return ((self.pole_pairs, False),)

    @property
    def checks(self):
        return {f"held-out fit above {self.floor_percent:g} %":
                self.fit_held_out > self.floor_percent,
                "identified model stable": bool(np.all(ct.poles(self.model).real < 0))}


def identify(data, n_poles, n_zeros, *, nb, nk, floor_percent, coherence=0.9, nperseg=2048):
    """Identify a continuous model and score it on the held-out part
    (:func:`piezolib.identification.identify_record`).

    Parameters
    ----------
    data : IdentificationData or Skipped
    n_poles, n_zeros : int
        Continuous model structure.
    nb, nk : int
        Discrete numerator terms and input delay [samples] of the RLS stage.
    floor_percent : float
        Least acceptable validation fit [%] (a check).
    coherence : float
        The empirical response is kept where the input-output coherence exceeds this.
    nperseg : int
        Segment length of the empirical response and the coherence.

    Returns
    -------
    Identification or Skipped
    """
    if not ran(data):
        return data
    check_type("data", data, IdentificationData, "the IdentificationData of "
               "prepare_identification")
    t0 = time.perf_counter()
    identified = ident.identify_record(data.estimation, n_poles, n_zeros, nb=nb, nk=nk)
    model = identified.model
    rec, n_est = data.record, len(data.estimation)
    y_sim = ident.zoh_simulate(model, rec.input, rec.fs)
    fit_held_out = ident.fit_percent(data.held_out.output, y_sim[n_est:])
    fit_estimation = ident.fit_percent(data.estimation.output, y_sim[:n_est])
    seconds = time.perf_counter() - t0
    w, h = ident.empirical_frequency_response(rec.input, rec.output, rec.fs, nperseg=nperseg)
    f_coh, coh = sg.coherence(rec.input, rec.output, rec.fs, nperseg=nperseg)
    band = ((w >= 2 * np.pi * data.band_Hz[0]) & (w <= 2 * np.pi * data.band_Hz[1])
            & (np.interp(w / (2 * np.pi), f_coh, coh) > coherence))
    return Identification(data, identified, model, y_sim, fit_estimation, fit_held_out,
                          float(floor_percent), seconds, (w[band], h[band]))


# -- known truth (the example records come from the virtual stage) -----------------------------

@dataclass(frozen=True, eq=False, repr=False)
class KnownTruth(_Shown):
    """The true plant of the virtual stage the example records come from.

    Attributes
    ----------
    plant : control.TransferFunction
        The stage's small-signal model (the paper's G), u_c [V] -> v_y [V].
    y_true : ndarray
        Its output simulated over the identification record [V].
    fit_truth : float
        Its fit on the held-out part [%]: the ceiling the sensor noise allows.
    omega : ndarray
        Analysis grid [rad/s].
    error : ndarray
        |G_true / G_id - 1| on ``omega``.
    dc_identified, dc_true : float
        DC gains [V/V].
    """

    plant: object
    y_true: np.ndarray
    fit_truth: float
    omega: np.ndarray
    error: np.ndarray
    dc_identified: float
    dc_true: float

    @property
    def error_below_top(self):
        """Largest |G_true / G_id - 1| below 1 kHz."""
        return float(self.error[self.omega < TRUTH_TOP_RAD_S].max())

    @property
    def lines(self):
        return (f"true plant on the held-out part: fit {self.fit_truth:.1f} % (the noise "
                "ceiling)",
                f"DC gain: identified {self.dc_identified:.4f}, true {self.dc_true:.4f} V/V; "
                f"largest |G/G_id - 1| below 1 kHz {self.error_below_top:.4f}")


def known_truth(identification, omega):
    """The virtual stage's plant against the identified model (known only for the example).

    Parameters
    ----------
    identification : Identification or Skipped
    omega : array_like
        Analysis grid [rad/s].

    Returns
    -------
    KnownTruth or Skipped
    """
    if not ran(identification):
        return identification
    check_type("identification", identification, Identification, "the Identification of "
               "identify")
    omega = np.asarray(omega, dtype=float)
    rec, n_est = identification.data.record, identification.n_estimation
    G_true, G_id = VirtualStage().small_signal_model(), identification.model
    y_true = ident.zoh_simulate(G_true, rec.input, rec.fs)
    fit_truth = ident.fit_percent(identification.data.held_out.output, y_true[n_est:])
    error = np.abs(np.ravel(G_true(1j * omega)) / np.ravel(G_id(1j * omega)) - 1)
    return KnownTruth(G_true, y_true, fit_truth, omega, error, float(ct.dcgain(G_id)),
                      float(ct.dcgain(G_true)))


# -- 4. uncertainty weight ---------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class UncertaintyWeight(_Shown):
    """The coefficient set of the identified model, its envelope and covering weight.

    Attributes
    ----------
    omega : ndarray
        Grid [rad/s].
    spread : float
        ± relative spread of the denominator coefficients.
    model_set : piezolib.uncertainty.ModelSet
    envelope : ndarray
        E_m(omega) of the stable members.
    weight : control.TransferFunction
        W_m, stable and minimum phase, fitted over the envelope.
    cover : object
        :func:`piezolib.uncertainty.coverage` of the weight on the grid.
    seconds : float
    covered_rad_s : float or None
        Known truth: up to where |W| covers |G_true / G_id - 1| [rad/s].
    """

    omega: np.ndarray
    spread: float
    model_set: object
    envelope: np.ndarray
    weight: object
    cover: object
    seconds: float
    covered_rad_s: object = None

    @property
    def lines(self):
        m = self.model_set
        out = [f"{m.size} models, {unc.unstable_members(m).size} unstable; "
               f"E_m peak {self.envelope.max():.3f}; weight peak "
               f"{robust.hinf_norm(self.weight)[0]:.3f}, covers E_m: {self.cover.covers} "
               f"({self.seconds:.1f} s)"]
        if self.covered_rad_s is not None:
            out.append(f"|W| >= |G_true/G_id - 1| up to {self.covered_rad_s:.0f} rad/s "
                       f"({self.covered_rad_s / 2 / np.pi:.0f} Hz)")
        return tuple(out)

    @property
    def checks(self):
        W = self.weight
        return {"the weight covers its model set's envelope": bool(self.cover.covers),
                "the weight is stable and minimum phase":
                bool(np.all(ct.poles(W).real < 0) and np.all(ct.zeros(W).real < 0))}


def uncertainty_weight(identification, spread, levels, order, omega, truth=None):
    """The covering weight of the identified model's coefficient set (Sec. III-B's method).

    Parameters
    ----------
    identification : Identification or Skipped
    spread : float
        ± relative spread of each denominator coefficient.
    levels : int
        Values per coefficient (``levels ** n_poles`` models).
    order : int
        Order of the covering weight.
    omega : array_like
        Grid [rad/s].
    truth : KnownTruth, optional
        Where known: up to where the weight covers the real model error.

    Returns
    -------
    UncertaintyWeight or Skipped
    """
    if not ran(identification):
        return identification
    spread = check_positive("spread", spread)
    omega = np.asarray(omega, dtype=float)
    t0 = time.perf_counter()
    mset = unc.model_set(identification.model, spread, levels)
    envelope = unc.relative_error_envelope(mset, omega, "stable")
    W_m = unc.fit_covering_weight(omega, envelope, order=order)
    cover = unc.coverage(W_m, omega, envelope)
    seconds = time.perf_counter() - t0
    covered = None
    if ran(truth):
        uncovered = omega[truth.error > np.abs(np.ravel(W_m(1j * omega)))]
        covered = float(uncovered.min()) if uncovered.size else np.inf
    return UncertaintyWeight(omega, spread, mset, envelope, W_m, cover, seconds, covered)


# -- 5. hysteresis -----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class HysteresisLoops(_Shown):
    """The hysteresis records after their start-up, from an input minimum, decimated.

    Attributes
    ----------
    data : dict
        {label: (u_c [V], v_y [V])}.
    dropped : dict
        {label: what was dropped at the start} (empty without ``skip_transient``).
    """

    data: dict
    dropped: dict

    @property
    def lines(self):
        return tuple(f"{label}: dropped the {text}" for label, text in self.dropped.items())


def prepare_loops(records, um_per_volt, decimation, skip_transient=True):
    """Each hysteresis record after its start-up, cut to start at an input minimum, decimated.

    The start-up (rest, the voltage step, the ringing after it, the virgin
    stroke: :func:`piezolib.records.find_start_up`) is dropped with
    ``skip_transient``; a record whose first turning point is a maximum is cut
    at the next one, so that every record starts after a descending stroke.

    Parameters
    ----------
    records : OwnRecords
    um_per_volt : float
        Output unit per sensor volt: the output becomes v_y [V].
    decimation : int
        Decimation factor (behind an anti-alias filter, :func:`piezolib.records.decimate`).
    skip_transient : bool

    Returns
    -------
    HysteresisLoops
    """
    check_type("records", records, OwnRecords, "the OwnRecords of load_records")
    um_per_volt = check_positive("um_per_volt", um_per_volt)
    decimation = check_integer("decimation", decimation, 1)
    data, dropped = {}, {}
    for label, rec in records.loops.items():
        cut = recs.cut_at_turning_points(rec, skip_transient=skip_transient)
        if cut.input[0] > cut.input[recs.turning_points(cut.input)[0]]:   # starts at a maximum
            cut = recs.cut_at_turning_points(rec, first=1, skip_transient=skip_transient)
        if skip_transient:
            dropped[label] = cut.metadata["dropped"]
        cut = recs.decimate(cut, decimation)
        data[label] = (cut.input, cut.output / um_per_volt)
    return HysteresisLoops(data, dropped)


@dataclass(frozen=True, eq=False, repr=False)
class HysteresisChoice(_Shown):
    """Dahl and Prandtl-Ishlinskii fits and the model chosen by validation.

    Attributes
    ----------
    fits : dict
        {"Dahl": fit, "PI": fit} (:func:`piezolib.hysteresis.fit_dahl`, :func:`~piezolib.hysteresis.fit_pi`).
    scores : pandas.DataFrame
        :func:`piezolib.hysteresis.validation_table` on the validation data.
    chosen_name : str
    validation_data : list of (v, x)
    validation_names : list of str
    held_out_in_time : bool
        No validation record that was not fitted: the second half of each
        fitted record was held out.
    fit_loops : tuple of str
    warnings : tuple of str
        The fits' warnings (a parameter on a bound or not identifiable).
    seconds : dict
        {"Dahl": s, "PI": s}.
    ceiling_percent : float
        Largest acceptable validation RMS [% of stroke] (a check).
    """

    fits: dict
    scores: pd.DataFrame
    chosen_name: str
    validation_data: list
    validation_names: list
    held_out_in_time: bool
    fit_loops: tuple
    warnings: tuple
    seconds: dict
    ceiling_percent: float

    @property
    def chosen(self):
        """The chosen model."""
        return self.fits[self.chosen_name].model

    @property
    def models(self):
        """{name: fitted model}."""
        return {name: f.model for name, f in self.fits.items()}

    def validation_rms(self, name):
        """Pooled validation RMS of a model [% of stroke]."""
        return float(self.scores.loc[name, "pooled RMS %"].iloc[0])

    @property
    def lines(self):
        out = []
        if self.held_out_in_time:
            out.append("No validation record that was not fitted: the models are fitted to the "
                       f"first half of {', '.join(self.fit_loops)} and validated on the second "
                       "half (held out in time).")
        out += [f"fit warning: {w}" for w in self.warnings]
        d, p = self.fits["Dahl"], self.fits["PI"]
        out.append(f"fit times: Dahl {self.seconds['Dahl']:.2f} s, PI {self.seconds['PI']:.3f} "
                   f"s; fit RMS: Dahl {d.pooled_rms_percent:.2f} %, PI "
                   f"{p.pooled_rms_percent:.2f} %; PI start {p.model.start!r}; validated on "
                   f"{', '.join(self.validation_names)}; chosen: {self.chosen_name}")
        return tuple(out)

    def _tables(self):
        return ((self.scores, True),)

    @property
    def checks(self):
        s = self.scores
        return {f"a model validates below {self.ceiling_percent:g} % of stroke":
                bool(min(s["RMS %"]) < self.ceiling_percent),
                "the chosen model validates best":
                bool(self.validation_rms(self.chosen_name) == s["pooled RMS %"].min())}


def fit_hysteresis(loops, fit_loops, validation_loops, *, gamma_a, plays, ceiling_percent):
    """Fit a Dahl and a Prandtl-Ishlinskii model; choose the one that validates best.

    The Dahl model (Bliman-Sorine form, output offset, from rest) and a PI
    model with ``plays`` plays (its start chosen by the data) are fitted to
    ``fit_loops``; the smaller pooled RMS error on ``validation_loops`` (the
    ones not fitted) decides.  With no validation record that was not fitted,
    the models are fitted to the first half of each fitted record and scored
    on its second half: never on the samples they were fitted to.

    Parameters
    ----------
    loops : HysteresisLoops
    fit_loops, validation_loops : sequence of str
        Labels of the records fitted and validated on.
    gamma_a : float
        Dahl input weight (only beta2 gamma_a is identifiable).
    plays : int
        Prandtl-Ishlinskii plays (the linear one included).
    ceiling_percent : float
        Largest acceptable validation RMS [% of stroke] (a check).

    Returns
    -------
    HysteresisChoice
    """
    check_type("loops", loops, HysteresisLoops, "the HysteresisLoops of prepare_loops")
    fit_loops, validation_loops = tuple(fit_loops), tuple(validation_loops)
    unknown = sorted(set(fit_loops + validation_loops) - set(loops.data))
    if unknown or not fit_loops:
        raise ValueError(f"fit_loops and validation_loops must name records among "
                         f"{sorted(loops.data)} (fit_loops at least one), got unknown {unknown}")
    held_out_in_time = not (set(validation_loops) - set(fit_loops))
    if held_out_in_time:
        halves = {label: hy.split_record(*loops.data[label], 0.5) for label in fit_loops}
        fit_data = [halves[label][0] for label in fit_loops]
        validation_data = [halves[label][1] for label in fit_loops]
        validation_names = [f"{label} (second half)" for label in fit_loops]
    else:
        fit_data = [loops.data[label] for label in fit_loops]
        validation_names = [label for label in validation_loops if label not in fit_loops]
        validation_data = [loops.data[label] for label in validation_names]
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as fit_warnings:
        warnings.simplefilter("always", hy.FitWarning)
        dahl_fit = hy.fit_dahl(fit_data, gamma_a, form="bliman_sorine", offset=True,
                               start="rest")
        t_dahl = time.perf_counter() - t0
        pi_fit = hy.fit_pi(fit_data, n_plays=plays, offset=True)     # start: by the data
    t_pi = time.perf_counter() - t0 - t_dahl
    fits = {"Dahl": dahl_fit, "PI": pi_fit}
    scores = hy.validation_table({name: f.model for name, f in fits.items()}, validation_data,
                                 names=validation_names)
    return HysteresisChoice(fits, scores, hy.pooled_rms(scores).idxmin(), validation_data,
                            validation_names, held_out_in_time, fit_loops,
                            tuple(str(w.message) for w in fit_warnings),
                            {"Dahl": t_dahl, "PI": t_pi}, float(ceiling_percent))


# -- 6. the mu controller at the control-loop rate ---------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class LoopDesign(_Shown):
    """The mu controller designed for the real-time loop, reduced and discretised.

    Attributes
    ----------
    H_e, H_y : control.TransferFunction
        Error and output weights.
    rolloff : piezolib.problem.genplant.RolloffWeight
    design : piezolib.problem.design.ControllerDesign
        What :func:`~piezolib.problem.design.design_controller` returned.
    delay_samples : int
        The loop's computation delay [samples].
    seconds : float
    """

    H_e: object
    H_y: object
    rolloff: object
    design: object
    delay_samples: int
    seconds: float

    @property
    def K(self):
        """The reduced continuous controller."""
        return self.design.K_reduced

    @property
    def K_d(self):
        """The discrete controller the loop runs."""
        return self.design.K_discrete

    @property
    def lines(self):
        d = self.design
        return (f"design {self.seconds:.1f} s: DK mu_RP {d.musyn.mu_peak:.3f} "
                f"(lower {d.musyn.mu_lower_peak:.3f}), {d.K_full.nstates} -> {self.K.nstates} "
                f"states; discretised at {d.fs:g} Hz, response match below "
                f"{d.discrete.check_Hz:g} Hz: {d.discrete.matches}",)

    @property
    def checks(self):
        d, h = self.design, self.design.musyn.history
        return {"DK bounds ordered (lower <= upper)":
                bool(np.all(h.mu_lower <= h.mu_upper * (1 + 1e-6))),
                "the discrete controller matches and its loop is stable":
                bool(d.discrete.matches and d.discrete.loop_stable)}


def design_for_loop(identification, weight, error_weight, output_weight, rolloff, *, order,
                    d_order, iterations, fs, delay_samples):
    """A mu controller for the identified model at the real-time loop's rate and delay.

    The synthesis plant models the loop's hold and computation delay (Padé)
    and the roll-off weight (:func:`piezolib.problem.design.design_controller`):
    a quick DK-iteration, balanced reduction to ``order`` states, Tustin
    discretisation.

    Parameters
    ----------
    identification : Identification or Skipped
    weight : UncertaintyWeight or Skipped
        H_m is its covering weight.
    error_weight, output_weight : dict
        Keyword arguments of :func:`piezolib.robust.sensitivity_weight` (H_e on |S|)
        and :func:`~piezolib.robust.complementary_sensitivity_weight` (H_y on |T|).
    rolloff : dict
        Keyword arguments of :class:`piezolib.problem.genplant.RolloffWeight`;
        its frequency [rad/s] must lie below the loop's Nyquist frequency pi fs.
    order, d_order, iterations : int
        Controller states, D-scaling order, DK-iterations.
    fs : float
        The real-time loop's rate [Hz] (not the records').
    delay_samples : int
        The loop's computation delay [samples].

    Returns
    -------
    LoopDesign or Skipped

    Raises
    ------
    ValueError
        When the roll-off corner lies above the loop's Nyquist frequency.
    """
    if not ran(identification):
        return identification
    fs = check_positive("fs", fs)
    H_e = robust.sensitivity_weight(**error_weight, inputs="v_e", outputs="y1", name="H_e")
    H_y = robust.complementary_sensitivity_weight(**output_weight, inputs="v_y", outputs="y2",
                                                  name="H_y")
    rolloff = genplant.RolloffWeight(**rolloff)
    if not rolloff.frequency < np.pi * fs:
        raise ValueError(f"rolloff: its frequency {rolloff.frequency:g} rad/s lies above the "
                         f"loop's Nyquist frequency {np.pi * fs:g} rad/s")
    t0 = time.perf_counter()
    design = design_controller(identification.model, weight.weight, H_e, H_y, order=order,
                               d_order=d_order, max_iter=iterations, fs=fs,
                               delay_samples=delay_samples, rolloff=rolloff, fixed_order=False)
    return LoopDesign(H_e, H_y, rolloff, design, delay_samples, time.perf_counter() - t0)


# -- verification, independent of the synthesis ------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class Verification(_Shown):
    """The designed loop recomputed: mu bounds (Padé and exact delay) and loop figures per plant.

    Attributes
    ----------
    loop : LoopDesign
    omega : ndarray
        The fine grid of the mu bounds [rad/s].
    mu_pade, mu_exact : piezolib.robust.MuResult
        mu_RP bounds of the reduced controller, with the Padé and the exact delay.
    plants : dict
        {"identified": G_id, ...}: the plants the loop is checked with.
    table : pandas.DataFrame
        One column per plant: closed-loop poles, Table 3's nominal norms,
        the sampled loop's spectral radius per delay, delay, phase and disk margins.
    seconds : float
    """

    loop: object
    omega: np.ndarray
    mu_pade: object
    mu_exact: object
    plants: dict
    table: pd.DataFrame
    seconds: float

    @property
    def lines(self):
        p, e = self.mu_pade, self.mu_exact
        return (f"mu_RP of the {self.loop.K.nstates}-state controller: Pade delay "
                f"{p.upper.max():.3f} (lower {p.lower.max():.3f}); exact delay "
                f"{e.upper.max():.3f} (lower {e.lower.max():.3f}); verification "
                f"{self.seconds:.1f} s",)

    def _tables(self):
        return ((self.table, True),)

    def radius(self, plant, delay):
        """Spectral radius of the sampled loop with ``delay`` samples, for one plant."""
        return float(self.table.loc[f"radius, {delay} delay", plant])

    @property
    def checks(self):
        K, r, delay = self.loop.K, self.loop.rolloff, self.loop.delay_samples
        high = self.omega[self.omega > 2 * r.frequency]
        col = self.table["identified"]
        return {
            "mu bounds ordered (Pade and exact delay)":
            all(bool(np.all(m.lower <= m.upper * (1 + 1e-6)))
                for m in (self.mu_pade, self.mu_exact)),
            "continuous loop stable": bool(col["max Re closed-loop pole [rad/s]"] < 0),
            f"sampled loop stable with {delay} sample(s) of delay":
            bool(col[f"radius, {delay} delay"] < 1),
            f"the controller rolls off: |K| < {r.hf_gain:g} above twice the roll-off frequency":
            bool(np.all(np.abs(np.ravel(K(1j * high))) < r.hf_gain))}


def verify_design(loop, identification, weight, truth=None):
    """Recompute the designed loop independently of the synthesis.

    mu upper and lower bounds of the reduced controller on a fine grid, with
    the synthesis plant's Padé delay and with the exact delay; with each plant
    (the identified one, and the true one where known): the continuous
    closed-loop poles, Table 3's nominal conditions, the spectral radius of the
    sampled loop (ZOH plant, z^-d, discrete controller) for 0 ... d + 1 samples
    of delay, the delay margin and the classical margins.

    Parameters
    ----------
    loop : LoopDesign or Skipped
    identification : Identification
    weight : UncertaintyWeight
    truth : KnownTruth, optional

    Returns
    -------
    Verification or Skipped
    """
    if not ran(loop):
        return loop
    check_type("loop", loop, LoopDesign, "the LoopDesign of design_for_loop")
    d = loop.design
    fs, delay = d.fs, loop.delay_samples
    t0 = time.perf_counter()
    fine = np.logspace(*VERIFICATION_GRID)                               # rad/s
    blk = genplant.DESIGN_BLOCK_STRUCTURE
    G_id, W_m, K = identification.model, weight.weight, loop.K
    mu_pade = robust.mussv(robust.lft_response(d.plant, K, fine), blk, fine)
    mu_exact = robust.mussv(genplant.delayed_closed_loop_response(
        K, G_id, W_m, loop.H_e, loop.H_y, fine, fs=fs, delay_samples=delay,
        rolloff=loop.rolloff), blk, fine)
    plants = {"identified": G_id, **({"true G (known here)": truth.plant} if ran(truth) else {})}
    rows = {}
    for name, G in plants.items():
        a = analysis.analyze(K, G, W_m, loop.H_e, loop.H_y, name=name)
        tol = robust.delay_tolerance(G, loop.K_d, delays=range(delay + 2))
        m = robust.loop_margins(G, K)
        rows[name] = {"max Re closed-loop pole [rad/s]": robust.closed_loop_poles(G, K).real.max(),
                      "||H_e S||": a.norm_He_S, "||H_y T||": a.norm_Hy_T, "mu_RS (H_m T)": a.mu_RS,
                      **{f"radius, {k} delay": r for k, r in zip(tol.delays, tol.spectral_radius)},
                      "delay margin [samples]": tol.delay_margin_samples,
                      "phase margin [deg]": m.phase_margin_deg, "disk margin": m.disk_margin}
    table = pd.DataFrame(rows)
    return Verification(loop, fine, mu_pade, mu_exact, plants, table, time.perf_counter() - t0)


# -- 7. feedforward ----------------------------------------------------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class FeedforwardCheck(_Shown):
    """Each fitted model's feedforward applied to every fitted model
    (:func:`piezolib.hysteresis.cross_check`).

    Attributes
    ----------
    table : pandas.DataFrame
        Indexed by (compensator, plant): RMS %, max %, hysteresis %.
    x_ref : ndarray
        The reference [sensor V]: the validation loop's input mapped through the chosen model.
    chosen_name : str
    """

    table: pd.DataFrame
    x_ref: np.ndarray
    chosen_name: str

    @property
    def lines(self):
        return ()

    def _tables(self):
        return ((self.table, True),)

    @property
    def checks(self):
        n = self.chosen_name
        return {"the chosen model's feedforward inverts it (RMS below 0.5 %)":
                bool(np.isclose(self.table.loc[(n, n), "RMS %"], 0, atol=0.5))}


def feedforward_cross_check(choice):
    """The fitted models' feedforwards, each applied to every fitted model.

    The reference is the first validation record's input mapped through the
    chosen model (a reachable displacement).

    Parameters
    ----------
    choice : HysteresisChoice

    Returns
    -------
    FeedforwardCheck
    """
    check_type("choice", choice, HysteresisChoice, "the HysteresisChoice of fit_hysteresis")
    x_ref = choice.chosen.simulate(choice.validation_data[0][0])
    models = choice.models
    return FeedforwardCheck(hy.cross_check(models, models, x_ref), x_ref, choice.chosen_name)


# -- 8. the Tables 4-5-style experiment on the virtual stage -----------------------------------

@dataclass(frozen=True, eq=False, repr=False)
class Experiments(_Shown):
    """Tables 4-5-style runs on the virtual stage with the Dahl feedforward (Cases I-III).

    Attributes
    ----------
    table4, table5 : piezolib.workbook.experiments results
        :func:`~piezolib.workbook.experiments.hysteresis_test` and
        :func:`~piezolib.workbook.experiments.tracking_test`.
    chosen4 : result or None
        Table 4 with the chosen model's feedforward when it is not the Dahl model.
    chosen_name : str
    n_warnings : int
        Warnings the runs raised.
    seconds : float
    """

    table4: object
    table5: object
    chosen4: object
    chosen_name: str
    n_warnings: int
    seconds: float

    @property
    def extra4(self):
        """{label: Series}: Case II with the chosen model's feedforward (empty for Dahl)."""
        return {} if self.chosen4 is None else {
            f"II: {self.chosen_name} feedforward": self.chosen4.table.loc["case_II"]}

    @property
    def table4_view(self):
        """Table 4 with the chosen model's Case II as a further row."""
        view = self.table4.table.copy()
        for label, series in self.extra4.items():
            view.loc[label] = series.values
        return view

    @property
    def saturated(self):
        """Samples at an output limit in all runs."""
        return int(self.table4.saturation.values.sum() + self.table5.saturation.values.sum())

    @property
    def lines(self):
        return (f"experiments {self.seconds:.1f} s; {self.n_warnings} warning(s); saturated "
                f"samples: {self.saturated}",)

    def _tables(self):
        return ((self.table4_view, True), (self.table5.table, True))

    @property
    def checks(self):
        cases = ["case_I", "case_II", "case_III"]
        return {"no experiment diverged (every Table 4-5 value finite)":
                all(bool(np.all(np.isfinite(t.loc[cases].values)))
                    for t in (self.table4.table, self.table5.table))}


def run_experiments(loop, choice, *, seed, noise_rms_V, amplitudes_V, periods, frequencies_Hz,
                    amplitude_um, delay_samples, loop_rate_Hz):
    """Tables 4-5-style runs on the virtual stage: Cases I-III with the Dahl feedforward.

    The tables use the Dahl feedforward (the paper's method); when another
    model is chosen, Table 4 runs with its feedforward as well.

    Parameters
    ----------
    loop : LoopDesign or Skipped
    choice : HysteresisChoice
    seed : int
        The stage's noise seed.
    noise_rms_V : float
        Sensor noise [V].
    amplitudes_V : sequence of float
        Table 4's actuator amplitudes [V].
    periods : int
        Periods per amplitude.
    frequencies_Hz : sequence of float
        Table 5's triangle frequencies [Hz].
    amplitude_um : float
        Table 5's amplitude [um].
    delay_samples : int
        The loop's computation delay [samples].
    loop_rate_Hz : float
        The rate the controller was designed for; the stage's loop must run at it.

    Returns
    -------
    Experiments or Skipped

    Raises
    ------
    ValueError
        When the virtual stage's loop does not run at ``loop_rate_Hz``.
    """
    if not ran(loop):
        return loop
    check_type("choice", choice, HysteresisChoice, "the HysteresisChoice of fit_hysteresis")
    stage = VirtualStage(seed=seed, noise_rms_V=noise_rms_V)
    if stage.fs != loop_rate_Hz:
        raise ValueError(f"loop_rate_Hz: the experiment loop runs at {stage.fs:g} Hz, the "
                         f"controller was designed for {loop_rate_Hz:g} Hz")
    chosen = choice.chosen
    dahl_ff = chosen if isinstance(chosen, hy.DahlModel) else choice.fits["Dahl"].model
    test4 = dict(amplitudes_V=amplitudes_V, periods=periods, discard_periods=DISCARD_PERIODS,
                 delay_samples=delay_samples)
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as run_warnings:
        warnings.simplefilter("always")
        table4 = exps.hysteresis_test(stage, dahl_ff, loop.K_d, **test4)
        table5 = exps.tracking_test(stage, dahl_ff, loop.K_d, frequencies_Hz=frequencies_Hz,
                                    amplitude_um=amplitude_um, delay_samples=delay_samples)
        chosen4 = None if chosen is dahl_ff else exps.hysteresis_test(stage, chosen, loop.K_d,
                                                                      **test4)
    return Experiments(table4, table5, chosen4, choice.chosen_name, len(run_warnings),
                       time.perf_counter() - t0)


# -- claims and checks -------------------------------------------------------------------------

def record_claims(claims, records, identification, weight, choice, loop, verification,
                  experiments, truth=None):
    """Add the notebook's results to its claim table (no published values: the paper has no
    such stage), in the order the notebook computes them.

    Parameters
    ----------
    claims : piezolib.workbook.report.ClaimTable
    records : OwnRecords
    identification, weight, loop, verification, experiments
        The stages' results (or :class:`Skipped`: their rows are left out).
    choice : HysteresisChoice
    truth : KnownTruth, optional
        Adds the comparisons with the true plant.

    Returns
    -------
    ClaimTable
        ``claims``.
    """
    c = SECTION
    claims.add(c, "record sampling rate", None, next(iter(records.loops.values())).fs, unit="Hz")
    known = ran(truth)
    if ran(identification):
        claims.add(c, "control-loop rate of the design", None, loop.design.fs, unit="Hz")
        claims.add(c, "validation fit on the held-out chirp", None, identification.fit_held_out,
                   unit="%", note=f"true plant on the same samples: {truth.fit_truth:.2f} % "
                   "(noise ceiling)" if known else "")
        claims.add(c, "DC gain of the identified model", None,
                   float(ct.dcgain(identification.model)), unit="V/V",
                   note=f"true {truth.dc_true:.4f}" if known else "")
        if known:
            claims.add(c, "largest |G_true/G_id - 1| below 1 kHz", None, truth.error_below_top)
            claims.add(c, "weight covers the true error up to", None, weight.covered_rad_s,
                       unit="rad/s")
    for name, f in choice.fits.items():
        claims.add(c, f"{name}: validation RMS on {', '.join(choice.validation_names)}", None,
                   choice.validation_rms(name), unit="% of stroke",
                   note=f"fit RMS {f.pooled_rms_percent:.3f} %" + (
                       "; held out in time: no validation record that was not fitted"
                       if choice.held_out_in_time else ""))
    claims.add(c, "hysteresis model chosen by validation", None, choice.chosen_name)
    if ran(verification):
        p, e = verification.mu_pade, verification.mu_exact
        claims.add(c, "mu_RP upper bound (Pade delay)", None, float(p.upper.max()),
                   note=f"lower {p.lower.max():.4f}; exact delay {e.upper.max():.4f}")
        delay = verification.loop.delay_samples
        for name in verification.plants:
            claims.add(c, f"sampled loop spectral radius, {delay} delay, {name}", None,
                       verification.radius(name, delay))
            claims.add(c, f"||H_y T||, {name}", None,
                       float(verification.table.loc["||H_y T||", name]))
    if ran(experiments):
        t4, t5 = experiments.table4.table, experiments.table5.table
        for A in t4.columns:
            for case in ("I", "II", "III"):
                claims.add(c, f"hysteresis %, {A:g} V, case {case}", None,
                           float(t4.loc[f"case_{case}", A]), unit="%")
            if experiments.chosen4 is not None:
                claims.add(c, f"hysteresis %, {A:g} V, case II with {experiments.chosen_name}",
                           None, float(experiments.chosen4.table.loc["case_II", A]), unit="%")
        for f in t5.columns:
            for case in ("I", "II", "III"):
                claims.add(c, f"tracking error %, {f:g} Hz, case {case}", None,
                           float(t5.loc[f"case_{case}", f]), unit="%")
    return claims


def stage_checks(*results):
    """The checks of every stage that ran, in one dict (what holds for any user's data).

    Examples
    --------
    >>> stage_checks(Skipped("no plant"), None)
    {}
    """
    out = {}
    for result in results:
        if ran(result):
            out.update(result.checks)
    return out


def known_truth_checks(truth, identification, weight, choice, verification, experiments):
    """What this example's known truth states (the records come from the virtual stage).

    The stage's hysteresis is made of play operators, so the PI model is
    chosen; with a plant: the identified model within 1 % in DC gain and 5 %
    below 1 kHz of the true one, its held-out fit within 15 points of the
    true plant's, the weight covering the real error past 1 kHz, the loop
    with the true plant stable (continuous and sampled with the delay),
    robust performance (mu_RP < 1) with the exact delay, and feedback and the
    chosen feedforward beating the open loop.

    Returns
    -------
    dict
        {what it states: bool}.
    """
    out = {"PI chosen (the stage's hysteresis is made of plays)": choice.chosen_name == "PI"}
    if not ran(truth):
        return out
    delay = verification.loop.delay_samples
    col = verification.table["true G (known here)"]
    t4, t5 = experiments.table4.table, experiments.table5.table
    out.update({
        "DC gain within 1 % of the true plant's":
        bool(abs(truth.dc_identified / truth.dc_true - 1) < 0.01),
        "|G_true/G_id - 1| below 5 % up to 1 kHz": truth.error_below_top < 0.05,
        "held-out fit within 15 points of the true plant's":
        bool(identification.fit_held_out > truth.fit_truth - 15),
        "the weight covers the real error past 1 kHz": weight.covered_rad_s > TRUTH_TOP_RAD_S,
        "loop with the true plant stable": bool(col["max Re closed-loop pole [rad/s]"] < 0),
        f"sampled loop with the true plant stable with {delay} sample(s) of delay":
        bool(col[f"radius, {delay} delay"] < 1),
        "robust performance with the exact loop delay (mu_RP < 1)":
        bool(verification.mu_exact.upper.max() < 1),
        "feedback beats open loop (Table 4)": bool((t4.loc["case_III"] < t4.loc["case_I"]).all()),
        "feedback beats open loop (Table 5)": bool((t5.loc["case_III"] < t5.loc["case_I"]).all())})
    if experiments.extra4:
        chosen_II = experiments.extra4[f"II: {experiments.chosen_name} feedforward"].values
        out[f"the {experiments.chosen_name} feedforward beats open loop (Table 4)"] = bool(
            (chosen_II < t4.loc["case_I"].values).all())
    return out


def summary_lines(records, seconds):
    """Findings of the notebook that are not claims: what ran, and how long it took.

    Examples
    --------
    >>> summary_lines(OwnRecords(None, {}, 5e3), 12.34)[-1]
    'the notebook ran in 12.3 s'
    """
    out = [] if records.have_plant else [NO_PLANT_NOTE]
    return out + [f"the notebook ran in {seconds:.1f} s"]
