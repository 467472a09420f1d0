"""Figures of the tracking experiments: Fig. 14 and Fig. 15 (notebook 06), tracking over
the uncertainty set (notebook 12)."""

from string import ascii_lowercase

import numpy as np

from piezolib.problem import paper
from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure
from piezolib.workbook.experiments import CASES

__all__ = ["fig14_hysteresis_cases", "fig15_tracking_error", "tracking_over_set"]


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


def tracking_over_set(results, nominal=None, goals=None):
    """Tracking error over a model set, per frequency: the spread, the worst member, the goals.

    One group of bars per frequency, one bar per result: a thick bar from the
    5th to the 95th percentile of the members' errors, a tick at the median,
    a cross at the worst member and a dot at the nominal plant; the goals
    of Sec. IV-B as a dashed line.

    Parameters
    ----------
    results : dict
        {label: :class:`~piezolib.workbook.set_tracking.SetTracking`} (same
        frequencies), at most seven.
    nominal : dict, optional
        {label: pandas.Series of the nominal stage's error per frequency [%]}.
    goals : dict, optional
        The paper's :data:`~piezolib.problem.paper.DESIGN_GOALS` by default.

    Returns
    -------
    matplotlib.figure.Figure
        Named ``extra_tracking_over_set``.
    """
    goals = paper.DESIGN_GOALS if goals is None else goals
    fig, ax = new_figure(figsize=(9.0, 5.6))
    labels = list(results)
    freqs = list(next(iter(results.values())).errors.columns)
    width = 0.8 / len(labels)
    if len(labels) > len(PALETTE.cycle):
        raise ValueError(f"results must hold at most {len(PALETTE.cycle)} results, got {len(labels)}")
    colours = PALETTE.peers if len(labels) <= len(PALETTE.peers) else PALETTE.cycle
    for i, (label, colour) in enumerate(zip(labels, colours)):
        res = results[label]
        x = np.arange(len(freqs)) + (i - (len(labels) - 1) / 2) * width
        e = res.errors
        low, mid, high = e.quantile(0.05), e.median(), e.quantile(0.95)
        run, size = int(e.notna().all(axis=1).sum()), res.mset.size
        ax.vlines(x, low, high, color=colour, lw=7, alpha=0.55,
                  label=f"{label}: {run} stable, {size - run} unstable")
        ax.scatter(x, mid, marker="_", s=120, color=colour, zorder=3)
        ax.scatter(x, e.max(), marker="x", s=30, color=colour, zorder=3)
        if nominal is not None and label in nominal:
            ax.scatter(x, nominal[label].reindex(freqs), marker="o", s=18, color=PALETTE.wire,
                       zorder=4)
    goal = [goals["peak_to_peak_error_pct_up_to_10Hz"] if f <= 10 else
            goals["peak_to_peak_error_pct_at_50Hz"] if f >= 50 else np.nan for f in freqs]
    ax.step(np.arange(len(freqs)), goal, where="mid", ls="--", color=PALETTE.seventh, lw=1.2,
            label="goals of Sec. IV-B")
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(freqs)), [f"{f:g} Hz" for f in freqs])
    ax.set_ylabel("tracking error max|e| / 12 um [%]")
    ax.set_title("Tracking over the model set: bar 5-95 % of the stable members, tick median, "
                 "x worst member, dot nominal stage", fontsize="medium")
    # below the axes: the worst members reach the top of the plot at every frequency
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), ncol=2, fontsize="small")
    plotting.name_figure(fig, None, "tracking_over_set")
    return fig
