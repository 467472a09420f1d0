"""Figures of notebook 03 (Dahl hysteresis): Fig. 7, Fig. 8 and the audit and Case II figures.

Axes are in the paper's units: actuator volts (10 x amplifier input) and
micrometres (3 um/V x sensor volts).
"""

import numpy as np

from piezolib.problem import paper
from piezolib.hysteresis import dahl_hysteresis, feedforward, hysteresis_percent
from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure
from piezolib.workbook.experiments import table4_reference

__all__ = ["extra_dahl_published_audit", "fig07_dahl_fit", "fig08_feedforward_on_model",
           "extra_case2_loops", "extra_case2_residual", "extra_model_validation"]

GAIN, UM = paper.AMPLIFIER_GAIN, paper.UM_PER_VOLT
#: Samples per period of the 10 Hz Table 4 triangle at the DAQ rate.
PERIOD = int(paper.SAMPLING_FREQUENCY_HZ / paper.HYSTERESIS_TEST["frequency_Hz"])
_FORM_COLORS = {"printed": PALETTE.primary, "bliman_sorine": PALETTE.contrast}


def _loop_width(v, x):
    """Hysteresis % of a (v, x) record, NaN when v never sweeps through V_M both ways."""
    try:
        return hysteresis_percent(v, x)
    except ValueError:
        return np.nan


def extra_dahl_published_audit(published, record, x_ranges):
    """The published Dahl parameters driven as printed: H, the 40 V stroke, loop width vs stroke.

    Parameters
    ----------
    published : dict
        {form: DahlModel} with the published parameters, both forms.
    record : StageRecord
        The 40 V Case I loop of the virtual stage (``u_c_V``, ``v_y_V``).
    x_ranges : dict
        {"x [um]": ..., "v_y (sensor) [V]": ..., ...}: the 40 V stroke of x in
        each unit convention (x-units).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_dahl_published_audit.png``.
    """
    fig, axes = new_figure(1, 3, figsize=(10.5, 3.3))
    t, x_path = table4_reference(40.0, periods=2)
    x_um = x_path * x_ranges["x [um]"] / x_path.max()
    for form, style, width in (("bliman_sorine", "--", 1.3), ("printed", "-", 2.6)):
        H = dahl_hysteresis(published[form], x_um)
        axes[0].plot(x_um, H, style, lw=width, color=_FORM_COLORS[form],
                     label=form.replace("_", "-"), zorder=3 - width)
    axes[0].set(xlabel="x [um] (driven, 2 periods)", ylabel="H [um]",
                title="(a) H of the published model, um convention")
    axes[0].legend()
    axes[1].plot(GAIN * record.u_c_V, UM * record.v_y_V, color="0.5", lw=0.8,
                 label="virtual stage, 40 V")
    for form, style in (("printed", "-"), ("bliman_sorine", "--")):
        x_v = x_path * x_ranges["v_y (sensor) [V]"] / x_path.max()
        v = feedforward(published[form], x_v)
        axes[1].plot(GAIN * v, UM * x_v, style, label=f"published, {form.replace('_', '-')}")
    axes[1].set(xlabel="actuator voltage 10 u_c [V]", ylabel="x = 3 v_y [um]",
                title="(b) 40 V stroke, v = u_c, x = v_y convention", ylim=(-1, 20))
    axes[1].legend(fontsize=7, loc="upper left")
    spans = np.logspace(-6, 5, 45)
    for form, style in (("printed", "-"), ("bliman_sorine", "--")):
        pct = []
        for span in spans:
            xs = x_path * span / x_path.max()
            pct.append(_loop_width(feedforward(published[form], xs)[PERIOD:], xs[PERIOD:]))
        axes[2].loglog(spans, np.maximum(pct, 1e-6), style, label=form.replace("_", "-"))
    for span in x_ranges.values():
        axes[2].axvline(span, color="0.6", lw=0.7)
    # unit tags as ticks of a top axis, clear of the curves
    tags = axes[2].secondary_xaxis("top")
    tags.set_xticks(list(x_ranges.values()), [u.split()[-1] for u in x_ranges], fontsize=7,
                    rotation=90)
    tags.minorticks_off()
    tags.set_xlabel("40 V stroke in each unit", fontsize=7)
    axes[2].axhspan(6, 13, color=PALETTE.agreement, alpha=0.2, label="Table 4, Case I")
    axes[2].set(xlabel="stroke of x [x-units]", ylabel="hysteresis % (eq. 26)",
                title="(c) loop width vs stroke length", ylim=(1e-6, 1e4))
    axes[2].legend(fontsize=7, loc="center right", bbox_to_anchor=(1.0, 0.3))
    plotting.name_figure(fig, None, "dahl_published_audit")
    return fig


