"""Figures of notebook 01: the virtual stage and the identification (Sec. II, III-A).

Each ``figNN_*`` / ``extra_*`` function draws one figure from computed
results, names it with :func:`piezolib.workbook.plotting.name_figure` (paper
number or ``extra_``) and returns the figure.  :func:`bode_overlay` is the
Bode plot of several models (and data) that the last figure is built on.
"""

import control as ct
import numpy as np

from piezolib import identification
from piezolib._checks import check_finite_array, check_signals, check_siso
from piezolib.robust.lti import frequency_grid, realize
from piezolib.workbook.plotting import name_figure
from piezolib.workbook.style import PALETTE, db, new_figure

__all__ = [
    "bode_overlay", "extra_stage_case_i_loops", "fig13_hysteresis_measure",
    "extra_identification_chirp",
    "extra_rls_convergence", "fig04_chirp_validation", "extra_residual_whiteness",
    "extra_bode_identified_vs_published",
]


def bode_overlay(systems, omega, measured=None, axes=None):
    """Bode magnitude and phase of several models (and optionally data).

    Parameters
    ----------
    systems : dict
        {label: control.LTI} (SISO).  Continuous models are evaluated at
        s = j omega, discrete ones at z = exp(j omega dt) (drawn dashed), as
        sampled data see them.
    omega : array_like
        Frequency grid [rad/s].
    measured : tuple, optional
        (omega [rad/s], complex response), e.g. from
        :func:`piezolib.identification.empirical_frequency_response`, drawn
        as dots.
    axes : pair of matplotlib Axes, optional
        Magnitude and phase axes; created when omitted.

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : (ax_mag, ax_phase)
    """
    omega = check_finite_array("omega", omega, ndim=1, min_length=2)
    if axes is None:
        fig, axes = new_figure(2, 1, sharex=True, figsize=(7.0, 5.0))
    ax_mag, ax_phase = axes
    fig = ax_mag.figure
    if measured is not None:
        w, h = measured
        ax_mag.semilogx(w, db(h), ".", ms=2.5, color="0.55", label="measured (Welch)")
        ax_phase.semilogx(w, np.degrees(np.unwrap(np.angle(h))), ".", ms=2.5, color="0.55")
    for label, sys in systems.items():
        check_siso(label, sys)
        if sys.isdtime(strict=True):
            w = omega[omega < np.pi / sys.dt]
            h = np.asarray(sys(np.exp(1j * w * sys.dt))).ravel()
            style = dict(ls="--", lw=1.0)
        else:
            w, h, style = omega, np.asarray(sys(1j * omega)).ravel(), {}
        ax_mag.semilogx(w, db(h), label=label, **style)
        ax_phase.semilogx(w, np.degrees(np.unwrap(np.angle(h))), **style)
    ax_mag.set_ylabel("magnitude [dB]")
    ax_phase.set_ylabel("phase [deg]")
    ax_phase.set_xlabel("frequency [rad/s]")
    ax_mag.legend()
    return fig, (ax_mag, ax_phase)


def extra_stage_case_i_loops(loops, percent, paper_percent):
    """The Table 4 Case I loops of the virtual stage, one panel per amplitude.

    Parameters
    ----------
    loops : dict
        {actuator amplitude [V]: StageRecord}, e.g.
        :func:`piezolib.problem.stage_data.load_hysteresis_loops`.
    percent : dict
        {amplitude: hysteresis % of the loop}.
    paper_percent : mapping
        {amplitude: published Case I hysteresis %}.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_stage_case_i_loops.png``.
    """
    fig, axes = new_figure(1, len(loops), figsize=(10.0, 2.8))
    for ax, (A, rec) in zip(np.atleast_1d(axes), loops.items()):
        ax.plot(rec.v_a_V, rec.x_measured_um, lw=0.8)
        ax.set_title(f"{A:g} V: {percent[A]:.2f} % (paper {paper_percent[A]:.2f} %)")
        ax.set_xlabel("actuator voltage v_a [V]")
    np.atleast_1d(axes)[0].set_ylabel("displacement 3 um/V * v_y [um]")
    fig.suptitle("Table 4, Case I: the recorded loops of data/hysteresis_loop_*.csv (3 periods "
                 "each, all measured); notebook 06 reruns Case I with its own noise", fontsize=8)
    name_figure(fig, None, "stage_case_i_loops")
    return fig


