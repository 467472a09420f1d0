"""Where the workbook reads its inputs and writes its outputs."""

import os
from pathlib import Path

__all__ = ["project_root", "data_dir", "results_dir", "figures_dir", "notebooks_dir"]


def project_root():
    """The workbook checkout: ``$PIEZOLIB_ROOT`` if set, else the folder above
    the package when it holds ``notebooks/`` (editable install), else the
    current directory."""
    env = os.environ.get("PIEZOLIB_ROOT")
    if env:
        return Path(env).resolve()
    here = Path(__file__).resolve().parents[1]
    if (here / "notebooks").is_dir():
        return here
    return Path.cwd()


def data_dir():
    """``data/``: published tables and virtual-stage experiment files."""
    return project_root() / "data"


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
