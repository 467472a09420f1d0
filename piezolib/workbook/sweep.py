"""Design sweeps: many studies at once, on local workers or on a dask cluster.

A sweep's spec (a base study and the points over its parameters, a grid or a
random sample) is read and checked by :mod:`piezolib.workbook.sweep_spec`.

Each point is a study run through the pipeline (:func:`evaluate_point`: the
cached design of :func:`piezolib.workbook.pipeline.derive_controllers`, its
margins, Case III tracking on the virtual stage).  Points run with joblib on
``jobs`` local processes, or through dask.distributed's joblib backend on a
cluster (``scheduler``).  Each finished point is stored at once in
``runs/sweeps/<name>/points/<key>.json`` (written atomically, sealed with a
SHA-256 of its content), keyed by a digest of the point's whole study, its
options and the evaluation: a sweep that is killed and run again computes
only the points it has no record of.  One run of a sweep at a time holds its
lock (``sweep.lock``, :data:`LOCK_NAME`); a record the disk refuses is kept and
written again after each later point; local workers end when the sweep's
process dies.  The table of every point
(``results.csv``, also ``results.parquet`` when pyarrow is installed) and
the Pareto figure (``extra_sweep_pareto.png``) are written under
``runs/sweeps/<name>/``, never to ``figures/`` or ``data/results/``.
Records committed under ``data/sweeps/<name>/`` (notebook 11's, re-derived by
a slow test) are copied in by :func:`seed_records` and then read like any
stored point.
"""

import functools
import json
import math
import os
import socket
import sys
import threading
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from piezolib import files, progress
from piezolib._checks import check_path, check_type
from piezolib.workbook import outputs
from piezolib.workbook import study as studies
from piezolib.workbook import sweep_spec as specs

__all__ = ["SweepResult", "METRICS", "TRACKING_FREQUENCIES_HZ", "LOCK_NAME", "evaluate_point",
           "run_sweep", "read_record", "seed_records", "committed_points_dir", "pareto_front",
           "check_scheduler_address"]

#: Triangle frequencies [Hz] of the Case III tracking run of each point: the two
#: design goals of Sec. IV-B (< 1 % up to 10 Hz, < 5 % at 50 Hz).
TRACKING_FREQUENCIES_HZ = (10.0, 50.0)

#: The columns :func:`evaluate_point` gives, with their meaning and unit.
METRICS = {
    "mu_RP": "mu_RP upper bound of the reported controller, delay-aware design problem",
    "mu_RP_full_order": "mu_RP upper bound of the full-order DK controller (same problem)",
    "controller_states": "states of the reported controller",
    "gain_margin_dB": "gain margin of the continuous loop [dB]",
    "phase_margin_deg": "phase margin of the continuous loop [deg]",
    "delay_margin_samples": "delay margin of the sampled loop [samples]",
    "stable_with_loop_delay": "sampled loop stable with the study's loop.delay_samples",
    "tracking_error_10Hz_percent": "Case III tracking error at 10 Hz, mean over seeds [%]",
    "tracking_error_50Hz_percent": "Case III tracking error at 50 Hz, mean over seeds [%]",
    "tracking_error_50Hz_low_percent": "its 95 % interval, low end [%]",
    "tracking_error_50Hz_high_percent": "its 95 % interval, high end [%]",
    "case_III_saturated_samples": "most limited samples of a Case III run (DAC, amplifier, ADC)",
}


