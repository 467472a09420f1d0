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
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from piezolib import paper, signals
from piezolib.problem.paths import data_dir
from piezolib.problem.stage import (ADC_RANGE_V, RECORD_COLUMNS, Saturation, StageRecord,
                                    VirtualStage, case_I_hysteresis, case_I_input)

__all__ = [
    "ChirpSettings", "IDENTIFICATION_CHIRP", "VALIDATION_CHIRP", "EXPERIMENT_SEEDS",
    "chirp_input", "ChirpExperiment", "experiment_paths", "write_experiment_files",
    "load_record", "load_chirp", "load_hysteresis_loops",
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
    """
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
    """
    d = data_dir() if directory is None else Path(directory)
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
    return written


def _write(path, record, stage, meta):
    s = stage.settings
    lines = [f"# piezolib virtual stage experiment, written by python -m piezolib data",
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
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="\n") as fh:
        fh.write("\n".join(lines) + "\n" + ",".join(_COLUMNS) + "\n" + body.getvalue())
    return path


def load_record(path):
    """Read an experiment CSV.

    Parameters
    ----------
    path : str or Path
        A file written by :func:`write_experiment_files`.

    Returns
    -------
    record : StageRecord
    metadata : dict
        The ``key = value`` lines of the header (numbers parsed).

    Raises
    ------
    FileNotFoundError
        When the file is missing (regenerate with ``python -m piezolib data``).
    ValueError
        When the column header is not :data:`~piezolib.problem.stage.RECORD_COLUMNS`.
    """
    meta, sat_counts, rows = {}, {}, []
    try:
        with open(path) as fh:
            text = fh.read().splitlines()
    except FileNotFoundError:
        raise FileNotFoundError(f"{path} is missing: regenerate the experiment files with "
                                "`python -m piezolib data`") from None
    header_done = False
    for line in text:
        if line.startswith("#"):
            body = line[1:].strip()
            if body.startswith("saturation ") and "count =" in body:
                where, count = body[len("saturation "):].split(": count =")
                sat_counts[where.strip()] = int(count)
            elif " = " in body:
                key, value = body.split(" = ", 1)
                meta[key.strip()] = _parse_value(value.strip())
        elif not header_done:
            if tuple(line.split(",")) != _COLUMNS:
                raise ValueError(f"{path}: expected columns {_COLUMNS}, got {line!r}")
            header_done = True
        else:
            rows.append(line)
    data = np.loadtxt(rows, delimiter=",", ndmin=2)
    sats = [Saturation(where, limits, sat_counts.get(where, 0)) for where, limits in
            (("DAC/amplifier input", paper.AMPLIFIER_INPUT_RANGE_V),
             ("amplifier output", paper.AMPLIFIER_OUTPUT_RANGE_V),
             ("ADC", ADC_RANGE_V))]
    record = StageRecord(*data.T, *sats, seed=meta.get("seed"))
    return record, meta


def _parse_value(text):
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text


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
    """
    paths = experiment_paths(directory)
    return {A: load_record(paths[A])[0] for A in EXPERIMENT_SEEDS}
