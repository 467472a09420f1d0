"""Interactive controls for the notebooks, and the plain callbacks behind them.

Three controls, one entry point each, every one taking its models explicitly:

* :func:`weight_design_control` (notebook 04): M_e, eps_e, omega_e [rad/s],
  M_y, eps_y, omega_y [rad/s] of eq. 15 over |S|, |T| and the NP / RS / RP
  peaks; a button re-designs the mu controller for the weights.
* :func:`spread_control` (notebook 02): the +- spread of the denominator
  coefficients over the relative-error envelope and its covering weight.
* :func:`dahl_control` (notebook 03): g_a, alpha1, alpha2, beta2, x0 of the
  Dahl model over the model and measured loops (u_c [V] -> v_y [V]).

Each control is a thin layer over a pure callback that computes a small
result object (:func:`weight_design_view`, :func:`spread_view`,
:func:`dahl_view`, and :func:`redesign`) and a drawing function
(:func:`draw_weight_design`, :func:`draw_spread`, :func:`draw_dahl`); the
callbacks are what the tests exercise.

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

import html
import importlib.util
import io
import os
import sys
from dataclasses import dataclass, field, fields, replace
from typing import NamedTuple

import control as ct
import matplotlib as mpl
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from piezolib.problem import paper
from piezolib import uncertainty as unc
from piezolib._checks import check_frequency_grid, check_integer, check_positive, check_siso
from piezolib.hysteresis.dahl import DahlModel, check_dahl_model, simulate_dahl
from piezolib.problem.analysis import RobustnessAnalysis, analyze, robust_performance_peak
from piezolib.problem.design import design_controller
from piezolib.robust.lti import frequency_grid, loop_functions
from piezolib.workbook import plotting

__all__ = [
    "STATIC_ENV", "interactive_available",
    "WEIGHT_PARAMETERS", "WeightDesignView", "weight_design_view", "draw_weight_design",
    "Redesign", "redesign", "weight_design_control",
    "SpreadView", "spread_view", "draw_spread", "spread_control",
    "DAHL_SLIDER_PARAMETERS", "DahlView", "dahl_view", "draw_dahl", "dahl_control",
]

#: Environment variable that makes every entry point draw its static figure
#: ("1", "true", "yes" or "on"; "0", "false", "no", "off" or unset leave the choice to
#: :func:`interactive_available`).
STATIC_ENV = "PIEZOLIB_STATIC"
_FALSE_WORDS = ("", "0", "false", "no", "off")

#: The six parameters of eq. 15, in slider order (frequencies in rad/s).
WEIGHT_PARAMETERS = ("M_e", "eps_e", "omega_e", "M_y", "eps_y", "omega_y")
#: Parameters of the Dahl model a person can move (beta1 stays 0, gamma_a only
#: scales beta2: only beta2 gamma_a enters H).
DAHL_SLIDER_PARAMETERS = ("g_a", "alpha1", "alpha2", "beta2", "x0")

#: Default grid [rad/s] of the |S|, |T| and template curves.
_WEIGHT_GRID = (1e0, 1e7, 1500)
#: Default grid [rad/s] of the relative-error envelope (that of notebook 02).
_SPREAD_GRID = (1e0, 1e6, 2000)
#: Order of the covering weight fitted to the envelope (that of notebook 02).
_COVER_ORDER = 5
#: Member curves drawn behind the envelope (a thinned selection: 729 curves are a grey blur).
_MEMBER_CURVES = 60


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
    shell = _ipython_shell()
    return shell is not None and getattr(shell, "kernel", None) is not None


def _ipython_shell():
    """The running IPython shell, or None (IPython is not imported unless it already is)."""
    ipython = sys.modules.get("IPython")
    return ipython.get_ipython() if ipython is not None else None


def _static(fig):
    """Return ``fig``, made to show as a PNG when it is a notebook cell's value.

    IPython learns to show figures as PNG only once a pyplot backend is
    resolved (inline) or never (``MPLBACKEND=Agg`` under the headless
    runners); without it the static figure of a control would show as
    ``<Figure size ...>``.  A formatter already registered is left alone.
    """
    shell = _ipython_shell()
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", None)
    if formatters and "image/png" in formatters:
        png = formatters["image/png"]
        try:
            png.lookup_by_type(Figure)
        except KeyError:
            png.for_type(Figure, _png)
    return fig


def _want_widget(interactive):
    if interactive is None:
        return interactive_available()
    if not isinstance(interactive, bool):
        raise TypeError(f"interactive must be True, False or None, got {interactive!r}")
    return interactive


def _ipywidgets():
    try:
        import ipywidgets
    except ImportError as exc:
        raise ImportError("interactive controls need ipywidgets "
                          "(pip install -r environment.txt)") from exc
    return ipywidgets


# --------------------------------------------------------------------------- figures
def _figure(fig, ncols, figsize):
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


def _png(fig):
    """PNG bytes of ``fig``: shown in an Image widget, whatever matplotlib backend is active."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=fig.dpi, metadata={"Software": None})
    return buffer.getvalue()


