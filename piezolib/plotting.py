"""One figure style for the workbook and one way to save figures.

Figures are named after the paper's numbering, ``figures/figNN_<what>.png``
(e.g. ``fig04_chirp_validation.png``); figures with no counterpart in the
paper are saved as ``figures/extra_<what>.png``.
"""

import re

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np

from ._paths import figures_dir

__all__ = ["STYLE", "use_style", "new_figure", "save_figure", "figure_path",
           "db", "plot_magnitude"]

#: rcParams of the workbook's figures (print-sized, readable at 100 %).
STYLE = {
    "figure.figsize": (7.0, 4.2),
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "savefig.bbox": "tight",
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "grid.linewidth": 0.5,
    "lines.linewidth": 1.3,
    "axes.prop_cycle": mpl.cycler(color=["#1f4e79", "#c0504d", "#4f8f3a", "#8064a2",
                                         "#d08a00", "#4bacc6", "#7f7f7f"]),
    # no timestamps or version strings in the files: reruns give identical PNGs
    "svg.hashsalt": "piezolib",
}

_WHAT = re.compile(r"^[a-z0-9][a-z0-9_]*$")


def use_style():
    """Apply :data:`STYLE` to matplotlib's global rcParams."""
    mpl.rcParams.update(STYLE)


def new_figure(nrows=1, ncols=1, **kwargs):
    """``plt.subplots`` in the workbook style (``constrained`` layout)."""
    use_style()
    kwargs.setdefault("layout", "constrained")
    return plt.subplots(nrows, ncols, **kwargs)


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
    """Save ``fig`` as ``figures/figNN_<what>.png`` and return the path.

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
    fig.savefig(path, metadata={"Software": None})
    return path


def db(x):
    """Magnitude in decibels, 20 log10 |x|."""
    return 20 * np.log10(np.abs(x))


def plot_magnitude(ax, omega, response, label=None, **kwargs):
    """Plot |response| in dB against omega [rad/s] on a log axis."""
    line, = ax.semilogx(omega, db(response), label=label, **kwargs)
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("magnitude [dB]")
    return line
