"""Table 3 for any controller: nominal/robust stability and performance.

========================  ==========================================================
condition (Table 3)       computed here
========================  ==========================================================
nominal stability (NS)    all poles of S, T, KS, GS (eq. 19-20) in Re s < 0
nominal performance (NP)  ||H_e S||_inf and ||H_y T||_inf (M22 of eq. 18), each < 1
robust stability (RS)     peak over omega of mu(M11) = |H_m T| (1 x 1 complex block)
robust performance (RP)   peak over omega of mu(M) for the structure of eq. 21
========================  ==========================================================

M is F_l(P, K) with the exact P of eq. 16 (no regularisation).  Norms use
:func:`piezolib.robust.hinf_norm` (grid + local refinement); mu uses
:func:`piezolib.robust.mu.mussv` on a grid (default 1e-2 ... 1e8 rad/s, 1500 points)
refined by a dense local grid around each peak.
"""

from dataclasses import dataclass, field

import control as ct
import numpy as np
import pandas as pd

from piezolib._checks import (check_finite_lti, check_frequency_grid, check_integer, check_model,
                              check_positive, check_siso)
from piezolib.problem.genplant import (BLOCK_STRUCTURE, check_models, effective_delay,
                                       generalized_plant)
from piezolib.robust.lft import lft_response
from piezolib.robust.mu import mussv
from piezolib.robust.achievable import performance_lower_bound
from piezolib.robust.discrete import discretize
from piezolib.robust.lti import closed_loop_poles, hinf_norm, is_stable, loop_functions, realize
from piezolib.robust.margins import delay_tolerance, loop_margins

__all__ = ["RobustnessAnalysis", "analyze", "table3", "table3_peaks", "robust_performance_peak",
           "ANALYSIS_GRID",
           "margins_table", "achievable_mu_lower_bound", "MARGIN_DELAYS", "box_stability_table",
           "exact_margins_with_delay"]

#: Computation delays [samples] of the sampled-loop check in :func:`margins_table`.
MARGIN_DELAYS = (0, 1, 2, 3)

#: Default analysis grid [rad/s].
ANALYSIS_GRID = np.logspace(-2, 8, 1500)


@dataclass(frozen=True)
class RobustnessAnalysis:
    """The four conditions of Table 3 for one controller.

    Scalars are peaks over frequency; ``omega_*`` give where they occur
    [rad/s].  The arrays (on ``omega``) are the bounds plotted in Fig. 12.

    Examples
    --------
    >>> import numpy as np
    >>> nan = np.full(1, np.nan)    # normally from analyze(...); the paper's peaks here
    >>> a = RobustnessAnalysis("K", True, nan, 0.81, 1e3, 0.92, 1e4, 0.48, 1e4, 0.71, 0.70, 1e4,
    ...                        nan, nan, nan, nan)
    >>> a.frame()[["condition", "value", "met"]].values.tolist()[1:4]
    [['NP', 0.81, True], ['NP', 0.92, True], ['RS', 0.48, True]]
    """

    name: str
    nominal_stability: bool
    closed_loop_poles: np.ndarray
    norm_He_S: float
    omega_He_S: float
    norm_Hy_T: float
    omega_Hy_T: float
    mu_RS: float
    omega_RS: float
    mu_RP: float
    mu_RP_lower: float
    omega_RP: float
    omega: np.ndarray = field(repr=False)
    mu_RS_curve: np.ndarray = field(repr=False)
    mu_RP_upper: np.ndarray = field(repr=False)
    mu_RP_lower_curve: np.ndarray = field(repr=False)

    def frame(self):
        """Table 3 rows as a DataFrame (value, peak frequency, condition met)."""
        rows = [
            ("NS", "S, T, KS, GS stable", float(self.nominal_stability), np.nan,
             self.nominal_stability),
            ("NP", "||H_e S||_inf", self.norm_He_S, self.omega_He_S, self.norm_He_S < 1),
            ("NP", "||H_y T||_inf", self.norm_Hy_T, self.omega_Hy_T, self.norm_Hy_T < 1),
            ("RS", "peak mu(M11) = peak |H_m T|", self.mu_RS, self.omega_RS, self.mu_RS < 1),
            ("RP", "peak mu(M) (upper bound)", self.mu_RP, self.omega_RP, self.mu_RP < 1),
            ("RP", "peak mu(M) (lower bound)", self.mu_RP_lower, self.omega_RP,
             self.mu_RP_lower < 1),
        ]
        return pd.DataFrame(rows, columns=["condition", "quantity", "value",
                                           "omega_peak [rad/s]", "met"])