def fig13_hysteresis_measure(v, x, measure, amplitude_V):
    """Fig. 13: how the hysteresis % of eq. 25-26 is read off a measured loop.

    The loop is drawn with the midpoint input V_M (eq. 25), the two branch
    outputs at V_M (X_UP above, X_LO below) and the output range X_MAX -
    X_MIN that eq. 26 divides by, all taken from ``measure``.

    Parameters
    ----------
    v : array_like
        Input of the loop: actuator voltage [V].
    x : array_like
        Measured displacement [um], same length.
    measure : piezolib.hysteresis.HysteresisMeasure
        :func:`piezolib.hysteresis.hysteresis_measure` of ``(v, x)``.
    amplitude_V : float
        Amplitude of the triangle [V] (title).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig13_hysteresis_measure.png``.
    """
    v, x = check_signals(8, v=v, x=x)
    x_up, x_lo = max(measure.x_up, measure.x_lo), min(measure.x_up, measure.x_lo)
    v_min, v_max = float(v.min()), float(v.max())
    fig, ax = new_figure(figsize=(6.4, 4.6))
    ax.plot(v, x, color="0.45", lw=0.8, label="measured loop (virtual stage)")
    ax.axvline(measure.v_mid, color=PALETTE.primary, lw=1.0, ls="--")
    for level in (measure.x_max, measure.x_min):
        ax.axhline(level, color="0.6", lw=0.8, ls=":")
    ax.plot([measure.v_mid] * 2, [x_up, x_lo], "o", color=PALETTE.contrast, ms=5, zorder=3)
    ax.annotate("", xy=(measure.v_mid, x_lo), xytext=(measure.v_mid, x_up),
                arrowprops=dict(arrowstyle="<->", color=PALETTE.contrast, lw=1.2, shrinkA=4,
                                shrinkB=4))
    span = v_max - v_min
    # X_UP up-left and X_LO down-right of their points: both away from the branches
    ax.text(measure.v_mid - 0.03 * span, x_up, "X_UP", color=PALETTE.contrast, va="bottom",
            ha="right", fontsize=8)
    ax.text(measure.v_mid + 0.03 * span, x_lo, "X_LO", color=PALETTE.contrast, va="top",
            ha="left", fontsize=8)
    ax.text(measure.v_mid + 0.01 * span, measure.x_max + 0.04 * (measure.x_max - measure.x_min),
            "V_M = (V_MAX - V_MIN)/2 + V_MIN", color=PALETTE.primary, ha="left", va="bottom",
            fontsize=7.5)
    ax.text(v_min, measure.x_max, "X_MAX", va="bottom", ha="left", fontsize=7.5, color="0.35")
    ax.text(v_max, measure.x_min, "X_MIN", va="top", ha="right", fontsize=7.5, color="0.35")
    ax.set_xlim(v_min - 0.04 * span, v_max + 0.04 * span)
    x_span = measure.x_max - measure.x_min
    ax.set_ylim(measure.x_min - 0.12 * x_span, measure.x_max + 0.12 * x_span)
    ax.set(xlabel="actuator voltage v_a [V]", ylabel="displacement x = 3 um/V * v_y [um]",
           title=f"{amplitude_V:g} V loop: hysteresis = |X_UP - X_LO| / (X_MAX - X_MIN) "
                 f"x 100 = {measure.percent:.2f} %  (eq. 26)")
    ax.legend(loc="lower right")
    name_figure(fig, 13, "hysteresis_measure")
    return fig


