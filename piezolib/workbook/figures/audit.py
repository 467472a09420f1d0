"""Figures of notebook 00 (the published design at a glance): Fig. 10 and 11.

The block diagrams of notebook 00 (Fig. 1, 2, 9) are in
:mod:`piezolib.workbook.figures.diagrams`.
"""

import control as ct
import numpy as np

from piezolib.robust.lti import frequency_grid
from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure, plot_magnitude

__all__ = ["fig10_step_responses", "fig11_sensitivity_templates",
           "sensitivity_templates_figure", "STEP_TITLES"]

#: Panel titles of the step responses of Fig. 10, in the order of LoopFunctions (S, T, KS, GS).
STEP_TITLES = {"S": "(a) S: v_r -> v_e", "T": "(b) T: v_r -> v_y",
               "KS": "(c) KS: v_r -> u_b", "GS": "(d) GS: input disturbance -> v_y"}


def fig10_step_responses(loop, t=None):
    """Fig. 10: step responses of S, T, KS and GS of one loop.

    Parameters
    ----------
    loop : piezolib.robust.lti.LoopFunctions
        The loop functions, e.g. ``robust.loop_functions(G, K)``.
    t : array_like, optional
        Time grid [s]; default 0 ... 10 ms, 2001 points.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig10_step_responses.png``.
    """
    t = np.linspace(0, 0.01, 2001) if t is None else t
    fig, axes = new_figure(2, 2, figsize=(8, 5), sharex=True)
    for ax, title, sys in zip(axes.flat, STEP_TITLES.values(), loop):
        resp = ct.step_response(sys, T=t)
        ax.plot(1e3 * resp.time, np.ravel(resp.outputs))
        ax.set_title(title)
        ax.set_ylabel("amplitude [V/V]")
    # a biproper K makes KS start at K(inf) (hundreds of V/V), a strictly proper one peaks
    # within microseconds: next to a settled value near 1, that needs a symmetric log axis
    axes[1, 0].set_yscale("symlog", linthresh=1.0)
    axes[1, 0].set_ylabel("amplitude [V/V] (log beyond +-1)")
    for ax in axes[1]:
        ax.set_xlabel("time [ms]")
    plotting.name_figure(fig, 10, "step_responses")
    return fig


def fig11_sensitivity_templates(loop, H_e, H_y, omega=None):
    """Fig. 11: |S| and |T| of one loop under their templates 1/|H_e| and 1/|H_y|.

    Parameters
    ----------
    loop : piezolib.robust.lti.LoopFunctions
    H_e, H_y : control.LTI
        Error and output weights (eq. 15).
    omega : array_like, optional
        Frequency grid [rad/s]; default 1 ... 1e7 rad/s, 3000 points.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig11_sensitivity_templates.png``.
    """
    fig = sensitivity_templates_figure({None: loop}, H_e, H_y, omega)
    plotting.name_figure(fig, 11, "sensitivity_templates")
    return fig


def sensitivity_templates_figure(loops, H_e, H_y, omega=None, template_color=None):
    """The two panels of Fig. 11, drawn but not named: |S| and |T| of each loop
    under their templates 1/|H_e| and 1/|H_y| (dotted).

    Parameters
    ----------
    loops : dict
        ``{label: LoopFunctions}``; the label ``None`` draws plain ``|S|``, ``|T|``.
    H_e, H_y : control.LTI
        Error and output weights (eq. 15).
    omega : array_like, optional
        Frequency grid [rad/s]; default 1 ... 1e7 rad/s, 3000 points.
    template_color : matplotlib color, optional
        Colour of the templates; default the next colour of the cycle.

    Returns
    -------
    matplotlib.figure.Figure
    """
    omega = frequency_grid(1e0, 1e7, 3000) if omega is None else omega
    s = 1j * omega
    fig, (ax_s, ax_t) = new_figure(1, 2, figsize=(9, 3.6), sharey=True)
    style = {"ls": ":"} if template_color is None else {"ls": ":", "color": template_color}
    for name, loop in loops.items():
        suffix = "" if name is None else f", {name}"
        plot_magnitude(ax_s, omega, np.ravel(loop.S(s)), label=f"|S|{suffix}")
        plot_magnitude(ax_t, omega, np.ravel(loop.T(s)), label=f"|T|{suffix}")
    plot_magnitude(ax_s, omega, 1 / np.ravel(H_e(s)), label="1/|H_e|", **style)
    plot_magnitude(ax_t, omega, 1 / np.ravel(H_y(s)), label="1/|H_y|", **style)
    ax_s.set_title("(a) output sensitivity S and its template")
    ax_t.set_title("(b) complementary sensitivity T and its template")
    ax_s.set_ylim(-80, 30)
    # the empty corners: S rises to 0 dB at high frequency, T falls from 0 dB
    ax_s.legend(loc="lower right")
    ax_t.legend(loc="lower left")
    return fig
