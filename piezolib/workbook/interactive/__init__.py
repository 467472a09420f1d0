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
(widget or figure, sliders, the live panel) is in the private ``_panel``;
:class:`LatestOnly` (:mod:`.coalesce`) draws only a slider's latest value, off
the kernel's thread, so that the figure follows the hand.

Headless degradation
--------------------
A widget needs a live frontend to render it: executed headless (nbclient,
papermill, ``jupyter nbconvert --execute``, nbval, ``python -m piezolib
reproduce``) it would leave a widget view that shows nothing when the saved
notebook or its HTML is read, and a ``VBox(...)`` text.  An IPython kernel
runs in both cases; what tells them apart is the request that runs the cell:
JupyterLab and Notebook 7 name the cell in it (``cellId``), the headless
clients do not (:func:`interactive_available`).  Without a frontend every
entry point draws the figure for its default parameters and returns that
:class:`matplotlib.figure.Figure` instead of the widget; no setting is
needed.  ``PIEZOLIB_STATIC=1`` forces the figure everywhere.

Where the widget is shown, its output also carries the current figure as
``image/png`` and a summary as ``text/plain``: a notebook saved from
JupyterLab without widget state, and nbconvert's HTML of it (which skips a
widget view without state), show the figure instead of nothing.  Figures
are not attached to pyplot, so a cell whose last expression is the entry
point shows the widget or the figure exactly once.
"""

from piezolib.workbook.interactive._panel import STATIC_ENV, interactive_available
from piezolib.workbook.interactive.coalesce import LatestOnly
from piezolib.workbook.interactive.dahl_panel import (DAHL_SLIDER_PARAMETERS, DahlView,
                                                      dahl_control, dahl_view, draw_dahl)
from piezolib.workbook.interactive.spread_panel import (SpreadView, draw_spread, spread_control,
                                                        spread_view, spread_view_from)
from piezolib.workbook.interactive.weight_panel import (WEIGHT_PARAMETERS, Redesign,
                                                        WeightDesignView, draw_weight_design,
                                                        redesign, weight_design_control,
                                                        weight_design_view)

__all__ = [
    "STATIC_ENV", "interactive_available", "LatestOnly",
    "WEIGHT_PARAMETERS", "WeightDesignView", "weight_design_view", "draw_weight_design",
    "Redesign", "redesign", "weight_design_control",
    "SpreadView", "spread_view", "spread_view_from", "draw_spread", "spread_control",
    "DAHL_SLIDER_PARAMETERS", "DahlView", "dahl_view", "draw_dahl", "dahl_control",
]
