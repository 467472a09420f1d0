"""Run the whole workbook headless: data files first, then every notebook.

``python -m piezolib reproduce`` checks the virtual-stage experiment files
against their manifest (its first line says how many it checked, or which it
regenerated and why), executes ``notebooks/NN_*.ipynb`` (the notebooks save
the figures into ``figures/`` and the paper-versus-reproduced tables into
``data/results/``), prints one progress line per step and exits non-zero,
naming the notebook and the cell, when a step fails (a cell that raises, runs
past the time limit or loses its kernel).  Two notebooks run side
by side on a machine with two cores or more (``--jobs``); the reproduction
report, which gathers the other notebooks' tables, runs last.  The notebooks
on disk are never modified: they are executed in memory.  First of all, the
temporary files that a killed earlier run left in ``data/`` and the study's
output folder are removed (:func:`remove_stale_temporaries`).

With ``--study``, the study's name or file is injected after each notebook's
cell tagged ``parameters`` (as papermill does), the figures and tables go to
``runs/<study>/`` and the executed notebooks to ``runs/<study>/notebooks/``.
"""

import contextlib
import errno
import importlib
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

from piezolib import files, progress
from piezolib._checks import check_path, check_positive, check_type
from piezolib.workbook import study as studies
from piezolib.workbook import warm_kernels
from piezolib.workbook.outputs import (data_dir, notebooks_dir, project_root,
                                       study_figures_dir, study_results_dir)

__all__ = ["DATA_STEPS", "DATA_CHECKS", "DATA_FILES", "STUDY_DESIGNS", "GATHERING", "EXPECTED_SECONDS", "KERNEL_ENVIRONMENT", "list_notebooks", "notebook_waves", "default_jobs", "inject_study", "study_spec",
           "run_notebook", "run", "remove_stale_temporaries", "NotebookFailure"]

#: Data-generating steps run before the notebooks, as "module:function" names
#: of functions that take no arguments and return the list of files written.
DATA_STEPS = ["piezolib.problem.stage_data:write_experiment_files"]

#: Checks run before the data steps, as "module:function" names of functions
#: that take no arguments and return ``{path: problem}`` for the files that
#: fail; each failing file gets one line when the data steps regenerate it.
DATA_CHECKS = ["piezolib.problem.stage_data:check_experiment_files"]

#: The files those checks look at, as "module:function" names of functions that take no
#: arguments and return them (for the line saying how many were checked).
DATA_FILES = ["piezolib.problem.stage_data:experiment_paths"]

#: Designs a study other than the reference needs before its notebooks run, as
#: (name prefixes of the notebooks that use them, what, "module:function" taking the study):
#: computed once, in the reproduce process (in parallel where the design allows), so that
#: no notebook cell waits minutes for them and no two notebooks design the same twice.
STUDY_DESIGNS = [
    (("04_", "05_", "06_", "09_", "12_"), "study controllers (DK designs)",
     "piezolib.workbook.pipeline:study_controllers"),
    (("09_",), "study mixed-mu designs (D,G-K, one per performance scale, 2 processes)",
     "piezolib.workbook.pipeline:study_mixed_designs"),
]

#: Name prefixes of the notebooks that read every other notebook's table
#: (the reproduction report): they run after all the others have finished.
GATHERING = ("07_",)

#: A notebook's seconds inside ``reproduce`` on an idle 2-core machine, as
#: ``benchmarks/bench_workbook.py`` printed them: only their order is used, to start the long
#: notebooks of a wave first so that two kernels finish close together (a notebook not listed
#: counts as the median, and equal ones go by name).
EXPECTED_SECONDS = {
    "00_published_design_audit.ipynb": 2.7, "01_identification.ipynb": 3.5,
    "02_uncertainty.ipynb": 5.6, "03_dahl_hysteresis.ipynb": 10.7,
    "04_weighting_design.ipynb": 3.7, "05_mu_synthesis.ipynb": 8.0,
    "06_tracking_experiments.ipynb": 8.9, "08_your_own_stage.ipynb": 9.4,
    "09_mixed_mu.ipynb": 11.6, "10_real_piezo_benchmark.ipynb": 23.7, "11_sweeps.ipynb": 1.3,
    "12_tracking_over_the_set.ipynb": 15.2, "07_reproduction_report.ipynb": 1.5}