@dataclass(frozen=True, eq=False)
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    spec : piezolib.workbook.sweep_spec.SweepSpec
    table : pandas.DataFrame
        One row per point: ``point``, the parameters, :data:`METRICS`,
        ``pareto`` (on the front of mu_RP against the 50 Hz tracking error),
        ``error`` (empty when the point ran) and ``key``.
    evaluated, reused, failed : int
        Points computed in this run, read from their records, and failed.
    seconds : float
        Wall time of the run [s].
    paths : dict
        ``{"table": csv path, "parquet": path or None, "figure": png path or None}``.
    backend : str
        Where the points ran (``"1 local worker(s)"``, a scheduler's address).
    problems : tuple of str
        What was computed but could not be written (a point's record, the
        table): each names the file and the system's reason.

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> from piezolib.workbook.sweep_spec import spec_from_dict
    >>> spec = spec_from_dict({"name": "demo", "grid": {"design.order": [4, 6]}})
    >>> with (tempfile.TemporaryDirectory() as root,          # a dry run evaluates nothing
    ...       mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root})):
    ...     result = run_sweep(spec, jobs=1, dry_run=True)
    [1/2] order=4  (to run, key ...)
    [2/2] order=6  (to run, key ...)
    sweep demo: 2 points, 0 stored, 2 to run; outputs in ...
    >>> result.evaluated, result.reused, list(result.table.columns)
    (0, 0, ['point', 'design.order', 'controller', 'stored', 'key'])
    """

    spec: specs.SweepSpec
    table: pd.DataFrame
    evaluated: int
    reused: int
    failed: int
    seconds: float
    paths: dict
    backend: str = ""
    problems: tuple = ()

    def overview(self):
        """The table as a reader wants it: each point's parameters, μ_RP, the controller's
        states, margins, the 10 and 50 Hz tracking errors [%] and whether it is on the front
        (the columns the table has)."""
        columns = ["point", *self.spec.parameters, *_OVERVIEW_COLUMNS]
        return self.table[[c for c in columns if c in self.table.columns]]

    @property
    def checks(self):
        """What holds for every sweep, {what it states: bool}: every point ran, its numbers
        are consistent, and the Pareto front is the set of undominated points.

        Examples
        --------
        >>> from piezolib.workbook.sweep_spec import spec_from_dict
        >>> spec = spec_from_dict({"name": "demo", "grid": {"design.order": [4, 6]}})
        >>> table = pd.DataFrame({"point": [1, 2], "design.order": [4, 6], "mu_RP": [1.2, 0.9],
        ...                       "controller_states": [4, 6],
        ...                       "tracking_error_50Hz_percent": [3.0, 4.0],
        ...                       "pareto": [True, True], "error": ["", ""]})
        >>> result = SweepResult(spec, table, 2, 0, 0, 1.0, {})
        >>> all(result.checks.values())
        True
        >>> result = SweepResult(spec, table.assign(pareto=[True, False]), 2, 0, 0, 1.0, {})
        >>> result.checks["the front holds every undominated point"]
        False
        """
        t = self.table
        column = functools.partial(_column, t)
        checks = {"every point ran": self.failed == 0 and len(t) == len(self.spec.points())}
        if "design.order" in self.spec.parameters:
            fixed = (t[specs._CONTROLLER] == "fixed_order" if specs._CONTROLLER in t
                     else pd.Series(True, index=t.index))
            checks["the deployed controller has the swept order"] = bool(
                (column("controller_states") == column("design.order"))[fixed].all())
        checks["mu_RP > 0 at every point"] = bool((column("mu_RP") > 0).all())
        if "stable_with_loop_delay" in t:
            checks["every sampled loop is stable with the loop's delay"] = bool(
                t["stable_with_loop_delay"].astype(bool).all())
        if {"tracking_error_50Hz_low_percent", "tracking_error_50Hz_high_percent"} <= set(t):
            y = column("tracking_error_50Hz_percent")
            checks["the 95 % interval of the 50 Hz error holds its mean"] = bool(
                ((t["tracking_error_50Hz_low_percent"] <= y)
                 & (y <= t["tracking_error_50Hz_high_percent"])).all())
        values = t[["mu_RP", "tracking_error_50Hz_percent"]].to_numpy(float)
        dominated = [bool(np.any(np.all(values <= v, axis=1) & np.any(values < v, axis=1)))
                     for v in values]
        on_front = (t["pareto"].astype(bool).to_numpy() if "pareto" in t
                    else np.zeros(len(t), dtype=bool))
        finite = np.isfinite(values).all(axis=1)
        checks["no point of the Pareto front is beaten in both numbers"] = \
            not any(np.asarray(dominated)[on_front])
        checks["the front holds every undominated point"] = bool(
            on_front[finite & ~np.asarray(dominated, dtype=bool)].all())
        checks["the front has a point"] = bool(on_front.any())
        return checks

    def resumed_checks(self, first):
        """{what it states: bool} of this run as a rerun of ``first`` (a SweepResult of
        the same spec): nothing computed again, every point read from its record, the
        same table."""
        check_type("first", first, SweepResult, "the SweepResult of the first run")
        try:
            pd.testing.assert_frame_equal(self.table, first.table)
            same = True
        except AssertionError:
            same = False
        return {"nothing computed again": self.evaluated == 0,
                "every point read from its record": self.reused == len(first.table),
                "the same table as the first run": same}

    def findings(self):
        """Markdown lines of what the sweep found: its designs, the lowest μ_RP, the lowest
        50 Hz tracking error and the Pareto front."""
        from piezolib.workbook.style import unit_text

        t, spec = self.table, self.spec
        names = {p: unit_text(n) for p, n in _short_names(spec.parameters).items()}
        over = " × ".join(
            f"{names[p]} ∈ {{{', '.join(_format(v) for v in dict.fromkeys(t[p]))}}}"
            for p in spec.parameters)
        iterations = ("" if "design.max_iter" in spec.parameters else
                      f" ({spec.base.design.max_iter} DK iteration(s) each)")
        lines = [f"**{len(t)} designs** over {over}{iterations} in {self.seconds:.1f} s on "
                 f"{self.backend or 'the workers'}; {self.reused} reused, {self.failed} failed."]
        where = functools.partial(_where, names)
        ok = t.dropna(subset=["mu_RP", "tracking_error_50Hz_percent"])
        if len(ok):
            best_mu = ok.loc[ok.mu_RP.idxmin()]
            best_e = ok.loc[ok.tracking_error_50Hz_percent.idxmin()]
            lines += [f"**Lowest μ_RP:** {best_mu.mu_RP:.3f} at {where(best_mu)} "
                      f"(50 Hz error {best_mu.tracking_error_50Hz_percent:.2f} %).",
                      f"**Lowest 50 Hz error:** {best_e.tracking_error_50Hz_percent:.2f} % at "
                      f"{where(best_e)} (μ_RP {best_e.mu_RP:.3f})."]
        if "pareto" in t:
            front = ", ".join(map(str, t.point[t.pareto.astype(bool)]))
            lines.append(f"**Pareto front:** points {front} of {len(t)}; table and figure in "
                         f"`{spec.directory}`.")
        return lines


#: The columns of :meth:`SweepResult.overview` after the point and its parameters.
_OVERVIEW_COLUMNS = ("mu_RP", "controller_states", "gain_margin_dB", "phase_margin_deg",
                     "delay_margin_samples", "tracking_error_10Hz_percent",
                     "tracking_error_50Hz_percent", "pareto")


def _column(table, name):
    """Column ``name`` of ``table``, or NaN throughout when it has none."""
    return table[name] if name in table else pd.Series(np.nan, index=table.index)


def _where(names, row):
    """``omega_e = 1000, order = 4``: the parameters of a table row."""
    return ", ".join(f"{names[p]} = {_format(row[p])}" for p in names)


# --------------------------------------------------------------------------- one point
def evaluate_point(study, controller="fixed_order"):
    """The numbers of one sweep point: design, margins and Case III tracking.

    The design is :func:`piezolib.workbook.pipeline.derive_controllers`
    (DK-iteration, reduction, fixed order; through the disk cache, so a point
    a notebook or an earlier sweep designed is not designed again; derived
    also for a point whose choices equal the reference's, so that every
    point comes from the same design path).  The
    reported controller is analysed on the study's plant: margins of the
    continuous loop and of the sampled loop at ``loop.fs_Hz``
    (:func:`piezolib.problem.analysis.margins_table`), and Case III tracking
    of 12 um triangles (``experiments.range_um``) at
    :data:`TRACKING_FREQUENCIES_HZ` only, on the virtual stage sampled at the
    loop rate, running the controller's float32 second-order sections with
    the study's loop delay, the workbook's Dahl feedforward, and the study's
    noise seeds (mean and 95 % interval, as in notebook 06).

    Parameters
    ----------
    study : Study, str or path
    controller : {"fixed_order", "full_order"}
        The deployed fixed-order controller (``design.order`` states) or the
        full-order DK one.

    Returns
    -------
    dict
        The :data:`METRICS` of the point (floats, ints and bools).
    """
    from piezolib.hysteresis import FitWarning
    from piezolib.problem import analysis
    from piezolib.problem.hysteresis_fits import workbook_dahl_fit
    from piezolib.problem.stage import StageSaturationWarning, VirtualStage
    from piezolib.robust import export
    from piezolib.robust.discrete import discretize
    from piezolib.workbook import experiments, pipeline

    study = studies.load(study)
    if controller not in specs.CONTROLLERS:
        raise ValueError(f"controller must be one of {list(specs.CONTROLLERS)}, got "
                         f"{controller!r}")
    found = pipeline.derive_controllers(study)
    K = found.K_fixed if controller == "fixed_order" else found.K_full
    fs, delay = study.loop.fs_Hz, study.loop.delay_samples
    G = pipeline.study_problem(study).G
    margins = analysis.margins_table({"K": K}, G, fs, delays=tuple(range(max(3, delay) + 1)))["K"]
    sections = export.controller_sos(discretize(K, fs, G=G).K, "K")
    with warnings.catch_warnings():
        # notebook 03 chose this fit knowing which parameters are identifiable only together;
        # saturation is reported as a number of the point instead of a warning per run
        warnings.simplefilter("ignore", FitWarning)
        warnings.simplefilter("ignore", StageSaturationWarning)
        dahl = workbook_dahl_fit().model
        stage = VirtualStage(seed=study.experiments.stage_seed, sample_rate_Hz=fs)
        tracking = experiments.tracking_test(
            stage, dahl, sections, TRACKING_FREQUENCIES_HZ, study.experiments.range_um,
            delay_samples=delay, seeds=study.experiments.seeds)
    low, high = tracking.interval("case_III", 50.0)
    return {
        "mu_RP": found.mu["fixed order" if controller == "fixed_order" else "delay-aware DK"],
        "mu_RP_full_order": found.mu["delay-aware DK"],
        "controller_states": int(K.nstates),
        "gain_margin_dB": float(margins["gain margin [dB]"]),
        "phase_margin_deg": float(margins["phase margin [deg]"]),
        "delay_margin_samples": float(margins["sampled loop delay margin [samples]"]),
        "stable_with_loop_delay": bool(margins[f"stable, delay {delay}"]),
        "tracking_error_10Hz_percent": float(tracking.table.loc["case_III", 10.0]),
        "tracking_error_50Hz_percent": float(tracking.table.loc["case_III", 50.0]),
        "tracking_error_50Hz_low_percent": low,
        "tracking_error_50Hz_high_percent": high,
        "case_III_saturated_samples": int(tracking.saturation.loc["case_III"].max()),
    }


def _evaluate_task(evaluate, study, options, key):
    """Run one point where a worker runs it; never raises for the point's own failure.

    Returns ``(key, metrics or None, error text or None, seconds, host)``.
    """
    from threadpoolctl import threadpool_limits

    start = time.perf_counter()
    try:
        # one core per point: the same rounding whichever backend runs it, and no
        # oversubscription when every core already runs a point
        with threadpool_limits(1):
            metrics = evaluate(study, **options)
        _check_metrics(metrics)
        error = None
    except Exception as exc:      # the point failed; the sweep goes on and reports it
        metrics, error = None, f"{type(exc).__name__}: {exc}"
    return key, metrics, error, time.perf_counter() - start, socket.gethostname()


def _check_metrics(metrics):
    if not isinstance(metrics, dict) or not all(
            isinstance(k, str) and (v is None or isinstance(v, (int, float, bool, str)))
            for k, v in metrics.items()):
        raise TypeError(f"an evaluation must return a dict of named numbers, got {metrics!r}")
    bad = _non_finite(metrics)
    if bad:
        # a NaN or inf metric is a failed evaluation: reported, not stored, run again next time
        raise ValueError(f"the evaluation returned non-finite metrics: {bad}")


def _non_finite(metrics):
    """The metrics of a point that are NaN or infinite, {name: value}."""
    return {k: v for k, v in metrics.items()
            if isinstance(v, float) and not math.isfinite(v)}


# --------------------------------------------------------------------------- records
def _record_path(spec, key):
    return spec.directory / "points" / f"{key}.json"


def _write_record(spec, point, key, evaluation, metrics, seconds, host):
    from piezolib.workbook import pipeline

    doc = {"format": specs.RECORD_FORMAT, "key": key, "sweep": spec.name, "index": point.index,
           "params": point.params, "options": point.options, "study": point.study.choices(),
           "evaluation": evaluation, "metrics": metrics, "seconds": seconds, "host": host,
           "library": pipeline.library_fingerprint()}
    path = _record_path(spec, key)
    return files.atomic_write(path, json.dumps(files.seal(doc), indent=1) + "\n")


def read_record(path, key=None):
    """The metrics of a stored point, or None when the record is missing or unusable.

    Parameters
    ----------
    path : path
        A ``points/<key>.json`` record of a sweep.
    key : str, optional
        The key it must carry (a renamed or copied file is not used).

    Returns
    -------
    dict or None
        The record (``metrics``, ``seconds``, ``library``, ...) when it is
        intact (its SHA-256 matches), of this format and of ``key``.

    Examples
    --------
    >>> import json, tempfile
    >>> from piezolib import files
    >>> doc = files.seal({"format": specs.RECORD_FORMAT, "key": "abc", "metrics": {"mu_RP": 0.9}})
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "abc.json"
    ...     _ = path.write_text(json.dumps(doc))
    ...     print(read_record(path, "abc")["metrics"], read_record(path, "other"),
    ...           read_record(Path(folder) / "missing.json"))
    {'mu_RP': 0.9} None None
    """
    path = Path(path) if isinstance(path, (str, os.PathLike)) else None
    if path is None:
        raise TypeError("path must be the path of a point record")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(doc, dict) or doc.get("format") != specs.RECORD_FORMAT \
            or files.seal_problem(doc) is not None or (key is not None and doc.get("key") != key):
        return None
    if not isinstance(doc.get("metrics"), dict) or _non_finite(doc["metrics"]):
        return None          # written before non-finite metrics counted as failures: rerun
    return doc


# --------------------------------------------------------------------------- the sweep
def run_sweep(spec, jobs=None, scheduler=None, evaluate=evaluate_point, dry_run=False,
              stream=None):
    """Run every point of a sweep that has no record yet; write the table and the figure.

    Parameters
    ----------
    spec : SweepSpec, str or path
        A spec (:func:`piezolib.workbook.sweep_spec.load_spec`).
    jobs : int, optional
        Local worker processes (joblib); default one per core.  1 runs the
        points one by one in this process.  Ignored with ``scheduler``.
    scheduler : str or distributed.Client, optional
        A dask scheduler's address (``"tcp://host:8786"``) or a client: the
        points run on its workers through dask.distributed's joblib backend.
        Each worker needs this checkout (``PIEZOLIB_ROOT``) importable; the
        records are written here, by the process that runs the sweep.
    evaluate : callable, optional
        ``evaluate(study, controller=...) -> dict`` of numbers
        (default :func:`evaluate_point`); a module-level function when the
        points run in other processes.
    dry_run : bool
        List the points (and whether each is stored) and run nothing.
    stream : file-like, optional
        Where the progress lines go (default ``sys.stdout``).

    Returns
    -------
    SweepResult
        A point whose record could not be written (a full disk) is in its
        table and named in its ``problems``; it is kept in memory and written
        again after each later point, and a later run computes only the points
        without a record.

    Raises
    ------
    piezolib.files.LockHeld
        Another process runs this sweep (its lock file ``sweep.lock`` in the
        output folder names it); a lock left by a killed run is taken over.
    OSError
        The output folder cannot be written, before any point is evaluated.

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> spec = specs.load_spec("omega_spread_order")    # studies/sweeps/omega_spread_order.toml
    >>> with (tempfile.TemporaryDirectory() as root,
    ...       mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root})):
    ...     result = run_sweep(spec, jobs=1, dry_run=True)   # lists the points, runs nothing
    [1/12] omega_e=1000  spread=0.02  order=4  (to run, key ...)
    ...
    sweep omega_spread_order: 12 points, 0 stored, 12 to run; outputs in ...
    >>> len(result.table), result.evaluated
    (12, 0)
    """
    stream = sys.stdout if stream is None else stream
    if not callable(evaluate):
        raise TypeError(f"evaluate must be a callable, got {evaluate!r}")
    jobs = _jobs(jobs)
    if isinstance(scheduler, str):
        check_scheduler_address(scheduler)      # before anything runs
    elif scheduler is not None:
        from distributed import Client

        check_type("scheduler", scheduler, Client,
                   "an address such as 'tcp://127.0.0.1:8786' or a distributed.Client")
    spec = specs.load_spec(spec)
    evaluation = f"{evaluate.__module__}.{evaluate.__qualname__}"
    points = spec.points()
    keys = {p.index: p.key(evaluation) for p in points}
    names = _short_names(spec.parameters)
    if dry_run:
        return _dry_run(spec, points, keys, _stored(spec, points, keys), names, stream)
    # one run of a sweep at a time: a second one would compute every point again
    with files.exclusive_lock(spec.directory / LOCK_NAME, f"sweep {spec.name}"):
        files.check_writable(spec.directory / "points")      # before the first evaluation
        files.remove_stale_temporaries(spec.directory)       # what a killed earlier run left
        stored = _stored(spec, points, keys)
        return _run(spec, points, keys, stored, names, evaluate, jobs, scheduler, stream)


#: The lock file of a running sweep in its folder (holder's pid, host and start time).
LOCK_NAME = "sweep.lock"


def committed_points_dir(name):
    """``data/sweeps/<name>/``: the point records of sweep ``name`` committed with the
    checkout (:func:`seed_records`), e.g. notebook 11's, re-derived by a slow test."""
    problem = outputs.study_name_problem(name)
    if problem:
        raise ValueError(f"name {problem}")
    return outputs.data_dir() / "sweeps" / name


