"""Paper-versus-reproduced comparison tables.

Every notebook states the paper's claims it checks as rows of a
:class:`ClaimTable` and writes them to ``data/results/<name>.csv``.  A row
holds the section, the quantity, its unit, the paper's value, the workbook's
value, the tolerance of the comparison, the verdict and a note.  A numeric
claim *agrees* when ``|ours - paper| <= max(atol, rtol * |paper|)``.
"""

import numbers

import numpy as np
import pandas as pd

from piezolib._checks import check_nonnegative
from piezolib.records import atomic_write
from piezolib.workbook.paths import results_dir

__all__ = ["COLUMNS", "REASONS", "NOTEBOOK_TABLES", "OTHER_TABLES", "verdict", "ClaimTable",
           "save_results", "load_claims", "reproduction_table", "verdict_counts"]

COLUMNS = ["section", "quantity", "unit", "paper", "ours", "tolerance",
           "verdict", "reason", "note"]

#: Why a recomputed value differs from the published one.
REASONS = {
    "typo": "a printing or transcription error in the paper",
    "inconsistent parameters": "the published parameters do not produce the published value",
    "model mismatch": "the workbook's model differs from the one the paper used",
    "virtual stage": "the virtual stage stands in for hardware the workbook does not have",
    "method": "the quantity was computed by a different, documented method",
}


def verdict(paper, ours, rtol=0.0, atol=0.0):
    """Return ``("agrees" | "differs", tolerance_text)`` for one claim.

    Numbers are compared with ``max(atol, rtol*|paper|)``; anything else
    (booleans, strings) must be equal.  A NaN result never agrees.
    """
    rtol = check_nonnegative("rtol", rtol)
    atol = check_nonnegative("atol", atol)
    if _is_number(paper) and _is_number(ours):
        tol = max(atol, rtol * abs(float(paper)))
        ok = bool(np.isfinite(float(ours))) and abs(float(ours) - float(paper)) <= tol
        text = (f"+-{rtol:.0%}" if rtol and tol == rtol * abs(float(paper))
                else f"+-{tol:g}")
        return ("agrees" if ok else "differs"), text
    return ("agrees" if paper == ours else "differs"), "equal"


class ClaimTable:
    """Collects claims of one notebook and writes them as one CSV."""

    def __init__(self, name):
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"name must be an identifier-like file stem, got {name!r}")
        self.name = name
        self.rows = []

    def add(self, section, quantity, paper, ours, *, unit="", rtol=0.0, atol=0.0,
            reason="", note=""):
        """Add one claim; its verdict is in the last row of :meth:`frame`.

        Parameters
        ----------
        section : str
            Paper location, e.g. ``"IV-C"`` or ``"Table 4"``.
        quantity : str
            What is compared, e.g. ``"||H_e S||_inf"``.
        paper, ours
            Published and recomputed values (``None`` for paper when the
            paper gives no number).
        unit : str, optional
        rtol, atol : float, optional
            Relative and absolute tolerance of the agreement.
        reason : str, optional
            One of :data:`REASONS`: why the values may differ.  Kept only on
            rows whose verdict is "differs".
        note : str, optional
            One line: why the values differ, or how ``ours`` was obtained.
        """
        if reason and reason not in REASONS:
            raise ValueError(f"reason must be one of {sorted(REASONS)}, got {reason!r}")
        if paper is None:
            result, tol = "not published", ""
        else:
            result, tol = verdict(paper, ours, rtol=rtol, atol=atol)
        self.rows.append(dict(section=section, quantity=quantity, unit=unit,
                              paper=paper, ours=_plain(ours), tolerance=tol,
                              verdict=result,
                              reason=reason if result == "differs" else "",
                              note=note))

    def frame(self):
        """The claims as a DataFrame with columns :data:`COLUMNS`."""
        return pd.DataFrame(self.rows, columns=COLUMNS)

    def save(self):
        """Write ``data/results/<name>.csv`` and return its path."""
        return save_results(self.frame(), self.name)


def save_results(frame, name):
    """Write a DataFrame to ``data/results/<name>.csv`` atomically (floats to 6 significant
    digits so that reruns on other machines give the same file)."""
    if not isinstance(frame, pd.DataFrame):
        raise TypeError(f"frame must be a pandas DataFrame, got {type(frame).__name__}")
    path = results_dir() / f"{name}.csv"
    # object columns mix numbers and text; round their floats like the rest
    frame = frame.apply(lambda col: col.map(_six_digits) if col.dtype == object else col)
    # one string, then a temporary file and a rename: a reader never sees a partial file
    return atomic_write(path, frame.to_csv(index=False, float_format="%.6g",
                                           lineterminator="\n"))


def _is_number(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _six_digits(x):
    return float(f"{x:.6g}") if isinstance(x, float) else x


def _plain(x):
    """numpy scalars to Python scalars so that CSV and display stay simple."""
    return x.item() if isinstance(x, np.generic) else x


#: The comparison table each notebook writes, in pipeline order.
NOTEBOOK_TABLES = {
    "audit": "00_published_design_audit",
    "identification": "01_identification",
    "uncertainty": "02_uncertainty",
    "hysteresis": "03_dahl_hysteresis",
    "weights": "04_weighting_design",
    "mu_synthesis": "05_mu_synthesis",
    "tracking": "06_tracking_experiments",
}

#: Result tables of notebooks that check no published claim (every row has
#: paper = None): loaded by :func:`load_claims` only when asked for by name.
OTHER_TABLES = {
    "own_stage": "08_your_own_stage",
    "mixed_mu": "09_mixed_mu",
}


def load_claims(names=None):
    """Concatenate the comparison tables written by the notebooks.

    Parameters
    ----------
    names : sequence of str, optional
        Table names (keys of :data:`NOTEBOOK_TABLES` or :data:`OTHER_TABLES`);
        default all of :data:`NOTEBOOK_TABLES`.

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS` plus ``source``, the notebook that wrote each row.

    Raises
    ------
    FileNotFoundError
        Naming the notebook to run when a table is missing.
    """
    names = list(NOTEBOOK_TABLES) if names is None else list(names)
    tables = {**NOTEBOOK_TABLES, **OTHER_TABLES}
    frames = []
    for name in names:
        if name not in tables:
            raise ValueError(f"unknown table {name!r}; expected one of {list(tables)}")
        path = results_dir() / f"{name}.csv"
        if not path.exists():
            raise FileNotFoundError(
                f"{path} is missing: run notebook {tables[name]} "
                f"(python -m piezolib reproduce {tables[name][:2]})")
        frame = pd.read_csv(path, dtype=str, keep_default_na=False)
        missing = set(COLUMNS) - set(frame.columns)
        if missing:
            raise ValueError(f"{path.name} lacks column(s) {sorted(missing)}")
        frame.insert(0, "source", tables[name])
        frames.append(frame[["source"] + COLUMNS])
    return pd.concat(frames, ignore_index=True)


def reproduction_table(claims):
    """The published claims only (rows with a paper value), one verdict each.

    A row that differs without a reason is marked ``"unexplained"`` in the
    ``reason`` column so that it cannot pass unnoticed.
    """
    published = claims[claims["verdict"] != "not published"].copy()
    unexplained = (published["verdict"] == "differs") & (published["reason"] == "")
    published.loc[unexplained, "reason"] = "unexplained"
    return published.reset_index(drop=True)


def verdict_counts(table):
    """Agrees / differs counts per source notebook (rows) as a DataFrame."""
    counts = pd.crosstab(table["source"], table["verdict"])
    counts.loc["all"] = counts.sum()
    return counts
