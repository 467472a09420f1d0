"""Figures of notebook 06 (tracking experiments): Fig. 14 and Fig. 15."""

from string import ascii_lowercase

from piezolib.problem import paper
from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure
from piezolib.workbook.experiments import CASES

__all__ = ["fig14_hysteresis_cases", "fig15_tracking_error"]


def fig14_hysteresis_cases(result, frequency_Hz=None, controller="our 6th-order mu controller"):
    """Fig. 14: the steady-state loops of the hysteresis test, one panel per case and amplitude.

    Parameters
    ----------
    result : piezolib.workbook.experiments.ExperimentResult
        A :func:`~piezolib.workbook.experiments.hysteresis_test` result.
    frequency_Hz : float, optional
        Triangle frequency [Hz]; default the paper's 10 Hz.
    controller : str
        Case III's controller, named in the title.

    Returns
    -------
    matplotlib.figure.Figure
        x = 3 um/V v_y [um] against 10 x reference [V]; named
        ``fig14_hysteresis_cases``.
    """
    frequency_Hz = paper.HYSTERESIS_TEST["frequency_Hz"] if frequency_Hz is None else frequency_Hz
    amplitudes = list(result.table.columns)
    fig, axes = new_figure(len(CASES), len(amplitudes), figsize=(10, 7.2), sharex="col",
                           squeeze=False)
    for k, A in enumerate(amplitudes):
        for i, case in enumerate(CASES):
            run = result.runs[case, A]
            s = run.steady_state(frequency_Hz)
            ax = axes[i, k]
            ax.plot(paper.AMPLIFIER_GAIN * run.v_r_V[s], run.x_um[s], lw=0.8)
            ax.set_title(f"({ascii_lowercase[len(amplitudes) * i + k]}) Case {case}, {A:.0f} V: "
                         f"{result.table.loc[f'case_{case}', A]:.2f} %")
            if k == 0:
                ax.set_ylabel("x = 3 v_y [um]")
        axes[-1, k].set_xlabel("10 x reference [V]")
    fig.suptitle(f"Fig. 14: loops at {frequency_Hz:g} Hz; I open loop, II Dahl feedforward, "
                 f"III feedforward + {controller}\n(every case run here in the loop and measured "
                 "after the first period: Case I differs slightly from the recorded data files)"
                 + _seeds_note(result))
    plotting.name_figure(fig, 14, "hysteresis_cases")
    return fig


def fig15_tracking_error(ours, published=None, fs=None):
    """Fig. 15: tracking error over the last period, one panel per case and frequency.

    Parameters
    ----------
    ours : piezolib.workbook.experiments.ExperimentResult
        A :func:`~piezolib.workbook.experiments.tracking_test` result with the
        workbook's 6th-order controller.
    published : ExperimentResult, optional
        The same test with the published K; its Case III is drawn dashed.
    fs : float, optional
        Sampling rate [Hz]; default the paper's 10 kHz.

    Returns
    -------
    matplotlib.figure.Figure
        e = x_r - 3 um/V v_y [um] against t / period; named
        ``fig15_tracking_error``.
    """
    fs = paper.SAMPLING_FREQUENCY_HZ if fs is None else fs
    frequencies = list(ours.table.columns)
    fig, axes = new_figure(len(CASES), len(frequencies), figsize=(11, 5.6), sharey="row",
                           squeeze=False)
    for k, f in enumerate(frequencies):
        for i, case in enumerate(CASES):
            ax = axes[i, k]
            results = {"ours (6th order)": ours}
            if case == "III" and published is not None:
                results["published K"] = published
            for (label, result), style in zip(results.items(), ("-", "--")):
                run = result.runs[case, f]
                last = slice(len(run) - 1 - int(round(fs / f)), None)   # the last period
                phase = (run.t_s[last] - run.t_s[last][0]) * f
                ax.plot(phase, run.error_um[last], style, lw=0.8, label=label)
            ax.set_title(f"({ascii_lowercase[len(frequencies) * i + k]}) {case}, {f:g} Hz: "
                         f"{ours.table.loc[f'case_{case}', f]:.2f} %", fontsize=8)
            if k == 0:
                ax.set_ylabel(f"Case {case}: e [um]")
        axes[-1, k].set_xlabel("t / period")
    axes[-1, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Fig. 15: tracking error of 12 um triangles over one steady-state period"
                 + _seeds_note(ours))
    plotting.name_figure(fig, 15, "tracking_error")
    return fig


def _seeds_note(result):
    """A line saying what the numbers in the titles are when the result spans noise seeds."""
    if result.seeds is None:
        return ""
    return (f"\ncurves: noise seed {result.seeds[0]}; numbers: mean over {len(result.seeds)} "
            "noise seeds")
