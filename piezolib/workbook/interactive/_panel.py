"""Plumbing the interactive controls share (private to :mod:`piezolib.workbook.interactive`).

Whether a control shows a live widget or a static figure
(:func:`interactive_available`, :func:`want_widget`, :func:`static_figure`),
pyplot-free figures and their PNG bytes, and :class:`LivePanel`, which ties
sliders to a callback, a plot and a summary line, in a box whose saved form
is the current figure (:func:`panel_box`); it draws only the latest values,
off the kernel's thread (:class:`~piezolib.workbook.interactive.LatestOnly`),
by repainting the artists that change.  Each panel module
builds its control from these; nothing outside the package imports them.
"""

import base64
import functools
import html
import importlib.util
import io
import os

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from PIL import Image

from piezolib import notebook_display
from piezolib.notebook_display import ipython_shell
from piezolib.workbook.interactive.coalesce import LatestOnly
from piezolib.workbook.style import db, unit_text

__all__ = ["STATIC_ENV", "interactive_available", "static_figure", "want_widget",
           "import_ipywidgets", "panel_figure", "png_bytes", "magnitude", "curve_db",
           "apply_unit_text_to", "REST_S", "LivePanel", "complete_view", "redrawn", "panel_box", "log_slider",
           "linear_slider", "finish"]

#: MIME type of a widget view in a notebook output.
WIDGET_VIEW_MIME = "application/vnd.jupyter.widget-view+json"

#: Environment variable that makes every entry point draw its static figure
#: ("1", "true", "yes" or "on"; "0", "false", "no", "off" or unset leave the choice to
#: :func:`interactive_available`).
STATIC_ENV = "PIEZOLIB_STATIC"
_FALSE_WORDS = ("", "0", "false", "no", "off")


# --------------------------------------------------------------------------- headless or not
def interactive_available():
    """True when a control can show a live widget, False when it should draw a static figure.

    All of these must hold:

    * ``PIEZOLIB_STATIC`` is unset or false ("0", "false", "no", "off");
      "1" forces the static figure everywhere.
    * ipywidgets is importable.
    * the code runs in an IPython kernel (a shell with a ``kernel``): plain
      Python and terminal IPython have no widget frontend.
    * the cell was sent by an interactive frontend: JupyterLab and Notebook
      7 name the cell in each execute request (``cellId``,
      :func:`piezolib.notebook_display.frontend_cell_id`).  The headless
      clients (nbclient, papermill, ``jupyter nbconvert --execute``, nbval)
      do not, and a widget they saved would show nothing when the notebook
      or its HTML is read later; they get the figure, with no setting.

    Returns
    -------
    bool
    """
    if os.environ.get(STATIC_ENV, "").strip().lower() not in _FALSE_WORDS:
        return False
    if importlib.util.find_spec("ipywidgets") is None:
        return False
    # IPython is loaded in every kernel; if it is not, no frontend can exist either
    return notebook_display.in_kernel() and notebook_display.frontend_cell_id() is not None


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
        fig.set_layout_engine("constrained")    # a live panel freezes the layout it drew
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


def apply_unit_text_to(artists):
    """:func:`piezolib.workbook.style.unit_text` on every text of ``artists`` (in place): what
    :func:`~piezolib.workbook.style.apply_unit_text` does to a figure, for the parts a frame
    changes."""
    for artist in artists:
        for text in artist.findobj(Text):
            old = text.get_text()
            new = unit_text(old)
            if new != old:
                text.set_text(new)


#: Seconds without a new value before a live panel computes the slow stage of a view.
REST_S = 0.3


