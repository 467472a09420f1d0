"""Figures of notebook 05 (mu-synthesis): D-scaling fit, Hankel values, the delay-aware
design, Fig. 10 and Fig. 12."""

import control as ct
import numpy as np
from matplotlib.lines import Line2D

from piezolib.robust.lti import loop_functions
from piezolib.workbook import plotting
from piezolib.workbook.design_run import SearchRecord
from piezolib.workbook.style import new_figure, plot_magnitude
from piezolib.workbook.figures.audit import STEP_TITLES

__all__ = ["extra_d_scaling_fit", "extra_hankel_singular_values", "extra_delay_aware_design",
           "fig10_step_responses_designs", "fig12_mu_bounds"]


def extra_d_scaling_fit(mu_run):
    """The optimal D-scaling of the final controller against the fit used to get it.

    Parameters
    ----------
    mu_run : piezolib.robust.dk.MusynResult or piezolib.workbook.design_run.SearchRecord
        A DK-iteration result or its record (its grid ``omega`` [rad/s], the optimal
        d(omega) and the fitted d(s) of the last K-step).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_d_scaling_fit.png``.
    """
    record = mu_run if isinstance(mu_run, SearchRecord) else SearchRecord.of_dk(mu_run)
    if record.d_fit is None:
        raise ValueError("mu_run has no fitted D-scaling (its first, unscaled K-step was "
                         "the best): nothing to compare")
    omega = record.omega
    fig, ax = new_figure(figsize=(6.5, 3.4))
    plot_magnitude(ax, omega, record.optimal_d, label="optimal d(omega) for the final K")
    plot_magnitude(ax, omega, record.d_fit,
                   label=f"order-{record.d_fit_order} fit used in the last K-step", ls="--")
    ax.set_ylabel("|d| [dB]")
    ax.legend()
    plotting.name_figure(fig, None, "d_scaling_fit")
    return fig


def extra_hankel_singular_values(hsv, order=6):
    """G S-weighted Hankel singular values of the full controller, cut after ``order``.

    Parameters
    ----------
    hsv : array_like
        Hankel singular values, largest first.
    order : int
        Order of the reduced controller (a dotted line after it).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_hankel_singular_values.png``.
    """
    hsv = np.asarray(hsv)
    fig, ax = new_figure(figsize=(6.5, 3.2))
    ax.semilogy(np.arange(1, hsv.size + 1), hsv, "o-")
    ax.axvline(order + 0.5, color="k", ls=":", lw=1)
    ax.set_xlabel("state (balanced)")
    ax.set_ylabel("G S-weighted Hankel singular value")
    plotting.name_figure(fig, None, "hankel_singular_values")
    return fig


def fig10_step_responses_designs(G, controllers, t=None):
    """Fig. 10 for several controllers: step responses of S, T, KS and GS.

    Parameters
    ----------
    G : control.LTI
        Plant, u_c [V] -> v_y [V].
    controllers : dict
        ``{label: K}``, continuous-time SISO controllers.
    t : array_like, optional
        Time grid [s]; default 0 ... 10 ms, 2001 points.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig10_step_responses_designs.png``; KS (which starts at
        K(inf)) is on a symmetric log axis.
    """
    t = np.linspace(0, 0.01, 2001) if t is None else t
    fig, axes = new_figure(2, 2, figsize=(9, 5.5), sharex=True)
    # overlapping designs stay visible: wide solid first, thinner dashed/dotted on top
    styles = [dict(ls="-", lw=2.6), dict(ls="--", lw=1.8), dict(ls="-.", lw=1.4),
              dict(ls=":", lw=1.8), dict(ls=(0, (5, 1, 1, 1)), lw=1.1)]
    for k, (name, K) in enumerate(controllers.items()):
        loop = loop_functions(G, K)
        for ax, title, sys in zip(axes.flat, STEP_TITLES.values(), loop):
            resp = ct.step_response(sys, T=t)
            ax.plot(1e3 * resp.time, np.ravel(resp.outputs), label=name,
                    **styles[k % len(styles)])
            ax.set_title(title)
    for ax in axes.flat:
        ax.set_ylabel("amplitude [V/V]")
    # a biproper K makes KS start at K(inf) (hundreds of V/V), a strictly proper one peaks
    # within microseconds: next to a settled value near 1, that needs a symmetric log axis
    axes[1, 0].set_yscale("symlog", linthresh=1.0)
    axes[1, 0].set_ylabel("amplitude [V/V] (log beyond +-1)")
    for ax in axes[1]:
        ax.set_xlabel("time [ms]")
    axes[0, 1].legend(loc="lower right")
    plotting.name_figure(fig, 10, "step_responses_designs")
    return fig


