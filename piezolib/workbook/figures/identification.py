"""Figures of notebook 01: the virtual stage and the identification (Sec. II, III-A).

Each ``figNN_*`` / ``extra_*`` function draws one figure from computed
results, saves it with :func:`piezolib.workbook.plotting.save_figure` (paper
number or ``extra_``) and returns the figure.  :func:`bode_overlay` is the
Bode plot of several models (and data) that the last figure is built on.
"""

import control as ct
import numpy as np

from piezolib import identification
from piezolib._checks import check_finite_array, check_siso
from piezolib.robust.lti import frequency_grid, realize
from piezolib.workbook.plotting import db, new_figure, save_figure

__all__ = [
    "bode_overlay", "extra_stage_case_i_loops", "extra_identification_chirp",
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
    np.atleast_1d(axes)[0].set_ylabel("displacement 3 µm/V · v_y [µm]")
    save_figure(fig, None, "stage_case_i_loops")
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
    save_figure(fig, None, "identification_chirp")
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
    ax_a.set_ylim(-7, 7)
    ax_b.set_ylim(-0.4, 0.4)
    ax_b.set_xlabel("time [s] (dashed: start of the sweep)")
    ax_a.set_title("parameter convergence of the final RLS pass (eq. 1–3)")
    save_figure(fig, None, "rls_convergence")
    return fig


def fig04_chirp_validation(y, y_sim, sweep_start, fs, zoom_s=(0.55, 0.57)):
    """Fig. 4: measured and simulated output of the validation chirp.

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
        Time window [s] after the sweep start of the residual panel.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig04_chirp_validation.png``.
    """
    y = check_finite_array("y", y, ndim=1, min_length=2)
    y_sim = check_finite_array("y_sim", y_sim, ndim=1, min_length=2)
    sweep = slice(sweep_start, None)
    fit = identification.fit_percent(y[sweep], y_sim[sweep])
    residual = y[sweep] - y_sim[sweep]
    t = (np.arange(len(y)) - sweep_start) / fs
    fig, (ax_full, ax_zoom) = new_figure(2, 1, figsize=(7.0, 5.0))
    for ax in (ax_full, ax_zoom):
        ax.plot(t[sweep], y[sweep], lw=0.8, label="measured (virtual stage)")
        ax.plot(t[sweep], y_sim[sweep], lw=0.8, ls="--", label="simulated (identified model)")
        ax.set_ylabel("v_y − operating point [V]")
    ax_full.set_title(f"validation chirp: fit {fit:.1f} %")
    ax_full.legend(loc="lower left")
    zoom = (t > zoom_s[0]) & (t < zoom_s[1])
    ax_zoom.plot(t[zoom], residual[zoom[sweep]], lw=0.6, color="0.4", label="residual")
    ax_zoom.set_xlim(*zoom_s)
    ax_zoom.set_xlabel("time since the start of the sweep [s]")
    ax_zoom.legend(loc="lower left")
    save_figure(fig, 4, "chirp_validation")
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
    save_figure(fig, None, "residual_whiteness")
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
    save_figure(fig, None, "bode_identified_vs_published")
    return fig