def _refined_peak(P, K, omega, res, points=201, lower=True):
    """Peak of mu refined on ``points`` frequencies spanning the grid cells next to the grid peak.

    Returns (upper peak, its frequency, largest lower bound seen).
    """
    k = int(np.argmax(res.upper))
    local = np.geomspace(omega[max(k - 1, 0)], omega[min(k + 1, len(omega) - 1)], points)
    fine = mussv(lft_response(P, K, local), BLOCK_STRUCTURE, lower=lower)
    j = int(np.argmax(fine.upper))
    lower_peak = float(max(res.lower.max(), fine.lower.max()))
    if fine.upper[j] > res.upper[k]:
        return float(fine.upper[j]), float(local[j]), lower_peak
    return float(res.upper[k]), float(omega[k]), lower_peak


def _analysis_grid(omega):
    """:data:`ANALYSIS_GRID` for None, else ``omega`` checked: the peak refinement spans
    the cells next to the grid peak geometrically, so the grid must be positive and
    increasing (a negative one used to give NaN peaks)."""
    return ANALYSIS_GRID if omega is None else check_frequency_grid("omega", omega,
                                                                    min_length=16)


def robust_performance_peak(K, G, H_m, H_e, H_y, *, omega=None):
    """Peak of the mu_RP upper bound and its frequency [rad/s] (inf, nan if K destabilises).

    A light version of :func:`analyze` for sweeps (no lower bound, no norms);
    arguments as in :func:`analyze`.

    Returns
    -------
    mu_peak : float
    omega_peak : float
        [rad/s]

    Examples
    --------
    >>> import numpy as np
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> mu, w = robust_performance_peak(K, G, H_m, H_e, H_y, omega=np.logspace(3, 5, 16))
    >>> print(f"{mu:.1f} at {w:.2g} rad/s")
    1.4 at 6.4e+03 rad/s
    """
    check_siso("K", K)
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    omega = _analysis_grid(omega)
    if not is_stable(G, K):
        return float("inf"), float("nan")
    P = generalized_plant(G, H_m, H_e, H_y)
    res = mussv(lft_response(P, K, omega), BLOCK_STRUCTURE, lower=False)
    return _refined_peak(P, K, omega, res, points=101, lower=False)[:2]


def analyze(K, G, H_m, H_e, H_y, *, omega=None, name=None):
    """Evaluate Table 3's conditions for the controller K.

    Parameters
    ----------
    K : control.LTI
        SISO controller from v_e [V] to u_b [V].
    G, H_m, H_e, H_y : control.LTI
        Plant (u_c [V] -> v_y [V]) and the weights of the problem, e.g. those
        of :func:`piezolib.problem.paper.problem`.
    omega : array_like, optional
        Analysis grid [rad/s], positive and increasing, at least 16 points; default
        :data:`ANALYSIS_GRID`.
    name : str, optional
        Label used by :func:`table3` (default ``K.name``).

    Returns
    -------
    RobustnessAnalysis
        For a K that does not stabilise G the norms and mu peaks are inf (no
        condition of Table 3 holds), their frequencies and the curves NaN.

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> round(analyze(K, G, H_m, H_e, H_y).norm_He_S, 2)
    0.81
    """
    check_siso("K", K)
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    omega = _analysis_grid(omega)
    loop = loop_functions(G, K)
    poles = closed_loop_poles(G, K)
    # NS asks all four closed-loop functions to be stable (hidden modes included)
    stable = all(np.all(ct.poles(f).real < 0) for f in loop) and bool(np.all(poles.real < 0))
    if not stable:
        inf, nan = float("inf"), float("nan")
        empty = np.full(omega.shape, nan)
        return RobustnessAnalysis(name or K.name, False, poles, inf, nan, inf, nan, inf, nan,
                                  inf, inf, nan, omega, empty, empty, empty)
    he_s = hinf_norm(realize(H_e) * loop.S)
    hy_t = hinf_norm(realize(H_y) * loop.T)
    hm_t = hinf_norm(realize(H_m) * loop.T)
    P = generalized_plant(G, H_m, H_e, H_y)
    M = lft_response(P, K, omega)
    rp = mussv(M, BLOCK_STRUCTURE)
    mu_rp, w_rp, mu_rp_lower = _refined_peak(P, K, omega, rp)
    # a 1 x 1 complex block: mu(M11) = |M11| exactly
    rs_curve = np.abs(M[:, 0, 0])
    return RobustnessAnalysis(
        name=name or K.name, nominal_stability=True, closed_loop_poles=poles,
        norm_He_S=he_s[0], omega_He_S=he_s[1], norm_Hy_T=hy_t[0], omega_Hy_T=hy_t[1],
        mu_RS=hm_t[0], omega_RS=hm_t[1], mu_RP=mu_rp, mu_RP_lower=min(mu_rp_lower, mu_rp),
        omega_RP=w_rp, omega=omega, mu_RS_curve=rs_curve, mu_RP_upper=rp.upper,
        mu_RP_lower_curve=rp.lower)


