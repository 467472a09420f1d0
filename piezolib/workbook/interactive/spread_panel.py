"""The spread control of notebook 02 (the coefficient spread over the relative-error envelope).

The +- spread of the denominator coefficients over the relative-error
envelope of the model set and a weight fitted to cover it.

:func:`spread_view` is the pure callback, :func:`draw_spread` the drawing,
:func:`spread_control` the entry point (a widget, or headless the figure:
:mod:`piezolib.workbook.interactive`); :func:`spread_view_from` makes the view of a
set the notebook has already surveyed and covered, so that the control starts there
without fitting the weight a second time.
"""

from dataclasses import dataclass, field

import control as ct
import matplotlib as mpl
import numpy as np

from piezolib.problem import paper
from piezolib.problem.coefficient_set import EnvelopeCover, ModelSetSurvey
from piezolib import uncertainty as unc
from piezolib._checks import (check_frequency_grid, check_integer, check_positive, check_siso,
                              check_type)
from piezolib.robust.lti import frequency_grid
from piezolib.workbook.interactive._panel import (LivePanel, curve_db, finish, import_ipywidgets,
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
    pick = _thinned(stable)
    weight = unc.fit_covering_weight(omega, envelope, order=_COVER_ORDER)
    return SpreadView(spread=float(mset.spread), levels=levels, omega=omega, members=mset.size,
                      unstable=unstable, envelope=envelope, envelope_all=errors.max(axis=0),
                      member_errors=errors[pick], weight=weight,
                      coverage=unc.coverage(weight, omega, envelope))


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
    check_type("view", view, SpreadView, "a SpreadView")
    if H_m is not None:
        check_siso("H_m", H_m)
    with mpl.rc_context(STYLE):
        fig, (ax,) = panel_figure(fig, 1, (7.0, 4.2))
        w = view.omega
        for k, err in enumerate(view.member_errors):
            ax.semilogx(w, curve_db(err), color="0.75", lw=0.5,
                        label="stable members (a selection)" if k == 0 else None)
        if view.n_unstable:
            ax.semilogx(w, curve_db(view.envelope_all), color=PALETTE.contrast, lw=0.9, ls=":",
                        label=f"envelope incl. {view.n_unstable} unstable members")
        ax.semilogx(w, curve_db(view.envelope), "k", lw=1.4, label="envelope E_m (stable members)")
        ax.semilogx(w, curve_db(magnitude(view.weight, w)), color=PALETTE.primary, lw=1.4,
                    label=f"fitted weight, order {_COVER_ORDER}")
        if H_m is not None:
            ax.semilogx(w, curve_db(magnitude(H_m, w)), color=PALETTE.highlight, ls="--", lw=1.4,
                        label="|H_m| (Table 2)")
        top = float(np.max(curve_db(view.envelope_all)))
        ax.set_ylim(-80, max(20.0, top + 10.0))
        ax.set_xlim(w[0], w[-1])
        ax.set_xlabel("frequency omega [rad/s]")
        ax.set_ylabel("relative error |G_k/G - 1| [dB]")
        # above the flat low-frequency level (~20 log10 spread) the left corner is empty;
        # below it the members' notches reach down
        ax.legend(loc="upper left")
        ax.set_title(_spread_summary(view, H_m).replace(";  ", "\n", 1))
    return apply_unit_text(fig)


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

    def view_of(value):
        """The view of one spread: ``start`` for its own, else computed."""
        if start is not None and np.isclose(value, start.spread):
            return start
        return spread_view(G, value, omega, levels)

    if not want_widget(interactive):
        return static_figure(draw_spread(view_of(spread), H_m))
    w = import_ipywidgets()
    slider = linear_slider(w, "spread", 100 * spread, 0.5, 10.0, 0.1,
                           description="spread +- [%]")
    slider.description = unit_text(slider.description)
    panel = LivePanel(w, {"spread": slider},
                      lambda values: view_of(values["spread"] / 100),
                      lambda view, fig: draw_spread(view, H_m, fig),
                      lambda view: _spread_summary(view, H_m))
    return finish(panel, panel.box())
