"""The paper's coefficient model set audited (notebook 02, Sec. III-B, Fig. 6, Table 2).

Eq. 5-8: each denominator coefficient a0 ... a5 of G takes three values, nominal and +-5 %,
which makes 729 models; the multiplicative weight H_m must cover their relative-error envelope
E_m, and the controller must keep every closed loop stable.  What is recomputed here:

* :func:`survey_model_set` -- the members, their poles and the unstable ones (where they
  cross the imaginary axis);
* :func:`envelope_peaks` -- the refined peak of E_m over the stable and over all members,
  against the maxima a plain grid finds;
* :func:`cover_envelope` -- the members' relative errors, the envelope, a fitted covering
  weight and how it and H_m cover the envelope (Fig. 6);
* :func:`compare_spreads` -- the same for other spreads (how far H_m lies from E_m);
* :func:`loop_margins` -- the exact parametric margin of a loop against the coefficient box,
  beside what the complex (small-gain) views certify;
* :func:`findings` -- the closing lines of the notebook that are not claim rows.

::

    from piezolib.problem import coefficient_set, paper

    survey = coefficient_set.survey_model_set(paper.plant(), 0.05, 3)
    survey.unstable.size
"""

from dataclasses import dataclass, field

import control as ct
import numpy as np
import pandas as pd

from piezolib import uncertainty as unc
from piezolib._checks import (check_finite_array, check_frequency_grid, check_integer,
                              check_integers, check_lti, check_positive, check_positive_values,
                              check_siso, check_type)
from piezolib.robust.lti import closed_loop_poles, frequency_grid

__all__ = ["GRID_SIZES", "COVER_ORDER", "KHARITONOV_SIGNS", "envelope_grid", "CoveredSpreads",
           "covered_spreads", "margin_gauges",
           "ModelSetSurvey", "survey_model_set", "EnvelopePeaks", "envelope_peaks",
           "EnvelopeCover", "cover_envelope", "SpreadComparison", "compare_spreads",
           "LoopMargins", "loop_margins", "critical_offsets_kind", "findings"]

#: Points of the plain grids (1 ... 1e6 rad/s) whose maxima of E_m are compared with its refined peak.
GRID_SIZES = (1000, 2000, 4000, 8000)
#: Order of the covering weight fitted to an envelope (that of H_m, eq. 8).
COVER_ORDER = 5
#: Sign patterns of the four Kharitonov polynomials in a0, a1, a2, a3 (period 4 in a_i).
KHARITONOV_SIGNS = ((1, 1, -1, -1), (-1, -1, 1, 1), (1, -1, -1, 1), (-1, 1, 1, -1))


def envelope_grid(points=2000):
    """The log grid 1 ... 1e6 rad/s of the relative-error envelope (notebook 02).

    Examples
    --------
    >>> w = envelope_grid(5)
    >>> float(w[0]), float(w[-1]), w.size
    (1.0, 1000000.0, 5)
    """
    return frequency_grid(1.0, 1e6, check_integer("points", points, minimum=2))


def _pct(spread):
    return f"±{100 * spread:.4g} %"


