"""The weight-design control of notebook 04 (eq. 15 weights over |S|, |T| and the peaks).

M_e, eps_e, omega_e [rad/s], M_y, eps_y, omega_y [rad/s] of eq. 15 over
|S|, |T| and the NP / RS / RP peaks; a button re-designs the mu controller
for the weights.

:func:`weight_design_view` and :func:`redesign` are the pure callbacks,
:func:`draw_weight_design` the drawing, :func:`weight_design_control` the
entry point (a widget, or headless the figure: :mod:`piezolib.workbook.interactive`).
"""

import html
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import control as ct
import matplotlib as mpl
import numpy as np

from piezolib import progress
from piezolib.problem import paper
from piezolib._checks import check_frequency_grid, check_positive, check_siso, check_type
from piezolib.problem.analysis import RobustnessAnalysis, analyze, robust_performance_peak
from piezolib.problem.design import design_controller
from piezolib.robust.lti import frequency_grid, loop_functions
from piezolib.workbook.interactive._panel import (LivePanel, apply_unit_text_to, curve_db, finish,
                                                  import_ipywidgets, linear_slider, log_slider,
                                                  magnitude, panel_figure, static_figure,
                                                  want_widget)
from piezolib.workbook.style import STYLE, apply_unit_text, unit_text

__all__ = ["WEIGHT_PARAMETERS", "WeightDesignView", "weight_design_view", "draw_weight_design",
           "Redesign", "redesign", "weight_design_control"]

#: The six parameters of eq. 15, in slider order (frequencies in rad/s).
WEIGHT_PARAMETERS = ("M_e", "eps_e", "omega_e", "M_y", "eps_y", "omega_y")

#: Default grid [rad/s] of the |S|, |T| and template curves.
_WEIGHT_GRID = (1e0, 1e7, 1500)


def _weight_parameters(params):
    """The six weight parameters as a dict of positive floats (None: the published ones)."""
    if params is None:
        return {name: float(getattr(paper.ERROR_WEIGHT if name.endswith("_e")
                                    else paper.OUTPUT_WEIGHT, name))
                for name in WEIGHT_PARAMETERS}
    if isinstance(params, dict):
        missing = [n for n in WEIGHT_PARAMETERS if n not in params]
        unknown = sorted(set(params) - set(WEIGHT_PARAMETERS))
        if unknown:
            raise ValueError(f"params has unknown key(s) {unknown}; "
                             f"expected {list(WEIGHT_PARAMETERS)}")
        get = params.get
    else:
        missing = [n for n in WEIGHT_PARAMETERS if not hasattr(params, n)]

        def get(name):
            return getattr(params, name)
    if missing:
        raise ValueError(f"params lacks {missing}; it needs all of {list(WEIGHT_PARAMETERS)}")
    return {name: check_positive(f"params[{name!r}]", get(name)) for name in WEIGHT_PARAMETERS}


def _weights(values):
    """H_e and H_y of eq. 15 for a dict of the six parameters."""
    H_e = paper.error_weight(paper.ErrorWeightParameters(
        M_e=values["M_e"], eps_e=values["eps_e"], omega_e=values["omega_e"]))
    H_y = paper.output_weight(paper.OutputWeightParameters(
        M_y=values["M_y"], eps_y=values["eps_y"], omega_y=values["omega_y"]))
    return H_e, H_y


def _unit_crossing(omega, mag):
    """First frequency [rad/s] where ``mag`` crosses 1, log-interpolated (NaN if it never does)."""
    log_mag = np.log(mag)
    change = np.flatnonzero(np.sign(log_mag[:-1]) * np.sign(log_mag[1:]) < 0)
    if change.size == 0:
        return float("nan")
    k = change[0]
    frac = log_mag[k] / (log_mag[k] - log_mag[k + 1])
    return float(np.exp(np.log(omega[k]) + frac * np.log(omega[k + 1] / omega[k])))