def _magnitude(sys_, omega):
    return np.abs(np.ravel(sys_(1j * omega)))


def _db(x):
    with np.errstate(divide="ignore"):
        return plotting.db(x)


# --------------------------------------------------------------------------- (a) weights
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
    analysis : piezolib.problem.analysis.RobustnessAnalysis
        Table 3 for K with these weights (on the analysis grid of
        :func:`piezolib.problem.analysis.analyze`).
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
    analysis: RobustnessAnalysis = field(repr=False)
    controller: str = "K"

    @property
    def norm_He_S(self):
        """NP: ||H_e S||_inf."""
        return self.analysis.norm_He_S

    @property
    def norm_Hy_T(self):
        """NP: ||H_y T||_inf."""
        return self.analysis.norm_Hy_T

    @property
    def mu_RS(self):
        """RS: peak of mu(M11) = |H_m T|."""
        return self.analysis.mu_RS

    @property
    def mu_RP(self):
        """RP: peak of the mu upper bound of M."""
        return self.analysis.mu_RP

    @property
    def stable(self):
        """Whether K stabilises G (Table 3's NS)."""
        return self.analysis.nominal_stability

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
    values = _weight_parameters(params)
    omega = (frequency_grid(*_WEIGHT_GRID) if omega is None
             else check_frequency_grid("omega", omega, min_length=16))
    H_e, H_y = _weights(values)
    loop = loop_functions(G, K)
    result = analyze(K, G, H_m, H_e, H_y)
    return WeightDesignView(
        params=values, H_e=H_e, H_y=H_y, omega=omega,
        S=_magnitude(loop.S, omega), T=_magnitude(loop.T, omega),
        inv_He=1 / _magnitude(H_e, omega), inv_Hy=1 / _magnitude(H_y, omega),
        analysis=result, controller=controller or K.name or "K")


def _weight_summary(view):
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
    if not isinstance(view, WeightDesignView):
        raise TypeError(f"view must be a WeightDesignView, got {type(view).__name__}")
    with mpl.rc_context(plotting.STYLE):
        fig, (ax_s, ax_t) = _figure(fig, 2, (9.0, 3.8))
        w = view.omega
        ax_s.semilogx(w, _db(view.S), label=f"|S| ({view.controller})")
        ax_s.semilogx(w, _db(view.inv_He), "k--", label="template 1/|H_e|")
        ax_t.semilogx(w, _db(view.T), label=f"|T| ({view.controller})")
        ax_t.semilogx(w, _db(view.inv_Hy), "k--", label="template 1/|H_y|")
        for ax, crossing, name in ((ax_s, view.crossing_He, "H_e"),
                                   (ax_t, view.crossing_Hy, "H_y")):
            if np.isfinite(crossing):
                ax.axvline(crossing, color="0.5", lw=0.8, ls=":",
                           label=f"1/|{name}| = 0 dB at {crossing:.3g} rad/s")
            ax.set_xlabel("frequency omega [rad/s]")
            ax.set_ylabel("magnitude [dB]")
            ax.set_xlim(w[0], w[-1])
        # the empty corners: |S| and 1/|H_e| rise to ~0 dB and M_e, |T| and 1/|H_y| fall
        ax_s.set_ylim(-100, 20)
        ax_t.set_ylim(-160, 20)
        ax_s.legend(loc="lower right")
        ax_t.legend(loc="lower left")
        ax_s.set_title(f"sensitivity: ||H_e S||_inf = {view.norm_He_S:.3f}")
        ax_t.set_title(f"complementary sensitivity: ||H_y T||_inf = {view.norm_Hy_T:.3f}")
        p = view.params
        fig.suptitle(f"{_weight_summary(view)}\nM_e = {p['M_e']:.3g}, eps_e = {p['eps_e']:.3g}, "
                     f"omega_e = {p['omega_e']:.3g} rad/s;  M_y = {p['M_y']:.3g}, "
                     f"eps_y = {p['eps_y']:.3g}, omega_y = {p['omega_y']:.3g} rad/s")
    return plotting.apply_unit_text(fig)


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