#: Environment variables a headless run sets for its kernels unless already set:
#: figures are saved, not drawn (Agg); threaded BLAS on small problems is slower on
#: 2 cores.  (Controls draw their static figure by themselves: a headless client
#: sends no cell id, see piezolib.notebook_display.)
KERNEL_ENVIRONMENT = {"MPLBACKEND": "Agg", "OPENBLAS_NUM_THREADS": "1"}


class NotebookFailure(RuntimeError):
    """A notebook cell raised; carries the notebook name and the cell index.

    Examples
    --------
    >>> exc = NotebookFailure("05_mu_synthesis.ipynb", 3, "x = 1 / 0", "ZeroDivisionError")
    >>> print(exc)
    05_mu_synthesis.ipynb: cell 3 failed ('x = 1 / 0'): ZeroDivisionError
    """

    def __init__(self, notebook, cell_index, source, error):
        self.notebook, self.cell_index, self.source, self.error = (
            notebook, cell_index, source, error)
        first_line = source.strip().splitlines()[0] if source.strip() else ""
        if cell_index is None:          # before or after the cells (the kernel, the file)
            super().__init__(f"{notebook}: failed: {error}")
        else:
            super().__init__(f"{notebook}: cell {cell_index} failed ({first_line!r}): {error}")


def list_notebooks(selection=None):
    """The numbered notebooks in pipeline order, optionally only those whose
    name starts with one of the prefixes in ``selection`` (e.g. ``["00"]``).

    Examples
    --------
    >>> [path.name for path in list_notebooks(["00", "07"])]
    ['00_published_design_audit.ipynb', '07_reproduction_report.ipynb']
    """
    paths = sorted(notebooks_dir().glob("[0-9][0-9]_*.ipynb"))
    selection = _prefixes(selection)
    if selection:
        paths = [p for p in paths if any(p.name.startswith(s) for s in selection)]
        if not paths:
            raise ValueError(f"selection: no notebook matches {selection!r}")
    return paths


def _prefixes(selection):
    """None or a list of name prefixes; one string is one prefix (not its characters)."""
    if selection is None or isinstance(selection, str):
        return None if selection is None else [selection]
    if not hasattr(selection, "__iter__"):
        raise TypeError(f"selection must be notebook name prefixes such as ['05'], "
                        f"got {selection!r}")
    selection = list(selection)
    bad = [s for s in selection if not isinstance(s, str)]
    if bad:
        raise TypeError(f"selection must hold text prefixes such as '05', got {bad[0]!r}")
    return selection


def _notebook_paths(paths, name="paths", must_exist=True):
    """``paths`` as a list of notebook paths, existing files if ``must_exist`` (``name``:
    the argument, for errors)."""
    if isinstance(paths, (str, os.PathLike)) or not hasattr(paths, "__iter__"):
        raise TypeError(f"{name} must be a list of notebook paths, got {paths!r}")
    paths = [check_path(name, p) for p in paths]
    missing = [p for p in paths if must_exist and not p.is_file()]
    if missing:
        raise FileNotFoundError(errno.ENOENT, f"{name}: there is no notebook",
                                str(missing[0]))
    return paths


def notebook_waves(paths):
    """Split notebooks into waves that run one after the other.

    Within a wave the notebooks are independent (each builds what it needs,
    the controllers come from the committed artifact or the study's disk
    cache) and may run side by side, the longest first
    (:data:`EXPECTED_SECONDS`: with two kernels the wave then ends about
    when its last notebook does); the notebooks named in :data:`GATHERING`
    form a last wave.  Empty waves are left out.

    Examples
    --------
    >>> waves = notebook_waves(list_notebooks(["05", "07", "10"]))
    >>> [[path.name for path in wave] for wave in waves]     # the report gathers, last
    [['10_real_piezo_benchmark.ipynb', '05_mu_synthesis.ipynb'], ['07_reproduction_report.ipynb']]
    """
    paths = _notebook_paths(paths, must_exist=False)
    first = sorted((p for p in paths if not p.name.startswith(GATHERING)),
                   key=lambda p: (-_expected_seconds(p), p.name))
    last = [p for p in paths if p.name.startswith(GATHERING)]
    return [wave for wave in (first, last) if wave]


