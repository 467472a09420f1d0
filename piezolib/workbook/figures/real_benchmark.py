"""Figures of notebook 10 (a real piezo benchmark): the BLA of the fine steering mirror at
each level with its noise and distortion levels, and the test scores beside the baselines."""

import numpy as np

from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, db, new_figure

__all__ = ["extra_fsm_bla", "extra_fsm_scores", "extra_fsm_level_weight"]


def _check_level_arrays(frequency_Hz, curves):
    f = np.asarray(frequency_Hz, dtype=float)
    if f.ndim != 1 or f.size < 2 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("frequency_Hz must be a 1-D array of positive frequencies")
    out = {}
    for name, per_level in curves.items():
        if not isinstance(per_level, dict) or not per_level:
            raise TypeError(f"{name} must be a non-empty dict {{level label: array}}")
        out[name] = {}
        for label, values in per_level.items():
            values = np.asarray(values)
            if values.ndim != 3 or values.shape[:2] != (3, 3) or values.shape[2] != f.size \
                    or not np.all(np.isfinite(values)):
                raise ValueError(f"{name}[{label!r}] must be finite of shape (3, 3, {f.size})")
            out[name][label] = values
    if not (out["G"].keys() == out["std_noise"].keys() == out["std_distortion"].keys()):
        raise ValueError("G, std_noise and std_distortion must have the same level labels")
    return f, out


def extra_fsm_bla(frequency_Hz, G, std_noise, std_distortion, input_labels=None,
                  output_labels=None, smooth=15):
    """3 x 3 grid of BLA magnitudes with the noise and distortion standard deviations.

    Parameters
    ----------
    frequency_Hz : array_like, shape (F,)
        Excited lines [Hz].
    G, std_noise, std_distortion : dict {str: array of shape (3, 3, F)}
        Per level (label, e.g. ``"100 mV"``): the BLA [m/V] and the standard
        deviations of the BLA due to noise and to nonlinear distortions [m/V].
    input_labels, output_labels : list of str, optional
        Names of the 3 inputs (columns) and 3 outputs (rows).
    smooth : int, optional
        The standard deviations are drawn as a moving RMS over this many lines
        (each line's estimate has few degrees of freedom); 1 draws them raw.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_fsm_bla.png``.
    """
    f, curves = _check_level_arrays(frequency_Hz, dict(G=G, std_noise=std_noise,
                                                       std_distortion=std_distortion))
    if isinstance(smooth, bool) or not isinstance(smooth, (int, np.integer)) or smooth < 1:
        raise ValueError(f"smooth must be a positive integer, got {smooth!r}")
    input_labels = input_labels or [f"u{j + 1}" for j in range(3)]
    output_labels = output_labels or [f"y{i + 1}" for i in range(3)]
    kernel = np.ones(smooth) / smooth

    def rms(x):
        return np.sqrt(np.convolve(x ** 2, kernel, mode="same"))

    fig, axes = new_figure(3, 3, figsize=(11, 8.2), sharex=True, sharey=True)
    colours = PALETTE.peers
    for k, label in enumerate(curves["G"]):
        colour = colours[k % len(colours)]
        for i in range(3):
            for j in range(3):
                ax = axes[i, j]
                ax.semilogx(f, db(np.abs(curves["G"][label][i, j])), color=colour, lw=1.0,
                            label=f"BLA {label}")
                ax.semilogx(f, db(rms(curves["std_noise"][label][i, j])), color=colour,
                            lw=0.6, ls=":", label=f"noise std {label}")
                ax.semilogx(f, db(rms(curves["std_distortion"][label][i, j]) + 1e-30),
                            color=colour, lw=0.6, ls="--", alpha=0.8,
                            label=f"distortion std {label}")
    for i in range(3):
        axes[i, 0].set_ylabel(f"{output_labels[i]} [dB re 1 m/V]")
    for j in range(3):
        axes[0, j].set_title(f"from {input_labels[j]}")
        axes[2, j].set_xlabel("frequency [Hz]")
    axes[0, 0].set_xlim(f[0], f[-1])
    top = max(float(np.max(db(np.abs(g)))) for g in curves["G"].values())
    axes[0, 0].set_ylim(top - 110, top + 10)
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center", ncol=3,
               fontsize=8)
    plotting.name_figure(fig, None, "fsm_bla")
    return fig