def seed_records(spec, folder=None):
    """Copy the committed records of ``spec``'s points into its ``points/`` folder, so that
    :func:`run_sweep` reads them instead of computing them (as when it resumes).

    Only intact records (:func:`read_record`) whose key is one of the spec's points'
    (same study choices, options and evaluation) are copied: a spec with other values
    computes its points.

    Parameters
    ----------
    spec : SweepSpec, str or path
    folder : path, optional
        Where the records are (default :func:`committed_points_dir` of the spec's name).

    Returns
    -------
    int
        The records copied.

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> spec = specs.spec_from_dict({"name": "demo", "grid": {"design.order": [4, 6]}})
    >>> with (tempfile.TemporaryDirectory() as root,
    ...       mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root})):
    ...     print(seed_records(spec))                  # nothing committed for this spec
    0
    """
    spec = specs.load_spec(spec)
    folder = committed_points_dir(spec.name) if folder is None else check_path("folder", folder)
    evaluation = f"{evaluate_point.__module__}.{evaluate_point.__qualname__}"
    copied = 0
    for point in spec.points():
        key = point.key(evaluation)
        source = folder / f"{key}.json"
        if source.is_file() and read_record(source, key) is not None:
            files.atomic_write(_record_path(spec, key), source.read_bytes())
            copied += 1
    return copied