def _expected_seconds(path):
    """A notebook's expected seconds (:data:`EXPECTED_SECONDS`; the median if not listed)."""
    median = sorted(EXPECTED_SECONDS.values())[len(EXPECTED_SECONDS) // 2]
    return EXPECTED_SECONDS.get(path.name, median)


def default_jobs():
    """Notebooks run side by side by default: 2, or 1 on a single-core machine.

    Each kernel computes on one core (``OPENBLAS_NUM_THREADS=1``); more than
    two at once mostly adds memory.

    Examples
    --------
    >>> default_jobs() in (1, 2)
    True
    """
    return max(1, min(2, os.cpu_count() or 1))


def inject_study(nb, study):
    """Insert ``study = <spec>`` after the cell tagged ``parameters`` (papermill's
    convention: the new cell is tagged ``injected-parameters``); return ``nb``.

    Raises
    ------
    ValueError
        When the notebook has no cell tagged ``parameters``.

    Examples
    --------
    >>> import nbformat
    >>> nb = nbformat.v4.new_notebook()
    >>> cell = nbformat.v4.new_code_cell('study = "reference"')
    >>> cell.metadata["tags"] = ["parameters"]
    >>> nb.cells = [cell]
    >>> [c.source for c in inject_study(nb, "wide_error_weight").cells]
    ['study = "reference"', "study = 'wide_error_weight'  # injected by reproduce"]
    """
    import nbformat

    check_type("nb", nb, nbformat.NotebookNode, "a notebook read with nbformat")
    studies.load(study)                   # an unknown or broken study fails here, not in a cell
    for index, cell in enumerate(nb.cells):
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            break
    else:
        raise ValueError("the notebook has no cell tagged 'parameters'")
    injected = nbformat.v4.new_code_cell(f"study = {str(study)!r}  # injected by reproduce")
    injected.metadata["tags"] = ["injected-parameters"]
    nb.cells.insert(index + 1, injected)
    return nb


def study_spec(study):
    """What :func:`inject_study` writes for ``study``: a name as it is, a TOML file as an
    absolute path (the kernel runs in ``notebooks/``, where a relative path means another file).

    Examples
    --------
    >>> study_spec("wide_error_weight"), study_spec(None)
    ('wide_error_weight', None)
    >>> Path(study_spec("studies/wide_error_weight.toml")).is_absolute()
    True
    """
    if study is None:
        return None
    return str(Path(study).resolve()) if str(study).endswith(".toml") else str(study)


def run_notebook(path, timeout=600, study=None, save_to=None, env=None):
    """Execute one notebook in memory with the current interpreter.

    Parameters
    ----------
    path : pathlib.Path
    timeout : float
        Per-cell time limit [s].
    study : str or pathlib.Path, optional
        Study to inject (:func:`inject_study`); default: the notebook's own.
    save_to : pathlib.Path, optional
        Folder to write the executed notebook to (also when it fails).
    env : dict, optional
        Environment variables of the kernel process (default: this process's).

    Raises
    ------
    NotebookFailure
        When a cell raises, runs longer than ``timeout`` or its kernel dies;
        names the notebook and the cell.
    """
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

    path = _notebook_paths([path], "path")[0]
    timeout = check_positive("timeout", timeout)
    if env is not None and not (isinstance(env, dict)
                                and all(isinstance(v, str) for v in env.values())):
        raise TypeError(f"env must be a dict of environment variables (text values), got {env!r}")
    if study is not None:
        studies.load(study)                   # before a kernel starts
    nb = nbformat.read(path, as_version=4)
    if study is not None:
        inject_study(nb, study)
    started = {}                     # the cell running when the kernel stops answering

    def note_cell(cell, cell_index, **_):
        started.update(index=cell_index, source=cell.source)

    # a run's kernels fork from its warm server (run(), warm_kernels) unless given an env
    warm = ({"kernel_manager_class": warm_kernels.kernel_manager_class()}
            if env is None and os.environ.get(warm_kernels.SOCKET_ENV) else {})
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}},
                            on_cell_start=note_cell, **warm)
    try:
        # the kernel process's own log (a TCP-transport notice) is noise here;
        # cell output, including stderr, still reaches the notebook
        client.execute(stderr=subprocess.DEVNULL, **({} if env is None else {"env": env}))
    except CellExecutionError as exc:
        index, source = _failed_cell(nb)
        raise NotebookFailure(path.name, index, source,
                              f"{exc.ename}: {exc.evalue}") from None
    except CellTimeoutError:
        raise NotebookFailure(path.name, started.get("index"), started.get("source", ""),
                              f"timed out: the cell ran longer than {timeout:g} s "
                              "(the per-cell limit, --timeout)") from None
    except DeadKernelError as exc:
        raise NotebookFailure(path.name, started.get("index"), started.get("source", ""),
                              f"the kernel died ({exc})") from None
    finally:
        if save_to is not None:
            save_to.mkdir(parents=True, exist_ok=True)
            nbformat.write(nb, save_to / path.name)
    return nb


