"""Run the whole workbook headless: data files first, then every notebook.

``python -m piezolib reproduce`` regenerates the virtual-stage experiment
files, executes ``notebooks/NN_*.ipynb`` in order (the notebooks save the
figures into ``figures/`` and the paper-versus-reproduced tables into
``data/results/``), prints one progress line per step and exits non-zero,
naming the notebook and the cell, when a step fails.  The notebooks on disk
are never modified: they are executed in memory.
"""

import importlib
import os
import subprocess
import sys
import time

from piezolib.workbook.paths import notebooks_dir, project_root

__all__ = ["DATA_STEPS", "DATA_CHECKS", "check_data", "list_notebooks", "run_notebook", "run", "NotebookFailure"]

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


def run_notebook(path, timeout=600):
    """Execute one notebook in memory with the current interpreter.

    Raises
    ------
    NotebookFailure
        When a cell raises; names the notebook and the cell.
    """
    import nbformat
    from nbclient import NotebookClient
    from nbclient.exceptions import CellExecutionError

    nb = nbformat.read(path, as_version=4)
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
    return nb


def run(selection=None, timeout=600, keep_going=False, data=True, stream=sys.stdout):
    """Regenerate data, then execute the notebooks; return the number of failures."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    # kernels inherit this: threaded BLAS on small problems is slower on 2 cores
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    os.environ.setdefault("PIEZOLIB_ROOT", str(project_root()))
    failures = 0
    steps = DATA_STEPS if data and not selection else []
    total = len(steps) + len(list_notebooks(selection))
    k = 0
    start_all = time.perf_counter()
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
        if failures and not keep_going:
            return failures
    for path in list_notebooks(selection):
        k += 1
        start = time.perf_counter()
        try:
            run_notebook(path, timeout=timeout)
            status = "ok"
        except NotebookFailure as exc:
            failures += 1
            lines = exc.error.strip().splitlines() or [""]
            status = f"FAILED at cell {exc.cell_index}: {lines[0][:160]}"
        _line(stream, k, total, path.name, time.perf_counter() - start, status)
        if status != "ok" and len(lines) > 1:   # the rest of a long error, indented
            detail = lines[1:21] + ([f"... ({len(lines) - 21} more lines)"] if len(lines) > 21 else [])
            print("\n".join("      " + line for line in detail), file=stream, flush=True)
        if failures and not keep_going:
            break
    print(f"{'all done' if not failures else f'{failures} step(s) failed'} in "
          f"{time.perf_counter() - start_all:.1f} s; figures in "
          f"{project_root() / 'figures'}, tables in {project_root() / 'data' / 'results'}",
          file=stream, flush=True)
    return failures


def check_data():
    """Run :data:`DATA_CHECKS`; return ``{path: problem}`` of the files that fail."""
    problems = {}
    for check in DATA_CHECKS:
        module, func = check.split(":")
        problems.update(getattr(importlib.import_module(module), func)())
    return problems


def _line(stream, k, total, name, seconds, status):
    print(f"[{k}/{total}] {name:<40s} {seconds:7.1f} s  {status}", file=stream, flush=True)


def _failed_cell(nb):
    """Index (among all cells, from 0) and source of the cell with an error output."""
    for index, cell in enumerate(nb.cells):
        for out in cell.get("outputs", []):
            if out.get("output_type") == "error":
                return index, cell.source
    return -1, ""
