"""The paper's coefficient box as real blocks: robust-stability margins and the mixed-mu design.

Notebook 09's analysis, for any controller of this stage's loop:

lft_exactness        the box as an exact upper LFT, checked against its polynomials and a member
stability_margins    per controller: the exact margin, mixed mu (real and complex blocks), the
                     small-gain certificates; their checks and claim rows
spread_bounds        mu_RS(omega) at one spread with real and complex blocks, against the exact
                     real mu (zero exclusion) and sum |m_i| (rank one)
recomputed_tradeoff  the mixed-mu designs' trade-off table, its margins recomputed and checked
check_chosen_design  the chosen mixed-mu controller: mu_RP with the exact delay, the box kept
                     stable by four methods, classical margins; its checks
mixed_claims         the claim rows of the chosen design (with its Case III tracking errors)
summary_lines        the findings of the notebook, one line each

Spreads are relative (0.045 = +-4.5 %), frequencies in rad/s.  Every result
with ``checks`` states what must hold as a dict {statement: bool}.
"""

import re
from dataclasses import dataclass, field
from functools import reduce

import numpy as np
import pandas as pd

from piezolib import uncertainty as unc
from piezolib._checks import check_integer, check_model, check_positive, check_siso, check_type
from piezolib.problem import mixed_end_points as end_points
from piezolib.problem import paper
from piezolib.problem.analysis import MARGIN_DELAYS, box_stability_table, margins_table
from piezolib.problem.design import MixedDesign, choose_mixed_design, tradeoff_table
from piezolib.problem.genplant import (DESIGN_DELAY_SAMPLES, delayed_parametric_loop_response,
                                       parametric_block_structure)
from piezolib.robust.export import SOSController
from piezolib.robust.lti import frequency_grid
from piezolib.robust.mu import mussv
from piezolib.uncertainty import parametric

__all__ = ["LFTExactness", "lft_exactness", "ControllerMargins", "BoxMargins",
           "stability_margins",
           "SpreadBounds", "spread_bounds", "MixedTradeoff", "recomputed_tradeoff",
           "ChosenDesignCheck", "check_chosen_design", "searched_end_points", "mixed_claims",
           "summary_lines",
           "LFT_CHECK_OMEGA", "MARGIN_GRID", "CERTIFICATE_GRID", "FIGURE_GRID", "PEAK_POINTS",
           "CHECK_GRIDS", "DEPLOYED", "MIXED"]

#: Frequencies [rad/s] at which the LFT is checked, with the critical frequency.
LFT_CHECK_OMEGA = (1e2, 1e3, 3e4)
#: Grid (omega_min, omega_max, points) of the mu margins [rad/s]: the peak is refined off it.
MARGIN_GRID = (1e2, 1e5, 120)
#: Grid of the small-gain and H_m certificates [rad/s].
CERTIFICATE_GRID = (1.0, 1e6, 2000)
#: Grid of the mu_RS bounds at one spread [rad/s] ...
FIGURE_GRID = (1e2, 1e5, 70)
#: ... and the extra points within +-15 % of the exact crossing.
PEAK_POINTS = 40
#: Grids whose union checks the chosen design's mu_RP with the exact delay [rad/s].
CHECK_GRIDS = ((1e-2, 1e7, 60), (1e3, 1e5, 360))
#: Random members of the box tried at each spread by the sampled loop's margin.
SAMPLED_MARGIN_SAMPLES = 300
#: Names of the two controllers the chosen design is checked beside.
DEPLOYED, MIXED = "our deployed K", "mixed-mu K"

_TOL = 1e-9          # bounds ordered up to rounding


def _pct(spread):
    return f"±{100 * spread:.4g} %"


def _grid(name, grid):
    """The logarithmic grid [rad/s] of a (omega_min, omega_max, points) tuple."""
    if not (isinstance(grid, (tuple, list)) and len(grid) == 3):
        raise TypeError(f"{name} must be a tuple (omega_min, omega_max, points) [rad/s], "
                        f"got {grid!r}"[:200])
    low = check_positive(f"{name} omega_min", grid[0])
    high = check_positive(f"{name} omega_max", grid[1])
    if high <= low:
        raise ValueError(f"{name} must run upwards: omega_max {high:g} <= omega_min {low:g} "
                         "[rad/s]")
    return frequency_grid(low, high, check_integer(f"{name} points", grid[2], minimum=3))


def _controllers(controllers):
    if not isinstance(controllers, dict) or not controllers:
        raise TypeError(f"controllers must be a non-empty dict {{name: K}}, got "
                        f"{controllers!r}"[:200])
    for name, K in controllers.items():
        check_model(f"controllers[{name!r}]", K, proper=True)
    return controllers


# -- the box as an exact upper LFT --------------------------------------------------------

