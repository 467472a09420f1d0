"""The performance weights of eq. 15 and the generalized plant of eq. 16 checked against the paper.

:func:`template_asymptotes` compares the limits and the 0 dB crossing of the
templates 1/H_e and 1/H_y with eq. 15; :func:`eq16_entries` every entry of
P(jw) with the products of eq. 16; :func:`eq18_error` M = F_l(P, K) with the
weighted closed-loop functions of eq. 18; :func:`templates_met` says whether
S and T of each controller stay under their templates (Fig. 11) and below the
peaks of Sec. IV-B, with the claim rows.  Notebook 04; each result has the
``checks`` the notebook states.
"""

from collections.abc import Iterable
from dataclasses import dataclass

import control as ct
import numpy as np
import pandas as pd

from piezolib._checks import check_frequency_grid, check_siso, check_type
from piezolib.problem import analysis, genplant, paper
from piezolib.robust.lti import bandwidth, frequency_grid, hinf_norm, loop_functions

__all__ = ["EQ16_GRID", "Templates", "template_asymptotes", "Eq16Entries", "eq16_entries",
           "eq18_error", "TemplatesMet", "templates_met"]

#: The frequencies [rad/s] at which P and M are compared with eq. 16 and 18.
EQ16_GRID = np.logspace(0, 6, 200)


def _check_models(**models):
    for name, sys in models.items():
        check_siso(name, sys)


def _response(f, omega):
    """f(j omega) of a SISO model as a 1-D complex array."""
    return np.ravel(f(1j * omega))


@dataclass(frozen=True)
class Templates:
    """The templates 1/|H_e| and 1/|H_y| against eq. 15 (:func:`template_asymptotes`).

    Attributes
    ----------
    omega : ndarray
        The frequency grid [rad/s] (0.1 ... 1e9, 3000 points).
    crossing_rad_s : float
        The 0 dB crossing of 1/|H_e| from eq. 15, w_e sqrt((1 - eps_e^2)/(1 - 1/M_e^2)).
    table : pandas.DataFrame
        Columns ``quantity``, ``from eq. 15`` and ``computed``.
    """

    omega: np.ndarray
    crossing_rad_s: float
    table: pd.DataFrame


def template_asymptotes(error_params, output_params):
    """The limits at DC and high frequency, and the 0 dB crossing, of the templates of eq. 15.

    Parameters
    ----------
    error_params : paper.ErrorWeightParameters
        M_e, eps_e, omega_e [rad/s] of H_e.
    output_params : paper.OutputWeightParameters
        M_y, eps_y, omega_y [rad/s] of H_y.

    Returns
    -------
    Templates

    Examples
    --------
    >>> t = template_asymptotes(paper.ERROR_WEIGHT, paper.OUTPUT_WEIGHT)
    >>> bool(np.allclose(t.table["from eq. 15"], t.table["computed"], rtol=1e-3))
    True
    """
    e = check_type("error_params", error_params, paper.ErrorWeightParameters,
                   "a paper.ErrorWeightParameters")
    y = check_type("output_params", output_params, paper.OutputWeightParameters,
                   "a paper.OutputWeightParameters")
    H_e, H_y = paper.error_weight(e), paper.output_weight(y)
    omega = frequency_grid(1e-1, 1e9, 3000)
    inv_He = 1 / np.abs(_response(H_e, omega))
    inv_Hy = 1 / np.abs(_response(H_y, omega))
    crossing = e.omega_e * np.sqrt((1 - e.eps_e ** 2) / (1 - 1 / e.M_e ** 2))
    table = pd.DataFrame(
        [("1/|H_e| at DC", e.eps_e, 1 / abs(ct.dcgain(H_e))),
         ("1/|H_e| at high frequency", e.M_e, inv_He[-1]),
         ("0 dB crossing of 1/|H_e| [rad/s]", crossing,
          float(np.interp(0.0, np.log(inv_He), omega))),
         ("1/|H_y| at DC", y.M_y ** 2, 1 / abs(ct.dcgain(H_y))),
         ("1/|H_y| at high frequency", y.eps_y ** 2, inv_Hy[-1])],
        columns=["quantity", "from eq. 15", "computed"])
    return Templates(omega, float(crossing), table)


@dataclass(frozen=True)
class Eq16Entries:
    """Every entry of P(jw) against eq. 16 (:func:`eq16_entries`).

    Attributes
    ----------
    table : pandas.DataFrame
        One row per (output, input): ``entry`` ("0" or "eq. 16"), the largest
        |P| of a zero entry and the largest relative error of the others.
    omega : ndarray
        The frequencies [rad/s] compared.
    """

    table: pd.DataFrame
    omega: np.ndarray

    @property
    def worst(self):
        """The largest relative error of a non-zero entry."""
        return float(np.nanmax(self.table["max relative error"]))

    @property
    def checks(self):
        """What the notebook states of P, each with whether it holds."""
        return {"every entry of eq. 16 to a relative error < 1e-7": self.worst < 1e-7,
                "the zero entries of eq. 16 are zero (|P| < 1e-9)":
                    bool(np.nanmax(self.table["max |P| (zero entries)"]) < 1e-9)}


