"""Figures of notebook 02 (uncertainty): Fig. 6 and the exact parametric margin."""

import numpy as np
from matplotlib.collections import LineCollection

from piezolib.workbook import plotting

__all__ = ["fig06_relative_error", "extra_parametric_margin"]


def fig06_relative_error(omega, errors, envelope, H_m, W_fit, spread):
    """Fig. 6: the members' relative errors, their envelope, H_m and a fitted weight.

    Parameters
    ----------
    omega : array_like
        Frequency grid [rad/s].
    errors : ndarray, shape (M, len(omega))
        |G_k/G - 1| of every member (dotted grey curves).
    envelope : ndarray
        E_m over the stable members on ``omega``.
    H_m : control.LTI
        The published multiplicative weight (eq. 8).
    W_fit : control.LTI
        A fitted covering weight (5th order in the notebook).
    spread : float
        Relative spread of the set (title).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig06_relative_error.png``.
    """
    omega = np.asarray(omega, dtype=float)
    log_w = np.log10(omega)
    fig, ax = plotting.new_figure(figsize=(7.0, 4.4))
    segments = [np.column_stack([log_w, np.log10(np.maximum(e, 1e-12))]) for e in errors]
    ax.add_collection(LineCollection(segments, colors="0.55", linewidths=0.4, linestyles=":",
                                     label=f"|G_k/G - 1|, {len(errors)} models (dotted)"))
    ax.plot(log_w, np.log10(envelope), color="0.2", lw=0.8, label="E_m, stable members")
    ax.plot(log_w, np.log10(np.abs(np.ravel(H_m(1j * omega)))), color="#c0504d", lw=1.8,
            label="published H_m (eq. 8)")
    ax.plot(log_w, np.log10(np.abs(np.ravel(W_fit(1j * omega)))), color="#1f4e79", lw=1.6,
            label="fitted 5th-order weight")
    ax.set(xlim=(0, 6), ylim=(-5, 3), xlabel="log10 frequency [rad/s]", ylabel="log10 magnitude",
           title=f"Relative errors of the +-{spread:.0%} set (Fig. 6)")
    ax.legend(loc="lower left")
    plotting.save_figure(fig, 6, "relative_error")
    return fig


def extra_parametric_margin(omega, gauge, gauge_open, margin, spread, small_gain, weight_spread):
    """The stability gauge against frequency, with the exact margin and the certified spreads.

    Parameters
    ----------
    omega : array_like
        Frequency grid [rad/s] of the gauges.
    gauge, gauge_open : ndarray
        :func:`piezolib.uncertainty.stability_gauge` with the controller and
        of the open loop, on ``omega``.
    margin : piezolib.uncertainty.ParametricMargin
        Exact margin of the closed loop (marked with a dot).
    spread : float
        The paper's spread (a horizontal line).
    small_gain : float
        Spread certified by the small-gain test with the exact envelope.
    weight_spread : float
        Spread certified by the published H_m.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_parametric_margin.png``.
    """
    omega = np.asarray(omega, dtype=float)
    fig, ax = plotting.new_figure(figsize=(7.0, 3.8))
    ax.loglog(omega, 100 * gauge,
              label="closed loop with K: smallest spread putting 0 in the value set")
    ax.loglog(omega, 100 * gauge_open, "--", label="open loop (stability of the members)")
    for value, style, text, shift in [
            (spread, ":", f"paper: +-{100 * spread:g} %", 1.08),
            (small_gain, "-.", "certified by small gain, pointwise", 1.08),
            (weight_spread, (0, (1, 3)), "certified by the published H_m", 0.80)]:
        ax.axhline(100 * value, ls=style, color="0.3", lw=1)
        ax.text(1.2 * omega[0], 100 * value * shift, text, fontsize=7)
    ax.plot(margin.omega, 100 * margin.spread, "o", color="#c0504d",
            label=f"delta* = {margin.spread:.2%} at {margin.omega:.0f} rad/s")
    ax.set(xlabel="frequency [rad/s]", ylabel="spread [%]", ylim=(1.0, 300),
           title="Zero exclusion: exact robust-stability margin against the coefficient spread")
    ax.legend(loc="upper right", fontsize=7)
    plotting.save_figure(fig, None, "parametric_margin")
    return fig
