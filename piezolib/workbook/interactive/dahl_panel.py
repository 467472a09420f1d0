"""The Dahl control of notebook 03 (the Dahl parameters over the model and measured loops).

g_a, alpha1, alpha2, beta2, x0 of the Dahl model over the model and
measured loops (u_c [V] -> v_y [V]).

:func:`dahl_view` is the pure callback, :func:`draw_dahl` the drawing,
:func:`dahl_control` the entry point (a widget, or headless the figure:
:mod:`piezolib.workbook.interactive`).
"""

from dataclasses import dataclass, field, fields, replace

import matplotlib as mpl
import numpy as np

from piezolib.problem import paper
from piezolib._checks import check_integer, check_type
from piezolib.hysteresis.dahl import DahlModel, check_dahl_model, simulate_dahl
from piezolib.workbook.interactive._panel import (LivePanel, apply_unit_text_to, finish,
                                                  import_ipywidgets, linear_slider, log_slider,
                                                  panel_figure, static_figure, want_widget)
from piezolib.workbook.style import PALETTE, STYLE, apply_unit_text

__all__ = ["DAHL_SLIDER_PARAMETERS", "DahlView", "dahl_view", "draw_dahl", "dahl_control"]

#: Parameters of the Dahl model a person can move (beta1 stays 0, gamma_a only
#: scales beta2: only beta2 gamma_a enters H).
DAHL_SLIDER_PARAMETERS = ("g_a", "alpha1", "alpha2", "beta2", "x0")


def _dahl_model(model_params):
    if isinstance(model_params, DahlModel):
        return model_params
    if isinstance(model_params, dict):
        names = {f.name for f in fields(DahlModel)}
        unknown = sorted(set(model_params) - names)
        if unknown:
            raise ValueError(f"model_params has unknown key(s) {unknown}; "
                             f"expected DahlModel fields {sorted(names)}")
        try:
            return DahlModel(**model_params)
        except TypeError as exc:
            raise TypeError(f"model_params: {exc}") from None
    raise TypeError("model_params must be a DahlModel or a dict of its fields, "
                    f"got {type(model_params).__name__}")


def _loop_signals(loop):
    """(v, x, t) of a loop: a StageRecord (u_c [V], v_y [V], t [s]) or a (v, x) pair."""
    if hasattr(loop, "u_c_V") and hasattr(loop, "v_y_V"):
        v, x, t = loop.u_c_V, loop.v_y_V, getattr(loop, "t_s", None)
    elif isinstance(loop, (tuple, list)) and len(loop) == 2:
        (v, x), t = loop, None
    else:
        raise TypeError("loop must be a stage record (u_c_V, v_y_V) or a (v, x) pair of arrays, "
                        f"got {type(loop).__name__}")
    v = np.asarray(v, dtype=float)
    x = np.asarray(x, dtype=float)
    if v.ndim != 1 or v.shape != x.shape or v.size < 8:
        raise ValueError("loop: v and x must be 1-D records of the same length (>= 8 samples), "
                         f"got shapes {v.shape} and {x.shape}")
    if t is None:
        t = np.arange(v.size) * paper.SAMPLE_TIME_S
    return v, x, np.asarray(t, dtype=float)


@dataclass(frozen=True)
class DahlView:
    """A Dahl model against a measured loop (notebook 03).

    Attributes
    ----------
    model : DahlModel
    t : ndarray
        Time [s].
    v : ndarray
        Input u_c [V].
    x : ndarray
        Measured v_y [V].
    x_model : ndarray
        The model's displacement for ``v`` from its ``start`` [V].
    discard : int
        Samples at the start left out of the score (the model still runs through them).
    rms_percent, max_percent : float
        RMS and largest |x_model - x| from ``discard`` on, in % of the measured
        stroke there (the score of :func:`piezolib.hysteresis.fit_dahl`).
    """

    model: DahlModel
    t: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    x_model: np.ndarray = field(repr=False)
    discard: int
    rms_percent: float
    max_percent: float

    @property
    def residual_percent(self):
        """(x_model - x) from ``discard`` on, in % of the stroke."""
        x = self.x[self.discard:]
        return 100 * (self.x_model[self.discard:] - x) / np.ptp(x)


