"""Experiment files of the virtual stage: chirps and Table 4 Case I loops.

:func:`write_experiment_files` (also ``python -m piezolib data``) runs the
experiments the notebooks read on default :class:`~piezolib.problem.stage.VirtualStage`
instances and writes them to ``data/`` as CSV: the identification and the
independent validation chirp (paper Sec. III-A, Step I) and the Table 4
Case I triangles of 10/20/30/40 V actuator amplitude at 10 Hz.  Fixed seeds
and float formats make reruns byte-identical.  :func:`load_chirp`,
:func:`load_hysteresis_loops` and :func:`load_record` read them back.  The
file format is described in ``data/README.md``.
"""

import io
import json
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from piezolib import files, records, signals
from piezolib._checks import check_path, check_positive, check_type
from piezolib.problem import paper
from piezolib.problem.paths import check_directory, data_dir
from piezolib.problem.stage import (ADC_RANGE_V, RECORD_COLUMNS, Saturation, StageRecord,
                                    VirtualStage)
from piezolib.problem.stage_calibration import case_I_hysteresis, case_I_input

__all__ = [
    "ChirpSettings", "IDENTIFICATION_CHIRP", "VALIDATION_CHIRP", "EXPERIMENT_SEEDS",
    "chirp_input", "ChirpExperiment", "experiment_paths", "write_experiment_files",
    "load_record", "load_chirp", "load_hysteresis_loops", "MANIFEST_NAME", "manifest_path",
    "read_manifest", "check_experiment_files", "write_foreign_records", "FOREIGN_FORM",
    "foreign_record_paths", "RAW_RECORD", "RawRecord", "raw_hysteresis_record",
]


# --- chirp experiments ------------------------------------------------------------
@dataclass(frozen=True)
class ChirpSettings:
    """A small-signal chirp experiment (paper Sec. III-A, Step I).

    u_c rises from 0 to ``top_V`` along a raised cosine (``ramp_s``), holds
    for ``hold_s`` (the operating point is read there), then follows
    ``top_V - amplitude_V (1 - cos phi(t))``: a cosine sweep from ``f0_Hz``
    to ``f1_Hz`` that starts at its crest and never exceeds ``top_V``.
    Approaching from below and staying below the last maximum keeps every
    play still when 2 ``amplitude_V`` is below the stage's small-signal limit.

    Examples
    --------
    >>> IDENTIFICATION_CHIRP.f0_Hz, IDENTIFICATION_CHIRP.f1_Hz, IDENTIFICATION_CHIRP.method
    (5.0, 4500.0, 'logarithmic')
    """

    name: str
    top_V: float
    amplitude_V: float
    f0_Hz: float
    f1_Hz: float
    duration_s: float
    method: str
    seed: int
    ramp_s: float = 0.2
    hold_s: float = 0.05


IDENTIFICATION_CHIRP = ChirpSettings("identification", top_V=2.0, amplitude_V=0.08,
                                     f0_Hz=5.0, f1_Hz=4500.0, duration_s=2.0,
                                     method="logarithmic", seed=1)
VALIDATION_CHIRP = ChirpSettings("validation", top_V=3.0, amplitude_V=0.06,
                                 f0_Hz=20.0, f1_Hz=4500.0, duration_s=1.5,
                                 method="linear", seed=2)

#: Noise seeds of the Table 4 Case I files (one per amplitude).
EXPERIMENT_SEEDS = {10.0: 10, 20.0: 20, 30.0: 30, 40.0: 40}


