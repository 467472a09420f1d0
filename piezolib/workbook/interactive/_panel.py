"""Plumbing the interactive controls share (private to :mod:`piezolib.workbook.interactive`).

Whether a control shows a live widget or a static figure
(:func:`interactive_available`, :func:`want_widget`, :func:`static_figure`),
pyplot-free figures and their PNG bytes, and :class:`LivePanel`, which ties
sliders to a callback, a drawing function and a summary line.  Each panel
module builds its control from these; nothing outside the package imports them.
"""

import html
import importlib.util
import io
import os
import sys

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from piezolib.workbook.style import db, unit_text

__all__ = ["STATIC_ENV", "interactive_available", "ipython_shell", "static_figure", "want_widget",
           "import_ipywidgets", "panel_figure", "png_bytes", "magnitude", "curve_db", "LivePanel",
           "log_slider", "linear_slider", "finish"]

#: Environment variable that makes every entry point draw its static figure
#: ("1", "true", "yes" or "on"; "0", "false", "no", "off" or unset leave the choice to
#: :func:`interactive_available`).
STATIC_ENV = "PIEZOLIB_STATIC"
_FALSE_WORDS = ("", "0", "false", "no", "off")


# --------------------------------------------------------------------------- headless or not
def interactive_available():
    """True when a control can show a live widget, False when it should draw a static figure.

    All of these must hold:

    * ``PIEZOLIB_STATIC`` is unset or false ("0", "false", "no", "off").
      Headless runners set it to "1": under nbclient or nbval an IPython
      kernel runs just as under JupyterLab, with no frontend to render widgets.
    * ipywidgets is importable.
    * the code runs in an IPython kernel (a shell with a ``kernel``): plain
      Python and terminal IPython have no widget frontend.

    Returns
    -------
    bool
    """
    if os.environ.get(STATIC_ENV, "").strip().lower() not in _FALSE_WORDS:
        return False
    if importlib.util.find_spec("ipywidgets") is None:
        return False
    # IPython is loaded in every kernel; if it is not, no frontend can exist either
    shell = ipython_shell()
    return shell is not None and getattr(shell, "kernel", None) is not None


def ipython_shell():
    """The running IPython shell, or None (IPython is not imported unless it already is)."""
    ipython = sys.modules.get("IPython")
    return ipython.get_ipython() if ipython is not None else None


def static_figure(fig):
    """Return ``fig``, made to show as a PNG when it is a notebook cell's value.

    IPython learns to show figures as PNG only once a pyplot backend is
    resolved (inline) or never (``MPLBACKEND=Agg`` under the headless
    runners); without it the static figure of a control would show as
    ``<Figure size ...>``.  A formatter already registered is left alone.
    """
    shell = ipython_shell()
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", None)
    if formatters and "image/png" in formatters:
        png = formatters["image/png"]
        try:
            png.lookup_by_type(Figure)
        except KeyError:
            png.for_type(Figure, png_bytes)
    return fig


def want_widget(interactive):
    """Whether an entry point shows its widget: ``interactive`` (True, False), or when None
    :func:`interactive_available`."""
    if interactive is None:
        return interactive_available()
    if not isinstance(interactive, bool):
        raise TypeError(f"interactive must be True, False or None, got {interactive!r}")
    return interactive


def import_ipywidgets():
    """The ipywidgets module, or an ImportError that says how to install it."""
    try:
        import ipywidgets
    except ImportError as exc:
        raise ImportError("interactive controls need ipywidgets "
                          "(pip install -r environment.txt)") from exc
    return ipywidgets


# --------------------------------------------------------------------------- figures
def panel_figure(fig, ncols, figsize):
    """A pyplot-free figure with ``ncols`` axes (``fig`` cleared and reused if given).

    Pyplot would show its figures once more at the end of the cell, beside the
    figure or widget the entry point returns.
    """
    if fig is None:
        fig = Figure(figsize=figsize, layout="constrained")
        FigureCanvasAgg(fig)    # a canvas that renders (text extents, PNG) without a GUI
    elif not isinstance(fig, Figure):
        raise TypeError(f"fig must be a matplotlib Figure or None, got {type(fig).__name__}")
    else:
        fig.clear()
    axes = fig.subplots(1, ncols, squeeze=False)[0]
    return fig, axes