def dahl_view(model_params, loop, *, discard=None):
    """Model loop against measured loop and its RMS error in % of the stroke.

    The callback of :func:`dahl_control`; with the fitted model of
    :func:`piezolib.problem.hysteresis_fits.workbook_dahl_fit` and one of the Case I
    loops it reproduces that fit's ``rms_percent`` for the loop.

    Parameters
    ----------
    model_params : DahlModel or dict
        The model, or its fields as a dict (``beta1`` must be 0).
    loop : StageRecord or (v, x)
        Input u_c [V] and measured output v_y [V], e.g. a record of
        :func:`piezolib.problem.stage_data.load_hysteresis_loops`.
    discard : int, optional
        Samples left out of the score; default one period of the 10 Hz
        triangle of Table 4 at 10 kHz (1000), as in the workbook's fit.

    Returns
    -------
    DahlView

    Raises
    ------
    piezolib.hysteresis.NotInvertibleError
        When the model is too weakly damped for x(v) to be unique.
    """
    model = check_dahl_model(_dahl_model(model_params))
    v, x, t = _loop_signals(loop)
    period = int(round(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"]))
    discard = period if discard is None else check_integer("discard", discard, minimum=0)
    if v.size - discard < 2 or np.ptp(x[discard:]) == 0:
        raise ValueError(f"discard = {discard} leaves no stroke of the loop to score "
                         f"({v.size} samples)")
    x_model = simulate_dahl(model, v).x
    r = x_model[discard:] - x[discard:]
    stroke = float(np.ptp(x[discard:]))
    return DahlView(model=model, t=t, v=v, x=x, x_model=x_model, discard=discard,
                    rms_percent=100 * float(np.sqrt(np.mean(r ** 2))) / stroke,
                    max_percent=100 * float(np.max(np.abs(r))) / stroke)


def _dahl_summary(view):
    m = view.model
    return (f"RMS error {view.rms_percent:.3f} % of stroke (max {view.max_percent:.2f} %);  "
            f"g_a = {m.g_a:.4g} V/V, alpha1 = {m.alpha1:.4g} 1/V, alpha2 = {m.alpha2:.4g} 1/V^2, "
            f"beta2 = {m.beta2:.4g}, x0 = {m.x0:.3g} V")


def draw_dahl(view, fig=None):
    """The measured and model loops (v_y [V] against u_c [V]) and the error [% of stroke] in time.

    Parameters
    ----------
    view : DahlView
    fig : matplotlib.figure.Figure, optional
        Figure to clear and draw into; default a new one, not attached to pyplot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return _DahlPlot(view, fig).figure


class _DahlPlot:
    """The figure of :func:`draw_dahl`, whose model curves, limits and texts follow a new view."""

    def __init__(self, view, fig=None):
        check_type("view", view, DahlView, "a DahlView")
        d = view.discard
        self.discard, self.samples = d, view.v.size
        with mpl.rc_context(STYLE):
            self.figure, (ax_loop, ax_err) = panel_figure(fig, 2, (9.0, 3.8))
            self.axes = (ax_loop, ax_err)
            (self.measured,) = ax_loop.plot(view.v[d:], view.x[d:], color="0.6", lw=0.8,
                                            label="measured")
            (self.model,) = ax_loop.plot(view.v[d:], view.x_model[d:], color=PALETTE.contrast,
                                         lw=1.2, label="Dahl model")
            ax_loop.set_xlabel("u_c (amplifier input) [V]")
            ax_loop.set_ylabel("v_y (sensor) [V]")
            # the loop runs along the diagonal: the upper left corner is empty
            ax_loop.legend(loc="upper left")
            ax_loop.set_title("loops after the first period")
            (self.error,) = ax_err.plot(view.t[d:], view.residual_percent, color=PALETTE.primary,
                                        lw=0.9)
            self.zero = ax_err.axhline(0.0, color="0.4", lw=0.6)
            ax_err.set_xlabel("time [s]")
            ax_err.set_ylabel("model - measured [% of stroke]")
        self.show(view)
        apply_unit_text(self.figure)

    @property
    def moving(self):
        """The artists a new model changes: the curves (the y limits follow them), the y axes,
        the legend and the titles (u_c and t, along x, stay)."""
        ax_loop, ax_err = self.axes
        return [self.measured, self.model, self.error, self.zero,
                *(ax.yaxis for ax in self.axes), ax_loop.get_legend(), ax_err.title,
                self.suptitle]

    def show(self, view):
        """Draw ``view`` into the figure; False for another loop length or discard."""
        check_type("view", view, DahlView, "a DahlView")
        if (view.discard, view.v.size) != (self.discard, self.samples):
            return False
        d = view.discard
        ax_loop, ax_err = self.axes
        self.measured.set_data(view.v[d:], view.x[d:])
        self.model.set_data(view.v[d:], view.x_model[d:])
        self.error.set_data(view.t[d:], view.residual_percent)
        for ax in self.axes:
            ax.relim()
            ax.autoscale_view()
        m = view.model
        with mpl.rc_context(STYLE):
            ax_err.set_title(f"RMS {view.rms_percent:.3f} %, max {view.max_percent:.2f} % "
                             "of stroke")
            self.suptitle = self.figure.suptitle(
                f"Dahl model ({m.form} form, start: {m.start})\ng_a = {m.g_a:.4g} V/V, "
                f"alpha1 = {m.alpha1:.4g} 1/V, alpha2 = {m.alpha2:.4g} 1/V^2, "
                f"beta2 = {m.beta2:.4g}, x0 = {m.x0:.3g} V")
        apply_unit_text_to(self.moving)
        return True


def dahl_control(model, loop, *, discard=None, interactive=None):
    """Sliders for the Dahl parameters around ``model`` over the model and measured loops.

    Parameters
    ----------
    model : DahlModel
        Starting model, e.g. ``workbook_dahl_fit().model``: the sliders span
        g_a +-25 %, alpha1 and alpha2 one decade each way, beta2 from 0 to
        twice its value, x0 +-0.5 V around it.
    loop : StageRecord or (v, x)
        Measured loop (u_c [V], v_y [V]), e.g. one of
        :func:`piezolib.problem.stage_data.load_hysteresis_loops`.
    discard : int, optional
        As in :func:`dahl_view`.
    interactive : bool, optional
        Force the widget (True) or the static figure (False); default
        :func:`interactive_available`.

    Returns
    -------
    ipywidgets.VBox or matplotlib.figure.Figure
        The widget (``box.controls`` holds the five sliders); headless the
        figure of :func:`draw_dahl` for ``model``.
    """
    model = check_dahl_model(model)
    if not want_widget(interactive):
        return static_figure(draw_dahl(dahl_view(model, loop, discard=discard)))
    w = import_ipywidgets()
    b2 = model.beta2
    sliders = {
        "g_a": linear_slider(w, "g_a", model.g_a, 0.75 * model.g_a, 1.25 * model.g_a,
                             model.g_a / 400, description="g_a [V/V]"),
        "alpha1": log_slider(w, "alpha1", model.alpha1, description="alpha1 [1/V]"),
        "alpha2": log_slider(w, "alpha2", model.alpha2, description="alpha2 [1/V^2]"),
        "beta2": linear_slider(w, "beta2", b2, min(0.0, 2 * b2), max(0.0, 2 * b2),
                               max(abs(b2), 1e-3) / 200),
        "x0": linear_slider(w, "x0", model.x0, model.x0 - 0.5, model.x0 + 0.5, 0.005,
                            description="x0 [V]"),
    }
    panel = LivePanel(w, sliders,
                      lambda values: dahl_view(replace(model, **values), loop, discard=discard),
                      _DahlPlot, _dahl_summary)
    return finish(panel, panel.box())