@dataclass(frozen=True)
class ModelSetSurvey:
    """The members of a coefficient model set, their poles and the unstable ones.

    Attributes
    ----------
    mset : piezolib.uncertainty.ModelSet
        The set (eq. 6).
    poles : ndarray, shape (M, n)
        Poles of every member [rad/s] (:func:`piezolib.uncertainty.member_poles`).
    unstable : ndarray of int
        Members with a pole in Re s >= 0.
    """

    mset: unc.ModelSet = field(repr=False)
    poles: np.ndarray = field(repr=False)
    unstable: np.ndarray

    def unstable_table(self):
        """The unstable members: their offsets q_i, largest real part and its |imaginary part|.

        Returns
        -------
        pandas.DataFrame
            Indexed by member; columns ``q0`` ... ``q{n-1}``, ``max Re(pole) [rad/s]`` and
            ``at |Im| [rad/s]`` (rounded to 0.1 and 1 rad/s).
        """
        u = self.unstable
        table = pd.DataFrame(self.mset.offsets[u].astype(int),
                             columns=[f"q{i}" for i in range(self.mset.order)], index=u)
        table["max Re(pole) [rad/s]"] = self.poles[u].real.max(axis=1).round(1)
        table["at |Im| [rad/s]"] = np.abs(
            self.poles[u, np.argmax(self.poles[u].real, axis=1)].imag).round(0)
        return table

    def crossings(self):
        """Where the unstable members cross the imaginary axis, against the least-damped
        pole pair of the nominal plant.

        Returns
        -------
        pandas.Series
            Rows without a value (no unstable member) are left out.
        """
        plant_poles = ct.poles(self.mset.plant)
        lightest = plant_poles[np.argmin(-plant_poles.real / np.abs(plant_poles))]
        crossing_at = self.unstable_table()["at |Im| [rad/s]"]
        return pd.Series({
            "unstable members": self.unstable.size,
            "least-damped plant pole, real part [rad/s]": lightest.real,
            "least-damped plant pole, |imaginary part| [rad/s]": abs(lightest.imag),
            "unstable members cross the axis from [rad/s]": crossing_at.min(),
            "... up to [rad/s]": crossing_at.max(),
            "largest |crossing / resonance - 1|":
                np.abs(crossing_at / abs(lightest.imag) - 1).max()},
            name=f"+-{100 * self.mset.spread:g} % set").dropna()

    @property
    def checks(self):
        """``{what it states: bool}`` (every study): the set's size, and the unstable members
        are those whose poles, recomputed one by one by python-control, say so."""
        recomputed = np.array([ct.poles(self.mset.member(i)).real.max()
                               for i in range(self.mset.size)])
        return {f"the set has {self.mset.levels}^{self.mset.order} members":
                    self.mset.size == self.mset.levels ** self.mset.order,
                "a member is unstable exactly when its recomputed poles say so":
                    bool(np.array_equal(np.flatnonzero(recomputed >= 0), self.unstable))}


def survey_model_set(G, spread, levels=3):
    """The coefficient model set of G for one spread, its poles and its unstable members.

    Parameters
    ----------
    G : control.LTI
        Nominal plant u_c [V] -> v_y [V].
    spread : float
        Relative spread of each denominator coefficient (0.05 for +-5 %).
    levels : int, optional
        Values per coefficient.

    Returns
    -------
    ModelSetSurvey

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> survey = survey_model_set(paper.plant(), 0.01, 2)
    >>> survey.mset.size, survey.unstable.size
    (64, 0)
    """
    mset = unc.model_set(G, spread, levels)
    return ModelSetSurvey(mset=mset, poles=unc.member_poles(mset),
                          unstable=unc.unstable_members(mset))


def _check_survey(survey):
    return check_type("survey", survey, ModelSetSurvey, "a ModelSetSurvey (survey_model_set)")


@dataclass(frozen=True)
class EnvelopePeaks:
    """The refined peak of E_m and the maxima plain grids find.

    Attributes
    ----------
    stable, all : tuple
        (peak, omega_peak [rad/s], member) over the stable and over all members
        (:func:`piezolib.uncertainty.envelope_peak`).
    damping : float
        Least damping ratio of the member that sets the stable peak.
    grid_maxima : dict
        {grid points: maximum of E_m (stable members) on a log grid 1 ... 1e6 rad/s}.
    """

    stable: tuple
    all: tuple
    damping: float
    grid_maxima: dict

    @property
    def width(self):
        """The -3 dB width 2 zeta omega of the resonance that sets the stable peak [rad/s]."""
        return 2 * self.damping * self.stable[1]

    def table(self):
        """The peak, its resonance and the grid maxima (the grid-independent value is the refined peak)."""
        grid_max = np.array(list(self.grid_maxima.values()))
        rows = {f"E_m on a {n}-point grid, maximum": value
                for n, value in self.grid_maxima.items()}
        return pd.Series({
            "least damping zeta of the peak member": self.damping,
            "its -3 dB resonance width [rad/s]": self.width,
            **rows,
            "grid maxima, smallest": grid_max.min(),
            "grid maxima, largest": grid_max.max(),
            "refined peak of E_m (stable members)": self.stable[0],
            "refined peak at [rad/s]": self.stable[1],
            "refined peak of E_m (all members)": self.all[0],
            "all members: at [rad/s]": self.all[1]}, name="E_m peak")