def fig12_mu_bounds(results):
    """Fig. 12: mu for robust stability and robust performance of several controllers.

    Parameters
    ----------
    results : dict
        ``{label: RobustnessAnalysis}`` (:func:`piezolib.problem.analysis.analyze`).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig12_mu_bounds.png``.  One legend below both panels: a
        colour per controller, and the line styles of the upper and lower
        bounds of (b); it covers no curve.
    """
    fig, (ax_rs, ax_rp) = new_figure(1, 2, figsize=(10, 4.4), sharey=True)
    handles = []
    for name, a in results.items():
        line, = ax_rs.semilogx(a.omega, a.mu_RS_curve, label=name)
        handles.append(line)
        ax_rp.semilogx(a.omega, a.mu_RP_upper, color=line.get_color(), lw=2.4, alpha=0.45,
                       label=f"{name}, upper")
        ax_rp.semilogx(a.omega, a.mu_RP_lower_curve, color=line.get_color(), ls="--", lw=1.0,
                       label=f"{name}, lower")
    # the two line styles of (b), drawn in grey: the colours name the controllers
    handles += [Line2D([], [], color="0.4", lw=2.4, alpha=0.45, label="(b) upper bound"),
                Line2D([], [], color="0.4", ls="--", lw=1.0, label="(b) lower bound")]
    for ax, title in ((ax_rs, "(a) robust stability: mu(M11) = |H_m T|"),
                      (ax_rp, "(b) robust performance: mu(M), upper and lower bounds")):
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xlim(1e0, 1e7)
        ax.set_xlabel("frequency [rad/s]")
        ax.set_title(title)
    ax_rs.set_ylabel("μ")
    # below both panels: inside, any study's curves may run where a legend sits
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 4),
               fontsize=7)
    plotting.name_figure(fig, 12, "mu_bounds")
    return fig


def extra_delay_aware_design(omega, mu_results, controllers, rolloff=None, lower_bound=None):
    """mu bounds of the delay-aware designs and the controllers' gains against the roll-off.

    Parameters
    ----------
    omega : array_like
        Frequencies [rad/s] of the mu results and of the gain plot.
    mu_results : dict
        ``{label: MuResult}`` on ``omega`` (upper bound solid, lower dotted).
    controllers : dict
        ``{label: K}``, continuous SISO controllers [V/V] for panel (b).
    rolloff : control.LTI, optional
        Roll-off weight W_u; 1 / |W_u| is drawn as the gain allowance.
    lower_bound : float, optional
        Lower bound on the achievable peak mu (horizontal line).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_delay_aware_design.png``.
    """
    omega = np.asarray(omega, float)
    fig, (ax_mu, ax_k) = new_figure(1, 2, figsize=(11, 4.0))
    for name, res in mu_results.items():
        line, = ax_mu.semilogx(omega, res.upper, label=f"{name}, upper")
        ax_mu.semilogx(omega, res.lower, ls=":", lw=2.2, color=line.get_color(),
                       label=f"{name}, lower")
    if lower_bound is not None:
        ax_mu.axhline(lower_bound, color="k", ls="--", lw=0.9,
                      label=f"no controller below {lower_bound:.3f}")
    ax_mu.set_xlim(omega[0], omega[-1])
    ax_mu.set_xlabel("frequency [rad/s]")
    ax_mu.set_ylabel("mu_RP")
    ax_mu.set_title("(a) mu_RP of the delay-aware problem")
    ax_mu.legend(fontsize=7, loc="lower left")
    for name, K in controllers.items():
        plot_magnitude(ax_k, omega, np.ravel(K(1j * omega)), label=name)
    if rolloff is not None:
        plot_magnitude(ax_k, omega, 1 / np.ravel(rolloff(1j * omega)), color="k",
                                ls="--", lw=0.9, label="1 / |W_u| (roll-off allowance)")
    ax_k.set_ylabel("|K| [dB]")
    ax_k.set_title("(b) controller gain")
    ax_k.legend(fontsize=7, loc="lower left")
    plotting.name_figure(fig, None, "delay_aware_design")
    return fig