# --------------------------------------------------------------------------- (b) spread
@dataclass(frozen=True)
class SpreadView:
    """The parametric model set of one spread, its envelope and a weight covering it (notebook 02).

    Attributes
    ----------
    spread : float
        Relative spread of each denominator coefficient (0.05 for +-5 %).
    levels : int
        Values per coefficient.
    omega : ndarray
        Frequency grid [rad/s].
    members : int
        Number of models (``levels ** n``).
    unstable : ndarray of int
        Indices of the members with a pole in Re s >= 0.
    envelope : ndarray
        E(omega) = max |G_k/G - 1| over the stable members.
    envelope_all : ndarray
        The same over all members.
    member_errors : ndarray, shape (m, len(omega))
        |G_k/G - 1| of an evenly thinned selection of the stable members (for drawing).
    weight : control.TransferFunction
        Stable, minimum-phase weight fitted to ``envelope``
        (:func:`piezolib.uncertainty.fit_covering_weight`, order 5).
    coverage : piezolib.uncertainty.Coverage
        How ``weight`` covers ``envelope`` on the grid.
    """

    spread: float
    levels: int
    omega: np.ndarray = field(repr=False)
    members: int
    unstable: np.ndarray
    envelope: np.ndarray = field(repr=False)
    envelope_all: np.ndarray = field(repr=False)
    member_errors: np.ndarray = field(repr=False)
    weight: ct.TransferFunction = field(repr=False)
    coverage: unc.Coverage

    @property
    def n_unstable(self):
        """Number of unstable members."""
        return int(self.unstable.size)


def spread_view(G, spread, omega=None, levels=3):
    """Model set of G for one spread: envelope, covering weight, unstable members.

    The callback of :func:`spread_control`.

    Parameters
    ----------
    G : control.LTI
        Nominal plant u_c [V] -> v_y [V].
    spread : float
        Relative spread of every denominator coefficient, 0 < spread < 1
        (0.05 for +-5 %).
    omega : array_like, optional
        Grid [rad/s], increasing; default 1 ... 1e6 rad/s, 2000 points (that
        of notebook 02).
    levels : int, optional
        Values per coefficient (3: the nominal value and both extremes).

    Returns
    -------
    SpreadView

    Raises
    ------
    ValueError
        When no member of the set is stable (no envelope to cover).
    """
    omega = (frequency_grid(*_SPREAD_GRID) if omega is None
             else check_frequency_grid("omega", omega, min_length=16))
    levels = check_integer("levels", levels, minimum=2)
    mset = unc.model_set(G, spread, levels)
    unstable = unc.unstable_members(mset)
    stable = np.setdiff1d(np.arange(mset.size), unstable)
    if stable.size == 0:
        raise ValueError(f"spread = {spread:g}: every member of the {levels}-level set is "
                         "unstable, there is no envelope of stable members to cover")
    errors = unc.relative_errors(mset, omega)
    envelope = errors[stable].max(axis=0)
    pick = stable[np.unique(np.linspace(0, stable.size - 1, min(_MEMBER_CURVES, stable.size))
                            .round().astype(int))]
    weight = unc.fit_covering_weight(omega, envelope, order=_COVER_ORDER)
    return SpreadView(spread=float(mset.spread), levels=levels, omega=omega, members=mset.size,
                      unstable=unstable, envelope=envelope, envelope_all=errors.max(axis=0),
                      member_errors=errors[pick], weight=weight,
                      coverage=unc.coverage(weight, omega, envelope))


