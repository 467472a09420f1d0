"""The spread control of notebook 02 (the coefficient spread over the relative-error envelope).

The +- spread of the denominator coefficients over the relative-error
envelope of the model set and a weight fitted to cover it.

:func:`spread_view` is the pure callback, :func:`draw_spread` the drawing,
:func:`spread_control` the entry point (a widget, or headless the figure:
:mod:`piezolib.workbook.interactive`); :func:`spread_view_from` makes the view of a
set the notebook has already surveyed and covered, so that the control starts there
without fitting the weight a second time.
"""

from dataclasses import dataclass, field, replace

import control as ct
import matplotlib as mpl
import numpy as np

from piezolib.problem import paper
from piezolib.problem.coefficient_set import EnvelopeCover, ModelSetSurvey
from piezolib import uncertainty as unc
from piezolib._checks import (check_frequency_grid, check_integer, check_positive, check_siso,
                              check_type)
from piezolib.robust.lti import frequency_grid
from piezolib.workbook.interactive._panel import (LivePanel, apply_unit_text_to, complete_view,
                                                  curve_db, finish, import_ipywidgets,
                                                  linear_slider, magnitude, panel_figure,
                                                  static_figure, want_widget)
from piezolib.workbook.style import PALETTE, STYLE, apply_unit_text, unit_text

__all__ = ["SpreadView", "spread_view", "spread_view_from", "draw_spread", "spread_control"]

