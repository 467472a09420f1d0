"""Figure of notebook 07 (reproduction report): the scorecard of every published number."""

import numpy as np
import pandas as pd

from piezolib.workbook import plotting
from piezolib.workbook.style import PALETTE, new_figure

__all__ = ["extra_reproduction_scorecard"]


def _ratio_band(paper_value, tolerance):
    """(low, high) of our/paper inside which a claim agrees, from the tolerance text."""
    text = str(tolerance).strip()
    if not text.startswith("+-"):
        return np.nan, np.nan
    if text.endswith("%"):
        tol = abs(paper_value) * float(text[2:-1]) / 100
    else:
        tol = float(text[2:])
    low, high = sorted(((paper_value - tol) / paper_value, (paper_value + tol) / paper_value))
    return low, high


def extra_reproduction_scorecard(table, seed=0):
    """Each numeric published number as a dot: our value / the paper's, per source notebook.

    Each dot carries its agreement band (grey bar): the ratios within the
    row's tolerance.  Rows whose paper value is not a nonzero number
    (booleans, zero) cannot be drawn as a ratio; the legend counts drawn rows
    against all rows of each verdict.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`piezolib.workbook.report.reproduction_table` output (columns
        ``source``, ``paper``, ``ours``, ``tolerance``, ``verdict``).
    seed : int
        Seed of the vertical jitter (for legibility only).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_reproduction_scorecard.png``.  Ratios and bands are
        clipped to 1e-2 ... 1e2.
    """
    missing = {"source", "paper", "ours", "tolerance", "verdict"} - set(table.columns)
    if missing:
        raise ValueError(f"table lacks the columns {sorted(missing)}")
    numeric = table.assign(paper_value=pd.to_numeric(table.paper, errors="coerce"),
                           our_value=pd.to_numeric(table.ours, errors="coerce"))
    # booleans read as 1/0 by to_numeric: keep only real numbers
    is_bool = table.paper.astype(str).isin(["True", "False"])
    numeric = numeric[(numeric.paper_value.abs() > 0) & numeric.our_value.notna() & ~is_bool]
    ratio = (numeric.our_value / numeric.paper_value).clip(1e-2, 1e2)
    bands = np.array([_ratio_band(p, t) for p, t in zip(numeric.paper_value, numeric.tolerance)])
    sources = list(dict.fromkeys(table.source))
    fig, ax = new_figure(figsize=(9.5, 4.2))
    rng = np.random.default_rng(seed)
    y = numeric.source.map(sources.index).to_numpy() + rng.uniform(-0.3, 0.3, len(numeric))
    if len(numeric):
        ax.hlines(y, np.clip(bands[:, 0], 1e-2, 1e2), np.clip(bands[:, 1], 1e-2, 1e2),
                  color="0.55", lw=2.2, alpha=0.6, label="agreement band of each claim")
    for verdict, colour in (("agrees", PALETTE.agreement), ("differs", PALETTE.contrast)):
        pick = (numeric.verdict == verdict).to_numpy()
        total = int((table.verdict == verdict).sum())
        ax.scatter(ratio[pick], y[pick], s=14, color=colour, zorder=3,
                   label=f"{verdict}: {pick.sum()} drawn of {total}")
    ax.set_xscale("log")
    ax.set_xlim(1e-2, 1e2)
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(range(len(sources)), sources)
    ax.set_ylim(len(sources) - 0.5, -0.5)
    ax.set_xlabel("our value / paper value")
    ax.set_title(f"{len(numeric)} of {len(table)} published claims are nonzero numbers and "
                 "drawn; a dot agrees when it lies on its grey band")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    plotting.name_figure(fig, None, "reproduction_scorecard")
    return fig
