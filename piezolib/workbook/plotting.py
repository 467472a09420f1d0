"""One figure style for the workbook and one way to save figures.

Figures are named after the paper's numbering, ``figures/figNN_<what>.png``
(e.g. ``fig04_chirp_validation.png``); figures with no counterpart in the
paper are saved as ``figures/extra_<what>.png``.
"""

import re

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np

from piezolib.workbook.paths import figures_dir

__all__ = ["STYLE", "use_style", "new_figure", "save_figure", "figure_path",
           "db", "plot_magnitude", "block_diagram"]

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


def block_diagram(ax, blocks, wires, title=None):
    """Draw a signal-flow block diagram on ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    blocks : dict
        ``name -> (x, y, label)``; a label starting with ``"o"`` and of length
        1 draws a summing junction, anything else a box.
    wires : list of tuple
        ``(from, to, label)`` where ``from``/``to`` are block names or
        ``(x, y)`` points; the label (signal name and unit) is written at the
        middle of the wire.
    """
    ax.set_axis_off()
    ax.set_aspect("equal")
    size = {}
    for name, (x, y, label) in blocks.items():
        if label == "o":
            ax.add_patch(mpl.patches.Circle((x, y), 0.18, fill=False, lw=1.2))
            ax.text(x, y, "+", ha="center", va="center", fontsize=8)
            size[name] = (0.18, 0.18)
        else:
            w = 0.16 * max(len(line) for line in label.splitlines()) + 0.5
            h = 0.35 + 0.28 * label.count("\n")
            ax.add_patch(mpl.patches.FancyBboxPatch(
                (x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.05",
                fc="#eef3f8", ec="#1f4e79", lw=1.2))
            ax.text(x, y, label, ha="center", va="center", fontsize=8)
            size[name] = (w / 2 + 0.05, h / 2 + 0.05)

    def anchor(end, toward):
        if not isinstance(end, str):
            return np.asarray(end, float)
        x, y, _ = blocks[end]
        hw, hh = size[end]
        dx, dy = toward[0] - x, toward[1] - y
        if abs(dx) * hh >= abs(dy) * hw:   # leave through a vertical side
            return np.array([x + np.sign(dx) * hw, y + dy * hw / max(abs(dx), 1e-9)])
        return np.array([x + dx * hh / max(abs(dy), 1e-9), y + np.sign(dy) * hh])

    def centre(end):
        return np.asarray(end, float) if not isinstance(end, str) else np.array(blocks[end][:2])

    xs, ys = [], []
    for start, stop, label in wires:
        a = anchor(start, centre(stop))
        b = anchor(stop, centre(start))
        ax.annotate("", xy=b, xytext=a,
                    arrowprops=dict(arrowstyle="-|>", lw=1.0, color="#333333"))
        mid = (a + b) / 2
        ax.text(mid[0], mid[1] + 0.12, label, ha="center", va="bottom", fontsize=7.5,
                color="#7a1f1f")
        xs += [a[0], b[0]]
        ys += [a[1], b[1]]
    for x, y, _ in blocks.values():
        xs.append(x)
        ys.append(y)
    ax.set_xlim(min(xs) - 1.2, max(xs) + 1.2)
    ax.set_ylim(min(ys) - 0.9, max(ys) + 0.9)
    if title:
        ax.set_title(title)