def chirp_input(settings, fs=paper.SAMPLING_FREQUENCY_HZ):
    """u_c [V] of a chirp experiment and the index where the sweep starts.

    Parameters
    ----------
    settings : ChirpSettings
    fs : float, optional
        Sampling frequency [Hz]; default the paper's 10 kHz.

    Returns
    -------
    u : ndarray
        Control input [V]: ramp, hold, sweep.
    start : int
        Index of the first sweep sample.

    Raises
    ------
    TypeError, ValueError
        ``settings`` is not a :class:`ChirpSettings` or ``fs`` is not positive.

    Examples
    --------
    >>> u, start = chirp_input(IDENTIFICATION_CHIRP)      # 0.2 s ramp, 0.05 s hold, 2 s sweep
    >>> u.shape, start, float(u.max())
    ((22500,), 2500, 2.0)
    """
    check_type("settings", settings, ChirpSettings, "a ChirpSettings")
    fs = check_positive("fs", fs)
    n_ramp = int(round(settings.ramp_s * fs))
    n_hold = int(round(settings.hold_s * fs))
    ramp = settings.top_V * (1 - np.cos(np.pi * np.arange(n_ramp) / n_ramp)) / 2
    _, sweep = signals.chirp(settings.amplitude_V, settings.f0_Hz, settings.f1_Hz,
                             settings.duration_s, fs, settings.method)
    # top - a (1 - cos): exactly top at the crests, never above it
    u = np.concatenate((ramp, np.full(n_hold, settings.top_V),
                        settings.top_V - (settings.amplitude_V - sweep)))
    return u, n_ramp + n_hold


@dataclass(frozen=True)
class ChirpExperiment:
    """A chirp record with its segments.

    Attributes
    ----------
    record : StageRecord
        The whole run (ramp, hold, sweep).
    start : int
        Index of the first sweep sample.
    hold_start : int
        Index of the first hold sample (operating point read between
        ``hold_start`` and ``start``).
    metadata : dict
        Header of the file (settings, seed, units).

    Examples
    --------
    >>> chirp = load_chirp("identification")              # data/chirp_identification.csv
    >>> chirp.hold_start, chirp.start, chirp.sweep.t_s.shape
    (2000, 2500, (20000,))
    >>> u, y, sweep_start = chirp.deviations()
    >>> u.shape, sweep_start
    ((20500,), 500)
    """

    record: StageRecord
    start: int
    hold_start: int
    metadata: dict

    @property
    def sweep(self):
        """The sweep part of the record."""
        return self.record.segment(self.start)

    @property
    def operating_point(self):
        """(u_c [V], v_y [V]) at the operating point: the held input and the
        mean measured output over the hold."""
        r = self.record
        return float(r.u_c_V[self.start - 1]), float(np.mean(r.v_y_V[self.hold_start:self.start]))

    def deviations(self):
        """Input and output as deviations from the operating point, from the
        start of the hold (the stage is at rest there): the data of
        :func:`piezolib.identification.identify`.

        Returns
        -------
        u, y : ndarray
            u_c - u_op and v_y - v_y,op [V] from ``hold_start`` on.
        sweep_start : int
            Index of the first sweep sample in ``u`` and ``y``.
        """
        u_op, y_op = self.operating_point
        rec = self.record.segment(self.hold_start)
        return rec.u_c_V - u_op, rec.v_y_V - y_op, self.start - self.hold_start


# --- experiment files ---------------------------------------------------------------
def _folder(directory, default):
    """``default()`` for None, else ``directory`` checked to be usable as a folder."""
    return default() if directory is None else check_directory(directory)


_COLUMNS = RECORD_COLUMNS
_FORMATS = ("%.4f", "%.7f", "%.6f", "%.6f", "%.7f")
_UNITS = ("time [s]", "control input u_c as produced by the DAC [V]",
          "actuator voltage v_a = amplifier output [V]",
          "true displacement x [um] (not available on real hardware)",
          "measured sensor output v_y [V], noise and ADC quantisation included")


def experiment_paths(directory=None):
    """Paths of the experiment files.

    Parameters
    ----------
    directory : str or Path, optional
        Folder of the files; default the workbook's ``data/``.

    Returns
    -------
    dict
        {key: Path} with keys ``"identification"``, ``"validation"`` and the
        Case I amplitudes 10.0 ... 40.0 [V].

    Raises
    ------
    TypeError, NotADirectoryError
        ``directory`` is not a path, or is a file (as in every function here that takes
        a ``directory``: :func:`piezolib.problem.paths.check_directory`).

    Examples
    --------
    >>> {key: path.name for key, path in experiment_paths().items()}
    {'identification': 'chirp_identification.csv', 'validation': 'chirp_validation.csv', 10.0: 'hysteresis_loop_10V.csv', 20.0: 'hysteresis_loop_20V.csv', 30.0: 'hysteresis_loop_30V.csv', 40.0: 'hysteresis_loop_40V.csv'}
    """
    d = _folder(directory, data_dir)
    paths = {"identification": d / "chirp_identification.csv",
             "validation": d / "chirp_validation.csv"}
    for A in paper.HYSTERESIS_TEST["actuator_amplitudes_V"]:
        paths[float(A)] = d / f"hysteresis_loop_{int(A)}V.csv"
    return paths