@dataclass(frozen=True)
class WeightDesignView:
    """The loop of G and K under the templates of one set of weights (notebook 04).

    Attributes
    ----------
    params : dict
        M_e, eps_e, omega_e [rad/s], M_y, eps_y, omega_y [rad/s].
    H_e, H_y : control.TransferFunction
        The weights of eq. 15 for ``params``.
    omega : ndarray
        Frequency grid [rad/s] of the curves.
    S, T : ndarray
        |S(j omega)|, |T(j omega)| of the loop of G and K (absolute values).
    inv_He, inv_Hy : ndarray
        The templates 1/|H_e(j omega)|, 1/|H_y(j omega)|.
    analysis : piezolib.problem.analysis.RobustnessAnalysis or None
        Table 3 for K with these weights (on the analysis grid of
        :func:`piezolib.problem.analysis.analyze`); None in the first frame a
        live control draws while the peaks are computed (they read NaN and
        ``stable`` None until then).
    controller : str
        Label of K.
    """

    params: dict
    H_e: ct.TransferFunction = field(repr=False)
    H_y: ct.TransferFunction = field(repr=False)
    omega: np.ndarray = field(repr=False)
    S: np.ndarray = field(repr=False)
    T: np.ndarray = field(repr=False)
    inv_He: np.ndarray = field(repr=False)
    inv_Hy: np.ndarray = field(repr=False)
    analysis: RobustnessAnalysis | None = field(repr=False)
    controller: str = "K"

    def _analysed(self, name):
        return float("nan") if self.analysis is None else getattr(self.analysis, name)

    @property
    def norm_He_S(self):
        """NP: ||H_e S||_inf."""
        return self._analysed("norm_He_S")

    @property
    def norm_Hy_T(self):
        """NP: ||H_y T||_inf."""
        return self._analysed("norm_Hy_T")

    @property
    def mu_RS(self):
        """RS: peak of mu(M11) = |H_m T|."""
        return self._analysed("mu_RS")

    @property
    def mu_RP(self):
        """RP: peak of the mu upper bound of M."""
        return self._analysed("mu_RP")

    @property
    def stable(self):
        """Whether K stabilises G (Table 3's NS); None before the analysis."""
        return None if self.analysis is None else self.analysis.nominal_stability

    @property
    def crossing_He(self):
        """Frequency [rad/s] where the template 1/|H_e| crosses 1 (0 dB), NaN if it does not."""
        return _unit_crossing(self.omega, self.inv_He)

    @property
    def crossing_Hy(self):
        """Frequency [rad/s] where the template 1/|H_y| crosses 1 (0 dB), NaN if it does not."""
        return _unit_crossing(self.omega, self.inv_Hy)

    def peaks(self):
        """{"||H_e S||_inf", "||H_y T||_inf", "mu_RS", "mu_RP"}: the NP, RS and RP peaks."""
        return {"||H_e S||_inf": self.norm_He_S, "||H_y T||_inf": self.norm_Hy_T,
                "mu_RS": self.mu_RS, "mu_RP": self.mu_RP}


def weight_design_view(G, H_m, K, params=None, omega=None, *, controller=None):
    """|S|, |T| of the loop of G and K, the templates of eq. 15 and the controller's peaks.

    The callback of :func:`weight_design_control`.

    Parameters
    ----------
    G : control.LTI
        Plant u_c [V] -> v_y [V].
    H_m : control.LTI
        Multiplicative uncertainty weight (eq. 8).
    K : control.LTI
        SISO controller v_e [V] -> u_b [V].
    params : dict or object, optional
        M_e, eps_e, omega_e [rad/s], M_y, eps_y, omega_y [rad/s], as dict keys
        or attributes (e.g. a study's ``weights``), all six, positive; default
        the published values of :mod:`piezolib.problem.paper`.
    omega : array_like, optional
        Grid [rad/s] of the curves, increasing; default 1 ... 1e7 rad/s,
        1500 points.  The peaks come from
        :func:`piezolib.problem.analysis.analyze` on its own grid.
    controller : str, optional
        Label of K in the figure (default ``K.name``).

    Returns
    -------
    WeightDesignView
        For a K that does not stabilise G the peaks are inf.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> view = weight_design_view(G, H_m, K)
    >>> round(view.norm_He_S, 2)
    0.81
    """
    check_siso("G", G)
    check_siso("K", K)
    omega = (frequency_grid(*_WEIGHT_GRID) if omega is None
             else check_frequency_grid("omega", omega, min_length=16))
    view = _curves_view(params, omega, controller or K.name or "K", _loop_curves(G, K, omega))
    return _with_analysis(view, G, H_m, K)


def _loop_curves(G, K, omega):
    """|S(j omega)|, |T(j omega)| of the loop of G and K (they do not depend on the weights)."""
    loop = loop_functions(G, K)
    return magnitude(loop.S, omega), magnitude(loop.T, omega)