@dataclass(frozen=True)
class LFTExactness:
    """The coefficient box of G as an upper LFT, checked (:func:`lft_exactness`).

    Attributes
    ----------
    blk : tuple
        The real scalar blocks ``(-1, 0)``, one per denominator coefficient.
    lft_error : float
        Largest |P_ss - P_poly| / max |P_poly| over the check frequencies: the
        state-space LFT against its polynomial formula.
    member_error : float
        Largest relative difference between F_u(P, diag(q*)) and the transfer
        function of the critical member q* of the exact margin.
    critical : piezolib.uncertainty.ParametricMargin
        The exact margin (zero exclusion) of the loop whose critical member is used.
    """

    blk: tuple
    lft_error: float
    member_error: float
    critical: object

    @property
    def checks(self):
        """{statement: holds}: the LFT is exact (not a first-order approximation)."""
        return {"the state-space LFT is its polynomial formula (to 1e-9)":
                    bool(self.lft_error < 1e-9),
                "the LFT closed with the critical offsets is that member (to 1e-8)":
                    bool(self.member_error < 1e-8)}

    def __str__(self):
        return (f"{len(self.blk)} real blocks {self.blk[0]}; state space vs polynomials: "
                f"{self.lft_error:.1e}; F_u(P, diag(q*)) vs the critical member: "
                f"{self.member_error:.1e}")


def lft_exactness(G, K):
    """Check the upper LFT of G's coefficient box on the critical member of the loop (G, K).

    The LFT :func:`piezolib.uncertainty.parametric.parametric_lft` is built at
    the exact margin delta* of the loop; its state space is compared with the
    polynomial formula :func:`~piezolib.uncertainty.parametric.parametric_response`,
    and F_u(P, diag(q*)) with the transfer function of the critical member q*
    (:func:`piezolib.uncertainty.perturbed_plant`), at :data:`LFT_CHECK_OMEGA`
    and the critical frequency.

    Parameters
    ----------
    G, K : control.LTI
        SISO plant u_c [V] -> v_y [V] and a controller that stabilises it
        (continuous time).

    Returns
    -------
    LFTExactness

    Examples
    --------
    >>> import control as ct
    >>> check = lft_exactness(ct.tf([1.0], [1.0, 0.8, 2.0, 1.0]), ct.tf([0.3], [1.0]))
    >>> all(check.checks.values()), len(check.blk), round(check.critical.spread, 4)
    (True, 3, 0.0735)
    """
    check_model("G", G, proper=True)
    check_model("K", K, proper=True)
    exact = unc.parametric_stability_margin(G, K)
    lft = parametric.parametric_lft(G, exact.spread)
    w = np.array([*LFT_CHECK_OMEGA[:2], exact.omega, *LFT_CHECK_OMEGA[2:]])
    P_ss = np.moveaxis(lft.P(1j * w), -1, 0)               # (nf, n + 1, n + 1)
    P_poly = parametric.parametric_response(G, exact.spread, w)
    n = len(lft.blk)
    Delta = np.diag(exact.offsets)
    closed = [P[n, n] + P[n, :n] @ Delta @ np.linalg.solve(np.eye(n) - P[:n, :n] @ Delta, P[:n, n])
              for P in P_ss]
    member = np.ravel(unc.perturbed_plant(G, exact.spread, exact.offsets)(1j * w))
    return LFTExactness(
        blk=tuple(lft.blk), critical=exact,
        lft_error=float(np.max(np.abs(P_ss - P_poly)) / np.max(np.abs(P_poly))),
        member_error=float(np.max(np.abs(np.array(closed) - member) / np.abs(member))))


# -- robust-stability margins per controller ------------------------------------------------

@dataclass(frozen=True)
class ControllerMargins:
    """How much of the coefficient box one controller keeps stable, by six methods.

    Attributes
    ----------
    exact : piezolib.uncertainty.ParametricMargin
        The exact margin (zero exclusion).
    real, complex : piezolib.uncertainty.parametric.MuMargin
        mu of the loop matrix with real blocks (the true structure) and with complex ones.
    small_gain : piezolib.uncertainty.SpreadBracket
        The small-gain certificate of the exact pointwise envelope.
    norm_HmT : float
        ||H_m T||_inf.
    hm : piezolib.uncertainty.SpreadBracket
        The spread the published weight H_m certifies.
    omega : ndarray
        The mu grid [rad/s].
    """

    exact: object
    real: object
    complex: object
    small_gain: object
    norm_HmT: float
    hm: object
    omega: np.ndarray

    @property
    def bracket(self):
        """Largest relative distance [-] of the two real-block bounds from the exact margin."""
        return max(abs(self.real.spread / self.exact.spread - 1),
                   abs(self.real.spread_upper / self.exact.spread - 1))

    @property
    def checks(self):
        """{statement: holds}: real mu is the exact margin; the relaxations certify less."""
        exact, real, cplx = self.exact, self.real, self.complex
        return {
            "mixed mu (real blocks) is the exact margin (to 0.1 %)":
                abs(real.spread - exact.spread) <= 1e-3 * exact.spread,
            "the real upper bound certifies no more than the exact margin":
                real.spread <= exact.spread * (1 + 1e-6),
            "the real lower bound has a destabilising member at the exact margin":
                exact.spread <= real.spread_upper * (1 + 1e-6),
            "the real-mu peak is at the critical frequency (to 0.1 %)":
                abs(real.omega - exact.omega) < 1e-3 * exact.omega,
            "complex blocks on the same LFT certify less than 90 % of it":
                cplx.spread < 0.9 * real.spread,
            "H_m certifies at most the exact envelope, which certifies less than real mu":
                self.hm.lower <= self.small_gain.lower < real.spread,
            "the critical frequency lies inside the mu grid":
                self.omega[0] < exact.omega < self.omega[-1]}