def write_experiment_files(directory=None):
    """Run the experiments on the default virtual stage and write the CSVs.

    Deterministic: fixed seeds and fixed float formats make reruns
    byte-identical.

    Parameters
    ----------
    directory : str or Path, optional
        Where to write; default the workbook's ``data/``.

    Returns
    -------
    list of Path
        The files written.
    """
    paths = experiment_paths(directory)
    written = []
    for settings in (IDENTIFICATION_CHIRP, VALIDATION_CHIRP):
        stage = VirtualStage(seed=settings.seed)
        u, start = chirp_input(settings, stage.fs)
        record = stage.run(u)
        meta = {"experiment": f"{settings.name} chirp (paper Sec. III-A, Step I)",
                **{f.name: getattr(settings, f.name) for f in fields(ChirpSettings)},
                "hold_start_index": start - int(round(settings.hold_s * stage.fs)),
                "sweep_start_index": start}
        written.append(_write(paths[settings.name], record, stage, meta))
    for A, seed in EXPERIMENT_SEEDS.items():
        stage = VirtualStage(seed=seed)
        record = stage.run(case_I_input(A, stage))
        meta = {"experiment": "Table 4 Case I: open loop, no compensator",
                "actuator_amplitude_V": A,
                "frequency_Hz": paper.HYSTERESIS_TEST["frequency_Hz"], "periods": 3,
                "seed": seed,
                "hysteresis_percent": round(case_I_hysteresis({A: record})[A], 4)}
        written.append(_write(paths[A], record, stage, meta))
    written.append(_write_manifest(paths, written))
    return written


def _write(path, record, stage, meta):
    s = stage.settings
    lines = ["# piezolib virtual stage experiment, written by python -m piezolib data",
             "# see data/README.md; stage settings are the VirtualStage defaults",
             f"# sample_rate_Hz = {stage.fs:g}"]
    lines += [f"# {k} = {v}" for k, v in meta.items()]
    lines += [f"# noise_rms_V = {s.noise_rms_V:g}",
              f"# hysteresis = {s.hysteresis!r}"]
    for sat in (record.input_saturation, record.output_saturation, record.adc_saturation):
        lines.append(f"# saturation {sat.where}: count = {sat.count}")
    lines += [f"# column {c}: {u}" for c, u in zip(_COLUMNS, _UNITS)]
    body = io.StringIO()
    np.savetxt(body, np.column_stack(list(record.columns().values())),
               fmt=list(_FORMATS), delimiter=",")
    return files.atomic_write(
        path, "\n".join(lines) + "\n" + ",".join(_COLUMNS) + "\n" + body.getvalue())


#: File name of the manifest next to the experiment files.
MANIFEST_NAME = "manifest.json"


def manifest_path(directory=None):
    """Path of the manifest of the experiment files (``data/manifest.json``).

    Examples
    --------
    >>> manifest_path().relative_to(data_dir()).as_posix()
    'manifest.json'
    """
    return _folder(directory, data_dir) / MANIFEST_NAME


def _data_rows(path):
    text = Path(path).read_text(encoding="utf-8").splitlines()
    return sum(1 for line in text if line and not line.startswith("#")) - 1   # minus names


def _write_manifest(paths, written, fs=paper.SAMPLING_FREQUENCY_HZ):
    directory = Path(written[0]).parent
    entries = {Path(p).name: files.manifest_entry(p, _data_rows(p), fs)
               for p in written}
    doc = {"about": "row count, sampling rate and SHA-256 of every experiment file; written "
                    "by python -m piezolib data (piezolib.problem.stage_data)",
           "files": dict(sorted(entries.items()))}
    return files.atomic_write(manifest_path(directory), json.dumps(doc, indent=1) + "\n")


