"""One figure style for the workbook: rcParams, named colours, the units rule, magnitude plots.

Units rule
----------
Figure functions write plain ASCII (``"x [um]"``, ``"mu_RP"``, ``"omega_e"``,
``"+-5 %"``); :func:`piezolib.workbook.plotting.save_figure` passes every text
of the figure through :func:`unit_text` once (by :func:`apply_unit_text`), so
that every saved figure spells micrometres ``µm``, the structured singular
value ``μ``, angular frequency ``ω`` and ``±`` the same way.  Frequencies are
in rad/s (models, grids) or Hz (trajectories), voltages in V, times in s or
ms, as in the units table of :mod:`piezolib.problem.paper`.

Colours
-------
:data:`PALETTE` names every colour the workbook's figures use besides greys:
figure functions say what a curve is (``PALETTE.contrast``), never which hex
value it has, and :data:`STYLE`'s colour cycle is made of the same colours.
"""

import re
from dataclasses import dataclass

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np

from piezolib._checks import check_finite_array, check_integer, check_type

__all__ = ["Palette", "PALETTE", "STYLE", "use_style", "new_figure", "unit_text",
           "apply_unit_text", "db", "plot_magnitude"]


@dataclass(frozen=True)
class Palette:
    """The workbook's named colours (hex strings), each named for what it shows.

    Attributes
    ----------
    primary : str
        Dark blue, the first curve of a figure: the result a figure is about
        (a fitted weight, a model's error), construction lines, the outlines
        of diagram blocks.
    contrast : str
        Brick red, the second curve: what the first is set against (a model
        over a measured loop, the published weight, the other Dahl form) and
        a verdict that differs.
    agreement : str
        Green, the third curve: a verdict that agrees, the range the paper
        reports (Table 4's Case I band).
    highlight : str
        Amber: one marked point or a reference weight beside the first two.
    fourth, sixth, seventh : str
        Violet, cyan and grey: further curves of the colour cycle.
    peer : str
        Matplotlib's blue, lighter than ``primary``: the first of several
        models or records compared on equal terms (see :attr:`peers`).
    measured : str
        Light blue: a measured trace drawn wide under its simulation.
    signal : str
        Dark red: a simulated trace over the measured one, and the names of
        the signals on a block diagram's wires.
    wire : str
        Near-black: a block diagram's wires, arrow heads and signs.
    box_fill : str
        Pale blue: the inside of a block diagram's boxes.

    Examples
    --------
    >>> PALETTE.primary, PALETTE.contrast
    ('#1f4e79', '#c0504d')
    >>> len(PALETTE.cycle), PALETTE.peers[0]
    (7, '#1f77b4')
    """

    primary: str = "#1f4e79"
    contrast: str = "#c0504d"
    agreement: str = "#4f8f3a"
    highlight: str = "#d08a00"
    fourth: str = "#8064a2"
    sixth: str = "#4bacc6"
    seventh: str = "#7f7f7f"
    peer: str = "#1f77b4"
    measured: str = "#7fa7cf"
    signal: str = "#7a1f1f"
    wire: str = "#333333"
    box_fill: str = "#eef3f8"

    @property
    def cycle(self):
        """The colours of successive curves (:data:`STYLE`'s ``axes.prop_cycle``)."""
        return (self.primary, self.contrast, self.agreement, self.fourth, self.highlight,
                self.sixth, self.seventh)

    @property
    def peers(self):
        """Colours of up to four models or records compared on equal terms."""
        return (self.peer, self.contrast, self.agreement, self.fourth)


#: The workbook's colours by meaning.
PALETTE = Palette()

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
    "axes.prop_cycle": mpl.cycler(color=list(PALETTE.cycle)),
    # no timestamps or version strings in the files: reruns give identical PNGs
    "svg.hashsalt": "piezolib",
}

#: The units rule: (pattern, replacement) applied in order by :func:`unit_text`.
_UNIT_RULES = [
    (re.compile(r"(?<![A-Za-z\\])um(?![A-Za-z])"), "µm"),        # 3 um/V, [um], nm stays
    (re.compile(r"(?<![A-Za-z\\])mu(?![A-Za-z])"), "μ"),               # mu, mu_RP, mu(M)
    (re.compile(r"(?<![A-Za-z\\])omega(?![A-Za-z])"), "ω"),
    (re.compile(r"(?<![A-Za-z\\])Delta(?![A-Za-z])"), "Δ"),
    (re.compile(r"\+-"), "±"),
    (re.compile(r"<="), "≤"),
    (re.compile(r">="), "≥"),
    (re.compile(r" -> "), " → "),
]