def png_bytes(fig):
    """PNG bytes of ``fig``: shown in an Image widget, whatever matplotlib backend is active."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=fig.dpi, metadata={"Software": None})
    return buffer.getvalue()


def magnitude(sys_, omega):
    """|sys_(j omega)| of a SISO system on the grid ``omega`` [rad/s], as a 1-D array."""
    return np.abs(np.ravel(sys_(1j * omega)))


def curve_db(x):
    """:func:`piezolib.workbook.style.db` of a curve, -inf where it is 0 (no warning)."""
    with np.errstate(divide="ignore"):
        return db(x)


# --------------------------------------------------------------------------- widgets
class LivePanel:
    """Sliders -> callback -> figure (as a PNG in an Image widget) and a summary line.

    The figure is rendered to PNG here rather than displayed through the
    matplotlib backend, so the control looks the same under the inline and
    any other backend, and a redraw replaces the image in place.
    """

    def __init__(self, widgets, sliders, compute, draw, describe):
        self.widgets = widgets
        self.sliders = sliders
        self.compute, self.draw, self.describe = compute, draw, describe
        self.image = widgets.Image(format="png", layout=widgets.Layout(max_width="100%"))
        self.summary = widgets.HTML()
        self.status = widgets.HTML()
        self.view = None
        self.figure = None
        for slider in sliders.values():
            slider.observe(self.refresh, names="value")

    def values(self):
        """{name: value} of the sliders (weights in rad/s, spread in %, Dahl parameters)."""
        return {name: float(slider.value) for name, slider in self.sliders.items()}

    def refresh(self, change=None):
        """Recompute and redraw for the sliders' values (every slider's observer)."""
        self.status.value = "<i>computing ...</i>"
        try:
            view = self.compute(self.values())
        # a widget callback's exception only reaches the kernel log, which nobody
        # watches: say what went wrong under the figure and keep the last one
        except Exception as exc:        # noqa: BLE001
            self.status.value = (f"<b>not updated</b> ({type(exc).__name__}): "
                                 f"{html.escape(str(exc))}")
            return
        self.view = view
        self.figure = self.draw(view, fig=self.figure)
        self.image.value = png_bytes(self.figure)
        self.summary.value = html.escape(unit_text(self.describe(view)))
        self.status.value = ""

    def box(self, extra=()):
        """The VBox: sliders, extra rows, summary, status, figure."""
        w = self.widgets
        return w.VBox([w.HBox(list(self.sliders.values())[i:i + 3])
                       for i in range(0, len(self.sliders), 3)]
                      + list(extra) + [self.summary, self.status, self.image])


def log_slider(widgets, name, value, decades=1.0, description=None):
    """A log slider around ``value`` (whole decades, at least ``decades`` each way)."""
    exponent = np.log10(value)
    return widgets.FloatLogSlider(
        value=value, base=10, min=float(np.floor(exponent - decades)),
        max=float(np.ceil(exponent + decades)), step=0.02, description=description or name,
        continuous_update=False, readout_format=".3g", style={"description_width": "initial"})


def linear_slider(widgets, name, value, low, high, step, description=None):
    """A linear slider from ``low`` to ``high`` (widened to hold ``value``)."""
    return widgets.FloatSlider(
        value=value, min=min(low, value), max=max(high, value), step=step,
        description=description or name, continuous_update=False, readout_format=".4g",
        style={"description_width": "initial"})


def finish(panel, box):
    """Attach the panel's parts to the box for programmatic use, draw the first figure."""
    box.controls = dict(panel.sliders)
    box.panel = panel
    panel.refresh()
    return box
