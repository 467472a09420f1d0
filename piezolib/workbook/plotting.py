"""Saving the workbook's figures: one name per figure, a file rewritten only when it changed.

A figure function draws its figure and names it after the paper's numbering
(:func:`name_figure`: ``figNN_<what>``, e.g. ``fig04_chirp_validation``, or
``extra_<what>`` for a figure with no counterpart in the paper); whoever
runs it decides where it goes: :func:`save_figure` writes
``<directory>/<name>.png`` (a notebook's session passes its study's
``figures/`` folder), after applying the units rule of
:mod:`piezolib.workbook.style` to every text.  The figure style itself is in
:mod:`piezolib.workbook.style`, the block-diagram engine in
:mod:`piezolib.workbook.figures.block_diagram`.
"""

import io
import os
import re
from pathlib import Path

import matplotlib as mpl
import matplotlib.image as mpimg
import numpy as np

from piezolib._checks import check_nonnegative, check_type
from piezolib.files import atomic_write
from piezolib.workbook.style import apply_unit_text

__all__ = ["name_figure", "figure_name", "save_figure", "same_picture", "PIXEL_TOLERANCE"]

_WHAT = re.compile(r"^[a-z0-9][a-z0-9_]*$")


def figure_name(number, what):
    """File stem of figure ``number`` (paper numbering, or None) showing ``what``.

    Examples
    --------
    >>> figure_name(4, "chirp_validation"), figure_name(None, "rls_convergence")
    ('fig04_chirp_validation', 'extra_rls_convergence')
    """
    if not isinstance(what, str) or not _WHAT.match(what):
        raise ValueError("what must be a lower-case identifier such as "
                         f"'chirp_validation', got {what!r}")
    if number is None:
        return f"extra_{what}"
    if isinstance(number, bool) or not isinstance(number, (int, np.integer)) or not 1 <= number <= 99:
        raise ValueError(f"number must be a paper figure number 1..99 or None, got {number!r}")
    return f"fig{int(number):02d}_{what}"


def name_figure(fig, number, what):
    """Give ``fig`` its file name (:func:`figure_name`) as its label and return it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    number : int or None
        The paper's figure number; ``None`` for a figure of the workbook's own.
    what : str
        Short lower-case description, e.g. ``"step_responses"``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> fig = name_figure(plt.figure(), 12, "mu_bounds")
    >>> fig.get_label()
    'fig12_mu_bounds'
    >>> plt.close(fig)
    """
    check_type("fig", fig, mpl.figure.Figure, "a matplotlib Figure")
    fig.set_label(figure_name(number, what))
    return fig


def save_figure(fig, directory):
    """Apply the units rule to ``fig`` and save it as ``<directory>/<name>.png``.

    An existing file showing the same picture up to antialiasing
    (:func:`same_picture`) is left as it is.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure named by :func:`name_figure`.
    directory : str or pathlib.Path
        Folder of the figures (created if missing), e.g. a study's
        :func:`piezolib.workbook.outputs.study_figures_dir`.

    Returns
    -------
    pathlib.Path
        The file written or kept.

    Examples
    --------
    >>> import tempfile
    >>> import matplotlib.pyplot as plt
    >>> fig = name_figure(plt.figure(figsize=(2, 1)), None, "demo")
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = save_figure(fig, folder)
    ...     print(path.name, path.stat().st_size > 0, save_figure(fig, folder) == path)
    extra_demo.png True True
    >>> plt.close(fig)
    """
    check_type("fig", fig, mpl.figure.Figure, "a matplotlib Figure")
    name = fig.get_label()
    if not name or not _WHAT.match(name):
        raise ValueError("fig has no file name: draw it with a figure function or call "
                         f"name_figure(fig, number, what) first (its label is {name!r})")
    if isinstance(directory, bool) or not isinstance(directory, (str, os.PathLike)):
        raise TypeError(f"directory must be a path, got {type(directory).__name__}")
    path = Path(directory) / f"{name}.png"
    path.parent.mkdir(parents=True, exist_ok=True)
    apply_unit_text(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    png = buffer.getvalue()
    if path.is_file() and same_picture(path.read_bytes(), png):
        return path         # the same figure up to antialiasing: leave the file as it is
    return atomic_write(path, png)


#: Largest change of any colour channel (0 ... 1) that :func:`same_picture` ignores.
PIXEL_TOLERANCE = 0.25


def same_picture(first, second, tolerance=PIXEL_TOLERANCE):
    """True when two PNG images (bytes) show the same figure.

    Same size, and no pixel differs by more than ``tolerance`` in any
    channel.  A curve that another machine's rounding moves by a small
    fraction of a pixel only changes the shades of its antialiased edge
    (seen: at most 0.19); a curve, a marker or a text that moved by a
    visible amount changes some pixel by more than a quarter.

    Parameters
    ----------
    first, second : bytes
        PNG files' contents.
    tolerance : float, optional
        Largest accepted difference of a channel (0..1 scale), >= 0.

    Examples
    --------
    >>> import io
    >>> import matplotlib.pyplot as plt
    >>> def png(y):
    ...     fig = plt.figure(figsize=(2, 1)); fig.gca().plot([0, 1], [0, y])
    ...     buffer = io.BytesIO(); fig.savefig(buffer, format="png"); plt.close(fig)
    ...     return buffer.getvalue()
    >>> same_picture(png(1.0), png(1.0)), same_picture(png(1.0), png(-1.0))
    (True, False)
    """
    tolerance = check_nonnegative("tolerance", tolerance)
    images = []
    for name, data in (("first", first), ("second", second)):
        if not isinstance(data, (bytes, bytearray)):
            raise TypeError(f"{name} must be PNG bytes, got {type(data).__name__}")
        try:
            images.append(mpimg.imread(io.BytesIO(data), format="png"))
        except (ValueError, SyntaxError, OSError) as exc:   # Pillow's "not a PNG file"
            raise ValueError(f"{name} is not a PNG image ({exc})") from None
    a, b = images
    return a.shape == b.shape and float(np.max(np.abs(a - b), initial=0.0)) <= tolerance