@dataclass(frozen=True)
class BoxMargins:
    """The margins of several controllers against the coefficient box (:func:`stability_margins`).

    Attributes
    ----------
    controllers : dict
        {name: ControllerMargins}, in the order given.
    """

    controllers: dict

    def table(self):
        """One row per controller: the spreads [%] of each method, ||H_m T||_inf and the
        critical frequencies [rad/s]."""
        return pd.DataFrame([{
            "controller": name, "exact [%]": 100 * r.exact.spread,
            "mixed mu, real: certified [%]": 100 * r.real.spread,
            "real: destabilised at [%]": 100 * r.real.spread_upper,
            "mu, complex: certified [%]": 100 * r.complex.spread,
            "small gain, exact envelope [%]": 100 * r.small_gain.lower,
            "H_m certificate [%]": 100 * r.hm.lower, "||H_m T||inf": r.norm_HmT,
            "omega exact [rad/s]": r.exact.omega, "omega real mu [rad/s]": r.real.omega,
            "omega complex mu [rad/s]": r.complex.omega}
            for name, r in self.controllers.items()]).set_index("controller")

    def comparison(self):
        """One column per controller: the real bounds against the exact margin, and the
        real-block margin over each certificate [-]."""
        return pd.DataFrame({name: {
            "real bounds vs exact margin (relative)": r.bracket,
            "real / complex blocks": r.real.spread / r.complex.spread,
            "real / small gain (exact envelope)": r.real.spread / r.small_gain.lower,
            "real / H_m certificate": r.real.spread / r.hm.lower}
            for name, r in self.controllers.items()})

    @property
    def checks(self):
        """Every controller's :attr:`ControllerMargins.checks`, named ``"<controller>: ..."``."""
        return {f"{name}: {what}": bool(holds) for name, r in self.controllers.items()
                for what, holds in r.checks.items()}

    def claims(self):
        """Claim rows (keyword arguments of ``ClaimTable.add``), six per controller."""
        rows = []
        for name, r in self.controllers.items():
            note = (f"at {r.real.omega:.0f} rad/s; exact {r.exact.spread:.6f} at "
                    f"{r.exact.omega:.0f} rad/s")
            rows += [
                _claim("IV", f"{name}: spread certified by mixed mu (real blocks)", r.real.spread,
                       unit="-", note=note + "; paper: robustly stable at +-5 %"),
                _claim("IV", f"{name}: spread with a destabilising member (real lower bound)",
                       r.real.spread_upper, unit="-"),
                _claim("IV", f"{name}: exact parametric margin (zero exclusion)", r.exact.spread,
                       unit="-"),
                _claim("IV", f"{name}: spread certified by mu (complex blocks)", r.complex.spread,
                       unit="-", note=f"same LFT, peak at {r.complex.omega:.0f} rad/s"),
                _claim("IV", f"{name}: spread certified by small gain (exact envelope)",
                       r.small_gain.lower, unit="-"),
                _claim("III-B", f"{name}: spread certified by H_m", r.hm.lower, unit="-",
                       note=f"||H_m T||inf = {r.norm_HmT:.4f}")]
        return rows


def _claim(section, quantity, ours, **options):
    """A claim row without a published number."""
    return dict(section=section, quantity=quantity, paper=None, ours=ours, **options)


def stability_margins(G, H_m, controllers, grid=MARGIN_GRID, certificate_grid=CERTIFICATE_GRID,
                      *, exact=None):
    """The margins of each controller against G's coefficient box, by six methods.

    Per controller: the exact margin (zero exclusion,
    :func:`piezolib.uncertainty.parametric_stability_margin`); mixed mu of the
    loop matrix with real blocks and with complex ones
    (:func:`piezolib.uncertainty.parametric.mu_stability_margin`, the grid bounded for
    its peak only, the peak refined off the grid); the small-gain certificate of the exact envelope
    (:func:`~piezolib.uncertainty.small_gain_spread`) and of the weight H_m
    (:func:`~piezolib.uncertainty.weight_certified_spread`).

    Parameters
    ----------
    G, H_m : control.LTI
        Plant u_c [V] -> v_y [V] and the multiplicative uncertainty weight.
    controllers : dict
        {name: K}: continuous controllers v_e [V] -> u_b [V] that stabilise G.
    grid, certificate_grid : tuple
        (omega_min, omega_max, points) [rad/s] of the mu margins and of the certificates.
    exact : dict, optional
        {name: ParametricMargin} already computed (e.g. ``lft_exactness(G, K).critical``).

    Returns
    -------
    BoxMargins
    """
    check_model("G", G, proper=True)
    check_model("H_m", H_m, proper=True)
    controllers = _controllers(controllers)
    exact = {} if exact is None else check_type("exact", exact, dict, "a dict {name: margin}")
    omega, omega_cert = _grid("grid", grid), _grid("certificate_grid", certificate_grid)
    results = {}
    for name, K in controllers.items():
        margin = exact[name] if name in exact else unc.parametric_stability_margin(G, K)
        norm_HmT, hm = unc.weight_certified_spread(H_m, G, K, omega_cert)
        results[name] = ControllerMargins(
            exact=margin, omega=omega,
            real=parametric.mu_stability_margin(G, K, omega, real=True, peak=True),
            complex=parametric.mu_stability_margin(G, K, omega, real=False, peak=True),
            small_gain=unc.small_gain_spread(G, K, omega_cert), norm_HmT=norm_HmT, hm=hm)
    return BoxMargins(results)


