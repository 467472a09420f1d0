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


def _ratio_limits(ratios, bands, margin=0.15):
    """Limits of the log ratio axis: whole decades around 1, every ratio and every positive
    band end, at least ``margin`` decades beyond the outermost (no dot on the edge)."""
    values = np.concatenate([[1.0], np.ravel(ratios), np.ravel(bands)])
    values = values[np.isfinite(values) & (values > 0)]
    low, high = np.log10(values.min()) - margin, np.log10(values.max()) + margin
    return 10.0 ** np.floor(low), 10.0 ** np.ceil(high)


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
        Saved as ``extra_reproduction_scorecard.png``.  The ratio axis spans
        every dot and band end with a margin (:func:`_ratio_limits`), so no dot
        sits on its edge; a band that reaches zero runs to the left edge, and a
        ratio that is not positive (a sign change) cannot be drawn on the log axis
        and is counted as not drawn.
    """
    missing = {"source", "paper", "ours", "tolerance", "verdict"} - set(table.columns)
    if missing:
        raise ValueError(f"table lacks the columns {sorted(missing)}")
    numeric = table.assign(paper_value=pd.to_numeric(table.paper, errors="coerce"),
                           our_value=pd.to_numeric(table.ours, errors="coerce"))
    # booleans read as 1/0 by to_numeric: keep only real numbers
    is_bool = table.paper.astype(str).isin(["True", "False"])
    numeric = numeric[(numeric.paper_value.abs() > 0) & numeric.our_value.notna() & ~is_bool]
    ratio = numeric.our_value / numeric.paper_value
    numeric, ratio = numeric[ratio > 0], ratio[ratio > 0]       # a log axis holds no sign change
    bands = np.array([_ratio_band(p, t) for p, t in zip(numeric.paper_value, numeric.tolerance)])
    bands = bands.reshape(-1, 2)
    x_low, x_high = _ratio_limits(ratio.to_numpy(), bands)
    sources = list(dict.fromkeys(table.source))
    fig, ax = new_figure(figsize=(9.5, 4.2))
    rng = np.random.default_rng(seed)
    y = numeric.source.map(sources.index).to_numpy() + rng.uniform(-0.3, 0.3, len(numeric))
    if len(numeric):
        # a band that reaches zero (or below) runs to the left edge
        ax.hlines(y, np.clip(bands[:, 0], x_low, x_high), np.clip(bands[:, 1], x_low, x_high),
                  color="0.55", lw=2.2, alpha=0.6, label="agreement band of each claim")
    for verdict, colour in (("agrees", PALETTE.agreement), ("differs", PALETTE.contrast)):
        pick = (numeric.verdict == verdict).to_numpy()
        total = int((table.verdict == verdict).sum())
        ax.scatter(ratio[pick], y[pick], s=14, color=colour, zorder=3,
                   label=f"{verdict}: {pick.sum()} drawn of {total}")
    ax.set_xscale("log")
    ax.set_xlim(x_low, x_high)
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(range(len(sources)), sources)
    ax.set_ylim(len(sources) - 0.5, -0.5)
    ax.set_xlabel("our value / paper value")
    ax.set_title(f"{len(numeric)} of {len(table)} published claims drawn (nonzero numbers, "
                 "ratio > 0); a dot agrees when it lies on its grey band")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    plotting.name_figure(fig, None, "reproduction_scorecard")
    return fig