def extra_identification_chirp(record):
    """Input and measured output of the identification chirp over time.

    Parameters
    ----------
    record : StageRecord
        The whole chirp run (ramp, hold, sweep).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_identification_chirp.png``.
    """
    fig, (ax_u, ax_y) = new_figure(2, 1, sharex=True, figsize=(7.0, 4.0))
    ax_u.plot(record.t_s, record.u_c_V, lw=0.6)
    ax_u.set_ylabel("u_c [V]")
    ax_y.plot(record.t_s, record.v_y_V, lw=0.4)
    ax_y.set_ylabel("v_y [V]")
    ax_y.set_xlabel("time [s]")
    ax_u.set_title("identification chirp: ramp, hold, logarithmic sweep")
    name_figure(fig, None, "identification_chirp")
    return fig


def extra_rls_convergence(model, fs, sweep_start):
    """Parameter histories of an RLS estimate (eq. 1-3), a_i above, b_i below.

    Parameters
    ----------
    model : piezolib.identification.ArxModel
        An RLS estimate, e.g. ``identify(...).discrete.final``.
    fs : float
        Sampling frequency [Hz] of the data.
    sweep_start : int
        Sample at which the sweep starts (dashed line).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_rls_convergence.png``.
    """
    history = model.rls.history
    na = len(model.a) - 1
    nb = history.shape[1] - na
    first = max(na, len(model.b) - 1)            # first predicted sample
    t_hist = (np.arange(len(history)) + first) / fs
    fig, (ax_a, ax_b) = new_figure(2, 1, sharex=True, figsize=(7.0, 4.6))
    for i in range(na):
        ax_a.plot(t_hist, history[:, i], lw=0.9, label=f"a{i + 1}")
    for i in range(nb):
        ax_b.plot(t_hist, history[:, na + i], lw=0.9, label=f"b{i + 1}")
    for ax, name in ((ax_a, "a"), (ax_b, "b")):
        ax.axvline(sweep_start / fs, color="0.6", lw=0.6, ls="--")
        ax.set_ylabel(f"{name}_i (discrete)")
        ax.legend(ncol=6, loc="lower right")
    ax_a.set_ylim(-8.5, 7)          # room for the legend under a3 (about -5)
    ax_b.set_ylim(-0.4, 0.4)
    ax_b.set_xlabel("time [s] (dashed: start of the sweep)")
    ax_a.set_title("parameter convergence of the final RLS pass (eq. 1–3)")
    name_figure(fig, None, "rls_convergence")
    return fig