def table3(*analyses, paper_values=None):
    """Side-by-side Table 3 for several :class:`RobustnessAnalysis` results.

    Parameters
    ----------
    *analyses : RobustnessAnalysis
    paper_values : dict, optional
        Published values keyed ``norm_He_S``, ``norm_Hy_T``, ``mu_RS``,
        ``mu_RP`` (e.g. ``piezolib.problem.paper.FIGURES_OF_MERIT``), shown as a column.

    Returns
    -------
    pandas.DataFrame
        Rows NS, NP (two), RS, RP; one column per controller.

    Examples
    --------
    >>> import numpy as np
    >>> from piezolib.problem import paper
    >>> nan = np.full(1, np.nan)    # normally from analyze(...)
    >>> a = RobustnessAnalysis("K", True, nan, 0.8, 1e3, 1.0, 1e4, 0.8, 1e4, 1.4, 1.4, 6e3,
    ...                        nan, nan, nan, nan)
    >>> t = table3(a, paper_values=paper.FIGURES_OF_MERIT)
    >>> list(t.columns), t.loc["RP: peak mu(M)"].tolist()
    (['paper', 'K'], [0.71, 1.4])
    """
    index = pd.Index(["NS: S, T, KS, GS stable", "NP: ||H_e S||_inf", "NP: ||H_y T||_inf",
                      "RS: peak mu(M11)", "RP: peak mu(M)"], name="Table 3")
    data = {}
    if paper_values is not None:
        data["paper"] = [True, paper_values["norm_He_S"], paper_values["norm_Hy_T"],
                         paper_values["mu_RS"], paper_values["mu_RP"]]
    for a in _analyses("table3", analyses):
        data[a.name] = [a.nominal_stability, a.norm_He_S, a.norm_Hy_T, a.mu_RS, a.mu_RP]
    return pd.DataFrame(data, index=index)


def table3_peaks(*analyses):
    """Where the peaks of Table 3 lie, and the lower bound of the mu_RP peak, side by side.

    Parameters
    ----------
    *analyses : RobustnessAnalysis

    Returns
    -------
    pandas.DataFrame
        Rows: the frequencies [rad/s] of the ||H_e S||, ||H_y T||, mu_RS and
        mu_RP peaks, and the mu_RP lower bound; one column per controller.

    Examples
    --------
    >>> import numpy as np
    >>> nan = np.full(1, np.nan)    # normally from analyze(...)
    >>> a = RobustnessAnalysis("K", True, nan, 0.8, 1e3, 1.0, 1e4, 0.8, 1e4, 1.4, 1.3, 6e3,
    ...                        nan, nan, nan, nan)
    >>> table3_peaks(a)["K"].tolist()
    [1000.0, 10000.0, 10000.0, 6000.0, 1.3]
    """
    return pd.DataFrame({a.name: {"omega of ||H_e S|| [rad/s]": a.omega_He_S,
                                  "omega of ||H_y T|| [rad/s]": a.omega_Hy_T,
                                  "omega of mu_RS peak [rad/s]": a.omega_RS,
                                  "omega of mu_RP peak [rad/s]": a.omega_RP,
                                  "mu_RP lower bound": a.mu_RP_lower}
                         for a in _analyses("table3_peaks", analyses)})