# -- mu_RS(omega) at one spread ---------------------------------------------------------

@dataclass(frozen=True)
class SpreadBounds:
    """mu_RS(omega) of one loop at one spread (:func:`spread_bounds`).

    Attributes
    ----------
    name : str
        The controller's name.
    spread : float
        The spread [-] the bounds are at.
    omega : ndarray
        Frequencies [rad/s]: the grid and the points around the exact crossing.
    real, complex : piezolib.robust.mu.MuResult
        Bounds with real and with complex scalar blocks.
    exact_real : ndarray
        Exact real mu, spread / stability gauge (zero exclusion, no ``mussv``).
    exact_complex : ndarray
        Exact complex mu, sum |m_i| (rank-one M, scalar blocks).
    critical : piezolib.uncertainty.ParametricMargin
        The loop's exact margin.
    """

    name: str
    spread: float
    omega: np.ndarray
    real: object
    complex: object
    exact_real: np.ndarray
    exact_complex: np.ndarray
    critical: object

    def table(self):
        """The peaks and the bounds' distances from the exact values (a Series)."""
        gap = (self.real.upper - self.real.lower) / self.real.upper
        excess = self.real.upper / self.exact_real - 1
        k_gap, k_excess = int(np.argmax(gap)), int(np.argmax(excess))
        return pd.Series({
            "exact real mu at the crossing (spread / delta*)": self.spread / self.critical.spread,
            "real upper bound, peak on the grid": self.real.upper.max(),
            "real lower bound, peak on the grid": self.real.lower.max(),
            "complex upper bound, peak on the grid": self.complex.upper.max(),
            "real bounds, largest gap (relative)": gap[k_gap],
            "real bounds, largest gap at [rad/s]": self.omega[k_gap],
            "real lower bound vs exact mu, at most (relative)":
                np.max(np.abs(self.real.lower / self.exact_real - 1)),
            "complex upper bound vs sum |m_i|, at most (relative)":
                np.max(np.abs(self.complex.upper / self.exact_complex - 1)),
            "real upper bound above the exact mu, at most (relative)": excess[k_excess],
            "real upper bound, largest excess at [rad/s]": self.omega[k_excess],
            "exact real mu at the largest excess": self.exact_real[k_excess]},
            name=f"{self.name} at +-{100 * self.spread:g} %")

    @property
    def checks(self):
        """{statement: holds}: the bounds are ordered and match the exact values; the loop is
        not robustly stable at this spread when its exact margin is smaller."""
        real, cplx = self.real, self.complex
        return {
            f"{self.name} is not robustly stable at +-{100 * self.spread:g} %: exact margin below, "
            "real lower bound above 1":
                bool(self.critical.spread < self.spread and real.lower.max() > 1),
            "real blocks: lower <= upper": bool(np.all(real.lower <= real.upper * (1 + _TOL))),
            "complex blocks: lower <= upper": bool(np.all(cplx.lower <= cplx.upper * (1 + _TOL))),
            "real upper <= complex upper": bool(np.all(real.upper <= cplx.upper * (1 + _TOL))),
            "the real lower bound is the exact real mu (to 1e-6)":
                bool(np.allclose(real.lower, self.exact_real, rtol=1e-6)),
            "the real upper bound is at or above the exact real mu":
                bool(np.all(real.upper >= self.exact_real * (1 - 1e-6))),
            "the complex bounds are sum |m_i| (to 1e-6)":
                bool(np.allclose(cplx.upper, self.exact_complex, rtol=1e-6)
                     and np.allclose(cplx.lower, self.exact_complex, rtol=1e-6))}

    def claims(self):
        """Claim rows: the peaks of the real and the complex upper bound."""
        at = f"{self.name}: peak mu_RS at +-{100 * self.spread:g} %"
        return [_claim("IV", f"{at}, real blocks (upper)", float(self.real.upper.max()),
                       note="> 1: not robustly stable for the paper's set"),
                _claim("IV", f"{at}, complex blocks (upper)", float(self.complex.upper.max()))]