def _committed_keys(spec, stored):
    """The keys of the stored records that are byte for byte the committed ones."""
    folder = committed_points_dir(spec.name)
    keys = set()
    for doc in stored.values():
        if doc is None:
            continue
        committed, here = folder / f"{doc['key']}.json", _record_path(spec, doc["key"])
        if committed.is_file() and committed.read_bytes() == here.read_bytes():
            keys.add(doc["key"])
    return keys


def _stored(spec, points, keys):
    """{point index: its record or None}."""
    return {p.index: read_record(_record_path(spec, keys[p.index]), keys[p.index])
            for p in points}


def _run(spec, points, keys, stored, names, evaluate, jobs, scheduler, stream):
    """Evaluate the points without a record; store each; write the table and the figure."""
    start = time.perf_counter()
    evaluation = f"{evaluate.__module__}.{evaluate.__qualname__}"
    todo = [p for p in points if stored[p.index] is None]
    reused = len(points) - len(todo)
    backend = (f"{scheduler if isinstance(scheduler, str) else 'the dask cluster'}"
               if scheduler is not None else f"{jobs} local worker(s)")
    rows = {p.index: _row(p, stored[p.index]["metrics"], None, keys[p.index])
            for p in points if stored[p.index] is not None}
    by_key = {keys[p.index]: p for p in todo}
    failed = 0
    client, own = _client(scheduler) if scheduler is not None and todo else (None, False)
    try:
        workers = jobs if client is None else max(1, sum(client.nthreads().values()))
        tally = _Tally(len(todo), workers, _median_seconds(stored))
        with progress.StatusLine(tally.status, file=stream) as status:
            records = _Records(spec, evaluation, status.write)
            status.write(f"sweep {spec.name}: {len(points)} points, {reused} stored "
                         f"(reused), {len(todo)} to run on {backend}")
            _warn_other_library(stored, status.write, _committed_keys(spec, stored))
            try:
                for k, (key, metrics, error, seconds, host) in enumerate(
                        _results(evaluate, todo, keys, jobs, client), reused + 1):
                    point = by_key[key]
                    tally.finished(seconds)
                    failed += error is not None
                    rows[point.index] = _row(point, metrics, error, key)
                    line = _progress_line(k, len(points), point, names, metrics, error,
                                          seconds)
                    status.write(f"{line}  | {tally.status()}")
                    if error is None:
                        records.add(point, key, metrics, seconds, host)
            finally:
                records.store()          # also on Ctrl-C: what was computed is kept
    finally:
        if own:
            client.close()
    problems = records.problems()
    table = _table([rows[i] for i in sorted(rows)])
    try:
        paths = _write_outputs(spec, table)
    except OSError as exc:               # the table is still returned, and the records kept
        paths = {"table": None, "parquet": None, "figure": None}
        problems.append(f"the table and the figure were not written: {exc}")
    seconds = time.perf_counter() - start
    _say(stream, f"sweep {spec.name}: {len(todo) - failed} evaluated, {reused} reused, "
         f"{failed} failed in {seconds:.1f} s; "
         + (f"table {paths['table']}" if paths["table"] else "no table written")
         + (f", figure {paths['figure']}" if paths["figure"] else ""))
    for line in problems:
        _say(stream, f"NOT STORED: {line}")
    return SweepResult(spec, table, len(todo) - failed, reused, failed, seconds, paths, backend,
                       tuple(problems))


