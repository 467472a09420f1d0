"""Run the whole workbook headless: data files first, then every notebook.

``python -m piezolib reproduce`` regenerates the virtual-stage experiment
files, executes ``notebooks/NN_*.ipynb`` in order (the notebooks save the
figures into ``figures/`` and the paper-versus-reproduced tables into
``data/results/``), prints one progress line per step and exits non-zero,
naming the notebook and the cell, when a step fails.  The notebooks on disk
are never modified: they are executed in memory.

With ``--study``, the study's name or file is injected after each notebook's
cell tagged ``parameters`` (as papermill does), the figures and tables go to
``runs/<study>/`` and the executed notebooks to ``runs/<study>/notebooks/``.
"""

import importlib
import os
import subprocess
import sys
import time
from pathlib import Path

from piezolib import progress
from piezolib.workbook import study as studies
from piezolib.workbook.paths import notebooks_dir, project_root, study_results_dir

__all__ = ["DATA_STEPS", "DATA_CHECKS", "check_data", "list_notebooks", "inject_study",
           "run_notebook", "run", "NotebookFailure"]

#: Data-generating steps run before the notebooks, as "module:function" names
#: of functions that take no arguments and return the list of files written.
DATA_STEPS = ["piezolib.problem.stage_data:write_experiment_files"]

#: Checks run before the data steps, as "module:function" names of functions
#: that take no arguments and return ``{path: problem}`` for the files that
#: fail; each failing file gets one line when the data steps regenerate it.
DATA_CHECKS = ["piezolib.problem.stage_data:check_experiment_files"]


class NotebookFailure(RuntimeError):
    """A notebook cell raised; carries the notebook name and the cell index."""

    def __init__(self, notebook, cell_index, source, error):
        self.notebook, self.cell_index, self.source, self.error = (
            notebook, cell_index, source, error)
        first_line = source.strip().splitlines()[0] if source.strip() else ""
        super().__init__(f"{notebook}: cell {cell_index} failed ({first_line!r}): {error}")


def list_notebooks(selection=None):
    """The numbered notebooks in pipeline order, optionally only those whose
    name starts with one of the prefixes in ``selection`` (e.g. ``["00"]``)."""
    paths = sorted(notebooks_dir().glob("[0-9][0-9]_*.ipynb"))
    if selection:
        paths = [p for p in paths if any(p.name.startswith(s) for s in selection)]
        if not paths:
            raise ValueError(f"no notebook matches {selection!r}")
    return paths


def inject_study(nb, study):
    """Insert ``study = <spec>`` after the cell tagged ``parameters`` (papermill's
    convention: the new cell is tagged ``injected-parameters``); return ``nb``.

    Raises
    ------
    ValueError
        When the notebook has no cell tagged ``parameters``.
    """
    import nbformat

    for index, cell in enumerate(nb.cells):
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            break
    else:
        raise ValueError("the notebook has no cell tagged 'parameters'")
    injected = nbformat.v4.new_code_cell(f"study = {str(study)!r}  # injected by reproduce")
    injected.metadata["tags"] = ["injected-parameters"]
    nb.cells.insert(index + 1, injected)
    return nb


def run_notebook(path, timeout=600, study=None, save_to=None):
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

    Raises
    ------
    NotebookFailure
        When a cell raises; names the notebook and the cell.
    """
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError

    nb = nbformat.read(path, as_version=4)
    if study is not None:
        inject_study(nb, study)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    try:
        # the kernel process's own log (a TCP-transport notice) is noise here;
        # cell output, including stderr, still reaches the notebook
        client.execute(stderr=subprocess.DEVNULL)
    except CellExecutionError as exc:
        index, source = _failed_cell(nb)
        raise NotebookFailure(path.name, index, source,
                              f"{exc.ename}: {exc.evalue}") from None
    finally:
        if save_to is not None:
            save_to.mkdir(parents=True, exist_ok=True)
            nbformat.write(nb, save_to / path.name)
    return nb


def run(selection=None, timeout=600, keep_going=False, data=True, stream=sys.stdout,
        study=None):
    """Regenerate data, then execute the notebooks; return the number of failures.

    ``study`` (a name in ``studies/`` or a path to a TOML file) is injected
    into every notebook; its outputs and the executed notebooks go to
    ``runs/<name>/`` unless it is the reference study.
    """
    chosen = studies.load(studies.REFERENCE if study is None else study)
    spec = None if study is None else (str(Path(study).resolve()) if str(study).endswith(".toml")
                                       else str(study))
    save_to = chosen.output_dir / "notebooks" if not chosen.is_reference else None
    os.environ.setdefault("MPLBACKEND", "Agg")
    # widgets have no frontend here: controls draw their static figure
    os.environ.setdefault("PIEZOLIB_STATIC", "1")
    # kernels inherit this: threaded BLAS on small problems is slower on 2 cores
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("PIEZOLIB_ROOT", str(project_root()))
    failures = 0
    steps = DATA_STEPS if data and not selection else []
    total = len(steps) + len(list_notebooks(selection))
    k = 0
    start_all = time.perf_counter()
    # a bar on stderr (a terminal), beside the one line per step on stream
    bar = progress.progress(total=total, desc="reproduce", unit="step")
    try:
        if steps:
            for path, problem in check_data().items():
                print(f"regenerating {path}: it failed its check ({problem})", file=stream,
                      flush=True)
        for step in steps:
            k += 1
            start = time.perf_counter()
            module, func = step.split(":")
            try:
                written = getattr(importlib.import_module(module), func)()
                status = f"ok ({len(written)} files)"
            except Exception as exc:  # report and continue or stop, like a notebook
                failures += 1
                status = f"FAILED: {type(exc).__name__}: {exc}"
            _line(stream, k, total, step, time.perf_counter() - start, status)
            bar.update()
            if failures and not keep_going:
                return failures
        for path in list_notebooks(selection):
            k += 1
            start = time.perf_counter()
            try:
                run_notebook(path, timeout=timeout, study=spec, save_to=save_to)
                status = "ok"
            except NotebookFailure as exc:
                failures += 1
                lines = exc.error.strip().splitlines() or [""]
                status = f"FAILED at cell {exc.cell_index}: {lines[0][:160]}"
            _line(stream, k, total, path.name, time.perf_counter() - start, status)
            bar.update()
            if status != "ok" and len(lines) > 1:   # the rest of a long error, indented
                detail = lines[1:21] + ([f"... ({len(lines) - 21} more lines)"] if len(lines) > 21 else [])
                print("\n".join("      " + line for line in detail), file=stream, flush=True)
            if failures and not keep_going:
                break
    finally:
        bar.close()
    out = chosen.output_dir
    tables = study_results_dir(chosen.name)
    print(f"{'all done' if not failures else f'{failures} step(s) failed'} in "
          f"{time.perf_counter() - start_all:.1f} s; study {chosen.name}: figures in "
          f"{out / 'figures'}, tables in {tables}"
          + (f", executed notebooks in {save_to}" if save_to else ""), file=stream, flush=True)
    return failures


def check_data():
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