def fig04_chirp_validation(y, y_sim, sweep_start, fs, zoom_s=(0.55, 0.57), window_s=0.005):
    """Fig. 4: measured and simulated output of the validation chirp.

    Three panels: (a) the whole sweep, each trace drawn as its envelope (its
    maximum and minimum over windows of ``window_s``), so that neither hides
    the other; (b) both traces over the ``zoom_s`` window; (c) the residual
    over that window [mV].

    Parameters
    ----------
    y : array_like
        Measured output deviation [V] from the start of the hold.
    y_sim : array_like
        Simulated output of the identified model [V], same samples.
    sweep_start : int
        Index of the first sweep sample in ``y``.
    fs : float
        Sampling frequency [Hz].
    zoom_s : pair of float, optional
        Time window [s] after the sweep start of panels (b) and (c).
    window_s : float, optional
        Length [s] of the envelope windows of panel (a).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig04_chirp_validation.png``.
    """
    y, y_sim = check_signals(2, y=y, y_sim=y_sim)
    sweep = slice(sweep_start, None)
    fit = identification.fit_percent(y[sweep], y_sim[sweep])
    t = (np.arange(len(y)) - sweep_start) / fs
    n = max(1, int(round(window_s * fs)))
    m = (len(y) - sweep_start) // n
    if m < 2:
        raise ValueError(f"window_s = {window_s} s leaves fewer than two windows in the sweep")
    t_env = t[sweep_start:sweep_start + m * n].reshape(m, n).mean(axis=1)
    fig, (ax_full, ax_zoom, ax_res) = new_figure(3, 1, figsize=(7.0, 7.0),
                                                 height_ratios=(1.3, 1.0, 0.7))
    styles = (("measured (virtual stage)", dict(color=PALETTE.measured, lw=2.2)),
              ("simulated (identified model)", dict(color=PALETTE.signal, lw=0.9, ls="--")))
    for (label, style), trace in zip(styles, (y, y_sim)):
        blocks = trace[sweep_start:sweep_start + m * n].reshape(m, n)
        ax_full.plot(t_env, blocks.max(axis=1), label=label, **style)
        ax_full.plot(t_env, blocks.min(axis=1), **style)
    ax_full.set(title=f"(a) whole sweep, envelopes over {1e3 * window_s:g} ms windows: "
                      f"fit {fit:.1f} %",
                xlabel="time since the start of the sweep [s]",
                ylabel="v_y − operating point [V]")
    ax_full.legend(loc="lower right")
    zoom = (t > zoom_s[0]) & (t < zoom_s[1])
    if zoom.sum() < 2:
        raise ValueError(f"zoom_s = {zoom_s} s holds fewer than two samples")
    for (label, style), trace in zip(styles, (y, y_sim)):
        ax_zoom.plot(t[zoom], trace[zoom], label=label, **style)
    ax_zoom.set(title=f"(b) {zoom_s[0]:g} ... {zoom_s[1]:g} s after the start of the sweep",
                xlim=zoom_s, xlabel="time since the start of the sweep [s]",
                ylabel="v_y − operating point [V]")
    ax_res.plot(t[zoom], 1e3 * (y[zoom] - y_sim[zoom]), lw=0.7, color="0.3")
    ax_res.set(title="(c) residual: measured − simulated", xlim=zoom_s,
               xlabel="time since the start of the sweep [s]", ylabel="residual [mV]")
    name_figure(fig, 4, "chirp_validation")
    return fig


def extra_residual_whiteness(white):
    """Autocorrelation of the validation residual with the 95 % band.

    Parameters
    ----------
    white : piezolib.identification.Whiteness

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_residual_whiteness.png``.
    """
    fig, ax = new_figure(figsize=(7.0, 2.8))
    ax.stem(white.lags, white.autocorrelation, basefmt=" ")
    ax.axhspan(-white.bound, white.bound, color="C1", alpha=0.2, label="95 % band, white noise")
    ax.set_xlabel("lag [samples]")
    ax.set_ylabel("R(i) / R(0)")
    ax.set_title(f"residual autocorrelation, validation chirp (Ljung–Box p = {white.p_value:.2f})")
    ax.legend()
    name_figure(fig, None, "residual_whiteness")
    return fig


def extra_bode_identified_vs_published(identified, published, u, y, fs, f_max_Hz):
    """Bode plot of the identified and published models over the data's estimate.

    Parameters
    ----------
    identified, published : control.LTI
        SISO continuous-time models.
    u, y : array_like
        Input and output deviations [V] of the validation sweep.
    fs : float
        Sampling frequency [Hz].
    f_max_Hz : float
        Highest frequency of the sweep [Hz]; the data are drawn up to 90 % of it.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_bode_identified_vs_published.png``.
    """
    omega = frequency_grid(2 * np.pi * 5, np.pi * fs, 600)
    w_data, h_data = identification.empirical_frequency_response(u, y, fs)
    in_sweep = w_data < 2 * np.pi * 0.9 * f_max_Hz
    sampled = ct.c2d(realize(identified), 1 / fs, "zoh")
    fig, axes = bode_overlay(
        {"identified": identified, "published G (eq. 4)": published,
         "identified, ZOH-sampled (what data see)": sampled},
        omega, measured=(w_data[in_sweep], h_data[in_sweep]))
    axes[0].set_title("identified vs published G, and the validation data")
    name_figure(fig, None, "bode_identified_vs_published")
    return fig