def read_manifest(directory=None):
    """The manifest entries ``{file name: entry}`` (empty when there is no manifest).

    Raises
    ------
    records.RecordError
        When the manifest itself is not valid JSON.

    Examples
    --------
    >>> entries = read_manifest()
    >>> "chirp_identification.csv" in entries
    True
    """
    path = manifest_path(directory)
    if not path.exists():
        return {}
    try:
        return json.loads(path.read_text(encoding="utf-8"))["files"]
    except (ValueError, KeyError) as exc:
        raise records.RecordError(f"not a valid manifest ({exc}): regenerate it with "
                                  "`python -m piezolib data`", path) from None


def check_experiment_files(directory=None):
    """Check every experiment file against the manifest.

    Parameters
    ----------
    directory : str or Path, optional
        Default ``data/``.

    Returns
    -------
    dict
        ``{Path: problem}`` for the files that are missing or fail their check
        (empty when all are fine); ``problem`` is a one-line message naming the
        file and, where it applies, the line.

    Examples
    --------
    >>> check_experiment_files()          # the committed files match their manifest
    {}
    """
    problems = {}
    try:
        manifest = read_manifest(directory)
    except records.RecordError as exc:
        return {manifest_path(directory): str(exc)}
    paths = experiment_paths(directory)
    if not manifest:
        return {manifest_path(directory): f"{manifest_path(directory)}: missing"}
    for path in paths.values():
        try:
            load_record(path)
            if path.name not in manifest:
                problems[path] = f"{path}: not in the manifest"
        except (OSError, ValueError) as exc:
            problems[path] = str(exc).splitlines()[0]
    return problems


def load_record(path):
    """Read an experiment CSV, checked line by line and against the manifest.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`write_experiment_files`.  When the folder
        holds a manifest with an entry for the file, the row count, the
        sampling rate and the SHA-256 are checked.

    Returns
    -------
    record : StageRecord
    metadata : dict
        The ``key = value`` lines of the header (numbers parsed).

    Raises
    ------
    TypeError
        ``path`` is not a str or path object.
    FileNotFoundError
        When the file is missing (regenerate with ``python -m piezolib data``).
    piezolib.records.RecordError
        (a ``ValueError``) naming the file and the line: a missing column,
        text or NaN in a number column, too few rows, or a file that differs
        from its manifest entry (truncated, changed).

    Examples
    --------
    >>> record, meta = load_record("data/hysteresis_loop_20V.csv")
    >>> meta["actuator_amplitude_V"], meta["frequency_Hz"], record.t_s.shape
    (20.0, 10.0, (3001,))
    >>> record.input_saturation.count
    0
    """
    path = check_path("path", path)
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: regenerate the experiment files with "
                                "`python -m piezolib data`")
    data, meta, lines = records.read_table(path, {c: c for c in _COLUMNS}, header=True)
    entry = read_manifest(path.parent).get(path.name)
    if entry is not None:
        files.verify_file(path, entry, rows=len(lines), fs=meta.get("sample_rate_Hz"))
    if len(lines) < 2:
        raise records.RecordError(f"too short: {len(lines)} data row(s)", path,
                                  int(lines[-1]) if len(lines) else None)
    sat_counts = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("# saturation ") and ": count =" in line:
            where, count = line[len("# saturation "):].split(": count =")
            sat_counts[where.strip()] = int(count)
    meta = {k: v for k, v in meta.items() if not k.startswith("saturation ")}
    sats = [Saturation(where, limits, sat_counts.get(where, 0)) for where, limits in
            (("DAC/amplifier input", paper.AMPLIFIER_INPUT_RANGE_V),
             ("amplifier output", paper.AMPLIFIER_OUTPUT_RANGE_V),
             ("ADC", ADC_RANGE_V))]
    record = StageRecord(*(data[c] for c in _COLUMNS), *sats, seed=meta.get("seed"))
    return record, meta