def spread_bounds(G, K, spread, critical, grid=FIGURE_GRID, peak_points=PEAK_POINTS, *,
                  name="published K"):
    """mu_RS(omega) of the loop (G, K) at ``spread``, real blocks against complex ones.

    The mu peak is sharp (a lightly damped crossing): ``peak_points`` extra
    frequencies lie within +-15 % of the exact crossing.

    Parameters
    ----------
    G, K : control.LTI
        Plant and stabilising controller (continuous time).
    spread : float
        Relative spread [-] of the box.
    critical : piezolib.uncertainty.ParametricMargin
        The loop's exact margin (its ``omega`` places the extra points).
    grid : tuple
        (omega_min, omega_max, points) [rad/s].
    peak_points : int
    name : str
        The controller's name in the checks and claims.

    Returns
    -------
    SpreadBounds
    """
    check_siso("G", check_model("G", G, proper=True))
    check_siso("K", check_model("K", K, proper=True))
    spread = check_positive("spread", spread)
    check_type("critical", critical, unc.ParametricMargin, "a ParametricMargin")
    check_type("name", name, str, "a str (the controller's name)")
    peak_points = check_integer("peak_points", peak_points, minimum=0)
    omega = np.union1d(_grid("grid", grid),
                       critical.omega * np.linspace(0.85, 1.15, peak_points))
    M = parametric.parametric_loop_response(G, K, spread, omega)
    n = M.shape[1]
    return SpreadBounds(name=name, spread=spread, omega=omega, critical=critical,
                        real=mussv(M, [(-1, 0)] * n, omega), complex=mussv(M, [(1, 1)] * n, omega),
                        exact_real=spread / unc.stability_gauge(G, K, omega),
                        exact_complex=np.abs(M[:, 0, :]).sum(axis=1))


# -- the mixed-mu designs -----------------------------------------------------------------

@dataclass(frozen=True)
class MixedTradeoff:
    """The mixed-mu trade-off, recomputed (:func:`recomputed_tradeoff`).

    Attributes
    ----------
    table : pandas.DataFrame
        :func:`piezolib.problem.design.tradeoff_table` (index: performance scale).
    chosen : MixedDesign or None
        :func:`~piezolib.problem.design.choose_mixed_design`.
    checks : dict
        {statement: holds}: the margins recomputed from each controller are the design's.
    """

    table: pd.DataFrame
    chosen: object
    checks: dict

    def margins(self):
        """{"delay d": exact margins [-] per design} (the figure's panel b)."""
        return {f"delay {d}": self.table[f"exact margin, delay {d} [%]"] / 100
                for d in MARGIN_DELAYS}


def recomputed_tradeoff(designs, G, H_e, H_y, fs, *, committed=True):
    """The trade-off of the mixed designs, its exact margins recomputed from the controllers.

    The bound no controller can cross at each scale (an H-infinity search, shown but not
    asserted) is the committed one where :mod:`~piezolib.problem.mixed_end_points` holds
    the design's problem, else computed.

    Parameters
    ----------
    designs : sequence of MixedDesign
    G, H_e, H_y : control.LTI
        The problem the designs were made for.
    fs : float
        Loop rate [Hz].
    committed : bool
        Read the committed bounds (False: compute every one).

    Returns
    -------
    MixedTradeoff
    """
    if not isinstance(designs, (list, tuple)):
        raise TypeError(f"designs must be a list or tuple of MixedDesign, got "
                        f"{type(designs).__name__}")
    fs = check_positive("fs", fs)
    bounds = end_points.committed_bounds(designs, G, H_e, H_y, fs) if committed else None
    table = tradeoff_table(designs, G, H_e, H_y, fs, bounds=bounds)
    same = all(abs(table.loc[d.performance_scale, f"exact margin, delay {k} [%]"] / 100 - m)
               <= 1e-6 * m for d in designs for k, m in d.margins.items())
    return MixedTradeoff(table=table, chosen=choose_mixed_design(designs), checks={
        "the exact margins recomputed from each controller are the design's (to 1e-6)": same})