def envelope_peaks(survey, omega, grid_sizes=GRID_SIZES):
    """The refined peak of E_m over the stable and all members, and grid maxima beside it.

    Parameters
    ----------
    survey : ModelSetSurvey
    omega : array_like
        Grid [rad/s] the peak search starts from.
    grid_sizes : sequence of int, optional
        Points of the plain grids 1 ... 1e6 rad/s whose maxima are compared.

    Returns
    -------
    EnvelopePeaks
    """
    _check_survey(survey)
    omega = check_frequency_grid("omega", omega, min_length=16)
    grid_sizes = check_integers("grid_sizes", grid_sizes, minimum=2)
    mset = survey.mset
    stable = unc.envelope_peak(mset, omega, "stable")
    everyone = unc.envelope_peak(mset, omega, "all")
    damping = -np.cos(np.angle(survey.poles[stable[2]]))
    grid_maxima = {n: unc.relative_error_envelope(mset, frequency_grid(1.0, 1e6, n)).max()
                   for n in grid_sizes}
    return EnvelopePeaks(stable=stable, all=everyone, damping=float(damping.min()),
                         grid_maxima=grid_maxima)


@dataclass(frozen=True)
class EnvelopeCover:
    """Fig. 6: the members' relative errors, E_m, a fitted covering weight and H_m's coverage.

    Attributes
    ----------
    omega : ndarray
        Grid [rad/s].
    errors : ndarray, shape (M, len(omega))
        |G_k/G - 1| of every member.
    envelope : ndarray
        E_m over the stable members.
    weight : control.TransferFunction
        Stable, minimum-phase weight of order :data:`COVER_ORDER` fitted to ``envelope``.
    fit : piezolib.uncertainty.Coverage
        How ``weight`` covers the envelope.
    published : piezolib.uncertainty.Coverage
        How the given H_m covers it.
    """

    omega: np.ndarray = field(repr=False)
    errors: np.ndarray = field(repr=False)
    envelope: np.ndarray = field(repr=False)
    weight: ct.TransferFunction = field(repr=False)
    fit: unc.Coverage
    published: unc.Coverage

    @property
    def order(self):
        """Number of poles of the fitted weight."""
        return int(len(ct.poles(self.weight)))

    @property
    def checks(self):
        """``{what it states: bool}`` (every study): the fitted weight covers its envelope."""
        return {"the fitted weight covers the envelope on the grid": bool(self.fit.covers)}


def cover_envelope(survey, omega, H_m, order=COVER_ORDER):
    """The relative errors of the set, their envelope and the weights that cover it (Fig. 6).

    Parameters
    ----------
    survey : ModelSetSurvey
    omega : array_like
        Grid [rad/s].
    H_m : control.LTI
        The multiplicative weight to judge (eq. 8).
    order : int, optional
        Order of the fitted covering weight.

    Returns
    -------
    EnvelopeCover
    """
    _check_survey(survey)
    check_siso("H_m", H_m)
    omega = check_frequency_grid("omega", omega, min_length=16)
    errors = unc.relative_errors(survey.mset, omega)
    envelope = unc.relative_error_envelope(survey.mset, omega, "stable")
    weight = unc.fit_covering_weight(omega, envelope, order=order)
    return EnvelopeCover(omega=omega, errors=errors, envelope=envelope, weight=weight,
                         fit=unc.coverage(weight, omega, envelope),
                         published=unc.coverage(H_m, omega, envelope))


@dataclass(frozen=True)
class SpreadComparison:
    """E_m, H_m's coverage and a fitted weight for several spreads.

    Attributes
    ----------
    table : pandas.DataFrame
        Indexed by ``spread [%]``: unstable members, the refined peak of E_m, H_m's worst
        ratio |H_m|/E_m and where, the fitted weight's largest and mean excess [dB].
    fits : dict
        {spread: fitted covering weight}.
    """

    table: pd.DataFrame
    fits: dict = field(repr=False)

    @property
    def checks(self):
        """``{what it states: bool}`` (every study): every fitted weight is stable and minimum phase."""
        return {"every fitted weight is stable and minimum phase": all(
            bool(np.all(ct.poles(W).real < 0) and np.all(ct.zeros(W).real < 0))
            for W in self.fits.values())}


