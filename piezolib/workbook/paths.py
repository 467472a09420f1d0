"""Where the workbook reads its inputs and writes its outputs."""

from piezolib.problem.paths import data_dir, project_root

__all__ = ["project_root", "data_dir", "results_dir", "figures_dir", "notebooks_dir"]


def results_dir():
    """``data/results/``: paper-versus-reproduced CSV tables (created on demand)."""
    path = data_dir() / "results"
    path.mkdir(parents=True, exist_ok=True)
    return path


def figures_dir():
    """``figures/``: regenerated figures (created on demand)."""
    path = project_root() / "figures"
    path.mkdir(parents=True, exist_ok=True)
    return path


def notebooks_dir():
    """``notebooks/``: the numbered notebooks."""
    return project_root() / "notebooks"