@dataclass(frozen=True)
class ChosenDesignCheck:
    """The chosen mixed-mu design checked independently (:func:`check_chosen_design`).

    Attributes
    ----------
    design : MixedDesign or None
        None when no design is certified for the box (the tables are then empty).
    spread : float
        The box [-] it must keep stable.
    omega : ndarray
        The grid [rad/s] of the mu check.
    mu_rp, mu_rs : piezolib.robust.mu.MuResult or None
        Mixed mu_RP and mu_RS with the exact delay, bounded for their peaks
        (``mussv(..., peak=True)``: the arrays are valid bounds at every frequency, tight
        where a frequency could set the peak; mu_RS without its lower bound).
    box : pandas.DataFrame
        :func:`piezolib.problem.analysis.box_stability_table`, one column per controller.
    margins : pandas.DataFrame
        :func:`piezolib.problem.analysis.margins_table`, one column per controller.
    delay_samples : int
        The design's computation delay [samples].
    sampled : dict
        {name: {d: piezolib.uncertainty.SampledMargin}}: the sampled loop's parametric
        margin (exact ZOH members, the float32 sections, z^-d) of each controller.
    """

    design: object
    spread: float
    omega: np.ndarray
    mu_rp: object
    mu_rs: object
    box: pd.DataFrame
    margins: pd.DataFrame
    delay_samples: int
    sampled: dict = field(default_factory=dict)

    def margin(self, delay):
        """The mixed-mu K's continuous stand-in margin [-]: zero exclusion on the continuous
        loop with the effective delay (d + 1/2) / fs for ``delay`` samples."""
        return self.box.loc[f"exact margin, delay {delay} [%]", MIXED] / 100

    def sampled_margin(self, delay, name=MIXED):
        """The sampled loop's parametric margin [-] of ``name`` with ``delay`` samples."""
        return self.sampled[name][delay].spread

    def unstable(self, delay):
        """(members of the grid, members whose sampled loop with ``delay`` samples of delay is
        unstable) of the mixed-mu K."""
        for row in self.box.index:
            found = re.fullmatch(rf"unstable of (\d+), sampled, delay {delay}", row)
            if found:
                return int(found.group(1)), self.box.loc[row, MIXED]
        raise KeyError(f"no sampled-loop row with delay {delay} in the box table")

    def table(self):
        """mu_RP (exact delay and the design's Pade model) and mu_RS of the chosen design."""
        if self.design is None:
            return pd.Series(dtype=float, name="no design certified for the box")
        return pd.Series({"performance scale": self.design.performance_scale,
                          "frequencies": self.omega.size,
                          "mu_RP upper, exact delay": self.mu_rp.upper.max(),
                          "mu_RP lower, exact delay": self.mu_rp.lower.max(),
                          "mu_RP upper, design (Pade)": self.design.mu_peak,
                          "mu_RS upper, exact delay": self.mu_rs.upper.max()},
                         name="chosen mixed-mu design")

    @property
    def checks(self):
        """{statement: holds}: the certificate of the chosen design."""
        if self.design is None:
            return {"a mixed-mu design is certified for the box": False}
        margin = self.margin(self.delay_samples)
        sampled = self.sampled[MIXED][self.delay_samples]
        return {
            f"the sampled loop with the loop's delay keeps the +-{100 * self.spread:g} % box "
            "(every vertex, edge point and sampled member tried)":
                bool(sampled.spread >= self.spread),
            "the sampled loop's margin is bracketed by a destabilising member within 0.2 %":
                bool(sampled.bounded and sampled.radius >= 1
                     and sampled.spread_unstable <= sampled.spread * 1.002),
            f"the continuous stand-in margin covers the +-{100 * self.spread:g} % box":
                bool(margin >= self.spread),
            "mu_RS with the exact delay is within 0.1 % of spread / margin (or below)":
                bool(self.mu_rs.upper.max() <= self.spread / margin * (1 + 1e-3)),
            "mu_RP: lower <= upper": bool(np.all(self.mu_rp.lower <= self.mu_rp.upper * (1 + _TOL))),
            "the nominal loop is stable with 0-3 samples of delay":
                bool(min(self.margin(d) for d in MARGIN_DELAYS) > 0)}


def check_chosen_design(design, deployed, sections, G, H_e, H_y, fs, grids=CHECK_GRIDS, *,
                        spread=None, delay_samples=DESIGN_DELAY_SAMPLES, committed=True):
    """Check the chosen mixed-mu design independently, beside the deployed controller.

    Mixed mu_RP on the union of ``grids`` with the **exact** delay e^{-j omega tau}
    instead of the design's Pade model
    (:func:`piezolib.problem.genplant.delayed_parametric_loop_response`) and
    mu_RS of its six real blocks; the box kept stable by four methods
    (:func:`~piezolib.problem.analysis.box_stability_table`) and the classical
    margins (:func:`~piezolib.problem.analysis.margins_table`) of both
    controllers (columns :data:`DEPLOYED`, :data:`MIXED`).

    Parameters
    ----------
    design : MixedDesign or None
        The chosen design (None: no design certified; only the deployed K is tabulated).
    deployed : control.LTI
        Our deployed continuous controller v_e [V] -> u_b [V].
    sections : dict
        {DEPLOYED: SOSController, MIXED: SOSController or None}: the float32
        sections the target runs.
    G, H_e, H_y : control.LTI
        The study's plant and tracking weights.
    fs : float
        Loop rate [Hz].
    grids : sequence of tuple
        (omega_min, omega_max, points) [rad/s] of the mu check.
    spread : float, optional
        The box [-]; default the paper's ``paper.UNCERTAINTY_SPREAD``.
    delay_samples : int
        Computation delay [samples] of the design.
    committed : bool
        Start each sampled-loop margin from its committed bracket
        (:mod:`~piezolib.problem.mixed_end_points`), verified here; False: search every one.

    Returns
    -------
    ChosenDesignCheck
    """
    if design is not None:
        check_type("design", design, MixedDesign, "a MixedDesign or None")
    check_model("deployed", deployed, proper=True)
    check_type("sections", sections, dict, "a dict {name: SOSController}")
    if not isinstance(sections.get(DEPLOYED), SOSController):
        raise TypeError(f"sections[{DEPLOYED!r}] must be the deployed SOSController")
    if design is not None and not isinstance(sections.get(MIXED), SOSController):
        raise TypeError(f"sections[{MIXED!r}] must be the chosen design's SOSController")
    spread = paper.UNCERTAINTY_SPREAD if spread is None else check_positive("spread", spread)
    for label, sys in (("G", G), ("H_e", H_e), ("H_y", H_y)):
        check_siso(label, check_model(label, sys, proper=True))
    fs = check_positive("fs", fs)              # before the mu bounds, which take seconds
    delay_samples = check_integer("delay_samples", delay_samples, minimum=0)
    if not isinstance(committed, bool):
        raise TypeError(f"committed must be True or False, got {committed!r}")
    if isinstance(grids, str) or not hasattr(grids, "__len__") or len(grids) == 0:
        raise TypeError(f"grids must be a non-empty sequence of (omega_min, omega_max, points), "
                        f"got {grids!r}"[:200])
    omega = reduce(np.union1d, [_grid("grids", g) for g in grids])
    pairs = {DEPLOYED: (deployed, sections[DEPLOYED].to_statespace("float32"))}
    mu_rp = mu_rs = None
    if design is not None:
        pairs[MIXED] = (design.K, sections[MIXED].to_statespace("float32"))
        M = delayed_parametric_loop_response(
            design.K, G, design.performance_scale * H_e, design.performance_scale * H_y,
            design.spread, omega, fs=fs, delay_samples=delay_samples)
        n = M.shape[2] - 1                                  # one real block per coefficient
        blk = parametric_block_structure(n)
        # only the peaks are claimed: bound where a frequency can set them
        mu_rp = mussv(M, blk, omega, peak=True)
        mu_rs = mussv(M[:, :n, :n], blk[:n], omega, lower=False, peak=True)
    sampled = {name: {d: _sampled_margin(G, Kd, d, committed) for d in MARGIN_DELAYS}
               for name, (_, Kd) in pairs.items()}
    box = box_stability_table(pairs, G, spread, fs)
    box = pd.concat([pd.DataFrame({name: {f"sampled-loop margin, delay {d} [%]": 100 * m.spread
                                          for d, m in by_delay.items()}
                                   for name, by_delay in sampled.items()}), box])
    return ChosenDesignCheck(
        design=design, spread=spread, omega=omega, mu_rp=mu_rp, mu_rs=mu_rs,
        delay_samples=delay_samples, box=box,
        margins=margins_table({name: K for name, (K, _) in pairs.items()}, G, fs),
        sampled=sampled)