def fig07_dahl_fit(loops, workbook, paper_form, amplitudes):
    """Fig. 7: the joint Dahl fits against the four Case I loops (periods 2-3).

    Parameters
    ----------
    loops : list of (u_c, v_y)
        The Case I loops [V], in the order of ``amplitudes``.
    workbook, paper_form : DahlFit
        The workbook model's fit and the fit of eq. 10-13 as printed, both to
        ``loops``.
    amplitudes : sequence of float
        Actuator amplitudes [V] (four: one panel each).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig07_dahl_fit.png``.
    """
    fig, axes = new_figure(2, 2, figsize=(8.5, 6.4))
    for ax, (k, A) in zip(axes.flat, enumerate(amplitudes)):
        u, v_y = loops[k]
        late = slice(PERIOD, None)
        ax.plot(GAIN * u[late], UM * v_y[late], color="0.55", lw=1.8,
                label="virtual stage (measured)")
        ax.plot(GAIN * u[late], UM * workbook.x_model[k][late], "-", lw=1.0,
                color=PALETTE.contrast,
                label=f"workbook model (RMS {workbook.rms_percent[k]:.1f} %)")
        ax.plot(GAIN * u[late], UM * paper_form.x_model[k][late], "--", lw=1.0,
                color=PALETTE.primary,
                label=f"eq. 10-13 as printed (RMS {paper_form.rms_percent[k]:.1f} %)")
        ax.set(title=f"({'abcd'[k]}) {A:.0f} V", xlabel="actuator voltage [V]",
               ylabel="displacement [um]")
        ax.legend(fontsize=7, loc="upper left")
    fig.suptitle("Fig. 7: joint fit to the four Case I loops (periods 2-3); workbook model = "
                 "Bliman-Sorine, offset x0, from rest", fontsize=9)
    plotting.name_figure(fig, 7, "dahl_fit")
    return fig


def fig08_feedforward_on_model(t, x_r, x_plain, x_comp):
    """Fig. 8: the Dahl model without and with the feedforward of eq. 14.

    Parameters
    ----------
    t : ndarray
        Time [s].
    x_r : ndarray
        Desired displacement [V].
    x_plain, x_comp : ndarray
        Model displacement [V] for u = (x_r - x0)/g_a and for u = u_f.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig08_feedforward_on_model.png``.
    """
    fig, axes = new_figure(1, 2, figsize=(8.5, 3.4))
    axes[0].plot(UM * x_r, UM * x_plain, label="u = (x_r - x0) / g_a (no compensation)")
    axes[0].plot(UM * x_r, UM * x_comp, "--", label="u = u_f (eq. 14)")
    axes[0].set(xlabel="desired displacement x_r [um]", ylabel="model displacement x [um]",
                title="(a) workbook Dahl model, 12 um, 10 Hz")
    axes[0].legend()
    error_nm = UM * (x_comp - x_r) * 1e3
    stroke_nm = UM * np.ptp(x_r) * 1e3
    if np.max(np.abs(error_nm)) <= 1e-9 * stroke_nm:
        # an identity up to floating-point round-off: say so rather than plot 1e-10 nm noise
        axes[1].axhline(0.0, color=PALETTE.primary)
        axes[1].set_ylim(-1, 1)
        axes[1].text(0.5, 0.6, "exact to round-off:\n"
                     f"max |x - x_r| = {np.max(np.abs(error_nm)):.0e} nm",
                     transform=axes[1].transAxes, ha="center", fontsize=8)
    else:
        axes[1].plot(t, error_nm)
    axes[1].set(xlabel="time [s]", ylabel="x - x_r [nm]", title="(b) compensation error")
    plotting.name_figure(fig, 8, "feedforward_on_model")
    return fig