def _curves_view(params, omega, controller, curves):
    """The view of the weights ``params`` over the loop ``curves`` (|S|, |T|), without the
    peaks (``analysis`` None): what a live control draws first."""
    values = _weight_parameters(params)
    H_e, H_y = _weights(values)
    S, T = curves
    return WeightDesignView(
        params=values, H_e=H_e, H_y=H_y, omega=omega, S=S, T=T,
        inv_He=1 / magnitude(H_e, omega), inv_Hy=1 / magnitude(H_y, omega),
        analysis=None, controller=controller)


def _with_analysis(view, G, H_m, K):
    """``view`` with Table 3 for K and its weights."""
    return replace(view, analysis=analyze(K, G, H_m, view.H_e, view.H_y))


def _weight_summary(view):
    if view.analysis is None:
        return f"{view.controller}:  computing the NP, RS and RP peaks ..."
    if not view.stable:
        return f"{view.controller} does not stabilise G: no condition of Table 3 holds"
    return (f"{view.controller}:  NP ||H_e S|| = {view.norm_He_S:.3f}, "
            f"||H_y T|| = {view.norm_Hy_T:.3f};  RS mu = {view.mu_RS:.3f};  "
            f"RP mu = {view.mu_RP:.3f}")


def draw_weight_design(view, fig=None):
    """|S| under 1/|H_e| and |T| under 1/|H_y| [dB] against frequency [rad/s], with the peaks.

    Parameters
    ----------
    view : WeightDesignView
    fig : matplotlib.figure.Figure, optional
        Figure to clear and draw into (the widget reuses one); default a new
        one, not attached to pyplot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    return _WeightPlot(view, fig).figure


def _peak_text(peak, view):
    """A peak in a title: three decimals, "..." while it is computed."""
    return "..." if view.analysis is None else f"{peak:.3f}"


class _WeightPlot:
    """The figure of :func:`draw_weight_design`, whose curves and texts follow a new view."""

    def __init__(self, view, fig=None):
        check_type("view", view, WeightDesignView, "a WeightDesignView")
        with mpl.rc_context(STYLE):
            self.figure, (ax_s, ax_t) = panel_figure(fig, 2, (9.0, 3.8))
            self.axes = (ax_s, ax_t)
            w = view.omega
            (self.S,) = ax_s.semilogx(w, curve_db(view.S))
            (self.inv_He,) = ax_s.semilogx(w, curve_db(view.inv_He), "k--",
                                           label="template 1/|H_e|")
            (self.T,) = ax_t.semilogx(w, curve_db(view.T))
            (self.inv_Hy,) = ax_t.semilogx(w, curve_db(view.inv_Hy), "k--",
                                           label="template 1/|H_y|")
            # where the template crosses 0 dB (hidden when it does not)
            self.crossings = [ax.axvline(1.0, color="0.5", lw=0.8, ls=":") for ax in self.axes]
            for ax in self.axes:
                ax.set_xlabel("frequency omega [rad/s]")
                ax.set_ylabel("magnitude [dB]")
                ax.set_xlim(w[0], w[-1])
            # the empty corners: |S| and 1/|H_e| rise to ~0 dB and M_e, |T| and 1/|H_y| fall
            ax_s.set_ylim(-100, 20)
            ax_t.set_ylim(-160, 20)
        self.show(view)
        apply_unit_text(self.figure)

    @property
    def moving(self):
        """The artists a new view changes: curves, crossing lines, legends and titles."""
        return [self.S, self.inv_He, self.T, self.inv_Hy, *self.crossings,
                *(ax.get_legend() for ax in self.axes), *(ax.title for ax in self.axes),
                self.suptitle]

    def show(self, view):
        """Draw ``view`` into the figure's curves and texts (always possible: True)."""
        check_type("view", view, WeightDesignView, "a WeightDesignView")
        ax_s, ax_t = self.axes
        w = view.omega
        with mpl.rc_context(STYLE):
            for line, curve in ((self.S, view.S), (self.inv_He, view.inv_He),
                                (self.T, view.T), (self.inv_Hy, view.inv_Hy)):
                line.set_data(w, curve_db(curve))
            self.S.set_label(f"|S| ({view.controller})")
            self.T.set_label(f"|T| ({view.controller})")
            for line, crossing, name in ((self.crossings[0], view.crossing_He, "H_e"),
                                         (self.crossings[1], view.crossing_Hy, "H_y")):
                line.set_visible(bool(np.isfinite(crossing)))
                if np.isfinite(crossing):
                    line.set_xdata([crossing, crossing])
                    line.set_label(f"1/|{name}| = 0 dB at {crossing:.3g} rad/s")
                else:
                    line.set_label("_hidden")
            ax_s.legend(loc="lower right")
            ax_t.legend(loc="lower left")
            ax_s.set_title(f"sensitivity: ||H_e S||_inf = {_peak_text(view.norm_He_S, view)}")
            ax_t.set_title("complementary sensitivity: ||H_y T||_inf = "
                           f"{_peak_text(view.norm_Hy_T, view)}")
            p = view.params
            self.suptitle = self.figure.suptitle(
                f"{_weight_summary(view)}\nM_e = {p['M_e']:.3g}, eps_e = {p['eps_e']:.3g}, "
                f"omega_e = {p['omega_e']:.3g} rad/s;  M_y = {p['M_y']:.3g}, "
                f"eps_y = {p['eps_y']:.3g}, omega_y = {p['omega_y']:.3g} rad/s")
        apply_unit_text_to(self.moving)
        return True