def _spread_summary(view, H_m=None):
    text = (f"+-{100 * view.spread:.3g} %, {view.levels} levels: {view.members} models, "
            f"{view.n_unstable} unstable;  fitted order-{_COVER_ORDER} weight exceeds E_m by "
            f"at most {view.coverage.max_excess_dB:.1f} dB")
    if H_m is not None:
        cover = unc.coverage(H_m, view.omega, view.envelope)
        text += (f";  |H_m| / E_m >= {cover.worst_ratio:.3g} "
                 f"({'covers' if cover.covers else 'does not cover'})")
    return text


def draw_spread(view, H_m=None, fig=None):
    """Relative errors |G_k/G - 1| [dB] of the set, their envelope and the covering weight(s).

    Parameters
    ----------
    view : SpreadView
    H_m : control.LTI, optional
        A weight to compare (e.g. the published one, Table 2).
    fig : matplotlib.figure.Figure, optional
        Figure to clear and draw into; default a new one, not attached to pyplot.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not isinstance(view, SpreadView):
        raise TypeError(f"view must be a SpreadView, got {type(view).__name__}")
    if H_m is not None:
        check_siso("H_m", H_m)
    with mpl.rc_context(plotting.STYLE):
        fig, (ax,) = _figure(fig, 1, (7.0, 4.2))
        w = view.omega
        for k, err in enumerate(view.member_errors):
            ax.semilogx(w, _db(err), color="0.75", lw=0.5,
                        label="stable members (a selection)" if k == 0 else None)
        if view.n_unstable:
            ax.semilogx(w, _db(view.envelope_all), color="#c0504d", lw=0.9, ls=":",
                        label=f"envelope incl. {view.n_unstable} unstable members")
        ax.semilogx(w, _db(view.envelope), "k", lw=1.4, label="envelope E_m (stable members)")
        ax.semilogx(w, _db(_magnitude(view.weight, w)), color="#1f4e79", lw=1.4,
                    label=f"fitted weight, order {_COVER_ORDER}")
        if H_m is not None:
            ax.semilogx(w, _db(_magnitude(H_m, w)), color="#d08a00", ls="--", lw=1.4,
                        label="|H_m| (Table 2)")
        top = float(np.max(_db(view.envelope_all)))
        ax.set_ylim(-80, max(20.0, top + 10.0))
        ax.set_xlim(w[0], w[-1])
        ax.set_xlabel("frequency omega [rad/s]")
        ax.set_ylabel("relative error |G_k/G - 1| [dB]")
        # above the flat low-frequency level (~20 log10 spread) the left corner is empty;
        # below it the members' notches reach down
        ax.legend(loc="upper left")
        ax.set_title(_spread_summary(view, H_m).replace(";  ", "\n", 1))
    return plotting.apply_unit_text(fig)


# --------------------------------------------------------------------------- (c) Dahl
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
    if not isinstance(view, DahlView):
        raise TypeError(f"view must be a DahlView, got {type(view).__name__}")
    d = view.discard
    with mpl.rc_context(plotting.STYLE):
        fig, (ax_loop, ax_err) = _figure(fig, 2, (9.0, 3.8))
        ax_loop.plot(view.v[d:], view.x[d:], color="0.6", lw=0.8, label="measured")
        ax_loop.plot(view.v[d:], view.x_model[d:], color="#c0504d", lw=1.2, label="Dahl model")
        ax_loop.set_xlabel("u_c (amplifier input) [V]")
        ax_loop.set_ylabel("v_y (sensor) [V]")
        # the loop runs along the diagonal: the upper left corner is empty
        ax_loop.legend(loc="upper left")
        ax_loop.set_title("loops after the first period")
        ax_err.plot(view.t[d:], view.residual_percent, color="#1f4e79", lw=0.9)
        ax_err.axhline(0.0, color="0.4", lw=0.6)
        ax_err.set_xlabel("time [s]")
        ax_err.set_ylabel("model - measured [% of stroke]")
        ax_err.set_title(f"RMS {view.rms_percent:.3f} %, max {view.max_percent:.2f} % of stroke")
        m = view.model
        fig.suptitle(f"Dahl model ({m.form} form, start: {m.start})\ng_a = {m.g_a:.4g} V/V, "
                     f"alpha1 = {m.alpha1:.4g} 1/V, alpha2 = {m.alpha2:.4g} 1/V^2, "
                     f"beta2 = {m.beta2:.4g}, x0 = {m.x0:.3g} V")
    return plotting.apply_unit_text(fig)


# --------------------------------------------------------------------------- widgets
class _LivePanel:
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
        self.image.value = _png(self.figure)
        self.summary.value = html.escape(plotting.unit_text(self.describe(view)))
        self.status.value = ""

    def box(self, extra=()):
        """The VBox: sliders, extra rows, summary, status, figure."""
        w = self.widgets
        return w.VBox([w.HBox(list(self.sliders.values())[i:i + 3])
                       for i in range(0, len(self.sliders), 3)]
                      + list(extra) + [self.summary, self.status, self.image])


def _log_slider(widgets, name, value, decades=1.0, description=None):
    exponent = np.log10(value)
    return widgets.FloatLogSlider(
        value=value, base=10, min=float(np.floor(exponent - decades)),
        max=float(np.ceil(exponent + decades)), step=0.02, description=description or name,
        continuous_update=False, readout_format=".3g", style={"description_width": "initial"})


def _linear_slider(widgets, name, value, low, high, step, description=None):
    return widgets.FloatSlider(
        value=value, min=min(low, value), max=max(high, value), step=step,
        description=description or name, continuous_update=False, readout_format=".4g",
        style={"description_width": "initial"})


def _finish(panel, box):
    """Attach the panel's parts to the box for programmatic use, draw the first figure."""
    box.controls = dict(panel.sliders)
    box.panel = panel
    panel.refresh()
    return box


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
        current weights, shows the new controller's mu_RP and adds it to the
        controller menu.  ``box.controls`` holds the sliders, the button
        ("redesign") and the menu ("controller"); ``box.panel.view`` the
        latest :class:`WeightDesignView`.  Headless: the figure of
        :func:`draw_weight_design` for ``params``.
    """
    start = _weight_parameters(params)
    design_options = dict(design_options or {})
    if not _want_widget(interactive):
        return _static(draw_weight_design(weight_design_view(G, H_m, K, start, omega)))
    w = _ipywidgets()
    sliders = {
        "M_e": _linear_slider(w, "M_e", start["M_e"], 1.05, 6.0, 0.05),
        "eps_e": _log_slider(w, "eps_e", start["eps_e"]),
        "omega_e": _log_slider(w, "omega_e", start["omega_e"], description="omega_e [rad/s]"),
        "M_y": _linear_slider(w, "M_y", start["M_y"], 1.05, 4.0, 0.05),
        "eps_y": _log_slider(w, "eps_y", start["eps_y"]),
        "omega_y": _log_slider(w, "omega_y", start["omega_y"], description="omega_y [rad/s]"),
    }
    for slider in sliders.values():
        slider.description = plotting.unit_text(slider.description)
    given = f"given K ({K.name})" if K.name else "given K"
    controllers = {given: K}
    menu = w.Dropdown(options=[given], value=given, description="controller")
    button = w.Button(description="re-design", tooltip="mu-synthesis for these weights",
                      icon="cogs")
    result = w.HTML()

    def compute(values):
        return weight_design_view(G, H_m, controllers[menu.value], values, omega,
                                  controller=menu.value)

    panel = _LivePanel(w, sliders, compute, draw_weight_design, _weight_summary)
    menu.observe(panel.refresh, names="value")

    def on_redesign(_):
        button.disabled = True
        result.value = "<i>re-designing (DK-iteration) ...</i>"
        try:
            K_new, mu_new = redesign(G, H_m, panel.values(), **design_options)
        except Exception as exc:        # noqa: BLE001 -- shown, not lost in the kernel log
            result.value = f"<b>re-design failed</b> ({type(exc).__name__}): {html.escape(str(exc))}"
            return
        finally:
            button.disabled = False
        label = f"re-designed K ({K_new.nstates} states)"
        controllers[label] = K_new
        result.value = html.escape(plotting.unit_text(
            f"{label}: peak mu_RP = {mu_new:.3f} for these weights"))
        if label not in menu.options:
            menu.options = list(menu.options) + [label]
        if menu.value == label:
            panel.refresh()
        else:
            menu.value = label

    button.on_click(on_redesign)
    box = _finish(panel, panel.box(extra=[w.HBox([menu, button, result])]))
    box.controls.update(redesign=button, controller=menu)
    box.redesign_result = result
    return box


def spread_control(G, H_m, omega=None, spread=paper.UNCERTAINTY_SPREAD, *, levels=3,
                   interactive=None):
    """A slider for the coefficient spread (0.5 ... 10 %) over the envelope and covering weights.

    Parameters
    ----------
    G : control.LTI
        Nominal plant u_c [V] -> v_y [V].
    H_m : control.LTI or None
        Weight drawn for comparison (the published one, Table 2).
    omega : array_like, optional
        Grid [rad/s] (default that of :func:`spread_view`).
    spread : float, optional
        Starting spread (0.05 for +-5 %).
    levels : int, optional
        Values per coefficient.
    interactive : bool, optional
        Force the widget (True) or the static figure (False); default
        :func:`interactive_available`.

    Returns
    -------
    ipywidgets.VBox or matplotlib.figure.Figure
        The widget (``box.controls["spread"]`` is the slider, in %); headless
        the figure of :func:`draw_spread` for ``spread``.
    """
    spread = check_positive("spread", spread)
    if not _want_widget(interactive):
        return _static(draw_spread(spread_view(G, spread, omega, levels), H_m))
    w = _ipywidgets()
    slider = _linear_slider(w, "spread", 100 * spread, 0.5, 10.0, 0.1,
                            description="spread +- [%]")
    slider.description = plotting.unit_text(slider.description)
    panel = _LivePanel(w, {"spread": slider},
                       lambda values: spread_view(G, values["spread"] / 100, omega, levels),
                       lambda view, fig: draw_spread(view, H_m, fig),
                       lambda view: _spread_summary(view, H_m))
    return _finish(panel, panel.box())


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
    if not _want_widget(interactive):
        return _static(draw_dahl(dahl_view(model, loop, discard=discard)))
    w = _ipywidgets()
    b2 = model.beta2
    sliders = {
        "g_a": _linear_slider(w, "g_a", model.g_a, 0.75 * model.g_a, 1.25 * model.g_a,
                              model.g_a / 400, description="g_a [V/V]"),
        "alpha1": _log_slider(w, "alpha1", model.alpha1, description="alpha1 [1/V]"),
        "alpha2": _log_slider(w, "alpha2", model.alpha2, description="alpha2 [1/V^2]"),
        "beta2": _linear_slider(w, "beta2", b2, min(0.0, 2 * b2), max(0.0, 2 * b2),
                                max(abs(b2), 1e-3) / 200),
        "x0": _linear_slider(w, "x0", model.x0, model.x0 - 0.5, model.x0 + 0.5, 0.005,
                             description="x0 [V]"),
    }
    panel = _LivePanel(w, sliders,
                       lambda values: dahl_view(replace(model, **values), loop, discard=discard),
                       draw_dahl, _dahl_summary)
    return _finish(panel, panel.box())
