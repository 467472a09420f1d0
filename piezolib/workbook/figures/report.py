"""Figure of notebook 07 (reproduction report): the scorecard of every published number."""

import numpy as np
import pandas as pd

from piezolib.workbook import plotting

__all__ = ["extra_reproduction_scorecard"]


def extra_reproduction_scorecard(table, seed=0):
    """Each published number as a dot: our value / the paper's, per source notebook.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`piezolib.workbook.report.reproduction_table` output (columns
        ``source``, ``paper``, ``ours``, ``verdict``).
    seed : int
        Seed of the vertical jitter (for legibility only).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_reproduction_scorecard.png``.  Ratios are clipped to
        1e-2 ... 1e2; rows without a nonzero numeric paper value are left out.
    """
    numeric = table.assign(paper_value=pd.to_numeric(table.paper, errors="coerce"),
                           our_value=pd.to_numeric(table.ours, errors="coerce"))
    numeric = numeric[(numeric.paper_value.abs() > 0) & numeric.our_value.notna()]
    ratio = (numeric.our_value / numeric.paper_value).clip(1e-2, 1e2)
    sources = list(dict.fromkeys(table.source))
    fig, ax = plotting.new_figure(figsize=(8, 3.8))
    rng = np.random.default_rng(seed)
    for verdict, colour in (("agrees", "#4f8f3a"), ("differs", "#c0504d")):
        pick = numeric.verdict == verdict
        y = numeric[pick].source.map(sources.index) + rng.uniform(-0.25, 0.25, pick.sum())
        ax.scatter(ratio[pick], y, s=14, color=colour, label=f"{verdict} ({pick.sum()})")
    ax.set_xscale("log")
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(range(len(sources)), sources)
    ax.invert_yaxis()
    ax.set_xlabel("our value / paper value")
    ax.legend(loc="lower right")
    plotting.save_figure(fig, None, "reproduction_scorecard")
    return fig
