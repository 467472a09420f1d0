"""Interactive controls for the notebooks, and the plain callbacks behind them.

Three controls, one entry point each, every one taking its models explicitly:

* :func:`weight_design_control` (notebook 04, :mod:`.weight_panel`): M_e,
  eps_e, omega_e [rad/s], M_y, eps_y, omega_y [rad/s] of eq. 15 over |S|,
  |T| and the NP / RS / RP peaks; a button re-designs the mu controller for
  the weights.
* :func:`spread_control` (notebook 02, :mod:`.spread_panel`): the +- spread
  of the denominator coefficients over the relative-error envelope and its
  covering weight.
* :func:`dahl_control` (notebook 03, :mod:`.dahl_panel`): g_a, alpha1,
  alpha2, beta2, x0 of the Dahl model over the model and measured loops
  (u_c [V] -> v_y [V]).

Each control is a thin layer over a pure callback that computes a small
result object (:func:`weight_design_view`, :func:`spread_view`,
:func:`dahl_view`, and :func:`redesign`) and a drawing function
(:func:`draw_weight_design`, :func:`draw_spread`, :func:`draw_dahl`); the
callbacks are what the tests exercise.  The plumbing the three share
(widget or figure, sliders, the live panel) is in the private ``_panel``.

Headless degradation
--------------------
A widget needs a live frontend to render it: executed headless (nbclient,
nbval, ``python -m piezolib reproduce``) it would leave nothing but a
``VBox(...)`` text in the notebook.  An IPython kernel runs in both cases, and
nothing the kernel sees tells them apart reliably, so the headless runners say
so: with the environment variable ``PIEZOLIB_STATIC=1`` (see
:func:`interactive_available`) every entry point draws the figure for its
default parameters and returns that :class:`matplotlib.figure.Figure`
instead of the widget.  Figures are not attached to pyplot, so a cell whose
last expression is the entry point shows the widget or the figure exactly once.
"""

from piezolib.workbook.interactive._panel import STATIC_ENV, interactive_available
from piezolib.workbook.interactive.dahl_panel import (DAHL_SLIDER_PARAMETERS, DahlView,
                                                      dahl_control, dahl_view, draw_dahl)
from piezolib.workbook.interactive.spread_panel import (SpreadView, draw_spread, spread_control,
                                                        spread_view)
from piezolib.workbook.interactive.weight_panel import (WEIGHT_PARAMETERS, Redesign,
                                                        WeightDesignView, draw_weight_design,
                                                        redesign, weight_design_control,
                                                        weight_design_view)

__all__ = [
    "STATIC_ENV", "interactive_available",
    "WEIGHT_PARAMETERS", "WeightDesignView", "weight_design_view", "draw_weight_design",
    "Redesign", "redesign", "weight_design_control",
    "SpreadView", "spread_view", "draw_spread", "spread_control",
    "DAHL_SLIDER_PARAMETERS", "DahlView", "dahl_view", "draw_dahl", "dahl_control",
]