def eq16_entries(P, G, H_m, H_e, H_y, omega=EQ16_GRID):
    """Compare every entry of the generalized plant P(jw) with the products of eq. 16.

    Parameters
    ----------
    P : control.StateSpace
        Inputs [u_Delta, v_r, u_b], outputs [y_Delta, y1, y2, v_e]
        (:func:`piezolib.problem.genplant.generalized_plant`).
    G, H_m, H_e, H_y : control.LTI
        The plant and weights it was built from.
    omega : array_like, optional
        Frequencies [rad/s]; default :data:`EQ16_GRID`.

    Returns
    -------
    Eq16Entries

    Examples
    --------
    >>> G, H_m, H_e, H_y, _ = paper.problem()
    >>> P = genplant.generalized_plant(G, H_m, H_e, H_y)
    >>> all(eq16_entries(P, G, H_m, H_e, H_y, omega=np.logspace(0, 6, 20)).checks.values())
    True
    """
    check_type("P", P, ct.StateSpace, "a control.StateSpace (genplant.generalized_plant)")
    _check_models(G=G, H_m=H_m, H_e=H_e, H_y=H_y)
    omega = check_frequency_grid("omega", omega)
    sc = 1j * omega
    g, hm, he, hy = (np.ravel(f(sc)) for f in (G, H_m, H_e, H_y))
    eq16 = {("y_Delta", "u_b"): hm,
            ("y1", "u_Delta"): -he * g, ("y1", "v_r"): he, ("y1", "u_b"): -he * g,
            ("y2", "u_Delta"): hy * g, ("y2", "u_b"): hy * g,
            ("v_e", "u_Delta"): -g, ("v_e", "v_r"): np.ones_like(g), ("v_e", "u_b"): -g}
    resp = np.moveaxis(P(sc, squeeze=False), -1, 0)
    rows = []
    for i, out in enumerate(P.output_labels):
        for j, inp in enumerate(P.input_labels):
            expected = eq16.get((out, inp))
            got = resp[:, i, j]
            if expected is None:
                rows.append((out, inp, "0", float(np.max(np.abs(got))), np.nan))
            else:
                rows.append((out, inp, "eq. 16", np.nan,
                             float(np.max(np.abs(got / expected - 1)))))
    return Eq16Entries(pd.DataFrame(rows, columns=["output", "input", "entry",
                                                   "max |P| (zero entries)",
                                                   "max relative error"]), omega)


def eq18_error(M, K, G, H_m, H_e, H_y, omega=EQ16_GRID):
    """The largest relative error of M = F_l(P, K) against the entries of eq. 18.

    Parameters
    ----------
    M : control.StateSpace
        From [u_Delta, v_r] to [y_Delta, y1, y2]
        (:func:`piezolib.problem.genplant.closed_loop_matrix`).
    K, G, H_m, H_e, H_y : control.LTI
        The controller, plant and weights it was built from.
    omega : array_like, optional
        Frequencies [rad/s]; default :data:`EQ16_GRID`.

    Returns
    -------
    float
        max over the grid and the six entries of |M - eq. 18| / |eq. 18|.

    Examples
    --------
    >>> G, H_m, H_e, H_y, K = paper.problem()
    >>> M = genplant.closed_loop_matrix(K, G, H_m, H_e, H_y)
    >>> eq18_error(M, K, G, H_m, H_e, H_y, omega=np.logspace(0, 6, 20)) < 1e-6
    True
    """
    check_type("M", M, ct.StateSpace, "a control.StateSpace (genplant.closed_loop_matrix)")
    _check_models(K=K, G=G, H_m=H_m, H_e=H_e, H_y=H_y)
    omega = check_frequency_grid("omega", omega)
    sc = 1j * omega
    hm, he, hy = (np.ravel(f(sc)) for f in (H_m, H_e, H_y))
    S, T, KS, GS = (np.ravel(f(sc)) for f in loop_functions(G, K))
    eq18 = np.stack([np.stack([-hm * T, hm * KS], -1), np.stack([-he * GS, he * S], -1),
                     np.stack([hy * GS, hy * T], -1)], 1)
    M_resp = np.moveaxis(M(sc, squeeze=False), -1, 0)
    return float(np.max(np.abs(M_resp - eq18) / np.abs(eq18)))


def _db(x):
    """20 log10 |x|."""
    return 20 * np.log10(np.abs(np.asarray(x)))


