"""Notebook 08's pipeline on a user's own records, from the records to the plant model: the
records, the operating point, identification, the example's known truth, the uncertainty weight.

Notebook 08 runs the workbook's pipeline on records in whatever form an
acquisition wrote them (columns, units, sampling rate: the notebook's
parameters).  Each stage is one call that returns a result object: what
the stage computed, the lines a reader sees under the cell (its display, with
any table in the one number format of :func:`piezolib.workbook.tables.readable`)
and ``checks``, a dict {what it states: bool} that the notebook asserts at its
end (:func:`~piezolib.workbook.your_stage_claims.stage_checks`)::

    records = load_records(folder, "chirp.csv", {"sine": "loop_sine.csv"}, columns=..., fs=5e3)
    data = prepare_identification(records, (0.15, 0.29), um_per_volt=3.0, hold_out=0.1,
                                  band_Hz=(5.0, 2000.0))       # operating point, cut, split
    model = identify(data, 6, 3, nb=6, nk=1, floor_percent=70.0)
    weight = uncertainty_weight(model, 0.015, 3, 4, omega)

The later stages are in :mod:`~piezolib.workbook.your_stage_hysteresis` (loops,
hysteresis choice, feedforward cross-check), :mod:`~piezolib.workbook.your_stage_control`
(loop design, verification, experiments) and :mod:`~piezolib.workbook.your_stage_claims`
(claim rows, checks, summary); the result display and :class:`Skipped` defined
here are theirs too.

A folder with hysteresis records only (no identification record) has no
plant: the stages that need one return :class:`Skipped`, which says why,
passes through the later stages and has no checks.  :func:`known_truth` is
the plant of the virtual stage the example records come from; on real data it
is left out (``truth=None`` everywhere) together with
:func:`~piezolib.workbook.your_stage_claims.known_truth_checks`.
"""

import html
import re
import time
from dataclasses import dataclass

import control as ct
import numpy as np
import pandas as pd
import scipy.signal as sg

from piezolib import identification as ident
from piezolib import records as recs
from piezolib import robust
from piezolib import uncertainty as unc
from piezolib._checks import (check_band, check_count, check_finite_array, check_frequency_grid,
                              check_integer, check_path, check_positive, check_type)
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import study as studies
from piezolib.workbook import tables
from piezolib.workbook.outputs import data_dir

__all__ = ["NO_PLANT_NOTE", "Skipped", "OwnRecords", "IdentificationData", "Identification",
           "KnownTruth", "UncertaintyWeight", "analysis_grid", "records_study", "load_records",
           "prepare_identification", "identify", "known_truth", "uncertainty_weight", "ran"]

#: What a stage that needs the plant says when there is no identification record.
NO_PLANT_NOTE = ("skipped: no identification record (CHIRP_FILE = None), so no plant model; "
                 "the hysteresis models are fitted and validated, the steps that need the "
                 "plant (weight, controller, experiments) are not run")

#: Largest variation of the input over the operating window, as a share of its range.
REST_WOBBLE = 1e-3
#: Frequency below which the identified model is compared with the true plant [rad/s].
TRUTH_TOP_RAD_S = 2 * np.pi * 1000.0


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


#: Most points of an analysis grid (:func:`analysis_grid`).
MAX_GRID_POINTS = 100_000


def analysis_grid(low_rad_s, high_rad_s, points=1000):
    """The logarithmic analysis grid of the notebook [rad/s]
    (:func:`piezolib.robust.frequency_grid`).

    Examples
    --------
    >>> w = analysis_grid(1.0, 1e6)
    >>> w.size, float(w[0]), float(w[-1])
    (1000, 1.0, 1000000.0)
    """
    low_rad_s = check_positive("low_rad_s", low_rad_s)
    high_rad_s = check_positive("high_rad_s", high_rad_s)
    if high_rad_s <= low_rad_s:
        raise ValueError(f"high_rad_s ({high_rad_s:g}) must exceed low_rad_s ({low_rad_s:g})")
    points = check_count("points", points, maximum=MAX_GRID_POINTS, minimum=2,
                         why="an analysis grid this fine only costs time")
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


