"""Where the workbook reads its inputs and writes its outputs, per study.

The reference study writes the committed outputs (``figures/``,
``data/results/``, ``data/controllers/``); any other study writes the same
files under ``runs/<study>/`` (git-ignored).  Every function takes the study's
name: no process-wide setting decides where an output goes.
"""

from piezolib.problem.paths import data_dir, project_root

__all__ = ["REFERENCE_STUDY", "RESERVED_NAMES", "study_name_problem", "project_root", "data_dir",
           "runs_dir", "report_dir", "notebooks_dir", "study_output_dir", "study_results_dir",
           "study_figures_dir", "study_controllers_dir", "sweep_output_dir"]

#: Name of the paper's reproduction: the one study that writes the committed outputs.
REFERENCE_STUDY = "reference"


#: Names no study may take: folders of ``runs/`` that hold something else.
RESERVED_NAMES = {"cache": "the pipeline's disk cache",
                  "report": "the report documents (python -m piezolib report)",
                  "sweeps": "the design sweeps (python -m piezolib sweep)"}


def study_name_problem(name):
    """What is wrong with ``name`` as a study name (a folder of ``runs/``), or None.

    A study name is ASCII letters, digits, '_' or '-' (so it is one safe path
    component: no '/', no '..') and not one of :data:`RESERVED_NAMES`.

    Examples
    --------
    >>> study_name_problem("wide_He") is None
    True
    >>> study_name_problem("../x")
    "must be letters, digits, '_' or '-', got '../x'"
    >>> study_name_problem("cache")
    "'cache' is reserved: runs/cache/ holds the pipeline's disk cache"
    """
    if not isinstance(name, str) or not name or not all(
            c.isascii() and (c.isalnum() or c in "_-") for c in name):
        return f"must be letters, digits, '_' or '-', got {name!r}"
    if name in RESERVED_NAMES:
        return f"{name!r} is reserved: runs/{name}/ holds {RESERVED_NAMES[name]}"
    return None


def _study_name(name):
    problem = study_name_problem(name)
    if problem:
        raise ValueError(f"name {problem}")
    return name


def runs_dir():
    """``runs/``: outputs of every study but the reference, and the cache (git-ignored).

    Examples
    --------
    >>> runs_dir().relative_to(project_root()).as_posix()
    'runs'
    """
    return project_root() / "runs"


def report_dir():
    """``runs/report/``: the report documents, one per study (git-ignored; not created here).

    Examples
    --------
    >>> report_dir().relative_to(project_root()).as_posix()
    'runs/report'
    """
    return runs_dir() / "report"


def notebooks_dir():
    """``notebooks/``: the numbered notebooks.

    Examples
    --------
    >>> notebooks_dir().relative_to(project_root()).as_posix()
    'notebooks'
    """
    return project_root() / "notebooks"


def study_output_dir(name):
    """Root of study ``name``'s outputs: the checkout for the reference, else ``runs/<name>/``.

    Examples
    --------
    >>> study_output_dir("reference") == project_root()
    True
    >>> study_output_dir("explore").relative_to(project_root()).as_posix()
    'runs/explore'
    """
    return project_root() if _study_name(name) == REFERENCE_STUDY else runs_dir() / name


def study_results_dir(name):
    """Study ``name``'s paper-versus-reproduced tables: ``data/results/`` or
    ``runs/<name>/results/`` (not created here).

    Examples
    --------
    >>> [study_results_dir(name).relative_to(project_root()).as_posix()
    ...  for name in ("reference", "explore")]
    ['data/results', 'runs/explore/results']
    """
    if _study_name(name) == REFERENCE_STUDY:
        return data_dir() / "results"
    return study_output_dir(name) / "results"


def study_figures_dir(name):
    """Study ``name``'s figures: ``figures/`` or ``runs/<name>/figures/`` (not created here).

    Examples
    --------
    >>> [study_figures_dir(name).relative_to(project_root()).as_posix()
    ...  for name in ("reference", "explore")]
    ['figures', 'runs/explore/figures']
    """
    return study_output_dir(name) / "figures"


def study_controllers_dir(name):
    """Study ``name``'s exported controllers: ``data/controllers/`` or
    ``runs/<name>/controllers/`` (not created here).

    Examples
    --------
    >>> [study_controllers_dir(name).relative_to(project_root()).as_posix()
    ...  for name in ("reference", "explore")]
    ['data/controllers', 'runs/explore/controllers']
    """
    if _study_name(name) == REFERENCE_STUDY:
        return data_dir() / "controllers"
    return study_output_dir(name) / "controllers"


def sweep_output_dir(name):
    """Sweep ``name``'s table, figure and point records: ``runs/sweeps/<name>/`` (not
    created here; a sweep never writes ``figures/`` or ``data/results/``).

    Examples
    --------
    >>> sweep_output_dir("omega_e").relative_to(project_root()).as_posix()
    'runs/sweeps/omega_e'
    """
    return runs_dir() / "sweeps" / _study_name(name)