def run(selection=None, timeout=600, keep_going=False, data=True, stream=sys.stdout,
        study=None, jobs=None):
    """Regenerate data, then execute the notebooks; return the number of failures.

    ``study`` (a name in ``studies/`` or a path to a TOML file) is injected
    into every notebook; its outputs and the executed notebooks go to
    ``runs/<name>/`` unless it is the reference study.  ``jobs`` notebooks
    run side by side (default :func:`default_jobs`; waves from
    :func:`notebook_waves`); one line is printed as each finishes.  After a
    failure, without ``keep_going``, no further notebook starts (those
    already running finish and are reported).
    """
    jobs = default_jobs() if jobs is None else jobs
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    timeout = check_positive("timeout", timeout)
    selection = _prefixes(selection)
    chosen = studies.load(studies.REFERENCE if study is None else study)
    spec = study_spec(study)
    save_to = chosen.output_dir / "notebooks" if not chosen.is_reference else None
    for name, value in KERNEL_ENVIRONMENT.items():          # the kernels inherit these
        os.environ.setdefault(name, value)
    os.environ.setdefault("PIEZOLIB_ROOT", str(project_root()))
    # before anything writes: what a killed earlier run left half-written
    remove_stale_temporaries(chosen)
    steps = DATA_STEPS if data and not selection else []
    notebooks = list_notebooks(selection)
    designs = [] if chosen.is_reference else [
        (what, step) for prefixes, what, step in STUDY_DESIGNS
        if any(p.name.startswith(prefixes) for p in notebooks)]
    counter = _Counter(stream, len(steps) + len(designs) + len(notebooks))
    start_all = time.perf_counter()
    with contextlib.ExitStack() as stack:
        # the kernels' imports, paid once: the server imports them while the data is checked
        # opt-in (PIEZOLIB_WARM_KERNELS=1): in a fresh environment a first kernel was seen to
        # die before its kernel_info reply, not yet understood
        if notebooks and warm_kernels.available() and os.environ.get(
                warm_kernels.SOCKET_ENV, "") == "1":
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="piezolib-")))
            stack.enter_context(warm_kernels.WarmKernels(folder))
        failures = _run_steps(steps, designs, notebooks, chosen, counter, stream, jobs,
                              keep_going, dict(timeout=timeout, study=spec, save_to=save_to))
    out = chosen.output_dir
    tables = study_results_dir(chosen.name)
    print(f"{'all done' if not failures else f'{failures} step(s) failed'} in "
          f"{time.perf_counter() - start_all:.1f} s; study {chosen.name}: figures in "
          f"{out / 'figures'}, tables in {tables}"
          + (f", executed notebooks in {save_to}" if save_to else ""), file=stream, flush=True)
    return failures


def _run_steps(steps, designs, notebooks, chosen, counter, stream, jobs, keep_going, options):
    """Data steps, design steps, then the notebooks' waves; return the number of failures."""
    try:
        failures = _run_data_steps(steps, counter, stream)
        if not failures or keep_going:
            failures += _run_design_steps(designs, chosen, counter)
        if not failures or keep_going:
            for wave in notebook_waves(notebooks):
                failures += _run_wave(wave, jobs, counter, keep_going, stream, options)
                if failures and not keep_going:
                    break
    finally:
        counter.close()
    return failures


def remove_stale_temporaries(study, older_than_s=files.STALE_AFTER_S):
    """Remove the temporary files a killed run left in ``data/`` and the study's outputs.

    The folders a run writes to: ``data/`` (experiment files, tables,
    controllers) and ``figures/`` for the reference study, ``data/`` and
    ``runs/<study>/`` for any other; each with its sub-folders, through
    :func:`piezolib.files.remove_stale_temporaries` (which logs each removal).

    Returns
    -------
    list of Path
        The files removed.
    """
    study = studies.load(study)
    own = study_figures_dir(study.name) if study.is_reference else study.output_dir
    return [path for folder in (data_dir(), own)
            for path in files.remove_stale_temporaries(folder, older_than_s)]


class _Counter:
    """Numbered progress lines ``[k/total]`` on the stream, with a bar on stderr."""

    def __init__(self, stream, total):
        self.stream, self.total, self.k = stream, total, 0
        self.bar = progress.progress(total=total, desc="reproduce", unit="step")

    def line(self, name, seconds, status):
        self.k += 1
        _line(self.stream, self.k, self.total, name, seconds, status)
        self.bar.update()

    def close(self):
        self.bar.close()


