"""Figure of notebook 10: the linear models' order validation curve per level (the
committed curve of :func:`piezolib.problem.fsm_models.read_order_curve`)."""

import numpy as np

from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure

__all__ = ["extra_fsm_order_curve"]


def extra_fsm_order_curve(orders, validation_error_percent, candidates=None):
    """Validation error against model order, one line per level, each level's best marked.

    Parameters
    ----------
    orders : sequence of int
        The orders of the curve (x axis), increasing.
    validation_error_percent : dict {str: sequence of float}
        Per level label: the relative FRF error on the other group of realisations [%],
        one value per order.
    candidates : (int, int), optional
        A narrower candidate range (first and last order), shaded.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_fsm_order_curve.png``.

    Examples
    --------
    >>> fig = extra_fsm_order_curve([8, 16, 24], {"100 mV": [3.0, 2.0, 2.5]}, candidates=(8, 16))
    >>> [line.get_label() for line in fig.axes[0].get_lines()][:2]
    ['100 mV', '100 mV: best 16']
    """
    x = np.asarray(orders, dtype=float)
    if x.ndim != 1 or x.size < 2 or not np.all(np.isfinite(x)) or np.any(np.diff(x) <= 0) \
            or np.any(x < 1):
        raise ValueError("orders must be at least two increasing positive orders")
    if not isinstance(validation_error_percent, dict) or not validation_error_percent:
        raise TypeError("validation_error_percent must be a non-empty dict {level label: "
                        "errors per order}")
    curves = {}
    for label, values in validation_error_percent.items():
        v = np.asarray(values, dtype=float)
        if v.shape != x.shape or not np.all(np.isfinite(v)) or np.any(v < 0):
            raise ValueError(f"validation_error_percent[{label!r}] must hold {x.size} finite "
                             "non-negative values")
        curves[str(label)] = v
    if candidates is not None:
        c = np.asarray(candidates, dtype=float)
        if c.shape != (2,) or not np.all(np.isfinite(c)) or c[0] >= c[1]:
            raise ValueError(f"candidates must be (first, last) order, got {candidates!r}")
    fig, ax = new_figure(figsize=(8, 4.2))
    colours = PALETTE.cycle
    for k, (label, v) in enumerate(curves.items()):
        colour = colours[k % len(colours)]
        ax.plot(x, v, marker=".", lw=1.0, color=colour, label=label)
        i = int(np.argmin(v))
        ax.plot(x[i], v[i], marker="o", ms=9, mfc="none", mew=1.5, ls="none", color=colour,
                label=f"{label}: best {x[i]:.0f}")
    if candidates is not None:
        ax.axvspan(c[0], c[1], color="0.9", zorder=0,
                   label=f"the working models' candidates {c[0]:.0f}-{c[1]:.0f}")
    ax.set_xlabel("model order (states)")
    ax.set_ylabel("validation error [%]")
    ax.set_title("linear models: relative FRF error on the other group of realisations",
                 fontsize=9)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside lower center", ncol=4, fontsize=8)
    plotting.name_figure(fig, None, "fsm_order_curve")
    return fig