def compare_spreads(G, H_m, omega, spreads, survey, cover, peaks, order=COVER_ORDER):
    """How far H_m lies from E_m for several spreads, each with its own fitted weight.

    Parameters
    ----------
    G, H_m : control.LTI
        Nominal plant and the weight to judge.
    omega : array_like
        Grid [rad/s].
    spreads : sequence of float
        Spreads besides the survey's (each 0 < spread < 1).
    survey : ModelSetSurvey
        The study's set: its spread is in the table with ``cover`` and ``peaks``
        (not recomputed).
    cover : EnvelopeCover
        :func:`cover_envelope` of ``survey``.
    peaks : EnvelopePeaks
        :func:`envelope_peaks` of ``survey``.
    order : int, optional
        Order of the fitted weights.

    Returns
    -------
    SpreadComparison
    """
    _check_survey(survey)
    check_type("cover", cover, EnvelopeCover, "an EnvelopeCover (cover_envelope)")
    check_type("peaks", peaks, EnvelopePeaks, "an EnvelopePeaks (envelope_peaks)")
    omega = check_frequency_grid("omega", omega, min_length=16)
    spreads = check_positive_values("spreads", spreads, upper=1.0).tolist()
    order = check_integer("order", order, minimum=1)
    study_spread, levels = survey.mset.spread, survey.mset.levels
    rows, fits = [], {}
    for spread in sorted(set(spreads) | {study_spread}):
        if spread == study_spread:
            unstable, env, W = survey.unstable, cover.envelope, cover.weight
            peak, w_peak = peaks.stable[:2]
        else:
            s_set = unc.model_set(G, spread, levels)
            unstable = unc.unstable_members(s_set)
            env = unc.relative_error_envelope(s_set, omega, "stable")
            peak, w_peak, _ = unc.envelope_peak(s_set, omega, "stable")
            W = unc.fit_covering_weight(omega, env, order=order)
        fits[spread] = W
        published, fitted = unc.coverage(H_m, omega, env), unc.coverage(W, omega, env)
        rows.append({"spread [%]": 100 * spread, "unstable members": unstable.size,
                     "peak E_m (stable)": peak, "at [rad/s]": w_peak,
                     "H_m worst ratio": published.worst_ratio,
                     "H_m worst at [rad/s]": published.omega_worst,
                     "fit max excess [dB]": fitted.max_excess_dB,
                     "fit mean excess [dB]": fitted.mean_excess_dB})
    return SpreadComparison(table=pd.DataFrame(rows).set_index("spread [%]"), fits=fits)


@dataclass(frozen=True)
class LoopMargins:
    """A loop's exact margin against the coefficient box, and what the complex views certify.

    Attributes
    ----------
    margin : piezolib.uncertainty.ParametricMargin
        Exact margin of the closed loop (zero exclusion).
    open_loop : piezolib.uncertainty.ParametricMargin
        The largest spread with every member (open loop) stable.
    small_gain : piezolib.uncertainty.SpreadBracket
        Spread certified by small gain with the exact pointwise envelope.
    norm_HmT : float
        ||H_m T||_inf of the loop.
    weight : piezolib.uncertainty.SpreadBracket
        Spread certified by H_m (at most what it covers, provided ||H_m T||_inf < 1).
    unstable_loops : ndarray of int
        Members of the set whose closed loop with K is unstable.
    critical_pole : complex
        The pole of the critical member's closed loop closest to j omega* [rad/s].
    spread : float
        The set's spread.
    unstable_members : int
        Open-loop unstable members of the set.
    """

    margin: tuple
    open_loop: tuple
    small_gain: tuple
    norm_HmT: float
    weight: tuple
    unstable_loops: np.ndarray
    critical_pole: complex
    spread: float
    unstable_members: int

    @property
    def checks(self):
        """``{what it states: bool}`` (every study): the margins are consistent with the set
        and with each other, and the critical member's loop has poles on the axis."""
        m, ol = self.margin, self.open_loop
        return {
            "no member is unstable below the open-loop margin":
                self.spread >= ol.spread or self.unstable_members == 0,
            "no closed loop is unstable below the exact margin":
                self.spread >= m.spread or self.unstable_loops.size == 0,
            "the exact margin is bounded and above the open-loop one":
                bool(m.bounded and ol.spread < m.spread),
            "H_m certifies at most small gain, small gain less than the exact margin":
                bool(self.weight.lower <= self.small_gain.lower < m.spread),
            "the critical member's closed loop has a pole pair at +-j omega*":
                bool(abs(self.critical_pole.real) < 1e-3 * m.omega),
        }

    def spreads_table(self, covered, levels):
        """The spreads each view certifies, and the exact margin divided by each.

        Parameters
        ----------
        covered : piezolib.uncertainty.SpreadBracket
            The largest spread H_m covers (:func:`piezolib.uncertainty.largest_covered_spread`).
        levels : int
            Values per coefficient of the set ``covered`` refers to.

        Returns
        -------
        pandas.DataFrame
            Columns ``spread [%]`` and ``delta* / spread``.
        """
        spreads = pd.Series({"exact margin delta* (real, zero exclusion)": self.margin.spread,
                             "every member open-loop stable up to": self.open_loop.spread,
                             "small gain, exact envelope": self.small_gain.lower,
                             "published H_m": self.weight.lower,
                             f"covered by H_m ({levels}-level set)": covered.lower,
                             "the study's set": self.spread})
        return pd.DataFrame({"spread [%]": 100 * spreads,
                             "delta* / spread": self.margin.spread / spreads})