def extra_fsm_scores(levels, scores, floor=None):
    """Test NRMSE per level: each model's bars side by side, the noise floor as a line.

    Parameters
    ----------
    levels : sequence of str
        Level labels (x axis), e.g. ``["100 mV", "200 mV", "300 mV"]``.
    scores : dict {str: sequence of float}
        NRMSE [%] per model (legend) and level.
    floor : sequence of float, optional
        The noise floor of the metric [%] per level.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_fsm_scores.png``.
    """
    levels = list(levels)
    if not levels or not all(isinstance(x, str) for x in levels):
        raise ValueError("levels must be a non-empty sequence of labels")
    if not isinstance(scores, dict) or not scores:
        raise TypeError("scores must be a non-empty dict {model: NRMSE per level}")
    values = {}
    for name, v in scores.items():
        v = np.asarray(v, dtype=float)
        if v.shape != (len(levels),) or not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError(f"scores[{name!r}] must hold one finite NRMSE per level")
        values[name] = v
    fig, ax = new_figure(figsize=(8, 4.4))
    x = np.arange(len(levels))
    width = 0.8 / len(values)
    colours = PALETTE.cycle
    for k, (name, v) in enumerate(values.items()):
        ax.bar(x - 0.4 + (k + 0.5) * width, v, width, label=name,
               color=colours[k % len(colours)])
    if floor is not None:
        floor = np.asarray(floor, dtype=float)
        if floor.shape != (len(levels),) or not np.all(np.isfinite(floor)):
            raise ValueError("floor must hold one finite NRMSE per level")
        for xi, fl in zip(x, floor):
            ax.hlines(fl, xi - 0.45, xi + 0.45, color="k", lw=1.2)
        ax.plot([], [], color="k", lw=1.2, label="noise floor of the metric")
    ax.set_xticks(x, levels)
    ax.set_ylabel("test NRMSE [%]")
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=2, fontsize=8)
    plotting.name_figure(fig, None, "fsm_scores")
    return fig


def extra_fsm_level_weight(frequency_Hz, relative_errors, envelope, weight_magnitude, pair_label):
    """Relative error of each level's model against the nominal one, its envelope and weight.

    Parameters
    ----------
    frequency_Hz : array_like, shape (F,)
        [Hz], positive.
    relative_errors : dict {str: array of shape (F,)}
        |G_level / G_nominal - 1| per level label.
    envelope, weight_magnitude : array_like, shape (F,)
        Their maximum and |W| of the covering weight on the same lines.
    pair_label : str
        The input-output pair, e.g. ``"v_a3 → d_3"``.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_fsm_level_weight.png``.
    """
    f = np.asarray(frequency_Hz, dtype=float)
    if f.ndim != 1 or f.size < 2 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise ValueError("frequency_Hz must be a 1-D array of positive frequencies")
    if not isinstance(relative_errors, dict) or not relative_errors:
        raise TypeError("relative_errors must be a non-empty dict {level label: array}")
    curves = {}
    for name, values in {**{f"relative_errors[{k!r}]": v for k, v in relative_errors.items()},
                         "envelope": envelope, "weight_magnitude": weight_magnitude}.items():
        values = np.asarray(values, dtype=float)
        if values.shape != f.shape or not np.all(np.isfinite(values)) or np.any(values < 0):
            raise ValueError(f"{name} must hold {f.size} finite non-negative values")
        curves[name] = values
    if not isinstance(pair_label, str):
        raise TypeError("pair_label must be a string")
    fig, ax = new_figure(figsize=(8, 4.2))
    colours = PALETTE.cycle
    for k, label in enumerate(relative_errors):
        ax.semilogy(f, curves[f"relative_errors[{label!r}]"], lw=0.7,
                    color=colours[k % len(colours)], label=f"{label} model / nominal − 1")
    ax.semilogy(f, curves["envelope"], color="k", lw=1.0, ls=":", label="envelope E(ω)")
    ax.semilogy(f, curves["weight_magnitude"], color="k", lw=1.6, label="covering weight |W|")
    ax.set_xscale("log")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("relative error [-]")
    ax.set_title(f"spread between the levels, {pair_label}, against the all-levels model",
                 fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=3, fontsize=8)
    plotting.name_figure(fig, None, "fsm_level_weight")
    return fig