def _run_data_steps(steps, counter, stream):
    """Checks, then the data steps when a file fails its check; returns the number of
    failures (stops at the first).  The first line says what was done: the files checked
    (none regenerated), or each file regenerated and why."""
    if not steps:
        return 0
    start = time.perf_counter()
    problems = _check_data()
    if not problems:
        for step in steps:
            counter.line("data files", time.perf_counter() - start,
                         f"checked {_checked_count()} files against their manifest: intact, "
                         "none regenerated")
        return 0
    for path, problem in problems.items():
        print(f"regenerating {path}: it failed its check ({problem})", file=stream,
              flush=True)
    for step in steps:
        start = time.perf_counter()
        module, func = step.split(":")
        try:
            written = getattr(importlib.import_module(module), func)()
            status = (f"regenerated {len(written)} files ({len(problems)} failed "
                      "their check)")
        except Exception as exc:  # report and stop, like a notebook
            counter.line(step, time.perf_counter() - start, f"FAILED: {type(exc).__name__}: {exc}")
            return 1
        counter.line("data files", time.perf_counter() - start, status)
    return 0


def _run_design_steps(steps, study, counter):
    """The study's designs (:data:`STUDY_DESIGNS`), one line each; returns the number of
    failures (stops at the first)."""
    for what, step in steps:
        start = time.perf_counter()
        module, func = step.split(":")
        try:
            found = getattr(importlib.import_module(module), func)(study)
        except Exception as exc:  # report and stop, like a notebook
            counter.line(what, time.perf_counter() - start,
                         f"FAILED: {type(exc).__name__}: {exc}")
            return 1
        counter.line(what, time.perf_counter() - start, f"ok ({getattr(found, 'source', 'ok')})")
    return 0


def _checked_count():
    """How many files :data:`DATA_CHECKS` look at (:data:`DATA_FILES`)."""
    count = 0
    for listing in DATA_FILES:
        module, func = listing.split(":")
        count += len(getattr(importlib.import_module(module), func)())
    return count


def _run_wave(paths, jobs, counter, keep_going, stream, options):
    """Execute one wave of notebooks, ``jobs`` at a time; return the number of failures."""
    failures = 0
    pending = list(paths)
    running = {}
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        while pending or running:
            while pending and len(running) < jobs and not (failures and not keep_going):
                path = pending.pop(0)
                future = pool.submit(_timed_notebook, path, options)
                running[future] = path
            if not running:
                break
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: running[f].name):
                path = running.pop(future)
                seconds, error = future.result()
                failures += error is not None
                _report(counter, stream, path.name, seconds, error)
    return failures


def _timed_notebook(path, options):
    """(seconds, None) or (seconds, NotebookFailure) of one notebook run."""
    start = time.perf_counter()
    try:
        run_notebook(path, **options)
        return time.perf_counter() - start, None
    except NotebookFailure as exc:
        return time.perf_counter() - start, exc
    except Exception as exc:       # a kernel that does not start, an unwritable save_to, ...
        return time.perf_counter() - start, NotebookFailure(
            path.name, None, "", f"{type(exc).__name__}: {exc}")


def _report(counter, stream, name, seconds, error):
    """One line per notebook; a failure's long error follows, indented."""
    if error is None:
        counter.line(name, seconds, "ok")
        return
    lines = error.error.strip().splitlines() or [""]
    where = "" if error.cell_index is None else f" at cell {error.cell_index}"
    counter.line(name, seconds, f"FAILED{where}: {lines[0][:160]}")
    if len(lines) > 1:
        detail = lines[1:21] + ([f"... ({len(lines) - 21} more lines)"] if len(lines) > 21 else [])
        print("\n".join("      " + line for line in detail), file=stream, flush=True)


def _check_data():
    """Run :data:`DATA_CHECKS`; return ``{path: problem}`` of the files that fail."""
    problems = {}
    for check in DATA_CHECKS:
        module, func = check.split(":")
        problems.update(getattr(importlib.import_module(module), func)())
    return problems


def _line(stream, k, total, name, seconds, status):
    # through the progress module: the line does not break a bar drawn on the terminal
    progress.write(f"[{k}/{total}] {name:<40s} {seconds:7.1f} s  {status}", file=stream)


def _failed_cell(nb):
    """Index (among all cells, from 0) and source of the cell with an error output."""
    for index, cell in enumerate(nb.cells):
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                return index, cell.source
    return -1, ""