def _analyses(what, analyses):
    for a in analyses:
        if not isinstance(a, RobustnessAnalysis):
            raise TypeError(f"{what}: analyses must be RobustnessAnalysis results, got "
                            f"{type(a).__name__}")
    return analyses


def margins_table(controllers, G, fs, *, delays=MARGIN_DELAYS):
    """Classical, disk and sampled-loop margins of several controllers on the plant G.

    Parameters
    ----------
    controllers : dict
        {name: K}: continuous-time SISO controllers (v_e [V] -> u_b [V]).
    G : control.LTI
        Plant u_c [V] -> v_y [V].
    fs : float
        Loop rate [Hz]: each K is discretised by Tustin
        (:func:`piezolib.robust.discrete.discretize`) and the sampled loop
        with the zero-order-hold plant is checked for each delay.
    delays : sequence of int
        Computation delays [samples], 0, 1, 2, ... consecutive.

    Returns
    -------
    pandas.DataFrame
        One column per controller; rows: the continuous margins of
        :meth:`piezolib.robust.margins.LoopMargins.as_dict`, the sampled
        loop's delay margin [samples] and, per delay d, its spectral radius
        and stability.
    """
    _check_margins_arguments(controllers, G, fs)
    data = {}
    for name, K in controllers.items():
        col = loop_margins(G, K).as_dict()
        tol = delay_tolerance(G, discretize(K, fs).K, delays=delays)
        col["sampled loop delay margin [samples]"] = tol.delay_margin_samples
        for d, r, ok in zip(tol.delays, tol.spectral_radius, tol.stable):
            col[f"spectral radius, delay {d}"] = float(r)
            col[f"stable, delay {d}"] = bool(ok)
        data[name] = col
    return pd.DataFrame(data)


def _check_margins_arguments(controllers, G, fs):
    """Check the models of :func:`margins_table` before any of them is analysed.

    Each must be SISO, continuous-time, finite and proper: an improper G otherwise fails
    in python-control's conversion with a message that names no argument.
    """
    check_siso("G", G)
    check_model("G", G, proper=True)
    if not isinstance(controllers, dict) or not controllers:
        raise TypeError("controllers must be a non-empty dict {name: K}")
    for name, K in controllers.items():
        check_siso(f"controllers[{name!r}]", K)
        check_model(f"controllers[{name!r}]", K, proper=True)
    check_positive("fs", fs)


def achievable_mu_lower_bound(G, H_m, H_e, H_y, **kwargs):
    """Lower bound on the peak mu_RP any stabilising controller can reach (eq. 16-21).

    mu_RP >= ||[H_e S; H_y T]||_inf >= inf over stabilising K of it, an
    H-infinity problem on the performance channels (v_r -> y1, y2) of the
    exact P of eq. 16, solved by
    :func:`piezolib.robust.achievable.performance_lower_bound`.

    Parameters
    ----------
    G, H_m, H_e, H_y : control.LTI
        As in :func:`analyze`.
    **kwargs
        Passed to :func:`~piezolib.robust.achievable.performance_lower_bound`.

    Returns
    -------
    piezolib.robust.achievable.LowerBound
    """
    G, H_m, H_e, H_y = check_models(G, H_m, H_e, H_y)
    P = generalized_plant(G, H_m, H_e, H_y)
    return performance_lower_bound(P, 1, 1, ["y1", "y2"], ["v_r"], **kwargs)


