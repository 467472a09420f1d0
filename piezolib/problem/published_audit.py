"""The published design audited (notebook 00): do the paper's own models give its own numbers?

Everything here takes the published models as printed (:func:`piezolib.problem.paper.problem`)
or the published tables, and recomputes what the paper states of them:

* :func:`units_table` -- the units convention of the workbook, one row per signal;
* :func:`pole_table` -- natural frequency, damping and frequency [Hz] of each pole pair;
* :func:`audit_nominal_loop` -- nominal stability and nominal performance of the loop
  (Table 3, Fig. 10, 11): closed-loop poles, S(0), the weighted norms, |S| and |T| peaks;
* :func:`table_consistency` -- the improvement rows of Tables 4-5 recomputed from their case
  rows, the averages of Sec. VI and the one number the text prints differently.

::

    from piezolib.problem import paper, published_audit

    G, H_m, H_e, H_y, K = paper.problem()
    nominal = published_audit.audit_nominal_loop(G, K, H_m, H_e, H_y)
    nominal.performance_table()
"""

from dataclasses import dataclass, field

import control as ct
import numpy as np
import pandas as pd

from piezolib._checks import check_siso
from piezolib.metrics import improvement_percent
from piezolib.problem import paper
from piezolib.problem.analysis import RobustnessAnalysis, analyze
from piezolib.robust.lti import bandwidth, hinf_norm, loop_functions

__all__ = ["units_table", "pole_table", "NominalAudit", "audit_nominal_loop",
           "TableConsistency", "table_consistency", "IMPROVEMENT_ATOL_PERCENT"]

#: Tolerance [percentage points] of a printed improvement against the one implied by its
#: case rows: the case rows are printed with two decimals, so the implied value is known
#: to about +-0.05 points.
IMPROVEMENT_ATOL_PERCENT = 0.06


def units_table():
    """The units convention of the workbook (Sec. II): symbol, meaning, unit and range.

    Returns
    -------
    pandas.DataFrame
        Columns ``symbol``, ``meaning``, ``unit``, ``range / relation``; one row per
        signal of Fig. 1 (the same table as in ``help(piezolib.paper)``).

    Examples
    --------
    >>> units_table().set_index("symbol").loc["u_c", "unit"]
    'V'
    """
    return pd.DataFrame(
        [("u_c", "control input = amplifier input", "V", f"{paper.AMPLIFIER_INPUT_RANGE_V}"),
         ("v_a", "actuator voltage = 10 u_c", "V", f"{paper.ACTUATOR_DRIVE_RANGE_V} driven"),
         ("v_y", "sensor output", "V", f"{paper.SENSOR_OUTPUT_RANGE_V}"),
         ("v_r, v_e", "reference, error v_r - v_y", "V", ""),
         ("x, x_r", "displacement", "um", f"{paper.UM_PER_VOLT} um per volt of v_r or v_y"),
         ("omega", "angular frequency", "rad/s", "all models and grids"),
         ("t", "time", "s", f"sampled at {paper.SAMPLING_FREQUENCY_HZ:.0f} Hz")],
        columns=["symbol", "meaning", "unit", "range / relation"])


def pole_table(sys):
    """Natural frequency, damping and frequency in Hz of each pole (one row per pair).

    Parameters
    ----------
    sys : control.LTI
        A continuous-time SISO model.

    Returns
    -------
    pandas.DataFrame
        Columns ``pole [rad/s]`` (the pole with Im >= 0, rounded to 0.1 rad/s),
        ``omega_n [rad/s]``, ``f_n [Hz]`` and ``damping``, sorted by natural frequency.

    Examples
    --------
    >>> table = pole_table(ct.tf([100.0], [1.0, 2.0, 100.0]))
    >>> float(table["omega_n [rad/s]"].iloc[0]), float(table["damping"].iloc[0])
    (10.0, 0.1)
    """
    check_siso("sys", sys)
    if ct.isdtime(sys, strict=True):
        raise ValueError("sys must be a continuous-time model, got a discrete one")
    p = ct.poles(sys)
    p = p[p.imag >= 0]
    wn = np.abs(p)
    return pd.DataFrame({"pole [rad/s]": np.round(p, 1), "omega_n [rad/s]": wn,
                         "f_n [Hz]": wn / (2 * np.pi), "damping": -p.real / wn}
                        ).sort_values("omega_n [rad/s]").reset_index(drop=True)