def extra_case2_loops(loops, case_I, runs, case_II):
    """Case I loops (top) and Case II loops of several feedforward models (bottom).

    Parameters
    ----------
    loops : dict
        {amplitude [V]: Case I StageRecord}.
    case_I : dict
        {amplitude: Case I hysteresis %}.
    runs : dict
        {model name: {amplitude: Case II LoopResult}}; the first two are drawn.
    case_II : dict
        {model name: {amplitude: Case II hysteresis %}}.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_case2_loops.png``.
    """
    amplitudes = list(loops)
    fig, axes = new_figure(2, len(amplitudes), figsize=(11, 5.2), sharex="col")
    for k, A in enumerate(amplitudes):
        rec = loops[A]
        axes[0, k].plot(GAIN * rec.u_c_V[PERIOD:], UM * rec.v_y_V[PERIOD:], color="0.5", lw=0.8)
        axes[0, k].set_title(f"Case I (data file), {A:.0f} V: {case_I[A]:.2f} %")
        for (name, by_amplitude), style in zip(runs.items(), ("-", "--")):
            run = by_amplitude[A]
            axes[1, k].plot(GAIN * run.v_r_V[PERIOD:], UM * run.v_y_V[PERIOD:], style,
                            lw=0.8, label=f"{name}: {case_II[name][A]:.2f} %")
        axes[1, k].legend(fontsize=6, loc="upper left", title="Case II", title_fontsize=7)
        axes[1, k].set_xlabel("10 x reference [V]")
    axes[0, 0].set_ylabel("x = 3 v_y [um]")
    axes[1, 0].set_ylabel("x = 3 v_y [um]")
    plotting.name_figure(fig, None, "case2_loops")
    return fig


def extra_case2_residual(runs, percents):
    """Case II residual x - x_r against the reference, one panel per amplitude.

    Parameters
    ----------
    runs : dict
        {amplitude [V]: Case II LoopResult} of one feedforward model.
    percents : dict
        {amplitude: Case II hysteresis %}.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_case2_residual.png``; eq. 26 reads the gap at the
        grey line (mid-input).
    """
    amplitudes = list(runs)
    fig, axes = new_figure(1, len(amplitudes), figsize=(11, 2.8))
    for k, A in enumerate(amplitudes):
        run = runs[A]
        late = slice(PERIOD, None)
        axes[k].plot(GAIN * run.v_r_V[late], UM * (run.v_y_V[late] - run.v_r_V[late]), lw=0.8)
        axes[k].axvline(A / 2, color="0.6", lw=0.7)
        axes[k].set(title=f"{A:.0f} V: {percents[A]:.2f} %", xlabel="10 x reference [V]")
    axes[0].set_ylabel("x - x_r [um]")
    fig.suptitle("Case II, workbook model: residual x - x_r against the reference "
                 "(eq. 26 reads the gap at the grey line)", fontsize=9)
    plotting.name_figure(fig, None, "case2_residual")
    return fig


def extra_model_validation(records, models, scores):
    """Validation records (not fitted) against each model: loops (top) and errors (bottom).

    Parameters
    ----------
    records : dict
        {label: (u_c [V], v_y [V], first scored sample)}.
    models : dict
        {name: model with ``simulate(u_c) -> v_y``}; up to three are drawn.
    scores : pandas.DataFrame
        :func:`piezolib.hysteresis.validation_table` of these models and records.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_model_validation.png``.
    """
    labels = list(records)
    fig, axes = new_figure(2, len(labels), figsize=(11.5, 5.6), sharex="col")
    styles = ("-", "--", ":")
    for k, label in enumerate(labels):
        u, v_y, first = records[label]
        late = slice(first, None)
        axes[0, k].plot(GAIN * u[late], UM * v_y[late], color="0.6", lw=2.0, label="stage")
        for (name, model), style, color in zip(models.items(), styles, PALETTE.peers):
            x = model.simulate(u)
            rms = scores.loc[(name, label), "RMS %"]
            axes[0, k].plot(GAIN * u[late], UM * x[late], style, lw=0.9, color=color,
                            label=f"{name} ({rms:.2f} %)")
            axes[1, k].plot(GAIN * u[late], UM * (x[late] - v_y[late]), style, lw=0.8,
                            color=color)
        axes[0, k].set_title(label, fontsize=9)
        axes[0, k].legend(fontsize=6, loc="upper left", title="RMS of stroke",
                          title_fontsize=6)
        axes[1, k].set_xlabel("actuator voltage 10 u_c [V]")
    axes[0, 0].set_ylabel("x = 3 v_y [um]")
    axes[1, 0].set_ylabel("model - stage [um]")
    fig.suptitle("Validation on virtual-stage records no model was fitted to "
                  "(all fitted to the Case I loops)", fontsize=9)
    plotting.name_figure(fig, None, "model_validation")
    return fig