@dataclass(frozen=True)
class TemplatesMet:
    """S and T of each controller against their templates (:func:`templates_met`).

    Attributes
    ----------
    loops : dict
        {controller name: LoopFunctions (S, T, KS, GS)}.
    table : pandas.DataFrame
        One row per controller: ``|S| < 1/|H_e|``, ``|T| < 1/|H_y|`` (that is
        ||H_e S|| < 1, ||H_y T|| < 1), ``||S|| [dB]``, ``||T|| [dB]`` and the
        ``bandwidth of T [Hz]``.
    stable : dict
        {controller name: bool}, nominal stability of each loop.
    published : tuple of str
        The names of controllers whose peak gains are not claimed here (the
        published K's are claims of notebook 00).
    """

    loops: dict
    table: pd.DataFrame
    stable: dict
    published: tuple = ()

    @property
    def checks(self):
        """That every loop is nominally stable, per controller."""
        return {f"{name}: the loop is stable": bool(ok) for name, ok in self.stable.items()}

    def design_checks(self, name):
        """What Sec. IV-B asks of the designed controller ``name``, each with whether it holds."""
        if name not in self.loops:
            raise ValueError(f"name must be one of {list(self.loops)}, got {name!r}")
        row = self.table.set_index("controller").loc[name]
        S_max, T_max = paper.DESIGN_GOALS["S_peak_dB_max"], paper.DESIGN_GOALS["T_peak_dB_max"]
        return {f"{name}: |S| under 1/|H_e| and |T| under 1/|H_y|":
                    bool(row["|S| < 1/|H_e|"] and row["|T| < 1/|H_y|"]),
                f"{name}: ||S|| < {S_max:g} dB and ||T|| < {T_max:g} dB":
                    bool(row["||S|| [dB]"] < S_max and row["||T|| [dB]"] < T_max),
                f"{name}: bandwidth of T within 300-450 Hz":
                    bool(300 < row["bandwidth of T [Hz]"] < 450)}

    def claims(self):
        """The claim rows of Fig. 11 and Sec. IV-B: keyword arguments of ``ClaimTable.add``.

        Per controller, |S| under 1/|H_e| (Fig. 11(a)) and |T| under 1/|H_y|
        (Fig. 11(b)); for a designed controller also the peaks of Sec. IV-B.
        """
        S_max, T_max = paper.DESIGN_GOALS["S_peak_dB_max"], paper.DESIGN_GOALS["T_peak_dB_max"]
        rows = []
        for _, row in self.table.iterrows():
            name = row.controller
            rows.append(dict(section="Fig. 11(a)", quantity=f"|S| below 1/|H_e| ({name})",
                             paper=True, ours=bool(row["|S| < 1/|H_e|"])))
            rows.append(dict(section="Fig. 11(b)", quantity=f"|T| below 1/|H_y| ({name})",
                             paper=True, ours=bool(row["|T| < 1/|H_y|"])))
            if name in self.published:
                continue
            rows.append(dict(section="Sec. IV-B", quantity=f"||S|| < {S_max:g} dB ({name})",
                             paper=True, ours=bool(row["||S|| [dB]"] < S_max),
                             note=f"{row['||S|| [dB]']:.2f} dB"))
            rows.append(dict(section="Sec. IV-B", quantity=f"||T|| < {T_max:g} dB ({name})",
                             paper=True, ours=bool(row["||T|| [dB]"] < T_max),
                             note=f"{row['||T|| [dB]']:.2f} dB"))
        return rows


def templates_met(controllers, G, H_m, H_e, H_y, published=(), omega=None):
    """Whether S and T of each controller stay under their templates, and their peaks.

    |S| < 1/|H_e| at every frequency is ||H_e S||_inf < 1 (likewise T and H_y),
    taken from :func:`piezolib.problem.analysis.analyze`.

    Parameters
    ----------
    controllers : dict
        {name: controller K (v_e -> u_b)}.
    G, H_m, H_e, H_y : control.LTI
        The plant and the weights.
    published : sequence of str, optional
        Names of controllers whose peaks are not claimed (the published K).
    omega : array_like, optional
        The grid [rad/s] of the template conditions
        (:func:`piezolib.problem.analysis.analyze`; default its grid).

    Returns
    -------
    TemplatesMet
    """
    controllers = check_type("controllers", controllers, dict, "a dict {name: controller}")
    if not controllers:
        raise ValueError("controllers must hold at least one controller")
    for name, K in controllers.items():
        check_siso(f"controllers[{name!r}]", K)
    if isinstance(published, (str, bytes)) or not isinstance(published, Iterable):
        raise TypeError(f"published must be a sequence of controller names, got {published!r}")
    published = tuple(published)
    unknown = [name for name in published if name not in controllers]
    if unknown:
        raise ValueError(f"published names {unknown} that are not in controllers "
                         f"({sorted(controllers)})")
    loops = {name: loop_functions(G, K) for name, K in controllers.items()}
    rows, stable = [], {}
    for name, loop in loops.items():
        nominal = analysis.analyze(controllers[name], G, H_m, H_e, H_y, omega=omega, name=name)
        stable[name] = bool(nominal.nominal_stability)
        if stable[name]:
            peaks = (float(_db(hinf_norm(loop.S)[0])), float(_db(hinf_norm(loop.T)[0])),
                     bandwidth(loop.T) / (2 * np.pi))
        else:                               # no peak of an unstable loop: the checks fail
            peaks = (np.inf, np.inf, np.nan)
        rows.append((name, bool(nominal.norm_He_S < 1), bool(nominal.norm_Hy_T < 1), *peaks))
    table = pd.DataFrame(rows, columns=["controller", "|S| < 1/|H_e|", "|T| < 1/|H_y|",
                                        "||S|| [dB]", "||T|| [dB]", "bandwidth of T [Hz]"])
    return TemplatesMet(loops, table, stable, published)