class _Records:
    """The records of the computed points: written as each point comes back; a point
    whose record the system refuses (a full disk) is kept and written again after each
    later point, so that no computed point is lost to a failed write."""

    def __init__(self, spec, evaluation, say):
        self.spec, self.evaluation, self.say = spec, evaluation, say
        self.pending, self.errors = {}, {}

    def add(self, point, key, metrics, seconds, host):
        self.pending[key] = (point, metrics, seconds, host)
        self.store()

    def store(self):
        for key, (point, metrics, seconds, host) in list(self.pending.items()):
            try:
                _write_record(self.spec, point, key, self.evaluation, metrics, seconds, host)
            except OSError as exc:
                if key not in self.errors:
                    self.say(f"point {point.index}: its record was not written ({exc}); kept "
                             "in memory, written again after the next point")
                self.errors[key] = exc
                continue
            del self.pending[key]
            self.errors.pop(key, None)

    def problems(self):
        """One line per point whose record could not be written."""
        return [f"point {point.index}: computed (its numbers are in this run's table) but "
                f"its record could not be written ({self.errors[key]}); the next run "
                "computes it again" for key, (point, *_) in self.pending.items()]


class _Tally:
    """Points done, running and left of a run, and an estimate of the time left."""

    def __init__(self, todo, workers, seconds_per_point=None):
        self.todo, self.workers, self.done = todo, workers, 0
        self.seconds = [] if seconds_per_point is None else [seconds_per_point]
        self.prior = seconds_per_point is not None
        self.start = self.last = time.perf_counter()

    def finished(self, seconds):
        if self.prior:                 # the points of this run replace the stored estimate
            self.seconds, self.prior = [], False
        self.done += 1
        self.seconds.append(seconds)
        self.last = time.perf_counter()

    def status(self):
        """``3 done, 2 running, 7 left; 2 min 10 s elapsed, about 4 min 0 s left``."""
        unfinished = self.todo - self.done
        running = min(self.workers, unfinished)
        elapsed = time.perf_counter() - self.start
        text = (f"{self.done} done, {running} running, {unfinished - running} left; "
                f"{_duration(elapsed)} elapsed")
        if not unfinished:
            return text
        if not self.seconds:
            return f"{text}, time left known after the first point"
        # the unfinished points run in waves of `workers`, each about as long as the points
        # so far; the running wave started when the last point came back, at the latest
        wave = float(np.mean(self.seconds))
        running_for = min(time.perf_counter() - self.last, wave)
        left = wave * math.ceil(unfinished / self.workers) - running_for
        return f"{text}, about {_duration(max(left, 1.0))} left"