#: The class of a progress bar still running (:mod:`piezolib.notebook_display` draws it).
_RUNNING_BAR = "piezolib-progress-running"


class _FinalStateHeld:
    """Bars and log lines drawn into the HTML widget ``target`` as they change, except a state
    with no bar running (the last one), which waits for :meth:`release`."""

    def __init__(self, target):
        self.target, self.held = target, None

    def __call__(self, html_text, _plain):
        if _RUNNING_BAR in html_text:
            self.held = None
            self.target.value = html_text
        else:
            self.held = html_text

    def release(self):
        """Show the state held back (if any)."""
        if self.held is not None:
            self.target.value, self.held = self.held, None


class Redesign(NamedTuple):
    """A mu controller re-designed for a set of weights (unpacks as ``K, mu_RP``).

    Attributes
    ----------
    K : control.StateSpace
        The reduced controller v_e [V] -> u_b [V] of the design.
    mu_RP : float
        Peak of its mu_RP upper bound on the exact P of eq. 16 with these
        weights (inf if it does not stabilise G).
    """

    K: ct.StateSpace
    mu_RP: float


def redesign(G, H_m, params=None, **design_options):
    """Design a mu controller for the weights ``params`` and return it with its mu_RP peak.

    DK-iteration and reduction by
    :func:`piezolib.problem.design.design_controller` on the paper's problem
    (no delay model, no fixed-order stage, unless ``design_options`` say
    otherwise); the peak is that of
    :func:`piezolib.problem.analysis.robust_performance_peak`.

    Parameters
    ----------
    G, H_m : control.LTI
        Plant u_c [V] -> v_y [V] and uncertainty weight.
    params : dict or object, optional
        The six weight parameters, as in :func:`weight_design_view`.
    **design_options
        Passed to ``design_controller``; defaults ``order=6``,
        ``delay_samples=None``, ``fixed_order=False`` (and its own ``max_iter``).
        ``max_iter=1`` or 2 gives a rough controller in about a second.

    Returns
    -------
    Redesign
        ``(K_reduced, mu_RP)``.
    """
    values = _weight_parameters(params)
    H_e, H_y = _weights(values)
    options = {"order": 6, "delay_samples": None, "fixed_order": False, **design_options}
    design = design_controller(G, H_m, H_e, H_y, **options)
    mu_peak, _ = robust_performance_peak(design.K_reduced, G, H_m, H_e, H_y)
    return Redesign(K=design.K_reduced, mu_RP=float(mu_peak))