def _sampled_margin(G, Kd, delay, committed):
    """The sampled loop's margin with ``delay`` samples, from the committed bracket if any."""
    known = end_points.committed_bracket(G, Kd, delay, SAMPLED_MARGIN_SAMPLES) \
        if committed else None
    return unc.sampled_parametric_margin(G, Kd, delay, samples=SAMPLED_MARGIN_SAMPLES,
                                         known=known)


def searched_end_points(designs, deployed, sections, G, H_e, H_y, fs):
    """Notebook 09's search end points derived from scratch, for
    :func:`piezolib.problem.mixed_end_points.write_end_points`.

    Parameters
    ----------
    designs : sequence of MixedDesign
        The trade-off's designs (their bounds).
    deployed, sections, G, H_e, H_y, fs
        As :func:`check_chosen_design`; the chosen design is
        :func:`~piezolib.problem.design.choose_mixed_design` of ``designs``.

    Returns
    -------
    bounds : dict
        {key: the bound no controller can cross} per design.
    margins : dict
        {key: SampledMargin} per controller and delay.
    """
    if not isinstance(designs, (list, tuple)):
        raise TypeError(f"designs must be a list or tuple of MixedDesign, got "
                        f"{type(designs).__name__}")
    fs = check_positive("fs", fs)
    chosen = check_chosen_design(choose_mixed_design(designs), deployed, sections, G, H_e,
                                 H_y, fs, grids=((1e3, 1e5, 3),), committed=False)
    table = tradeoff_table(designs, G, H_e, H_y, fs)
    bounds = {end_points.bound_key(G, H_e, H_y, d.performance_scale, d.spread, fs):
              float(table.loc[d.performance_scale, "no controller below"]) for d in designs}
    kd = {DEPLOYED: sections[DEPLOYED].to_statespace("float32")}
    if chosen.design is not None:
        kd[MIXED] = sections[MIXED].to_statespace("float32")
    margins = {end_points.margin_key(G, kd[name], d, SAMPLED_MARGIN_SAMPLES): m
               for name, by_delay in chosen.sampled.items() for d, m in by_delay.items()}
    return bounds, margins


# -- claims and the closing summary -------------------------------------------------------

def _case_III(tracking, name=MIXED):
    """(largest Case III error up to 10 Hz, Case III error at 50 Hz) [%] of ``name``."""
    row = tracking.loc[f"Case III, {name}"]
    return float(row[[f for f in row.index if f <= 10]].max()), float(row[50])