def loop_margins(G, K, H_m, survey, omega):
    """The exact parametric margin of the loop of G and K, and the complex views beside it.

    Parameters
    ----------
    G, K : control.LTI
        Nominal plant and controller.
    H_m : control.LTI
        Multiplicative weight (eq. 8).
    survey : ModelSetSurvey
        The set whose closed loops with K are checked member by member.
    omega : array_like
        Grid [rad/s] of the small-gain views.

    Returns
    -------
    LoopMargins
    """
    _check_survey(survey)
    check_siso("K", K)
    omega = check_frequency_grid("omega", omega, min_length=16)
    margin = unc.parametric_stability_margin(G, K)
    norm_HmT, bracket = unc.weight_certified_spread(H_m, G, K, omega)
    cl = closed_loop_poles(unc.perturbed_plant(G, margin.spread, margin.offsets), K)
    return LoopMargins(margin=margin, open_loop=unc.parametric_stability_margin(G),
                       small_gain=unc.small_gain_spread(G, K, omega), norm_HmT=float(norm_HmT),
                       weight=bracket, unstable_loops=unc.unstable_members(survey.mset, K),
                       critical_pole=cl[np.argmin(np.abs(cl - 1j * margin.omega))],
                       spread=float(survey.mset.spread),
                       unstable_members=int(survey.unstable.size))


@dataclass(frozen=True)
class CoveredSpreads:
    """The largest spreads a weight covers.

    Attributes
    ----------
    set : piezolib.uncertainty.SpreadBracket
        For the ``levels``-level set, its stable members.
    box : piezolib.uncertainty.SpreadBracket
        For the continuous box.
    levels : int
        Values per coefficient of ``set``.
    """

    set: tuple
    box: tuple
    levels: int

    def table(self, cover, spread):
        """The spreads covered and the worst ratio |H_m|/E_m at ``spread``.

        Parameters
        ----------
        cover : piezolib.uncertainty.Coverage
            The weight's coverage of the envelope at ``spread`` (``EnvelopeCover.published``).
        spread : float
            The spread ``cover`` refers to.

        Returns
        -------
        pandas.Series
        """
        return pd.Series({f"largest spread covered, {self.levels}-level set [%]":
                              100 * self.set.lower,
                          "largest spread covered, continuous box [%]": 100 * self.box.lower,
                          f"worst |H_m|/E_m at +-{100 * spread:g} %": cover.worst_ratio,
                          "worst ratio at [rad/s]": cover.omega_worst}, name="published H_m")