def load_chirp(which="identification", directory=None):
    """Load the identification or the validation chirp experiment.

    Parameters
    ----------
    which : {"identification", "validation"}
    directory : path, optional
        Default ``data/``.

    Returns
    -------
    ChirpExperiment

    Examples
    --------
    >>> chirp = load_chirp("validation")
    >>> chirp.metadata["method"], chirp.metadata["f1_Hz"]
    ('linear', 4500.0)
    >>> u_op, y_op = chirp.operating_point
    >>> round(u_op, 3)
    3.0
    """
    if which not in ("identification", "validation"):
        raise ValueError(f"which must be 'identification' or 'validation', got {which!r}")
    record, meta = load_record(experiment_paths(directory)[which])
    return ChirpExperiment(record, int(meta["sweep_start_index"]),
                           int(meta["hold_start_index"]), meta)


def load_hysteresis_loops(directory=None):
    """Load the Table 4 Case I loops.

    Parameters
    ----------
    directory : str or Path, optional
        Default ``data/``.

    Returns
    -------
    dict
        {actuator amplitude [V] (10.0, 20.0, 30.0, 40.0): StageRecord} with
        time, u_c, v_a, x and v_y of three periods of the 10 Hz triangle.

    Examples
    --------
    >>> loops = load_hysteresis_loops()
    >>> sorted(loops), loops[40.0].v_y_V.shape
    ([10.0, 20.0, 30.0, 40.0], (3001,))
    """
    paths = experiment_paths(directory)
    return {A: load_record(paths[A])[0] for A in EXPERIMENT_SEEDS}


# --- records in a foreign form (notebook 08) ------------------------------------------------
#: How :func:`write_foreign_records` differs from the workbook's own files: a
#: user's acquisition at 5 kHz, displacement in um, 5x the sensor noise, no
#: header, each run starting at rest with a voltage step.
FOREIGN_FORM = {"sample_rate_Hz": 5000.0, "noise_factor": 5.0, "rest_s": 0.05,
                "columns": ("time [s]", "amplifier input u_c [V]",
                            "measured displacement [um] = 3 um/V x v_y"),
                "formats": ("%.5f", "%.6f", "%.5f")}

_FOREIGN_RUNS = {
    # chirp: step to 2 V, settle, then 2 V - 0.08 V (1 - cos) sweeping 5 Hz ... 2 kHz
    "chirp.csv": dict(kind="chirp", seed=101, offset_V=2.0, settle_s=0.25, amplitude_V=0.08,
                      f0_Hz=5.0, f1_Hz=2000.0, duration_s=2.0),
    # loops: step to the mid value, then a sine / a triangle around it
    "loop_sine.csv": dict(kind="sine", seed=102, offset_V=2.0, amplitude_V=1.6,
                          frequency_Hz=10.0, periods=4),
    "loop_triangle.csv": dict(kind="triangle", seed=103, offset_V=1.5, amplitude_V=1.5,
                              frequency_Hz=10.0, periods=4),
}


def foreign_record_paths(directory=None):
    """Paths of the foreign-form records (default ``data/own_stage/``), by file name.

    Examples
    --------
    >>> sorted(foreign_record_paths())
    ['chirp.csv', 'loop_sine.csv', 'loop_triangle.csv']
    """
    d = _folder(directory, lambda: data_dir() / "own_stage")
    return {name: d / name for name in _FOREIGN_RUNS}


def _foreign_input(run, fs):
    n_rest = int(round(FOREIGN_FORM["rest_s"] * fs))
    rest = np.zeros(n_rest)
    if run["kind"] == "chirp":
        _, sweep = signals.chirp(run["amplitude_V"], run["f0_Hz"], run["f1_Hz"],
                                 run["duration_s"], fs, "logarithmic")
        settle = np.full(int(round(run["settle_s"] * fs)), run["offset_V"])
        return np.concatenate((rest, settle, run["offset_V"] - (run["amplitude_V"] - sweep)))
    n = int(round(run["periods"] * fs / run["frequency_Hz"]))
    phase = 2 * np.pi * run["frequency_Hz"] * np.arange(n) / fs
    if run["kind"] == "sine":
        wave = np.sin(phase)
    else:                         # triangle starting at its middle, rising
        wave = 2 / np.pi * np.arcsin(np.sin(phase))
    return np.concatenate((rest, run["offset_V"] + run["amplitude_V"] * wave))


