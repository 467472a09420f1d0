"""Figures of notebook 10's 3 x 3 section: the step matrix of the mirror's closed loop, the
3 x 3 μ controller beside three SISO loops."""

import numpy as np

from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure

__all__ = ["extra_fsm_mimo_steps"]


def extra_fsm_mimo_steps(time_s, responses, output_labels=None):
    """3 x 3 grid of closed-loop step responses, one curve per controller.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Time [s], increasing.
    responses : dict {str: array of shape (3, 3, N)}
        Per controller: ``y[j, i]`` the displacement j [um] for a 1 um step on
        reference i.
    output_labels : list of str, optional
        Names of the three axes.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_fsm_mimo_steps.png``.

    Examples
    --------
    >>> import matplotlib.pyplot as plt
    >>> t = np.linspace(0, 0.1, 50)
    >>> fig = extra_fsm_mimo_steps(t, {"K": np.ones((3, 3, 50))})
    >>> fig.get_label(), len(fig.axes)
    ('extra_fsm_mimo_steps', 9)
    >>> plt.close(fig)
    """
    t = np.asarray(time_s, dtype=float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ValueError("time_s must be a 1-D increasing array of finite times")
    if not isinstance(responses, dict) or not responses:
        raise TypeError("responses must be a non-empty dict {controller name: array}")
    curves = {}
    for name, y in responses.items():
        y = np.asarray(y, dtype=float)
        if y.shape != (3, 3, t.size) or not np.all(np.isfinite(y)):
            raise ValueError(f"responses[{name!r}] must be finite of shape (3, 3, {t.size})")
        curves[name] = y
    labels = output_labels or [f"y{i + 1}" for i in range(3)]
    if len(labels) != 3:
        raise ValueError("output_labels must name 3 axes")
    fig, axes = new_figure(3, 3, sharex=True, figsize=(9, 6.5))
    colours = PALETTE.cycle
    for j in range(3):
        for i in range(3):
            ax = axes[j, i]
            for k, (name, y) in enumerate(curves.items()):
                ax.plot(1e3 * t, y[j, i], color=colours[k % len(colours)], lw=1.0, label=name)
            if j == 0:
                ax.set_title(f"step on r of {labels[i]}", fontsize=8)
            if i == 0:
                ax.set_ylabel(f"{labels[j]} [µm]")
            if j == 2:
                ax.set_xlabel("time [ms]")
    fig.legend(*axes[0, 0].get_legend_handles_labels(), loc="outside lower center",
               ncol=len(curves), fontsize=8)
    plotting.name_figure(fig, None, "fsm_mimo_steps")
    return fig
