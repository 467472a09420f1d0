"""Notebook 04's closing findings beyond its claim rows: eq. 16-18, the templates, each loop.

:func:`findings` turns the results of :mod:`piezolib.problem.weighting` into
the lines of :meth:`piezolib.workbook.session.Session.summary`.
"""

from piezolib._checks import check_nonnegative, check_type
from piezolib.problem import paper
from piezolib.problem.weighting import Eq16Entries, Templates, TemplatesMet

__all__ = ["findings"]


def _verdict(ok):
    return "yes" if ok else "**no**"


def _met(ok):
    return "met" if ok else "**not met**"


def findings(entries, lft_error, templates, error_params, met):
    """The findings of notebook 04 as Markdown lines (without their bullets).

    Parameters
    ----------
    entries : piezolib.problem.weighting.Eq16Entries
        P against eq. 16.
    lft_error : float
        The largest relative error of F_l(P, K) against eq. 18.
    templates : piezolib.problem.weighting.Templates
        The templates against eq. 15.
    error_params : paper.ErrorWeightParameters
        The parameters of H_e.
    met : piezolib.problem.weighting.TemplatesMet
        S and T of each controller under the templates.

    Returns
    -------
    list of str
        One line for eq. 16-18, one for the templates, one per controller.

    Examples
    --------
    >>> import numpy as np, pandas as pd
    >>> from piezolib.problem import weighting
    >>> t = weighting.template_asymptotes(paper.ERROR_WEIGHT, paper.OUTPUT_WEIGHT)
    >>> table = pd.DataFrame({"max relative error": [1e-10], "max |P| (zero entries)": [0.0]})
    >>> met = weighting.TemplatesMet({}, pd.DataFrame([("K", True, True, 1.0, -0.5, 400.0)],
    ...     columns=["controller", "|S| < 1/|H_e|", "|T| < 1/|H_y|", "||S|| [dB]",
    ...              "||T|| [dB]", "bandwidth of T [Hz]"]), {"K": True})
    >>> findings(weighting.Eq16Entries(table, np.logspace(0, 6, 200)), 3e-11, t, paper.ERROR_WEIGHT, met)[2]
    '**K:** |S| under 1/|H_e| yes, |T| under 1/|H_y| yes; ‖S‖∞ = 1.00 dB (limit 6 dB: met), ‖T‖∞ = -0.50 dB (limit 3.5 dB: met), bandwidth of T 400 Hz.'
    """
    check_type("entries", entries, Eq16Entries, "an Eq16Entries (weighting.eq16_entries)")
    check_type("templates", templates, Templates, "a Templates (weighting.template_asymptotes)")
    e = check_type("error_params", error_params, paper.ErrorWeightParameters,
                   "a paper.ErrorWeightParameters")
    check_type("met", met, TemplatesMet, "a TemplatesMet (weighting.templates_met)")
    check_nonnegative("lft_error", lft_error)
    S_max, T_max = paper.DESIGN_GOALS["S_peak_dB_max"], paper.DESIGN_GOALS["T_peak_dB_max"]
    lines = [f"**Eq. 16.** Our P reproduces every entry of eq. 16 to a relative error of "
             f"{entries.worst:.0e} ({entries.omega.size} frequencies); F_l(P, K) of the published K "
             f"equals eq. 18 to {lft_error:.0e}.",
             f"**Templates.** 1/|H_e| runs from ε_e = {e.eps_e:g} at DC to M_e = {e.M_e:g} at "
             f"high frequency and crosses 0 dB at {templates.crossing_rad_s:.4g} rad/s "
             f"(ω_e = {e.omega_e:g})."]
    for _, row in met.table.iterrows():
        lines.append(f"**{row.controller}:** |S| under 1/|H_e| {_verdict(row['|S| < 1/|H_e|'])}, "
                     f"|T| under 1/|H_y| {_verdict(row['|T| < 1/|H_y|'])}; ‖S‖∞ = "
                     f"{row['||S|| [dB]']:.2f} dB (limit {S_max:g} dB: "
                     f"{_met(row['||S|| [dB]'] < S_max)}), ‖T‖∞ = {row['||T|| [dB]']:.2f} dB "
                     f"(limit {T_max:g} dB: {_met(row['||T|| [dB]'] < T_max)}), bandwidth of T "
                     f"{row['bandwidth of T [Hz]']:.0f} Hz.")
    return lines