def covered_spreads(H_m, G, omega, levels=3):
    """The largest spreads the weight H_m covers: the ``levels``-level set and the continuous box.

    Parameters
    ----------
    H_m, G : control.LTI
        Weight and nominal plant.
    omega : array_like
        Grid [rad/s].
    levels : int, optional

    Returns
    -------
    CoveredSpreads
        By :func:`piezolib.uncertainty.largest_covered_spread`.
    """
    check_lti("H_m", H_m)
    omega = check_frequency_grid("omega", omega, min_length=16)
    return CoveredSpreads(
        set=unc.largest_covered_spread(H_m, G, omega, levels=levels, members="stable"),
        box=unc.largest_covered_spread(H_m, G, omega, levels=None), levels=levels)


def margin_gauges(G, K, omega=None):
    """The stability gauge of the closed loop and of the open loop (the figure of the margin).

    Parameters
    ----------
    G, K : control.LTI
        Plant and controller.
    omega : array_like, optional
        Grid [rad/s]; default 1e2 ... 1e6 rad/s, 3000 points.

    Returns
    -------
    omega : ndarray
    gauge, gauge_open : ndarray
        :func:`piezolib.uncertainty.stability_gauge` with K and without.
    """
    omega = frequency_grid(1e2, 1e6, 3000) if omega is None else check_frequency_grid(
        "omega", omega, min_length=16)
    return omega, unc.stability_gauge(G, K, omega), unc.stability_gauge(G, None, omega)


def critical_offsets_kind(offsets):
    """What the critical offsets q* of a margin are: a Kharitonov polynomial, a corner, or neither.

    Parameters
    ----------
    offsets : array_like
        q* in [-1, 1]^n (:attr:`ParametricMargin.offsets`).

    Returns
    -------
    str
        ``"a Kharitonov polynomial"`` (a corner with a sign pattern of
        :data:`KHARITONOV_SIGNS`), ``"a corner of the box"`` or ``"not a corner"``.

    Examples
    --------
    >>> critical_offsets_kind([1, 1, -1, -1, 1, 1]), critical_offsets_kind([1, 0.5, 1])
    ('a Kharitonov polynomial', 'not a corner')
    """
    offsets = check_finite_array("offsets", offsets, ndim=1, min_length=1, real=True)
    q = np.round(offsets).astype(int)
    corner = np.allclose(np.abs(offsets), 1, atol=1e-6)
    if corner and any(np.array_equal(q, np.resize(k, q.size)) for k in KHARITONOV_SIGNS):
        return "a Kharitonov polynomial"
    return "a corner of the box" if corner else "not a corner"


def findings(peaks, cover, margins, mu_RS_paper):
    """The notebook's closing findings that the claim rows do not state, one line each.

    Parameters
    ----------
    peaks : EnvelopePeaks
    cover : EnvelopeCover
    margins : LoopMargins
    mu_RS_paper : float
        The paper's mu_RS (Fig. 12(a)).

    Returns
    -------
    list of str
        Markdown lines: the resonance behind the peak of E_m, how the fitted weight covers,
        and how much less the complex views certify.
    """
    check_type("peaks", peaks, EnvelopePeaks, "an EnvelopePeaks")
    check_type("cover", cover, EnvelopeCover, "an EnvelopeCover")
    check_type("margins", margins, LoopMargins, "a LoopMargins")
    mu_RS_paper = check_positive("mu_RS_paper", mu_RS_paper)
    grid_max = np.array(list(peaks.grid_maxima.values()))
    yes = "yes" if cover.fit.covers else "no"
    return [
        f"peak of E_m over the stable members: {peaks.stable[0]:.4g} at "
        f"{peaks.stable[1]:.4g} rad/s (ζ = {peaks.damping:.4g}; grid maxima "
        f"{grid_max.min():.4g}–{grid_max.max():.4g})",
        f"order-{cover.order} weight fitted to that envelope covers it: {yes} — excess up to "
        f"{cover.fit.max_excess_dB:.4g} dB",
        f"complex views certify less: small gain {_pct(margins.small_gain.lower)}, H_m "
        f"{_pct(margins.weight.lower)} (‖H_m T‖∞ = {margins.norm_HmT:.4g}; paper μ_RS "
        f"{mu_RS_paper}) — δ* is {margins.margin.spread / margins.small_gain.lower:.4g}× "
        "the small-gain spread",
    ]
