"""Where the workbook checkout and its ``data/`` folder are."""

import os
from pathlib import Path

__all__ = ["project_root", "data_dir"]


def project_root():
    """The workbook checkout: ``$PIEZOLIB_ROOT`` if set, else the folder above
    the package when it holds ``notebooks/`` (editable install), else the
    current directory."""
    env = os.environ.get("PIEZOLIB_ROOT")
    if env:
        return Path(env).resolve()
    here = Path(__file__).resolve().parents[2]
    if (here / "notebooks").is_dir():
        return here
    return Path.cwd()


def data_dir():
    """``data/``: virtual-stage experiment files and the results tables."""
    return project_root() / "data"