#: Default grid [rad/s] of the relative-error envelope (that of notebook 02).
_SPREAD_GRID = (1e0, 1e6, 2000)
#: Order of the covering weight fitted to the envelope (that of notebook 02).
_COVER_ORDER = 5
#: Member curves drawn behind the envelope (a thinned selection: 729 curves are a grey blur).
_MEMBER_CURVES = 60


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
    weight : control.TransferFunction or None
        Stable, minimum-phase weight fitted to ``envelope``
        (:func:`piezolib.uncertainty.fit_covering_weight`, order 5); None in
        the first frame a live control draws while the weight is fitted.
    coverage : piezolib.uncertainty.Coverage or None
        How ``weight`` covers ``envelope`` on the grid (None with ``weight``).
    """

    spread: float
    levels: int
    omega: np.ndarray = field(repr=False)
    members: int
    unstable: np.ndarray
    envelope: np.ndarray = field(repr=False)
    envelope_all: np.ndarray = field(repr=False)
    member_errors: np.ndarray = field(repr=False)
    weight: ct.TransferFunction | None = field(repr=False)
    coverage: unc.Coverage | None

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
    return _with_weight(_envelope_view(G, spread, omega, levels))


def _envelope_view(G, spread, omega=None, levels=3):
    """:func:`spread_view` without the covering weight (``weight`` and ``coverage`` None):
    what a live panel draws while the weight is fitted."""
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
    return SpreadView(spread=float(mset.spread), levels=levels, omega=omega, members=mset.size,
                      unstable=unstable, envelope=errors[stable].max(axis=0),
                      envelope_all=errors.max(axis=0), member_errors=errors[_thinned(stable)],
                      weight=None, coverage=None)


def _with_weight(view):
    """``view`` with the order-5 weight fitted to its envelope, and its coverage."""
    weight = unc.fit_covering_weight(view.omega, view.envelope, order=_COVER_ORDER)
    return replace(view, weight=weight, coverage=unc.coverage(weight, view.omega, view.envelope))


def _thinned(stable):
    """An evenly spaced selection of at most :data:`_MEMBER_CURVES` of the stable members."""
    return stable[np.unique(np.linspace(0, stable.size - 1, min(_MEMBER_CURVES, stable.size))
                            .round().astype(int))]


def spread_view_from(survey, cover):
    """The :class:`SpreadView` of a set already surveyed and covered (nothing is fitted again).

    Parameters
    ----------
    survey : piezolib.problem.coefficient_set.ModelSetSurvey
        The set and its unstable members.
    cover : piezolib.problem.coefficient_set.EnvelopeCover
        Its relative errors, the envelope of the stable members and the covering weight
        fitted to it (of order 5, as :func:`spread_view` fits).

    Returns
    -------
    SpreadView
        The view :func:`spread_view` computes for the survey's spread, levels and the
        cover's grid, for :func:`spread_control`'s ``start``.
    """
    check_type("survey", survey, ModelSetSurvey, "a ModelSetSurvey (coefficient_set.survey_model_set)")
    check_type("cover", cover, EnvelopeCover, "an EnvelopeCover (coefficient_set.cover_envelope)")
    mset = survey.mset
    if cover.errors.shape[0] != mset.size:
        raise ValueError(f"cover holds {cover.errors.shape[0]} members, survey {mset.size}: "
                         "cover must be cover_envelope(survey, ...)")
    stable = np.setdiff1d(np.arange(mset.size), survey.unstable)
    if stable.size == 0:
        raise ValueError("survey: every member is unstable, there is no envelope to cover")
    return SpreadView(spread=float(mset.spread), levels=mset.levels, omega=cover.omega,
                      members=mset.size, unstable=survey.unstable, envelope=cover.envelope,
                      envelope_all=cover.errors.max(axis=0),
                      member_errors=cover.errors[_thinned(stable)], weight=cover.weight,
                      coverage=cover.fit)


def _spread_summary(view, H_m=None):
    text = (f"+-{100 * view.spread:.3g} %, {view.levels} levels: {view.members} models, "
            f"{view.n_unstable} unstable;  ")
    if view.coverage is None:
        text += f"fitting an order-{_COVER_ORDER} weight ..."
    else:
        text += (f"fitted order-{_COVER_ORDER} weight exceeds E_m by "
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
    return _SpreadPlot(view, H_m, fig).figure


class _SpreadPlot:
    """The figure of :func:`draw_spread`, whose curves, limits and texts follow a new view."""

    def __init__(self, view, H_m=None, fig=None):
        check_type("view", view, SpreadView, "a SpreadView")
        if H_m is not None:
            check_siso("H_m", H_m)
        with mpl.rc_context(STYLE):
            self.figure, (ax,) = panel_figure(fig, 1, (7.0, 4.2))
            self.ax, w = ax, view.omega
            self.members = [ax.semilogx(w, curve_db(err), color="0.75", lw=0.5,
                                        label="stable members (a selection)" if k == 0 else None)[0]
                            for k, err in enumerate(view.member_errors)]
            # shown when the set has unstable members
            (self.envelope_all,) = ax.semilogx(w, curve_db(view.envelope_all),
                                               color=PALETTE.contrast, lw=0.9, ls=":")
            (self.envelope,) = ax.semilogx(w, curve_db(view.envelope), "k", lw=1.4,
                                           label="envelope E_m (stable members)")
            # shown once the weight is fitted
            (self.weight,) = ax.semilogx(w, curve_db(view.envelope), color=PALETTE.primary,
                                         lw=1.4)
            self.H_m = None
            if H_m is not None:
                (self.H_m,) = ax.semilogx(w, curve_db(magnitude(H_m, w)), color=PALETTE.highlight,
                                          ls="--", lw=1.4, label="|H_m| (Table 2)")
            self.H_m_model = H_m
            ax.set_xlim(w[0], w[-1])
            ax.set_xlabel("frequency omega [rad/s]")
            ax.set_ylabel("relative error |G_k/G - 1| [dB]")
        self.show(view)
        apply_unit_text(self.figure)

    @property
    def moving(self):
        """The artists a new view changes: every curve (the y limits follow the set), the
        y axis, the legend and the title."""
        lines = [*self.members, self.envelope_all, self.envelope, self.weight]
        return lines + ([self.H_m] if self.H_m is not None else []) + [
            self.ax.yaxis, self.ax.get_legend(), self.ax.title]

    def show(self, view):
        """Draw ``view`` into the figure; False when it has more member curves than the figure."""
        check_type("view", view, SpreadView, "a SpreadView")
        ax, w = self.ax, view.omega
        if (len(view.member_errors) > len(self.members)
                or w.shape != self.envelope.get_xdata().shape):
            return False
        for k, line in enumerate(self.members):
            line.set_visible(k < len(view.member_errors))
            if k < len(view.member_errors):
                line.set_data(w, curve_db(view.member_errors[k]))
        self.envelope_all.set_data(w, curve_db(view.envelope_all))
        self.envelope_all.set_visible(bool(view.n_unstable))
        self.envelope_all.set_label(f"envelope incl. {view.n_unstable} unstable members"
                                    if view.n_unstable else "_hidden")
        self.envelope.set_data(w, curve_db(view.envelope))
        self.weight.set_visible(view.weight is not None)
        if view.weight is not None:
            self.weight.set_data(w, curve_db(magnitude(view.weight, w)))
        self.weight.set_label(f"fitted weight, order {_COVER_ORDER}" if view.weight is not None
                              else "_hidden")
        with mpl.rc_context(STYLE):
            top = float(np.max(curve_db(view.envelope_all)))
            ax.set_ylim(-80, max(20.0, top + 10.0))
            # above the flat low-frequency level (~20 log10 spread) the left corner is empty;
            # below it the members' notches reach down
            ax.legend(loc="upper left")
            ax.set_title(_spread_summary(view, self.H_m_model).replace(";  ", "\n", 1))
        apply_unit_text_to(self.moving)
        return True


def spread_control(G, H_m, omega=None, spread=paper.UNCERTAINTY_SPREAD, *, levels=3,
                   interactive=None, start=None):
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
    start : SpreadView, optional
        The view of the starting spread when it is already computed
        (:func:`spread_view_from`): drawn as it is instead of fitted again.

    Returns
    -------
    ipywidgets.VBox or matplotlib.figure.Figure
        The widget (``box.controls["spread"]`` is the slider, in %); headless
        the figure of :func:`draw_spread` for ``spread``.
    """
    spread = check_positive("spread", spread)
    if start is not None:
        check_type("start", start, SpreadView, "a SpreadView (spread_view_from)")
        if not (np.isclose(start.spread, spread) and start.levels == levels):
            raise ValueError(f"start is the view of +-{100 * start.spread:g} % with "
                             f"{start.levels} levels, the control starts at +-{100 * spread:g} % "
                             f"with {levels}")
        if omega is not None and not np.array_equal(np.asarray(omega, dtype=float), start.omega):
            raise ValueError("start was computed on another grid than omega: pass the grid "
                             "of its cover (or omega=None)")

    def stages_of(value):
        """The stages of one spread's view: ``start`` for its own, else the envelope, then
        with its fitted weight (the fit takes the longest: the set is shown before it)."""
        if start is not None and np.isclose(value, start.spread):
            return [lambda _: start]
        return [lambda _: _envelope_view(G, value, omega, levels), _with_weight]

    if not want_widget(interactive):
        return static_figure(draw_spread(complete_view(stages_of(spread)), H_m))
    w = import_ipywidgets()
    slider = linear_slider(w, "spread", 100 * spread, 0.5, 10.0, 0.1,
                           description="spread +- [%]")
    slider.description = unit_text(slider.description)
    panel = LivePanel(w, {"spread": slider}, lambda values: stages_of(values["spread"] / 100),
                      lambda view, fig: _SpreadPlot(view, H_m, fig),
                      lambda view: _spread_summary(view, H_m))
    return finish(panel, panel.box())