@dataclass(frozen=True)
class NominalAudit:
    """Nominal stability and nominal performance of one loop (Table 3, Fig. 10, 11).

    Attributes
    ----------
    analysis : piezolib.problem.analysis.RobustnessAnalysis
        Table 3 for the controller (the weighted norms, mu_RS, closed-loop poles).
    loop : piezolib.robust.lti.LoopFunctions
        S, T, KS, GS of the loop.
    slowest_pole : complex
        The closed-loop pole with the largest real part [rad/s].
    steady_state_error : float
        S(0) = 1 / (1 + K(0) G(0)): the error left by a unit step [V/V].
    dc_T : float
        T(0) [V/V].
    norm_S, omega_S, norm_T, omega_T : float
        ||S||_inf, ||T||_inf [V/V] and where they peak [rad/s].
    bandwidth_Hz : float
        The -3 dB bandwidth of T.
    """

    analysis: RobustnessAnalysis = field(repr=False)
    loop: object = field(repr=False)
    slowest_pole: complex
    steady_state_error: float
    dc_T: float
    norm_S: float
    omega_S: float
    norm_T: float
    omega_T: float
    bandwidth_Hz: float

    @property
    def S_peak_dB(self):
        """||S||_inf in dB."""
        return float(20 * np.log10(self.norm_S))

    @property
    def T_peak_dB(self):
        """||T||_inf in dB."""
        return float(20 * np.log10(self.norm_T))

    @property
    def stable(self):
        """True when S, T, KS, GS are stable and every closed-loop pole lies in Re s < 0."""
        return bool(self.analysis.nominal_stability
                    and np.all(self.analysis.closed_loop_poles.real < 0))

    def performance_table(self):
        """The nominal-performance numbers against the paper's (Sec. IV-B/C, Fig. 11, 12(a)).

        Returns
        -------
        pandas.DataFrame
            Columns ``quantity``, ``paper``, ``recomputed``, ``at omega [rad/s]``.
        """
        fom, a = paper.FIGURES_OF_MERIT, self.analysis
        return pd.DataFrame(
            [("||H_e S||_inf", fom["norm_He_S"], a.norm_He_S, a.omega_He_S),
             ("||H_y T||_inf", fom["norm_Hy_T"], a.norm_Hy_T, a.omega_Hy_T),
             ("max |H_m T| = mu_RS (1x1 complex block)", fom["mu_RS"], a.mu_RS, a.omega_RS),
             ("||S||_inf [dB] (goal < 6 dB)", None, self.S_peak_dB, self.omega_S),
             ("||T||_inf [dB] (goal < 3.5 dB)", None, self.T_peak_dB, self.omega_T),
             ("-3 dB bandwidth of T [Hz]", None, self.bandwidth_Hz, np.nan)],
            columns=["quantity", "paper", "recomputed", "at omega [rad/s]"])


def audit_nominal_loop(G, K, H_m, H_e, H_y, *, omega=None):
    """Nominal stability and performance of the loop of G and K with the paper's weights.

    Parameters
    ----------
    G, K : control.LTI
        Plant u_c [V] -> v_y [V] and controller v_e [V] -> u_b [V].
    H_m, H_e, H_y : control.LTI
        Uncertainty, error and output weights (eq. 8, 15).
    omega : array_like, optional
        Grid [rad/s] of the mu analysis (:func:`piezolib.problem.analysis.analyze`; default
        its :data:`~piezolib.problem.analysis.ANALYSIS_GRID`).

    Returns
    -------
    NominalAudit
        With Table 3 by :func:`piezolib.problem.analysis.analyze` and the peaks of
        |S| and |T| by :func:`piezolib.robust.hinf_norm` (dense grid, refined peak).
    """
    check_siso("K", K)
    check_siso("G", G)
    table3 = analyze(K, G, H_m, H_e, H_y, omega=omega, name="published K")
    poles = table3.closed_loop_poles
    loop = loop_functions(G, K)
    norm_S, omega_S = hinf_norm(loop.S)
    norm_T, omega_T = hinf_norm(loop.T)
    return NominalAudit(analysis=table3, loop=loop, slowest_pole=poles[np.argmax(poles.real)],
                        steady_state_error=float(ct.dcgain(loop.S)),
                        dc_T=float(ct.dcgain(loop.T)), norm_S=float(norm_S),
                        omega_S=float(omega_S), norm_T=float(norm_T), omega_T=float(omega_T),
                        bandwidth_Hz=float(bandwidth(loop.T) / (2 * np.pi)))


