"""Saving the workbook's figures: one name per figure, a file rewritten only when it changed.

Figures are named after the paper's numbering, ``figures/figNN_<what>.png``
(e.g. ``fig04_chirp_validation.png``); figures with no counterpart in the
paper are saved as ``figures/extra_<what>.png``.  :func:`save_figure` applies
the units rule of :mod:`piezolib.workbook.style` to every text first.  The
figure style itself is in :mod:`piezolib.workbook.style`, the block-diagram
engine in :mod:`piezolib.workbook.figures.block_diagram`.
"""

import io
import re

import matplotlib as mpl
import matplotlib.image as mpimg
import numpy as np

from piezolib.records import atomic_write
from piezolib.workbook.outputs import figures_dir
from piezolib.workbook.style import apply_unit_text
# kept for the notebooks' start cells until they use the façade
from piezolib.workbook.style import db, new_figure, use_style  # noqa: F401

__all__ = ["figure_path", "save_figure", "same_picture", "PIXEL_TOLERANCE"]

_WHAT = re.compile(r"^[a-z0-9][a-z0-9_]*$")


def figure_path(number, what):
    """Path of figure ``number`` (paper numbering, or None) showing ``what``."""
    if not isinstance(what, str) or not _WHAT.match(what):
        raise ValueError("what must be a lower-case identifier such as "
                         f"'chirp_validation', got {what!r}")
    if number is None:
        return figures_dir() / f"extra_{what}.png"
    if isinstance(number, bool) or not isinstance(number, (int, np.integer)) or not 1 <= number <= 99:
        raise ValueError(f"number must be a paper figure number 1..99 or None, got {number!r}")
    return figures_dir() / f"fig{int(number):02d}_{what}.png"


def save_figure(fig, number, what):
    """Apply the units rule to ``fig``, save it as ``figures/figNN_<what>.png``, return the path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    number : int or None
        The paper's figure number; ``None`` for a figure of the workbook's own.
    what : str
        Short lower-case description, e.g. ``"step_responses"``.
    """
    if not isinstance(fig, mpl.figure.Figure):
        raise TypeError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    path = figure_path(number, what)
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
    """
    a, b = (mpimg.imread(io.BytesIO(x), format="png") for x in (first, second))
    return a.shape == b.shape and float(np.max(np.abs(a - b), initial=0.0)) <= tolerance