def _median_seconds(stored):
    """The median time [s] of the stored points (the estimate before a point of this run
    is back), or None."""
    seconds = [doc["seconds"] for doc in stored.values()
               if doc is not None and isinstance(doc.get("seconds"), (int, float))]
    return float(np.median(seconds)) if seconds else None


def _duration(seconds):
    """``42 s``, ``3 min 5 s``, ``2 h 10 min``."""
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60} min"


def _jobs(jobs):
    if jobs is None:
        return os.cpu_count() or 1
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    return jobs


def _results(evaluate, todo, keys, jobs, client):
    """``_evaluate_task`` results of the points, each as soon as it is done (on ``jobs``
    local processes, or on the workers of a dask ``client``)."""
    if not todo:
        return
    import joblib

    tasks = [joblib.delayed(_evaluate_task)(evaluate, p.study, p.options, keys[p.index])
             for p in todo]
    # batch_size=1: a point takes seconds to minutes, and its record is written as soon
    # as it is back (a batch would hold finished points back)
    if client is None:
        # each local worker ends itself when this process dies (kill -9 included)
        with joblib.parallel_config(backend="loky", initializer=_exit_with_parent):
            yield from joblib.Parallel(n_jobs=jobs, batch_size=1,
                                       return_as="generator_unordered")(tasks)
        return
    with joblib.parallel_config(backend="dask"):
        yield from joblib.Parallel(n_jobs=-1, batch_size=1,
                                   return_as="generator_unordered")(tasks)


