"""Where the workbook checkout and its ``data/`` folder are; the check of a folder argument."""

import errno
import os
from pathlib import Path

from piezolib._checks import check_type

__all__ = ["project_root", "data_dir", "check_directory"]


def project_root():
    """The workbook checkout: ``$PIEZOLIB_ROOT`` if set, else the folder above
    the package when it holds ``notebooks/`` (editable install), else the
    current directory.

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> with tempfile.TemporaryDirectory() as root, mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root}):
    ...     project_root() == Path(root).resolve()
    True
    """
    env = os.environ.get("PIEZOLIB_ROOT")
    if env:
        return Path(env).resolve()
    here = Path(__file__).resolve().parents[2]
    if (here / "notebooks").is_dir():
        return here
    return Path.cwd()


def data_dir():
    """``data/``: virtual-stage experiment files and the results tables.

    Examples
    --------
    >>> data_dir() == project_root() / "data"
    True
    """
    return project_root() / "data"


def check_directory(directory, name="directory"):
    """Return ``directory`` as a Path after checking it can be a folder.

    The folder need not exist yet (writers create it); an existing file in its place
    fails here, naming the argument, instead of as a "Not a directory" error on the
    first file read or written inside it, after other work was done.

    Parameters
    ----------
    directory : str or os.PathLike
        The folder.
    name : str, optional
        Argument name used in the error messages.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    TypeError
        ``directory`` is not a str or path object.
    NotADirectoryError
        ``directory`` exists and is not a folder (the error's ``filename``).

    Examples
    --------
    >>> check_directory("data").name
    'data'
    >>> check_directory(3)
    Traceback (most recent call last):
    ...
    TypeError: directory must be a folder path (str or os.PathLike), got int
    """
    check_type(name, directory, (str, os.PathLike), "a folder path (str or os.PathLike)")
    path = Path(directory)
    if path.exists() and not path.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, f"{name} must be a folder, got a file",
                                 str(path))
    return path