# --------------------------------------------------------------------------- widgets
class LivePanel:
    """Sliders -> callback -> figure (as a PNG in an Image widget) and a summary line.

    The figure is rendered to PNG here rather than displayed through the
    matplotlib backend, so the control looks the same under the inline and
    any other backend, and a redraw replaces the image in place.

    A slider's change only records its value (:class:`LatestOnly`): one
    worker thread computes and draws the latest values when it is free, so
    a burst of key presses costs one or two frames, not one per press.  A
    frame repaints only the plot's moving artists over a picture of the rest
    taken once (blitting), and a callback in stages (a quick view, then the
    complete one) has each drawn in turn, unless a newer value is waiting by
    then; a later stage starts once no new value has come for :data:`REST_S`
    (while the keys are pressed the quick view follows them, and the slow one
    is not computed for values already left).

    Parameters
    ----------
    widgets : module
        ipywidgets.
    sliders : dict
        {name: slider}; their values go to ``compute`` as {name: float}.
    compute : callable
        ``compute(values)`` returns a view, or a list of stages, functions
        that make the next view from the one before (the first gets None):
        a quick view first, the complete one last (:func:`complete_view`).
    plot : callable
        ``plot(view, fig)`` returns a plot of ``view`` drawn into ``fig``
        (None: a new figure), an object with ``figure``, ``moving`` (the
        artists a new view changes) and ``show(view)`` (update them; False
        when the view needs a new plot); :func:`redrawn` makes one of a
        drawing function.
    describe : callable
        ``describe(view)``: the summary line (plain text).
    """

    def __init__(self, widgets, sliders, compute, plot, describe):
        self.widgets = widgets
        self.sliders = sliders
        self.compute, self.make_plot, self.describe = compute, plot, describe
        self.image = widgets.Image(format="png", layout=widgets.Layout(max_width="100%"))
        self.summary = widgets.HTML()
        self.status = widgets.HTML()
        self.view = None
        self.plot = None
        self.png = None
        self.frames = 0
        self._background = None
        self.rest_s = REST_S
        self.worker = LatestOnly(self._render)
        for slider in sliders.values():
            slider.observe(self.refresh, names="value")

    @property
    def figure(self):
        """The figure shown (None before the first frame)."""
        return None if self.plot is None else self.plot.figure

    def values(self):
        """{name: value} of the sliders (weights in rad/s, spread in %, Dahl parameters)."""
        return {name: float(slider.value) for name, slider in self.sliders.items()}

    def refresh(self, change=None, *, then=None):
        """Draw the sliders' values soon (every slider's observer); returns at once.

        ``then()`` is called once the figure for these values (or later ones) is shown.
        """
        self.status.value = "<i>computing ...</i>"
        self.worker.submit(self.values(), then=then)

    def wait(self, timeout=None):
        """Block until the figure shows the latest values; False if not within ``timeout`` [s]."""
        return self.worker.wait(timeout)

    def draw_now(self):
        """Compute and draw the sliders' values in this thread (the first figure)."""
        self._render(self.values(), lambda within=0.0: False)

    def _render(self, values, superseded):
        try:
            result = self.compute(values)
            stages = result if isinstance(result, list) else [lambda _: result]
            view = None
            for k, stage in enumerate(stages):
                # a later stage is the slow one: it starts once the slider rests
                if k and superseded(within=self.rest_s):
                    return
                view = stage(view)
                if superseded():
                    return
                self._show(view)
        # a widget callback's exception only reaches the kernel log, which nobody
        # watches: say what went wrong under the figure and keep the last one
        except Exception as exc:        # noqa: BLE001
            self.status.value = (f"<b>not updated</b> ({type(exc).__name__}): "
                                 f"{html.escape(str(exc))}")
            return
        if not superseded():
            self.status.value = ""

    def _show(self, view):
        if self.plot is None or not self.plot.show(view):
            self.plot = self.make_plot(view, self.figure)
            self._background = None
        png = self._frame()
        self.view, self.png = view, png
        self.image.value = png
        self.summary.value = html.escape(unit_text(self.describe(view)))
        self.frames += 1

    def _frame(self):
        """PNG of the plot: the moving artists painted over the cached rest of the figure."""
        fig = self.plot.figure
        canvas = fig.canvas
        moving = sorted(self.plot.moving, key=lambda artist: artist.get_zorder())
        if self._background is None:
            canvas.draw()                   # the layout settles with every artist in place
            fig.set_layout_engine("none")   # and stays: a frame changes the moving artists only
            for artist in moving:
                artist.set_animated(True)
            try:
                canvas.draw()
            finally:
                for artist in moving:
                    artist.set_animated(False)
            self._background = canvas.copy_from_bbox(fig.bbox)
        canvas.restore_region(self._background)
        for artist in moving:
            fig.draw_artist(artist)
        buffer = io.BytesIO()
        # level 1: a fifth of the encoding time of the default for 2 % more bytes
        Image.fromarray(np.asarray(canvas.buffer_rgba())).save(buffer, format="png",
                                                               compress_level=1)
        return buffer.getvalue()

    def box(self, extra=()):
        """The box (:func:`panel_box`): sliders, extra rows, summary, status, figure."""
        w = self.widgets
        return panel_box(w, [w.HBox(list(self.sliders.values())[i:i + 3])
                             for i in range(0, len(self.sliders), 3)]
                         + list(extra) + [self.summary, self.status, self.image], self)

    def mime_bundle(self, bundle):
        """``bundle`` (a widget's view) with the figure shown as image/png and the summary
        as text/plain: what a reader sees where the widget cannot be drawn."""
        bundle = dict(bundle)
        if self.png is not None:
            bundle["image/png"] = base64.b64encode(self.png).decode("ascii")
        summary = html.unescape(self.summary.value) or "no figure drawn yet"
        bundle["text/plain"] = f"interactive control (figure for the values shown): {summary}"
        return bundle


def complete_view(stages):
    """The last view of a :class:`LivePanel` callback's ``stages`` (each run in turn)."""
    view = None
    for stage in stages:
        view = stage(view)
    return view


class _Redrawn:
    """The plot of a drawing function: every view is drawn again in full."""

    moving = ()

    def __init__(self, draw, view, fig):
        self.figure = draw(view, fig=fig)

    def show(self, view):
        return False


def redrawn(draw):
    """A :class:`LivePanel` ``plot`` of ``draw(view, fig=None) -> Figure`` (no blitting)."""
    return functools.partial(_Redrawn, draw)


@functools.cache
def _panel_box_class(widgets):
    """A VBox class whose output also carries its panel's figure (made once per ipywidgets)."""

    class PanelBox(widgets.VBox):
        """A control's VBox; its output holds the widget view, the figure (image/png) and the
        summary (text/plain), so a notebook saved without widget state (or its HTML, which
        skips a view without state) still shows the figure, never the ``VBox(...)`` repr."""

        def _repr_mimebundle_(self, **kwargs):
            bundle = super()._repr_mimebundle_(**kwargs)
            panel = getattr(self, "panel", None)
            return bundle if panel is None else panel.mime_bundle(bundle)

    return PanelBox


def panel_box(widgets, children, panel):
    """A VBox of ``children`` displayed with the figure of ``panel`` as its static fallback.

    Parameters
    ----------
    widgets : module
        ipywidgets.
    children : list of ipywidgets.Widget
    panel : LivePanel
        Its figure and summary are the fallback (read when the box is displayed).

    Returns
    -------
    ipywidgets.VBox
        With ``box.panel = panel``.
    """
    box = _panel_box_class(widgets)(children)
    box.panel = panel
    return box


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
    """Attach the panel's parts to the box for programmatic use, draw the first figure
    (in this thread: the box is shown, and saved, with it)."""
    box.controls = dict(panel.sliders)
    box.panel = panel
    panel.draw_now()
    return box