def _exit_with_parent(period_s=0.5):
    """Initializer of a local worker process: a daemon thread ends the process when its
    parent (the sweep) is gone, so that a killed sweep leaves no worker computing for
    nobody and holding its output pipe (loky's own workers notice only when idle)."""
    parent = os.getppid()
    threading.Thread(target=_watch_parent, args=(parent, period_s), daemon=True,
                     name="piezolib-sweep-parent-watch").start()


def _watch_parent(parent, period_s):
    while os.getppid() == parent:          # a child of a dead process is given another parent
        time.sleep(period_s)
    os._exit(1)


def _client(scheduler):
    """(distributed.Client, whether this call opened it) for an address or a client."""
    from distributed import Client

    if isinstance(scheduler, Client):
        return scheduler, False
    try:
        return Client(scheduler, timeout=30, set_as_default=True), True
    except (OSError, TimeoutError) as exc:
        raise OSError(f"scheduler: cannot reach the dask scheduler at {scheduler} ({exc})") \
            from None


def check_scheduler_address(address):
    """Raise a ValueError naming ``scheduler`` unless ``address`` looks like
    ``tcp://host:port`` (or another dask protocol).

    Examples
    --------
    >>> check_scheduler_address("tcp://127.0.0.1:8786")
    'tcp://127.0.0.1:8786'
    >>> check_scheduler_address("localhost")
    Traceback (most recent call last):
    ...
    ValueError: scheduler must be a dask scheduler address such as 'tcp://127.0.0.1:8786' or a distributed.Client, got 'localhost'
    """
    protocol, _, rest = address.partition("://") if isinstance(address, str) else ("", "", "")
    host, _, port = rest.rpartition(":")
    if protocol not in ("tcp", "tls", "inproc", "ws", "wss", "ucx") or not (
            protocol == "inproc" or (host and port.isdigit())):
        raise ValueError(f"scheduler must be a dask scheduler address such as "
                         f"'tcp://127.0.0.1:8786' or a distributed.Client, got {address!r}")
    return address


def _row(point, metrics, error, key):
    return {"point": point.index, **point.params, **point.options, **(metrics or {}),
            "error": error or "", "key": key}


def _table(rows):
    table = pd.DataFrame(rows)
    x, y = "mu_RP", "tracking_error_50Hz_percent"
    if {x, y} <= set(table.columns):
        table.insert(table.columns.get_loc("error"), "pareto", pareto_front(table, x, y))
    return table


