"""Figures of notebook 02 (uncertainty): Fig. 6 and the exact parametric margin."""

import numpy as np
from matplotlib.collections import LineCollection

from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure

__all__ = ["fig06_relative_error", "extra_parametric_margin"]


def fig06_relative_error(omega, errors, envelope, H_m, W_fit, spread, peak=None):
    """Fig. 6: the members' relative errors, their envelope, H_m and a fitted weight.

    Log-log axes.  The envelope E_m is drawn on ``omega``; its peak is set by
    resonances a few rad/s wide that a grid samples by chance, so the
    grid-independent (refined) peak is marked separately when ``peak`` is
    given.  The legend states how far the fitted weight rises above E_m
    (its largest ratio |W_fit| / E_m on the grid).

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
    peak : pair of float, optional
        (value, omega [rad/s]) of the refined peak of E_m
        (:func:`piezolib.uncertainty.envelope_peak`), marked with a dot.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig06_relative_error.png``.
    """
    omega = np.asarray(omega, dtype=float)
    envelope = np.asarray(envelope, dtype=float)
    log_w = np.log10(omega)
    fig, ax = new_figure(figsize=(7.0, 4.6))
    segments = [np.column_stack([omega, np.maximum(e, 1e-12)]) for e in errors]
    ax.add_collection(LineCollection(segments, colors="0.6", linewidths=0.4, linestyles=":",
                                     label=f"|G_k/G - 1|, {len(errors)} models (dotted)"))
    W_mag = np.abs(np.ravel(W_fit(1j * omega)))
    excess = np.max(W_mag / envelope)
    ax.loglog(omega, envelope, color="0.15", lw=0.9,
              label=f"E_m, stable members, on the {omega.size}-point grid "
                    f"(grid maximum {envelope.max():.0f})")
    ax.loglog(omega, np.abs(np.ravel(H_m(1j * omega))), color=PALETTE.contrast, lw=1.8,
              label="published H_m (eq. 8)")
    ax.loglog(omega, W_mag, color=PALETTE.primary, lw=1.6,
              label=f"fitted 5th-order weight: covers E_m, up to {excess:.0f}x "
                    f"({20 * np.log10(excess):.0f} dB) above it")
    if peak is not None:
        value, w_peak = float(peak[0]), float(peak[1])
        ax.loglog(w_peak, value, "o", color=PALETTE.highlight, ms=5,
                  label=f"refined peak of E_m: {value:.0f} at {w_peak:.0f} rad/s "
                        "(a resonance too narrow for the grid)")
    ax.set(xlim=(10 ** np.floor(log_w[0]), 10 ** np.ceil(log_w[-1])), ylim=(1e-5, 3e3),
           xlabel="frequency [rad/s]", ylabel="magnitude [-]",
           title=f"Relative errors of the +-{spread:.0%} set (Fig. 6)")
    ax.legend(loc="lower left", fontsize=7)
    plotting.name_figure(fig, 6, "relative_error")
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
    fig, ax = new_figure(figsize=(7.0, 3.8))
    ax.loglog(omega, 100 * gauge, label="closed loop with K")
    ax.loglog(omega, 100 * gauge_open, "--", label="open loop (members)")
    for value, style, text, shift in [
            (spread, ":", f"paper: +-{100 * spread:g} %", 1.08),
            (small_gain, "-.", "certified by small gain, pointwise", 1.08),
            (weight_spread, (0, (1, 3)), "certified by the published H_m", 0.80)]:
        ax.axhline(100 * value, ls=style, color="0.3", lw=1)
        ax.text(1.2 * omega[0], 100 * value * shift, text, fontsize=7)
    ax.plot(margin.omega, 100 * margin.spread, "o", color=PALETTE.contrast,
            label=f"delta* = {margin.spread:.2%} at {margin.omega:.0f} rad/s")
    ax.set(xlabel="frequency [rad/s]", ylabel="smallest spread putting 0\nin the value set [%]",
           ylim=(1.0, 300),
           title="Zero exclusion: exact robust-stability margin against the coefficient spread")
    ax.legend(loc="center right", fontsize=7)       # right of the curves, above the lines
    plotting.name_figure(fig, None, "parametric_margin")
    return fig