def records_study(study, folder):
    """The study notebook 08 writes under: the one given, or one of the records' own.

    The reference study's outputs (``data/results/``, ``figures/``) are the
    committed results of the example records; a user's records never write
    there.

    Parameters
    ----------
    study : str, pathlib.Path, Study or None
        As :func:`piezolib.workbook.session.start`; None: ``"reference"`` for
        the example records, and for records of one's own a study named
        ``own_<folder name>`` (outputs under ``runs/own_<folder name>/``).
    folder : str, pathlib.Path or None
        The records' folder (None: the example records).

    Returns
    -------
    str, pathlib.Path or Study
        What to pass to :func:`~piezolib.workbook.session.start`.

    Raises
    ------
    ValueError
        The reference study named for records of one's own.

    Examples
    --------
    >>> records_study(None, None)
    'reference'
    >>> records_study(None, "../my stage/runs 2026").name
    'own_runs_2026'
    >>> records_study("wide_error_weight", "../runs")          # a study of studies/
    'wide_error_weight'
    """
    if folder is None:
        return studies.REFERENCE if study is None else study
    folder = check_path("folder", folder)
    if study is None:
        name = "own_" + (re.sub(r"[^A-Za-z0-9_-]+", "_", folder.resolve().name).strip("_")
                         or "records")
        return studies.load(studies.REFERENCE).replace(
            name=name, description=f"notebook 08 on the records in {folder}")
    if studies.load(study).is_reference:
        raise ValueError(f"study {studies.REFERENCE!r} holds the example records' committed "
                         f"results; records of one's own ({folder}) need a study of their "
                         "own: leave study = None (runs/own_<folder name>/) or name one")
    return study


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
    folder = data_dir() / "own_stage" if folder is None else check_path("folder", folder)
    if chirp_file is not None:
        check_path("chirp_file", chirp_file)
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
        scale = spec[2]
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) \
                or not np.isfinite(scale) or scale == 0:
            raise ValueError(f"{name} scale must be a finite non-zero number, got {scale!r}")
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
    if isinstance(window_s, (str, bytes)):
        raise TypeError(f"window_s must be a pair (start, end) [s], got {window_s!r}")
    window = check_finite_array("window_s", window_s, shape=(2,), real=True)
    if window[1] <= window[0]:
        raise ValueError(f"window_s must be (start, end) with start < end [s], got {tuple(window)}")
    um_per_volt = check_positive("um_per_volt", um_per_volt)
    if not 0 < check_positive("hold_out", hold_out) < 1:
        raise ValueError(f"hold_out must lie between 0 and 1, got {hold_out!r}")
    check_band("band_Hz", band_Hz)
    if not records.have_plant:
        return Skipped(NO_PLANT_NOTE)
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
    n_poles = check_integer("n_poles", n_poles, minimum=1)
    n_zeros = check_integer("n_zeros", n_zeros, minimum=0)
    nb = check_integer("nb", nb, minimum=1)
    nk = check_integer("nk", nk, minimum=0)
    floor_percent = check_positive("floor_percent", floor_percent)
    coherence = float(check_finite_array("coherence", coherence, ndim=0, real=True))
    if not 0 <= coherence < 1:
        raise ValueError(f"coherence must lie in [0, 1), got {coherence!r}")
    nperseg = check_integer("nperseg", nperseg, minimum=8)
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
    if not ran(identification):                 # a skip passes on
        return identification
    check_type("identification", identification, Identification, "the Identification of "
               "identify")
    omega = check_frequency_grid("omega", omega)
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
    if not ran(identification):                 # a skip passes on
        return identification
    check_type("identification", identification, Identification, "the Identification of "
               "identify")
    spread = check_positive("spread", spread)
    levels = check_integer("levels", levels, minimum=2)
    order = check_integer("order", order, minimum=1)
    omega = check_frequency_grid("omega", omega)
    if truth is not None and not isinstance(truth, Skipped):
        check_type("truth", truth, KnownTruth, "the KnownTruth of known_truth, or None")
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