def pareto_front(table, x, y):
    """Which rows are on the Pareto front when both ``x`` and ``y`` are minimised.

    A row is on the front when no other row is at least as good in both
    columns and better in one; rows with a missing value are not.

    Parameters
    ----------
    table : pandas.DataFrame
    x, y : str
        Column names.

    Returns
    -------
    pandas.Series of bool
        Indexed like ``table``.

    Examples
    --------
    >>> t = pd.DataFrame({"a": [1.0, 2.0, 3.0, 2.0], "b": [3.0, 1.0, 2.0, 2.0]})
    >>> pareto_front(t, "a", "b").tolist()
    [True, True, False, False]
    """
    if not isinstance(table, pd.DataFrame):
        raise TypeError(f"table must be a pandas DataFrame, got {type(table).__name__}")
    for name, column in (("x", x), ("y", y)):
        if column not in table.columns:
            raise ValueError(f"{name}: the table has no column {column!r}")
    values = table[[x, y]].apply(pd.to_numeric, errors="coerce").to_numpy(float)
    ok = np.isfinite(values).all(axis=1)
    front = np.zeros(len(table), dtype=bool)
    for i in np.flatnonzero(ok):
        others = values[ok]
        dominated = np.any(np.all(others <= values[i], axis=1)
                           & np.any(others < values[i], axis=1))
        front[i] = not dominated
    return pd.Series(front, index=table.index, name="pareto")


def _write_outputs(spec, table):
    """The table (CSV, Parquet when pyarrow is there) and the Pareto figure."""
    directory = spec.directory
    csv = files.atomic_write(directory / "results.csv", table.to_csv(index=False))
    parquet = None
    try:
        import pyarrow  # noqa: F401  (optional: only its presence is asked)
    except ImportError:
        pass
    else:
        with files.atomic_path(directory / "results.parquet") as tmp:
            table.to_parquet(tmp, index=False)
        parquet = directory / "results.parquet"
    figure = None
    if "pareto" in table and table["pareto"].any():
        import matplotlib.pyplot as plt

        from piezolib.workbook import plotting
        from piezolib.workbook.figures import sweeps as sweep_figures

        # no sweep name in the title: the units rule would respell a name like omega_e_sweep
        fig = sweep_figures.extra_sweep_pareto(table)
        figure = plotting.save_figure(fig, directory)
        plt.close(fig)
    return {"table": csv, "parquet": parquet, "figure": figure}


# --------------------------------------------------------------------------- lines
def _say(stream, line):
    progress.write(line, file=stream)


def _short_names(parameters):
    """The field name of each parameter, or its full name where two fields share one."""
    fields_ = [p.rpartition(".")[2] for p in parameters]
    return {p: f if fields_.count(f) == 1 else p for p, f in zip(parameters, fields_)}


def _format(value):
    return f"{value:g}" if isinstance(value, float) else str(value)


def _progress_line(k, n, point, names, metrics, error, seconds):
    params = " ".join(f"{names[p]}={_format(v)}" for p, v in point.params.items())
    if error is not None:
        result = f"FAILED: {error[:160]}"
    else:
        shown = [f"{label} {metrics[m]:.4g}{unit}" for m, label, unit in (
            ("mu_RP", "mu_RP", ""), ("tracking_error_50Hz_percent", "e(50 Hz)", " %"))
            if isinstance(metrics.get(m), (int, float))]
        result = "  ".join(shown) or "ok"
    return f"[{k}/{n}] {params}  {result}  {seconds:.1f} s"


def _dry_run(spec, points, keys, stored, names, stream):
    for p in points:
        params = " ".join(f"{names[q]}={_format(v)}" for q, v in p.params.items())
        state = "stored" if stored[p.index] is not None else "to run"
        _say(stream, f"[{p.index}/{len(points)}] {params}  ({state}, key {keys[p.index]})")
    reused = sum(s is not None for s in stored.values())
    _say(stream, f"sweep {spec.name}: {len(points)} points, {reused} stored, "
         f"{len(points) - reused} to run; outputs in {spec.directory}")
    table = pd.DataFrame([{"point": p.index, **p.params, **p.options,
                           "stored": stored[p.index] is not None, "key": keys[p.index]}
                          for p in points])
    return SweepResult(spec, table, 0, reused, 0, 0.0,
                       {"table": None, "parquet": None, "figure": None})


def _warn_other_library(stored, say, committed=()):
    from piezolib.workbook import pipeline

    here = pipeline.library_fingerprint()
    # a committed record comes from another version by construction; its slow test re-derives it
    other = sum(1 for doc in stored.values() if doc is not None and doc.get("library") != here
                and doc.get("key") not in committed)
    if other:
        say(f"note: {other} stored point(s) were computed by another version of piezolib "
            "(library fingerprint); delete their records under points/ to recompute them")
