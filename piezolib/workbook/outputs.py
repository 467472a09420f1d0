"""Where the workbook reads its inputs and writes its outputs.

The reference study writes the committed outputs (``figures/``,
``data/results/``, ``data/controllers/``); any other study writes the same
files under ``runs/<study>/`` (git-ignored), chosen by
:func:`set_output_study` (called by :func:`piezolib.workbook.study.use`).
"""

from piezolib.problem.paths import data_dir, project_root

__all__ = ["REFERENCE_STUDY", "project_root", "data_dir", "results_dir", "figures_dir",
           "controllers_dir", "notebooks_dir", "runs_dir", "study_output_dir",
           "study_results_dir", "set_output_study", "output_study"]

#: Name of the paper's reproduction: the one study that writes the committed outputs.
REFERENCE_STUDY = "reference"
_output_study = REFERENCE_STUDY


def set_output_study(name):
    """Send this process's figures and tables to the folder of study ``name``."""
    global _output_study
    if not isinstance(name, str) or not name:
        raise ValueError(f"name must be a study name, got {name!r}")
    _output_study = name


def output_study():
    """Name of the study whose folder receives the outputs (default ``reference``)."""
    return _output_study


def runs_dir():
    """``runs/``: outputs of every study but the reference, and the cache (git-ignored)."""
    return project_root() / "runs"


def study_output_dir(name):
    """Root of study ``name``'s outputs: the checkout for the reference, else ``runs/<name>/``."""
    return project_root() if name == REFERENCE_STUDY else runs_dir() / name


def _made(path):
    path.mkdir(parents=True, exist_ok=True)
    return path


def study_results_dir(name):
    """Where study ``name``'s tables are: ``data/results/`` or ``runs/<name>/results/``."""
    if name == REFERENCE_STUDY:
        return data_dir() / "results"
    return study_output_dir(name) / "results"


def results_dir():
    """Paper-versus-reproduced CSV tables of this process's study (created on demand)."""
    return _made(study_results_dir(_output_study))


def figures_dir():
    """Regenerated figures: ``figures/`` or ``runs/<study>/figures/``."""
    return _made(study_output_dir(_output_study) / "figures")


def controllers_dir():
    """Exported controllers: ``data/controllers/`` or ``runs/<study>/controllers/``."""
    if _output_study == REFERENCE_STUDY:
        return _made(data_dir() / "controllers")
    return _made(study_output_dir(_output_study) / "controllers")


def notebooks_dir():
    """``notebooks/``: the numbered notebooks."""
    return project_root() / "notebooks"
