"""Figure of notebook 11 (sweeps) and of ``python -m piezolib sweep``: the Pareto front."""

import numpy as np
import pandas as pd

from piezolib._checks import check_type
from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure

__all__ = ["extra_sweep_pareto"]

_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def extra_sweep_pareto(table, x="mu_RP", y="tracking_error_50Hz_percent",
                       group="controller_states", title=None):
    """Every point of a sweep: μ_RP against the 50 Hz tracking error, the Pareto front joined.

    Parameters
    ----------
    table : pandas.DataFrame
        :attr:`piezolib.workbook.sweep.SweepResult.table`: columns ``point``,
        ``x``, ``y``, ``group`` and ``pareto``; with
        ``tracking_error_50Hz_low_percent`` / ``_high_percent``, the 95 %
        interval of ``y`` is drawn as an error bar.
    x, y : str
        Columns on the axes (both minimised): μ_RP [-], the tracking error [%].
    group : str
        Column that picks colour and marker (the controller's states).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_sweep_pareto.png``.  Points without a value (failed)
        are left out; the legend says how many.
    """
    check_type("table", table, pd.DataFrame, "a pandas DataFrame (SweepResult.table)")
    missing = {"point", x, y, group, "pareto"} - set(table.columns)
    if missing:
        raise ValueError(f"table lacks the columns {sorted(missing)}")
    values = table[[x, y]].apply(pd.to_numeric, errors="coerce")
    drawn = table[np.isfinite(values.to_numpy(float)).all(axis=1)]
    fig, ax = new_figure(figsize=(7.0, 4.2))
    colours = list(PALETTE.cycle)
    stem = y.removesuffix("_percent")
    low, high = f"{stem}_low_percent", f"{stem}_high_percent"
    has_interval = y.endswith("_percent") and {low, high} <= set(table.columns)
    for i, (states, part) in enumerate(drawn.groupby(group, sort=True)):
        style = dict(color=colours[i % len(colours)], marker=_MARKERS[i % len(_MARKERS)])
        if has_interval:       # the 95 % interval over the noise seeds
            err = np.abs(np.vstack([part[y] - part[low], part[high] - part[y]]))
            ax.errorbar(part[x], part[y], yerr=err, ls="none", lw=0.8, capsize=2, **style)
        ax.scatter(part[x], part[y], s=28, zorder=3, label=f"{group.replace('_', ' ')} "
                   f"{states} ({len(part)})", **style)
    front = drawn[drawn["pareto"].astype(bool)].sort_values(x)
    ax.step(front[x], front[y], where="post", color=PALETTE.seventh, lw=1.0, zorder=2,
            label=f"Pareto front ({len(front)} points)")
    for _, row in front.iterrows():
        ax.annotate(str(row["point"]), (row[x], row[y]), xytext=(4, 4),
                    textcoords="offset points", fontsize=7)
    left_out = len(table) - len(drawn)
    ax.set_xlabel("mu_RP (delay-aware problem)" if x == "mu_RP" else x)
    ax.set_ylabel("Case III tracking error at 50 Hz [%]"
                  if y == "tracking_error_50Hz_percent" else y)
    ax.set_title((title + ": " if title else "") + f"{len(drawn)} designs"
                 + (f", {left_out} failed (not drawn)" if left_out else "")
                 + "; front numbers = points")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    plotting.name_figure(fig, None, "sweep_pareto")
    return fig