def box_stability_table(controllers, G, spread, fs, *, delays=MARGIN_DELAYS, levels=3):
    """How much of G's coefficient box each controller keeps stable, by four methods.

    Rows, per controller (one column each): the exact parametric margin
    (zero exclusion) of the continuous loop with the effective delay
    (d + 1/2) / fs for each d in ``delays``; the members of the ``levels``^n
    grid of the box of ``spread`` whose continuous loop (no delay) is
    unstable; the members whose sampled loop (exact ZOH model, the controller
    as given, z^-d) is unstable for each d; the grid spread of the sampled loop
    with the first nonzero delay (an upper bound of its margin).

    Parameters
    ----------
    controllers : dict
        {name: (K, Kd)}: the continuous controller (v_e [V] -> u_b [V]) and the
        discrete one the target runs (e.g. float32 sections as a state space).
    G : control.LTI
        Nominal plant u_c [V] -> v_y [V].
    spread : float
        Relative size of the box [-].
    fs : float
        Loop rate [Hz].
    delays : sequence of int
        Computation delays [samples].
    levels : int
        Values per coefficient of the grid.

    Returns
    -------
    pandas.DataFrame
        Margins in % of the coefficients, counts as integers.
    """
    from piezolib import uncertainty as unc
    from piezolib.uncertainty import sampled

    spread = check_positive("spread", spread)
    fs = check_positive("fs", fs)
    delays = _check_delays(delays)
    grid = unc.model_set(G, spread, levels=levels)
    if not isinstance(controllers, dict) or not controllers:
        raise TypeError("controllers must be a non-empty dict {name: (K, Kd)}, got "
                        f"{controllers!r}"[:200])
    for name, pair in controllers.items():
        if not (isinstance(pair, tuple) and len(pair) == 2):
            raise TypeError(f"controllers[{name!r}] must be a pair (K, Kd), got {pair!r}"[:200])
        check_model(f"controllers[{name!r}] K", pair[0])
        check_finite_lti(f"controllers[{name!r}] Kd", pair[1])
        if not pair[1].isdtime(strict=True):
            raise ValueError(f"controllers[{name!r}] Kd must be the discrete-time controller "
                             "the loop runs (dt = 1 / fs)")
    first = next((d for d in delays if d > 0), max(delays))
    data = {}
    for name, (K, Kd) in controllers.items():
        col = {f"exact margin, delay {d} [%]": 100 * m
               for d, m in exact_margins_with_delay(G, K, fs, delays).items()}
        col[f"unstable of {grid.size}, continuous, no delay"] = int(
            unc.unstable_members(grid, K).size)
        for d in delays:
            col[f"unstable of {grid.size}, sampled, delay {d}"] = int(
                sampled.sampled_loop_unstable(grid, Kd, 1.0 / fs, d).size)
        col[f"grid spread, sampled, delay {first} [%]"] = 100 * sampled.sampled_loop_spread(
            G, Kd, 1.0 / fs, first)
        data[name] = col
    return pd.DataFrame(data)


def exact_margins_with_delay(G, K, fs, delays=MARGIN_DELAYS):
    """{d: exact parametric margin [-] of the loop with the delay (d + 1/2) / fs} for each d.

    Zero exclusion on G's coefficient box with the effective delay of a sampled
    loop with d samples of computation delay
    (:func:`piezolib.uncertainty.parametric_stability_margin`); 0 where the
    nominal loop is unstable.

    Parameters
    ----------
    G, K : control.LTI
        Plant u_c [V] -> v_y [V] and continuous controller v_e [V] -> u_b [V].
    fs : float
        Loop rate [Hz].
    delays : sequence of int
        Computation delays [samples].

    Returns
    -------
    dict

    Examples
    --------
    >>> from piezolib.problem import paper
    >>> margins = exact_margins_with_delay(paper.plant(), paper.controller(), 10e3, delays=(0, 1))
    >>> {d: round(100 * m, 1) for d, m in margins.items()}       # in % of the coefficients
    {0: 3.7, 1: 1.9}
    """
    from piezolib.uncertainty import parametric_stability_margin

    fs = check_positive("fs", fs)
    return {d: parametric_stability_margin(G, K, delay=effective_delay(fs, d)).spread
            for d in _check_delays(delays)}


def _check_delays(delays):
    """A non-empty sequence of computation delays [samples] as ints >= 0."""
    if isinstance(delays, str) or not hasattr(delays, "__len__") or len(delays) == 0:
        raise TypeError(f"delays must be a non-empty sequence of integers, got {delays!r}")
    return [check_integer("delays", d, minimum=0) for d in delays]