def mixed_claims(chosen, tracking):
    """Claim rows of the chosen mixed-mu design: its exact margins and unstable members per
    delay, mu_RP with the exact delay, its Case III tracking errors (none without a design).

    Parameters
    ----------
    chosen : ChosenDesignCheck
    tracking : pandas.DataFrame
        Tracking errors [%] with a row ``"Case III, mixed-mu K"`` and columns in Hz
        (including 50 and some up to 10).

    Returns
    -------
    list of dict
        Keyword arguments of ``ClaimTable.add``.
    """
    check_type("chosen", chosen, ChosenDesignCheck, "a ChosenDesignCheck")
    check_type("tracking", tracking, pd.DataFrame, "a pandas DataFrame")
    if chosen.design is None:
        return []
    rows = []
    for d in MARGIN_DELAYS:
        members, unstable = chosen.unstable(d)
        sampled = chosen.sampled[MIXED][d]
        rows += [_claim("IV", f"{MIXED}: sampled-loop parametric margin, delay {d}",
                        sampled.spread, unit="-",
                        note=f"exact ZOH members, float32 sections, z^-{d}: vertices, edges, "
                             f"{SAMPLED_MARGIN_SAMPLES} sampled members stable; a member "
                             f"unstable at {sampled.spread_unstable:.5f}"),
                 _claim("IV", f"{MIXED}: continuous stand-in margin, delay {d}",
                        chosen.margin(d), unit="-",
                        note="zero exclusion on the continuous loop with the delay "
                             "(d + 1/2) / fs standing in for the sampled loop"),
                 _claim("IV", f"{MIXED}: unstable of {members}, sampled loop, delay {d}",
                        unstable, note="exact ZOH members, float32 sections")]
    goal_10, at_50 = _case_III(tracking)
    return rows + [
        _claim("IV", f"{MIXED}: mu_RP with the exact delay (upper)",
               float(chosen.mu_rp.upper.max()),
               note=f"performance scale {chosen.design.performance_scale} on H_e, H_y"),
        _claim("V", f"{MIXED}: Case III tracking error up to 10 Hz", goal_10, unit="%",
               note="goal < 1 %"),
        _claim("V", f"{MIXED}: Case III tracking error at 50 Hz", at_50, unit="%",
               note="goal < 5 %")]


def summary_lines(lft, margins, bounds, chosen, tracking, published="published K"):
    """The notebook's findings, one Markdown line each (before the claim rows).

    Parameters
    ----------
    lft : LFTExactness
    margins : BoxMargins
        With the published controller ``published`` (and optionally :data:`DEPLOYED`).
    bounds : SpreadBounds
    chosen : ChosenDesignCheck
    tracking : pandas.DataFrame
        As in :func:`mixed_claims`.
    published : str
        The published controller's name in ``margins``.

    Returns
    -------
    list of str
    """
    check_type("lft", lft, LFTExactness, "an LFTExactness")
    check_type("margins", margins, BoxMargins, "a BoxMargins")
    check_type("bounds", bounds, SpreadBounds, "a SpreadBounds")
    check_type("chosen", chosen, ChosenDesignCheck, "a ChosenDesignCheck")
    check_type("tracking", tracking, pd.DataFrame, "a pandas DataFrame")
    check_type("published", published, str, "a str (the published controller's name)")
    if published not in margins.controllers:
        raise ValueError(f"published {published!r} is not a controller of margins "
                         f"({sorted(margins.controllers)})")
    pub = margins.controllers[published]
    real, exact, stated = pub.real, pub.exact, paper.UNCERTAINTY_SPREAD
    lines = [
        f"the LFT is exact: state space vs polynomials {lft.lft_error:.1e}, critical member "
        f"reproduced to {lft.member_error:.1e}",
        f"{published}, real blocks: μ certifies {_pct(real.spread)}, destabilised at "
        f"{_pct(real.spread_upper)} — the exact margin {_pct(exact.spread)} within "
        f"{pub.bracket:.1e}, at {exact.omega:.4g} rad/s",
        f"paper's {_pct(stated)} robustly stable for the real set: "
        f"{'yes' if exact.spread >= stated else 'no'} — exact real μ at {_pct(bounds.spread)} "
        f"peaks at {bounds.spread / bounds.critical.spread:.4g}",
        f"complex blocks on the same LFT: {_pct(pub.complex.spread)}, "
        f"{100 * (1 - pub.complex.spread / real.spread):.4g} % of the margin lost",
        f"small gain without an LFT: exact envelope {_pct(pub.small_gain.lower)}, published H_m "
        f"{_pct(pub.hm.lower)} (‖H_m T‖∞ = {pub.norm_HmT:.4g}), "
        f"{100 * (1 - pub.hm.lower / real.spread):.4g} % of the margin lost"]
    if DEPLOYED in margins.controllers:
        ours = margins.controllers[DEPLOYED]
        lines.append(f"{DEPLOYED} (notebook 05): exact margin {_pct(ours.exact.spread)} "
                     f"(real μ {_pct(ours.real.spread)}), complex blocks "
                     f"{_pct(ours.complex.spread)}, small gain {_pct(ours.small_gain.lower)}, "
                     f"H_m {_pct(ours.hm.lower)} (‖H_m T‖∞ = {ours.norm_HmT:.4g})")
    if chosen.design is not None:
        goal_10, at_50 = _case_III(tracking)
        members, unstable = chosen.unstable(chosen.delay_samples)
        lines.append(
            f"mixed-μ K (D,G–K steps, {chosen.design.K.nstates}th order, performance scale "
            f"{chosen.design.performance_scale} on H_e, H_y): μ_RP "
            f"{chosen.mu_rp.upper.max():.3g} with the exact delay; sampled-loop margin "
            + ", ".join(f"{100 * chosen.sampled_margin(d):.3g} % (delay {d})"
                        for d in MARGIN_DELAYS)
            + " (continuous stand-in with (d + 1/2) / fs: "
            + ", ".join(f"{100 * chosen.margin(d):.3g} %" for d in MARGIN_DELAYS) + ")"
            + f"; unstable sampled loops of {members} with delay {chosen.delay_samples}: "
            f"{unstable}; Case III {goal_10:.3g} % up to 10 Hz, {at_50:.3g} % at 50 Hz")
    return lines