def write_foreign_records(directory=None):
    """Write virtual-stage records in the form a user's own stage might give them.

    The runs (a chirp for identification, a sine and a triangle loop for
    hysteresis) go through :class:`~piezolib.problem.stage.VirtualStage` at
    5 kHz with 5x its sensor noise; each starts at rest and steps to its
    first value.  The files have no header and no comments: three columns,
    time [s], amplifier input u_c [V] and displacement [um] (3 um/V x the
    measured v_y), as :data:`FOREIGN_FORM` describes.  Deterministic (fixed
    seeds and formats).

    Parameters
    ----------
    directory : str or Path, optional
        Default ``data/own_stage/``.

    Returns
    -------
    list of Path
    """
    paths = foreign_record_paths(directory)
    fs = FOREIGN_FORM["sample_rate_Hz"]
    written = []
    for name, run in _FOREIGN_RUNS.items():
        stage = VirtualStage(seed=run["seed"], sample_rate_Hz=fs,
                             noise_rms_V=FOREIGN_FORM["noise_factor"]
                             * VirtualStage().settings.noise_rms_V)
        record = stage.run(_foreign_input(run, fs))
        table = np.column_stack((record.t_s, record.u_c_V, record.x_measured_um))
        body = io.StringIO()
        np.savetxt(body, table, fmt=list(FOREIGN_FORM["formats"]), delimiter=",")
        written.append(files.atomic_write(paths[name], body.getvalue()))
    return written


# --- a raw hysteresis record that starts at rest ------------------------------------------
#: The default raw record of :func:`raw_hysteresis_record`: 5 kHz, 5x the stage's sensor noise,
#: 0.2 s at rest at 0 V, a step to the top of the excitation ``top_V``, then a 1 Hz cosine
#: dipping from the top by twice each of ``amplitudes_V`` (two periods per amplitude) [V of u_c].
RAW_RECORD = {"sample_rate_Hz": 5000.0, "noise_factor": 5.0, "rest_s": 0.2, "top_V": 3.5,
              "amplitudes_V": (0.4, 0.8, 1.2, 1.6, 1.6), "periods": 2, "frequency_Hz": 1.0,
              "seed": 36}


@dataclass(frozen=True)
class RawRecord:
    """A raw hysteresis record of the virtual stage and its noise-free twin.

    Attributes
    ----------
    record : piezolib.records.Record
        u_c [V] -> v_y [V] as measured: sensor noise and ADC quantisation included.
    noise_free : piezolib.records.Record
        The same run without noise and ADC: u_c [V] -> y [V], the true output.
    step_index : int
        The sample at which the input steps from rest to the top of the excitation.
    noise_rms_V : float
        The sensor noise of ``record`` [V rms].
    """

    record: records.Record
    noise_free: records.Record
    step_index: int
    noise_rms_V: float