@dataclass(frozen=True)
class TableConsistency:
    """The printed Tables 4-5 against themselves and against the text (Sec. V, VI).

    Attributes
    ----------
    improvements : pandas.DataFrame
        One row per improvement cell: ``table`` ("Table 4" | "Table 5"), ``row``,
        ``column`` (amplitude [V] or frequency [Hz]), ``printed`` and ``implied``
        (100 (e_before - e_after) / e_before from the printed case rows) [%].
    averages : pandas.Series
        Mean of each improvement row that Sec. VI quotes, keyed as
        :data:`piezolib.problem.paper.CONCLUSION_AVERAGES` [%].
    text_variants : pandas.DataFrame
        Numbers the text prints differently from its table: ``table``, ``row``,
        ``column``, ``text`` and ``table_value`` [%].
    """

    improvements: pd.DataFrame
    averages: pd.Series
    text_variants: pd.DataFrame

    @property
    def worst(self):
        """Largest |implied - printed| per table [percentage points]."""
        gap = (self.improvements.implied - self.improvements.printed).abs()
        return gap.groupby(self.improvements.table).max().to_dict()

    @property
    def checks(self):
        """``{what it states: bool}``: the printed improvements follow from the case rows."""
        return {f"printed improvements follow from the case rows (within "
                f"{IMPROVEMENT_ATOL_PERCENT} points)":
                max(self.worst.values()) < IMPROVEMENT_ATOL_PERCENT}

    def claims(self):
        """The claim rows of this audit, in order (for ``ClaimTable.add(**row)``).

        Returns
        -------
        list of dict
            Keys ``section``, ``quantity``, ``paper``, ``ours`` and the keywords
            ``unit``, ``atol``, ``reason``, ``note``: every improvement cell, the
            averages of Sec. VI, then the text variants.
        """
        rows = [dict(section=r.table, quantity=f"{r.row} at {r.column:g}", paper=r.printed,
                     ours=round(r.implied, 2), unit="%", atol=IMPROVEMENT_ATOL_PERCENT,
                     note="recomputed from the case rows")
                for r in self.improvements.itertuples()]
        rows += [dict(section="Sec. VI", quantity=f"average {key}",
                      paper=paper.CONCLUSION_AVERAGES[key], ours=round(value, 2), unit="%",
                      atol=0.02, note="mean of the improvement row")
                 for key, value in self.averages.items()]
        rows += [dict(section="Sec. V-B text",
                      quantity=f"Case {_improved_case(r.row)} improvement at {r.column:g} Hz "
                               "(text)",
                      paper=r.text, ours=r.table_value, unit="%",
                      atol=IMPROVEMENT_ATOL_PERCENT, reason="typo",
                      note=f"the text prints {r.text:.2f}; Table {r.table[-1]} and its case "
                           f"rows give {r.table_value:.2f}: a typo in the text")
                 for r in self.text_variants.itertuples()]
        return rows


def _improved_case(row):
    """The improved case of an improvement row: ``"improvement_II_vs_I"`` -> ``"II"``."""
    return row.split("_")[1]


def table_consistency():
    """Recompute the improvement rows of Tables 4-5 from their case rows, and Sec. VI's averages.

    Returns
    -------
    TableConsistency

    Examples
    --------
    >>> consistency = table_consistency()
    >>> all(consistency.checks.values()), len(consistency.improvements)
    (True, 30)
    """
    rows = []
    tables = {"Table 4": paper.table4(), "Table 5": paper.table5()}
    for name, table in tables.items():
        I, II, III = (table.loc[f"case_{c}"].to_numpy(dtype=float) for c in ("I", "II", "III"))
        implied = {"improvement_II_vs_I": improvement_percent(I, II),
                   "improvement_III_vs_I": improvement_percent(I, III),
                   "improvement_III_vs_II": improvement_percent(II, III)}
        for row, values in implied.items():
            for column, value in zip(table.columns, values):
                rows.append(dict(table=name, row=row, column=column,
                                 printed=float(table.loc[row, column]), implied=float(value)))
    t4, t5 = tables["Table 4"], tables["Table 5"]
    averages = pd.Series({"hysteresis_III_vs_I": t4.loc["improvement_III_vs_I"].mean(),
                          "hysteresis_III_vs_II": t4.loc["improvement_III_vs_II"].mean(),
                          "tracking_III_vs_I": t5.loc["improvement_III_vs_I"].mean(),
                          "tracking_III_vs_II": t5.loc["improvement_III_vs_II"].mean()})
    variants = pd.DataFrame(
        [dict(table=key[0], row=key[1], column=key[2], text=text,
              table_value=float({"table4": t4, "table5": t5}[key[0]].loc[key[1], key[2]]))
         for key, text in paper.TEXT_VARIANTS.items()],
        columns=["table", "row", "column", "text", "table_value"])
    return TableConsistency(pd.DataFrame(rows), averages, variants)