def use_style():
    """Apply :data:`STYLE` to matplotlib's global rcParams.

    Examples
    --------
    >>> import matplotlib as mpl
    >>> with mpl.rc_context():                  # restores the rcParams afterwards
    ...     use_style()
    ...     mpl.rcParams["savefig.dpi"], mpl.rcParams["axes.grid"]
    (150.0, True)
    """
    mpl.rcParams.update(STYLE)


def new_figure(nrows=1, ncols=1, **kwargs):
    """``plt.subplots`` in the workbook style (``constrained`` layout).

    Examples
    --------
    >>> import matplotlib as mpl
    >>> with mpl.rc_context():
    ...     fig, axes = new_figure(2, 1, sharex=True)
    ...     print(len(axes), fig.get_layout_engine().__class__.__name__)
    2 ConstrainedLayoutEngine
    >>> plt.close(fig)
    """
    nrows = check_integer("nrows", nrows, minimum=1)
    ncols = check_integer("ncols", ncols, minimum=1)
    use_style()
    kwargs.setdefault("layout", "constrained")
    return plt.subplots(nrows, ncols, **kwargs)


def unit_text(text):
    """Spell units and symbols of a plain-ASCII label the workbook's way.

    Parameters
    ----------
    text : str
        E.g. ``"x = 3 um/V * v_y [um]"``.

    Returns
    -------
    str
        ``um`` -> ``µm``, ``mu`` -> ``μ``, ``omega`` -> ``ω``, ``Delta`` ->
        ``Δ``, ``+-`` -> ``±``, ``<=`` -> ``≤``, ``>=`` -> ``≥``, `` -> `` ->
        `` → ``; words containing these
        letters (``maximum``, ``sum``, ``mu-law``) are left alone, and so is
        any text holding mathtext (``$``).

    Examples
    --------
    >>> unit_text("x [um], mu_RP at omega = 1 rad/s, +-5 %")
    'x [µm], μ_RP at ω = 1 rad/s, ±5 %'
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be a str, got {type(text).__name__}")
    if "$" in text:
        return text
    for pattern, replacement in _UNIT_RULES:
        text = pattern.sub(replacement, text)
    return text


def apply_unit_text(fig):
    """Apply :func:`unit_text` to every text of ``fig`` (in place) and return ``fig``.

    Examples
    --------
    >>> fig, ax = plt.subplots()
    >>> _ = ax.set_xlabel("omega [rad/s]"); _ = ax.set_ylabel("x [um]")
    >>> apply_unit_text(fig) is fig, ax.get_xlabel(), ax.get_ylabel()
    (True, 'ω [rad/s]', 'x [µm]')
    >>> plt.close(fig)
    """
    check_type("fig", fig, mpl.figure.Figure, "a matplotlib Figure")
    for text in fig.findobj(mpl.text.Text):
        old = text.get_text()
        new = unit_text(old)
        if new != old:
            text.set_text(new)
    return fig


def db(x):
    """Magnitude in decibels, 20 log10 |x| (-inf for 0; NaN and inf pass through).

    Examples
    --------
    >>> db([1.0, 10.0, 0.5]).round(2).tolist()
    [0.0, 20.0, -6.02]
    """
    x = np.asarray(x)
    if not np.issubdtype(x.dtype, np.number):
        raise TypeError(f"x must be numeric, got dtype {x.dtype}")
    with np.errstate(divide="ignore"):
        return 20 * np.log10(np.abs(x))


def plot_magnitude(ax, omega, response, label=None, **kwargs):
    """Plot |response| in dB against omega [rad/s] on a log axis.

    Examples
    --------
    >>> import numpy as np
    >>> fig, ax = plt.subplots()
    >>> omega = np.logspace(0, 3, 50)
    >>> line = plot_magnitude(ax, omega, 1 / (1 + 1j * omega / 10), label="low-pass")
    >>> ax.get_xscale(), ax.get_ylabel(), line.get_label()
    ('log', 'magnitude [dB]', 'low-pass')
    >>> plt.close(fig)
    """
    check_type("ax", ax, mpl.axes.Axes, "a matplotlib Axes")
    omega = check_finite_array("omega", omega, ndim=1, min_length=1, real=True)
    if np.any(omega <= 0):
        raise ValueError("omega must be positive frequencies [rad/s] (a log axis)")
    response = np.asarray(response)
    if response.shape != omega.shape:
        raise ValueError(f"response must have the shape of omega {omega.shape}, "
                         f"got {response.shape}")
    line, = ax.semilogx(omega, db(response), label=label, **kwargs)
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("magnitude [dB]")
    return line