def raw_hysteresis_record(seed=None, *, sample_rate_Hz=None, amplitudes_V=None, top_V=None,
                          rest_s=None, periods=None, frequency_Hz=None, noise_factor=None):
    """A raw hysteresis record as a real stage gives one: rest, a step, ringing, large sines.

    The stage (:class:`~piezolib.problem.stage.VirtualStage` at ``sample_rate_Hz``, its
    hysteresis truth and linear dynamics G) sits at rest at u_c = 0 V for ``rest_s``,
    the input then jumps to ``top_V`` in one sample, which rings G's resonances for some
    tens of milliseconds, and falls straight into a cosine of ``frequency_Hz``
    dipping by 2 A from the top, ``periods`` periods for each A of ``amplitudes_V``:
    u_c = top - A (1 - cos 2 pi f t).  The step sample is the input's first maximum, so
    the first turning point of the record is the step itself.  Every argument left out
    takes its value from :data:`RAW_RECORD`.

    Parameters
    ----------
    seed : int, optional
        Sensor-noise seed (default ``RAW_RECORD["seed"]``).
    sample_rate_Hz : float, optional
        Sampling rate of the record [Hz].
    amplitudes_V : sequence of float, optional
        Cosine amplitudes A [V of u_c], each > 0 with top - 2 A >= the DAC's lower limit.
    top_V : float, optional
        The level the step goes to, the cosine's top [V of u_c].
    rest_s : float, optional
        Time at rest before the step [s].
    periods : int, optional
        Periods per amplitude.
    frequency_Hz : float, optional
        Cosine frequency [Hz].
    noise_factor : float, optional
        Sensor noise as a multiple of the default stage's 0.5 mV rms.

    Returns
    -------
    RawRecord
        The measured record, its noise-free twin, the step's index and the noise level.

    Examples
    --------
    >>> raw = raw_hysteresis_record()
    >>> len(raw.record), raw.record.fs, raw.step_index
    (51001, 5000.0, 1000)
    """
    d = RAW_RECORD
    seed = d["seed"] if seed is None else seed
    fs = check_positive("sample_rate_Hz", d["sample_rate_Hz"] if sample_rate_Hz is None
                        else sample_rate_Hz)
    top = float(d["top_V"] if top_V is None else check_positive("top_V", top_V))
    rest = check_positive("rest_s", d["rest_s"] if rest_s is None else rest_s)
    f = check_positive("frequency_Hz", d["frequency_Hz"] if frequency_Hz is None
                       else frequency_Hz)
    factor = d["noise_factor"] if noise_factor is None else noise_factor
    if not isinstance(factor, (int, float)) or isinstance(factor, bool) or not factor >= 0 \
            or not np.isfinite(factor):
        raise ValueError(f"noise_factor must be a finite number >= 0, got {factor!r}")
    n_periods = d["periods"] if periods is None else periods
    if isinstance(n_periods, bool) or not isinstance(n_periods, (int, np.integer)) \
            or n_periods < 1:
        raise ValueError(f"periods must be an integer >= 1, got {n_periods!r}")
    amps = d["amplitudes_V"] if amplitudes_V is None else amplitudes_V
    amps = np.asarray(amps, dtype=float) if np.ndim(amps) == 1 else None
    if amps is None or amps.size == 0 or not np.all(np.isfinite(amps)) or np.any(amps <= 0):
        raise ValueError(f"amplitudes_V must be a 1-D sequence of positive numbers, "
                         f"got {amplitudes_V!r}")
    lowest = paper.AMPLIFIER_INPUT_RANGE_V[0]
    if top - 2 * amps.max() < lowest or top > paper.AMPLIFIER_INPUT_RANGE_V[1]:
        raise ValueError(f"top_V = {top:g} V and amplitudes_V up to {amps.max():g} V leave the "
                         f"DAC range {paper.AMPLIFIER_INPUT_RANGE_V} V")
    n_rest = int(round(rest * fs))
    if n_rest < 2:
        raise ValueError(f"rest_s = {rest:g} s keeps fewer than 2 samples at {fs:g} Hz")
    n_period = int(round(fs / f))
    phase = 2 * np.pi * np.arange(n_period) / n_period
    wave = np.concatenate([top - a * (1 - np.cos(phase)) for a in amps
                           for _ in range(int(n_periods))] + [[top]])
    u = np.concatenate((np.zeros(n_rest), wave))
    noise = factor * VirtualStage().settings.noise_rms_V
    stage = VirtualStage(seed=seed, sample_rate_Hz=fs, noise_rms_V=noise)
    rec = stage.run(u)
    meta = {"source": "piezolib.problem.stage_data.raw_hysteresis_record", "seed": int(seed),
            "step_index": n_rest, "noise_rms_V": noise}
    measured = records.Record(rec.u_c_V, rec.v_y_V, fs, input_name="u_c", output_name="v_y",
                              metadata=meta)
    true = records.Record(rec.u_c_V, rec.x_um / paper.UM_PER_VOLT, fs, input_name="u_c",
                          output_name="y", metadata={**meta, "noise_free": True})
    return RawRecord(measured, true, n_rest, noise)