def weight_design_control(G, H_m, K, params=None, omega=None, *, design_options=None,
                          interactive=None):
    """Sliders for the six weights of eq. 15 over |S|, |T| and the peaks, and a re-design button.

    Parameters
    ----------
    G, H_m, K : control.LTI
        Plant u_c [V] -> v_y [V], uncertainty weight and controller v_e [V] -> u_b [V].
    params : dict or object, optional
        Starting weights, as in :func:`weight_design_view` (default: published).
    omega : array_like, optional
        Grid [rad/s] of the curves.
    design_options : dict, optional
        Options of :func:`redesign` (e.g. ``{"max_iter": 4}``).
    interactive : bool, optional
        Force the widget (True) or the static figure (False); default
        :func:`interactive_available`.

    Returns
    -------
    ipywidgets.VBox or matplotlib.figure.Figure
        The widget: M_e and M_y linear sliders, eps_e, eps_y, omega_e [rad/s]
        and omega_y [rad/s] log sliders; the figure and the NP / RS / RP
        peaks follow every change; "re-design" runs :func:`redesign` for the
        current weights, shows its progress bar and log lines under the
        button (``box.redesign_progress``), the new controller's mu_RP
        (``box.redesign_result``), and adds it to the controller menu.
        ``box.controls`` holds the sliders, the button ("redesign") and the
        menu ("controller"); ``box.panel.view`` the latest
        :class:`WeightDesignView` (a change is drawn by a worker thread:
        ``box.panel.wait()`` blocks until the figure shows the latest values;
        the re-design's done line and result appear with the figure of the
        new controller).  Saved without a frontend, the widget's
        output holds the figure as image/png.  Headless: the figure of
        :func:`draw_weight_design` for ``params``.
    """
    start = _weight_parameters(params)
    design_options = dict(design_options or {})
    if not want_widget(interactive):
        return static_figure(draw_weight_design(weight_design_view(G, H_m, K, start, omega)))
    w = import_ipywidgets()
    sliders = {
        "M_e": linear_slider(w, "M_e", start["M_e"], 1.05, 6.0, 0.05),
        "eps_e": log_slider(w, "eps_e", start["eps_e"]),
        "omega_e": log_slider(w, "omega_e", start["omega_e"], description="omega_e [rad/s]"),
        "M_y": linear_slider(w, "M_y", start["M_y"], 1.05, 4.0, 0.05),
        "eps_y": log_slider(w, "eps_y", start["eps_y"]),
        "omega_y": log_slider(w, "omega_y", start["omega_y"], description="omega_y [rad/s]"),
    }
    for slider in sliders.values():
        slider.description = unit_text(slider.description)
    # the menu names the controller as the text does (K_mu6 -> K_μ6)
    given = unit_text(f"given K ({K.name})" if K.name else "given K")
    controllers = {given: K}
    menu = w.Dropdown(options=[given], value=given, description="controller")
    button = w.Button(description="re-design", tooltip="mu-synthesis for these weights",
                      icon="cogs")
    result = w.HTML()

    grid = (frequency_grid(*_WEIGHT_GRID) if omega is None
            else check_frequency_grid("omega", omega, min_length=16))
    curves = {}         # |S|, |T| of each controller: the sliders move the weights only

    def compute(values):
        """The curves under the new templates at once, then the peaks (the slow part)."""
        label = menu.value
        K_now = controllers[label]
        if label not in curves:
            curves[label] = _loop_curves(G, K_now, grid)
        return [lambda _: _curves_view(values, grid, label, curves[label]),
                lambda view: _with_analysis(view, G, H_m, K_now)]

    panel = LivePanel(w, sliders, compute, _WeightPlot, _weight_summary)
    menu.observe(panel.refresh, names="value")

    activity = w.HTML()

    def on_redesign(_):
        button.disabled = True
        result.value = "<i>re-designing (DK-iteration) ...</i>"
        bars = _FinalStateHeld(activity)
        try:
            # a button's callback runs outside any cell: its bars and log lines would only
            # reach the hidden log console, so they are drawn under the button instead
            with progress.shown_in(bars):
                K_new, mu_new = redesign(G, H_m, panel.values(), **design_options)
        except Exception as exc:        # noqa: BLE001 -- shown, not lost in the kernel log
            bars.release()
            result.value = f"<b>re-design failed</b> ({type(exc).__name__}): {html.escape(str(exc))}"
            return
        finally:
            button.disabled = False
        label = f"re-designed K ({K_new.nstates} states)"
        controllers[label] = K_new
        curves.pop(label, None)         # a new design under a label already used
        done = html.escape(unit_text(f"{label}: peak mu_RP = {mu_new:.3f} for these weights"))

        def announce():
            bars.release()
            result.value = done

        if label not in menu.options:
            menu.options = list(menu.options) + [label]
        menu.value = label
        # the done line comes with the figure of the new controller, not before it
        panel.refresh(then=announce)

    button.on_click(on_redesign)
    box = finish(panel, panel.box(extra=[w.HBox([menu, button, result]), activity]))
    box.controls.update(redesign=button, controller=menu)
    box.redesign_result = result
    box.redesign_progress = activity
    return box
