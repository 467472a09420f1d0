"""Paper-versus-reproduced comparison tables.

Every notebook states the paper's claims it checks as rows of a
:class:`ClaimTable` and writes them to ``data/results/<name>.csv`` (for a
study other than the reference: ``runs/<study>/results/<name>.csv``).  A row
holds the section, the quantity, its unit, the paper's value, the workbook's
value (and, for a statistic over noise seeds, its 95 % interval ``low`` ...
``high``), the precision of that value, the tolerance of the comparison, the
verdict and a note.  A numeric claim *agrees* when
``|ours - paper| <= max(atol, rtol * |paper|)``; a statistic agrees when its
interval meets that band (the noise cannot tell it from agreement).

Reproducibility rule: two values of a row are the same result when they
differ by less than the row's ``precision`` (default: one unit of the 4th
significant digit, the digits the file keeps).  A rerun rewrites a table only
when a row changed beyond that, or its verdict or text changed
(:func:`save_results`), and :func:`compare_studies` reports only such rows.
"""

import functools
import io
import numbers
from collections.abc import Iterable

import numpy as np
import pandas as pd

from piezolib._checks import check_nonnegative, check_type
from piezolib.files import atomic_write
from piezolib.workbook import outputs
from piezolib.workbook.outputs import REFERENCE_STUDY

__all__ = ["COLUMNS", "REASONS", "NOTEBOOK_TABLES", "OTHER_TABLES", "SIGNIFICANT_DIGITS",
           "verdict", "goal_verdict", "side_by_side", "ClaimTable", "save_results", "load_claims", "compare_studies",
           "same_result", "reproduction_table", "inconsistent_verdicts", "verdict_counts",
           "summary", "FINDINGS", "findings", "figure_path"]

COLUMNS = ["section", "quantity", "unit", "paper", "ours", "low", "high", "precision",
           "tolerance", "verdict", "reason", "note"]
_NUMBERS = ("paper", "ours", "low", "high")

#: Why a recomputed value differs from the published one.
REASONS = {
    "typo": "a printing or transcription error in the paper",
    "inconsistent parameters": "the published parameters do not produce the published value",
    "model mismatch": "the workbook's model differs from the one the paper used",
    "virtual stage": "the virtual stage stands in for hardware the workbook does not have",
    "method": "the quantity was computed by a different, documented method",
    "study": "the study changes one of the paper's choices (studies/<name>.toml)",
}


def verdict(paper, ours, rtol=0.0, atol=0.0, interval=None):
    """Return ``("agrees" | "differs", tolerance_text)`` for one claim.

    Numbers are compared with ``max(atol, rtol*|paper|)``; anything else
    (booleans, strings) must be equal.  A NaN result never agrees.  With
    ``interval = (low, high)`` (a statistic's 95 % interval) the claim agrees
    when the interval meets the band ``paper +- tol``: only an interval wholly
    outside it shows a difference that the noise cannot explain.

    Examples
    --------
    >>> verdict(0.81, 0.808, rtol=0.01)
    ('agrees', '+-1%')
    >>> verdict(0.71, 1.45, rtol=0.05)
    ('differs', '+-5%')
    >>> verdict(0.43, 0.5, atol=0.05, interval=(0.4, 0.6))    # the interval meets the band
    ('agrees', '+-0.05')
    """
    rtol = check_nonnegative("rtol", rtol)
    atol = check_nonnegative("atol", atol)
    if _is_number(paper) and _is_number(ours):
        tol = max(atol, rtol * abs(float(paper)))
        low, high = (float(ours), float(ours)) if interval is None else _interval(interval)
        gap = max(low - float(paper), float(paper) - high)     # <= 0: the interval holds paper
        ok = bool(np.isfinite(float(ours))) and gap <= tol
        text = (f"+-{rtol:.0%}" if rtol and tol == rtol * abs(float(paper))
                else f"+-{tol:g}")
        return ("agrees" if ok else "differs"), text
    if interval is not None:
        raise ValueError("interval is only meaningful for numeric claims")
    return ("agrees" if paper == ours else "differs"), "equal"


def goal_verdict(low, high, goal):
    """``"met"``, ``"missed"`` or ``"undecided"``: a statistic's 95 % interval against an upper goal.

    Met when the whole interval lies below the goal, missed when it lies at
    or above it; an interval that holds the goal cannot tell (a NaN interval
    neither).

    Examples
    --------
    >>> goal_verdict(0.8, 0.9, 1.0), goal_verdict(1.0, 1.2, 1.0), goal_verdict(0.9, 1.1, 1.0)
    ('met', 'missed', 'undecided')
    """
    for name, value in (("low", low), ("high", high), ("goal", goal)):
        if not _is_number(value):
            raise TypeError(f"{name} must be a real number, got {value!r}")
    if not np.isfinite(goal):
        raise ValueError(f"goal must be finite, got {goal!r}")
    if low > high:                   # False for NaN: a NaN interval stays undecided
        raise ValueError(f"high = {high!r} lies below low = {low!r}: not an interval")
    return "met" if high < goal else "missed" if low >= goal else "undecided"


def side_by_side(published, ours):
    """A published table and the workbook's, each column pair ``(column, "paper" | "ours")``.

    Parameters
    ----------
    published, ours : pandas.DataFrame
        Same rows; ``ours`` holds at least the published columns.

    Returns
    -------
    pandas.DataFrame
        Columns in the published table's sorted order, the paper's value
        before ours.

    Examples
    --------
    >>> published = pd.DataFrame({"x": [1.0], "y": [2.0]})
    >>> side_by_side(published, 1.1 * published).columns.tolist()
    [('x', 'paper'), ('x', 'ours'), ('y', 'paper'), ('y', 'ours')]
    """
    _check_frame("published", published)
    _check_frame("ours", ours, published.columns)
    both = pd.concat({"paper": published, "ours": ours}, axis=1).swaplevel(axis=1)
    return both[sorted(published.columns)]


def _check_frame(name, frame, columns=()):
    """Raise unless ``frame`` is a DataFrame holding ``columns``."""
    check_type(name, frame, pd.DataFrame, "a pandas DataFrame")
    missing = [c for c in columns if c not in frame.columns]
    if missing:
        raise ValueError(f"{name} lacks the column(s) {missing}")
    return frame


def _interval(interval):
    """(low, high) as finite floats with low <= high."""
    try:
        low, high = (float(x) for x in interval)
    except (TypeError, ValueError):
        raise ValueError(f"interval must be a pair (low, high) of numbers, got {interval!r}") \
            from None
    if not (np.isfinite(low) and np.isfinite(high) and low <= high):
        raise ValueError(f"interval must be finite with low <= high, got ({low}, {high})")
    return low, high


class ClaimTable:
    """Collects claims of one notebook of one study and writes them as one CSV.

    Parameters
    ----------
    name : str
        File stem of the table, e.g. ``"tracking"``.
    study : str
        Name of the study whose run the claims come from: the table goes to
        that study's results folder (:func:`piezolib.workbook.outputs.study_results_dir`),
        and a claim of a study other than the reference that differs from
        the paper gets the reason ``"study"`` unless it states one.

    Examples
    --------
    >>> claims = ClaimTable("demo", "explore")
    >>> claims.add("IV-C", "mu_RP", 0.71, 1.448, rtol=0.05)
    >>> claims.add("IV-B", "controller order", 6, 6)
    >>> claims.frame()[["quantity", "verdict", "reason"]].values.tolist()
    [['mu_RP', 'differs', 'study'], ['controller order', 'agrees', '']]
    """

    def __init__(self, name, study):
        if not isinstance(name, str) or not name.isidentifier():
            raise ValueError(f"name must be an identifier-like file stem, got {name!r}")
        if not isinstance(study, str) or not study:
            raise ValueError(f"study must be a study name, got {study!r}")
        self.name = name
        self.study = study
        self.rows = []

    def add(self, section, quantity, paper, ours, *, unit="", rtol=0.0, atol=0.0,
            interval=None, precision=None, reason="", note=""):
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
        interval : (float, float), optional
            For a statistic (e.g. a mean over noise seeds): its 95 % interval;
            the verdict is decided on it (:func:`verdict`).
        precision : float, optional
            Differences of ``ours`` below this are not results (same unit as
            ``ours``): a rerun that moves it less leaves the file as it is.
            Default: a quarter of the interval's width (about one standard
            error of a mean) with an interval, else one unit of the 4th
            significant digit.  State it for values that are rounding
            residuals (e.g. ``precision=atol`` for "max relative error").
        reason : str, optional
            One of :data:`REASONS`: why the values may differ.  Kept only on
            rows whose verdict is "differs".
        note : str, optional
            One line: why the values differ, or how ``ours`` was obtained.
        """
        if reason and reason not in REASONS:
            raise ValueError(f"reason must be one of {sorted(REASONS)}, got {reason!r}")
        low = high = None
        if interval is not None:
            if not _is_number(ours):
                raise ValueError(f"interval needs a numeric ours, got {ours!r}")
            low, high = _interval(interval)
            if not low <= float(ours) <= high:
                raise ValueError(f"ours = {ours!r} lies outside its interval ({low}, {high})")
            if precision is None:
                precision = (high - low) / 4
        if precision is not None:
            precision = check_nonnegative("precision", precision)
        if paper is None:
            result, tol = "not published", ""
        else:
            result, tol = verdict(paper, ours, rtol=rtol, atol=atol, interval=interval)
        if result == "differs" and not reason and self.study != REFERENCE_STUDY:
            reason = "study"      # the study changed one of the paper's choices
        self.rows.append(dict(section=section, quantity=quantity, unit=unit,
                              paper=paper, ours=_plain(ours), low=low, high=high,
                              precision=precision, tolerance=tol,
                              verdict=result,
                              reason=reason if result == "differs" else "",
                              note=note))

    def frame(self):
        """The claims as a DataFrame with columns :data:`COLUMNS`."""
        return pd.DataFrame(self.rows, columns=COLUMNS)

    def save(self):
        """Write ``<name>.csv`` to the study's results folder and return its path."""
        return save_results(self.frame(), self.name, self.study)


#: Significant digits of the numbers in the committed tables (the reproducibility
#: rule, README "Reproducible results").
SIGNIFICANT_DIGITS = 4


def save_results(frame, name, study):
    """Write a DataFrame to ``<results>/<name>.csv`` atomically, floats rounded to
    :data:`SIGNIFICANT_DIGITS`; keep the file when it holds the same results.

    ``<results>`` is ``data/results/`` for the reference study and
    ``runs/<study>/results/`` for any other
    (:func:`piezolib.workbook.outputs.study_results_dir` of the name ``study``).
    An existing file is left as it is when every row is the same result
    (:func:`same_result`): a rerun on another machine, whose rounding moves
    a value within its precision, leaves the committed table unchanged.

    Examples
    --------
    >>> import os, tempfile
    >>> from unittest import mock
    >>> frame = pd.DataFrame({"quantity": ["mu_RP"], "ours": [1.448321]})
    >>> with (tempfile.TemporaryDirectory() as root,
    ...       mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root})):
    ...     path = save_results(frame, "demo", "explore")
    ...     print(path.relative_to(os.path.realpath(root)).as_posix(), path.read_text().split())
    runs/explore/results/demo.csv ['quantity,ours', 'mu_RP,1.448']
    """
    _check_frame("frame", frame)
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"name must be an identifier-like file stem, got {name!r}")
    problem = outputs.study_name_problem(study)
    if problem:
        raise ValueError(f"study {problem}")
    directory = outputs.study_results_dir(study)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.csv"
    # object columns mix numbers and text; round their floats like the rest
    frame = frame.apply(lambda col: col.map(_rounded) if col.dtype == object else col)
    text = frame.to_csv(index=False, float_format=f"%.{SIGNIFICANT_DIGITS}g", lineterminator="\n")
    if path.is_file() and _same_tables(path.read_text(encoding="utf-8"), text):
        return path
    # one string, then a temporary file and a rename: a reader never sees a partial file
    return atomic_write(path, text)


def _same_tables(old_text, new_text):
    """True when two CSV texts hold the same columns and rows, row by row the same result."""
    read = functools.partial(pd.read_csv, dtype=str, keep_default_na=False)
    old, new = read(io.StringIO(old_text)), read(io.StringIO(new_text))
    if list(old.columns) != list(new.columns) or len(old) != len(new):
        return False
    if "precision" not in new.columns:        # not a claim table: numbers at 4 digits
        return all(_same_number(a, b, "", "") for col in new.columns
                   for a, b in zip(old[col], new[col]))
    return all(same_result(a, b) for (_, a), (_, b) in zip(old.iterrows(), new.iterrows()))


def same_result(first, second):
    """True when two rows of a claim table (string or numeric cells) state the same result.

    Text cells (quantity, verdict, tolerance, note, ...) must be equal; the
    numbers (``paper``, ``ours``, ``low``, ``high``) may differ by less than
    the larger of the two rows' ``precision`` (empty: one unit of the 4th
    significant digit of the larger value).

    Examples
    --------
    >>> row = pd.Series({"quantity": "mu_RP", "ours": "1.448", "precision": "", "verdict": "differs"})
    >>> same_result(row, row.replace("1.448", "1.4481"))      # within the 4th digit
    True
    >>> same_result(row, row.replace("1.448", "1.46"))
    False
    """
    check_type("first", first, pd.Series, "a row (pandas Series) of a claim table")
    check_type("second", second, pd.Series, "a row (pandas Series) of a claim table")
    for col in first.index:
        if col == "precision":
            continue
        if col in _NUMBERS:
            if not _same_number(first[col], second[col], first.get("precision", ""),
                                second.get("precision", "")):
                return False
        elif str(first[col]) != str(second[col]):
            return False
    return True


def _same_number(a, b, precision_a, precision_b):
    try:
        x, y = float(a), float(b)
    except (TypeError, ValueError):
        return str(a) == str(b)
    if not (np.isfinite(x) and np.isfinite(y)):
        return str(a) == str(b)
    stated = [float(p) for p in (precision_a, precision_b) if str(p) not in ("", "nan", "None")]
    big = max(abs(x), abs(y))
    unit = 10.0 ** (np.floor(np.log10(big)) - (SIGNIFICANT_DIGITS - 1)) if big > 0 else 0.0
    # the printed digits themselves: one unit of the last kept digit (a rounding boundary)
    return abs(x - y) <= max([unit * (1 + 1e-9)] + stated)


def _is_number(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _rounded(x):
    return float(f"{x:.{SIGNIFICANT_DIGITS}g}") if isinstance(x, float) else x


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
    "real_benchmark": "10_real_piezo_benchmark",
    "tracking_over_set": "12_tracking_over_the_set",
}


#: The workbook's findings beyond the paper, in notebook order: the result table of each
#: section of the report, the notebook that writes it, the one figure the report shows (None:
#: the section shares its notebook's figure) and (optionally) the words a row's quantity must
#: contain to belong to the section.
FINDINGS = {
    "own_stage": ("08_your_own_stage", "extra_own_stage_mu.png", ""),
    "mixed_mu": ("09_mixed_mu", "extra_mixed_tradeoff.png", ""),
    "real_benchmark": ("10_real_piezo_benchmark", "extra_fsm_scores.png", ""),
    "tracking_over_set": ("12_tracking_over_the_set", "extra_tracking_over_set.png", ""),
    "case_iv": ("12_tracking_over_the_set", None, "Case IV"),
}

#: The columns of a findings table the report shows (most rows publish no number).
_FINDING_COLUMNS = ["quantity", "unit", "paper", "ours", "note"]


def findings(name, study=REFERENCE_STUDY):
    """The rows of one section of the report's "beyond the paper" part.

    Parameters
    ----------
    name : str
        A key of :data:`FINDINGS` (``"own_stage"``, ``"mixed_mu"``,
        ``"real_benchmark"``, ``"tracking_over_set"``, ``"case_iv"``).
    study : str
        The study whose table is read (the reference's when the study has not
        written it, as :func:`load_claims`).

    Returns
    -------
    pandas.DataFrame
        Columns ``quantity``, ``unit``, ``paper``, ``ours``, ``note`` (text
        cells as the result file holds them); ``paper`` is empty where the paper
        publishes no number.

    Examples
    --------
    >>> rows = findings("real_benchmark")                  # the committed table
    >>> list(rows.columns)
    ['quantity', 'unit', 'paper', 'ours', 'note']
    """
    if not isinstance(name, str) or name not in FINDINGS:
        raise ValueError(f"name must be one of {list(FINDINGS)}, got {name!r}")
    _check_study_exists(study)
    table = "tracking_over_set" if name == "case_iv" else name
    rows = load_claims([table], study=study)
    words = FINDINGS[name][2]
    if words:
        rows = rows[rows["quantity"].str.contains(words, regex=False)]
    return rows[_FINDING_COLUMNS].reset_index(drop=True)


def figure_path(name, study=REFERENCE_STUDY):
    """Path of the figure file ``name`` of ``study`` (the reference's when the study has none).

    Raises
    ------
    FileNotFoundError
        Naming the notebook to run when neither exists.

    Examples
    --------
    >>> figure_path("fig12_mu_bounds.png").relative_to(outputs.project_root()).as_posix()
    'figures/fig12_mu_bounds.png'
    """
    check_type("name", name, str, "a figure file name such as 'fig12_mu_bounds.png'")
    _check_study_exists(study)
    own = outputs.study_figures_dir(study) / name
    if own.is_file():
        return own
    reference = outputs.study_figures_dir(REFERENCE_STUDY) / name
    if not reference.is_file():
        raise FileNotFoundError(f"{reference} is missing: run python -m piezolib reproduce")
    return reference


def load_claims(names=None, study=REFERENCE_STUDY):
    """Concatenate the comparison tables written by the notebooks.

    Parameters
    ----------
    names : sequence of str, optional
        Table names (keys of :data:`NOTEBOOK_TABLES` or :data:`OTHER_TABLES`);
        default all of :data:`NOTEBOOK_TABLES`.
    study : str, optional
        Name of the study whose tables to read (default: the reference).  A
        table the study has not written yet is read from the reference
        study's ``data/results/``, and the ``study`` column says so.

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS` plus ``source``, the notebook that wrote each row,
        and ``study``, the study whose run it comes from.

    Raises
    ------
    FileNotFoundError
        Naming the notebook to run when a table is missing.

    Examples
    --------
    >>> claims = load_claims(["audit"])                 # data/results/audit.csv
    >>> list(claims.columns[:4]), set(claims.study)
    (['source', 'study', 'section', 'quantity'], {'reference'})
    """
    if isinstance(names, str) or not (names is None or isinstance(names, Iterable)):
        raise TypeError(f"names must be a sequence of table names, got {names!r}")
    names = list(NOTEBOOK_TABLES) if names is None else list(names)
    tables = {**NOTEBOOK_TABLES, **OTHER_TABLES}
    _check_study_exists(study)
    frames = []
    for name in names:
        if name not in tables:
            raise ValueError(f"unknown table {name!r}; expected one of {list(tables)}")
        path, origin = _study_table(study, name)
        if not path.exists():
            raise FileNotFoundError(
                f"{path} is missing: run notebook {tables[name]} "
                f"(python -m piezolib reproduce {tables[name][:2]})")
        frame = pd.read_csv(path, dtype=str, keep_default_na=False)
        missing = set(COLUMNS) - set(frame.columns)
        if missing:
            raise ValueError(f"{path.name} lacks column(s) {sorted(missing)}")
        frame.insert(0, "source", tables[name])
        frame.insert(1, "study", origin)
        frames.append(frame[["source", "study"] + COLUMNS])
    return pd.concat(frames, ignore_index=True)


def _check_study_exists(study):
    """Raise unless ``study`` names the reference, a study that has run, or a study file:
    a misspelt name must not silently read the reference's tables."""
    problem = outputs.study_name_problem(study)
    if problem:
        raise ValueError(f"study {problem}")
    if study != REFERENCE_STUDY and not outputs.study_output_dir(study).is_dir():
        from piezolib.workbook import study as studies

        studies.load(study)          # StudyError for an unknown study


def _study_table(study, name):
    """Path of table ``name`` of ``study`` and the study it belongs to (the
    reference's when the study has not written it)."""
    own = outputs.study_results_dir(study) / f"{name}.csv"
    if study == REFERENCE_STUDY or own.exists():
        return own, study
    return outputs.study_results_dir(REFERENCE_STUDY) / f"{name}.csv", REFERENCE_STUDY


def compare_studies(first, second, names=None, changed_only=True):
    """Key numbers of two studies side by side, from their result tables.

    Parameters
    ----------
    first, second : str
        Study names (e.g. ``"reference"`` and ``"wide_error_weight"``); each
        must have been run (``python -m piezolib reproduce --study ...``).
    names : sequence of str, optional
        Tables to compare (default: every notebook table).
    changed_only : bool
        Keep only the rows whose value differs between the two studies.

    Returns
    -------
    pandas.DataFrame
        Index (source, quantity); columns ``unit``, ``paper``, the two
        studies' values and verdicts.

    Examples
    --------
    >>> table = compare_studies("reference", "wide_error_weight", names=["weights"])
    >>> list(table.columns)
    ['unit', 'paper', 'reference', 'wide_error_weight', 'verdict (reference)', 'verdict (wide_error_weight)', 'from (wide_error_weight)']
    """
    for name, value in (("first", first), ("second", second)):
        if not isinstance(value, str):
            raise TypeError(f"{name} must be a study name, got {type(value).__name__}")
    if first == second:
        raise ValueError(f"first and second name the same study {first!r}")
    key = ["source", "section", "quantity"]
    frames = []
    for name in (first, second):
        claims = load_claims(names, study=name)
        claims = claims.drop_duplicates(key)
        frames.append(claims.set_index(key)[["unit", "paper", "ours", "precision", "verdict",
                                             "study"]])
    a, b = frames
    b = b.reindex(a.index)
    table = a[["unit", "paper"]].copy()
    table[first], table[second] = a["ours"], b["ours"]
    table[f"verdict ({first})"] = a["verdict"]
    table[f"verdict ({second})"] = b["verdict"]
    table[f"from ({second})"] = b["study"]
    if changed_only:
        # a difference within the rows' precision (rounding, another machine) is no change
        same = [a.loc[i, "verdict"] == b.loc[i, "verdict"]
                and _same_number(a.loc[i, "ours"], b.loc[i, "ours"], a.loc[i, "precision"],
                                 b.loc[i, "precision"]) for i in a.index]
        table = table[~np.array(same, dtype=bool)]
    return table


def reproduction_table(claims):
    """The published claims only (rows with a paper value), one verdict each.

    A row that differs without a reason is marked ``"unexplained"`` in the
    ``reason`` column so that it cannot pass unnoticed.

    Examples
    --------
    >>> claims = pd.DataFrame({"quantity": ["mu_RP", "order", "mu_RS"],
    ...                        "verdict": ["differs", "agrees", "not published"],
    ...                        "reason": ["", "", ""]})
    >>> reproduction_table(claims)[["quantity", "reason"]].values.tolist()
    [['mu_RP', 'unexplained'], ['order', '']]
    """
    _check_frame("claims", claims, ["verdict", "reason"])
    published = claims[claims["verdict"] != "not published"].copy()
    unexplained = (published["verdict"] == "differs") & (published["reason"] == "")
    published.loc[unexplained, "reason"] = "unexplained"
    return published.reset_index(drop=True)


def inconsistent_verdicts(table):
    """Rows whose stored verdict does not follow from their stored values and tolerance.

    Recomputes each numeric verdict from the table as written (``paper``,
    ``ours`` or its interval ``low`` ... ``high`` rounded to
    :data:`SIGNIFICANT_DIGITS`, ``tolerance`` as
    ``+-x%`` or ``+-x``): a value that sits on the edge of its tolerance band
    can change its verdict when rounded, and this finds it.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :func:`load_claims` (string columns).

    Returns
    -------
    pandas.DataFrame
        The offending rows (empty when every verdict is consistent).

    Examples
    --------
    >>> table = pd.DataFrame({"paper": ["1.0", "1.0"], "ours": ["1.2", "1.01"],
    ...                       "tolerance": ["+-5%", "+-5%"], "verdict": ["agrees", "agrees"],
    ...                       "low": ["", ""]})
    >>> inconsistent_verdicts(table).index.tolist()     # 1.2 is not within 5 % of 1.0
    [0]
    """
    _check_frame("table", table, ["paper", "ours", "tolerance", "verdict"])
    bad = []
    for index, row in table.iterrows():
        tol = str(row["tolerance"])
        if row["verdict"] not in ("agrees", "differs") or not tol.startswith("+-"):
            continue
        try:
            paper_value, ours = float(row["paper"]), float(row["ours"])
        except ValueError:
            continue
        low, high = ((float(row["low"]), float(row["high"])) if str(row.get("low", "")) != ""
                     else (ours, ours))
        width = (float(tol[2:-1]) / 100 * abs(paper_value) if tol.endswith("%")
                 else float(tol[2:]))
        # the stored tolerance text is itself rounded: allow its last printed digit
        slack = 1e-9 + 0.5e-2 * width
        gap = max(low - paper_value, paper_value - high)      # as in verdict()
        expected = gap <= width
        borderline = abs(gap - width) <= slack
        if not borderline and expected != (row["verdict"] == "agrees"):
            bad.append(index)
    return table.loc[bad]


def verdict_counts(table):
    """Agrees / differs counts per source notebook (rows) as a DataFrame.

    Examples
    --------
    >>> table = pd.DataFrame({"source": ["00_audit", "00_audit", "05_mu"],
    ...                       "verdict": ["agrees", "differs", "agrees"]})
    >>> verdict_counts(table).loc["all"].tolist()
    [2, 1]
    """
    _check_frame("table", table, ["source", "verdict"])
    counts = pd.crosstab(table["source"], table["verdict"])
    counts.loc["all"] = counts.sum()
    return counts


def summary(table, study=REFERENCE_STUDY):
    """The reproduction in a few sentences (Markdown), computed from its table.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`reproduction_table` output (columns ``source``, ``study``,
        ``verdict``, ``reason``).
    study : str
        The study whose run the table reports.

    Returns
    -------
    str
        Counts of agreeing and differing claims, the reasons of the
        differences (the unexplained ones named first), the counts per
        notebook and, when the study has not written some tables, how many
        rows come from the reference's.

    Examples
    --------
    >>> table = pd.DataFrame({"source": ["00_audit", "05_mu"], "study": ["explore"] * 2,
    ...                       "verdict": ["agrees", "differs"], "reason": ["", "study"]})
    >>> print(summary(table, study="explore"))
    **2 published numbers recomputed** (study `explore`): **1 agree** with the paper within their tolerance, **1 differ**.
    <BLANKLINE>
    - Every difference has a reason: 1 study.
    - Per notebook (agree of published): 00: 1 of 1, 05: 0 of 1.
    """
    _check_frame("table", table, ["source", "study", "verdict", "reason"])
    counts = table["verdict"].value_counts()
    agree, differ = int(counts.get("agrees", 0)), int(counts.get("differs", 0))
    reasons = table.loc[table["verdict"] == "differs", "reason"].value_counts()
    unexplained = int(reasons.pop("unexplained")) if "unexplained" in reasons else 0
    lines = [f"**{len(table)} published numbers recomputed** (study `{study}`): "
             f"**{agree} agree** with the paper within their tolerance, **{differ} differ**.", ""]
    why = ", ".join(f"{n} {reason}" for reason, n in reasons.items())
    if unexplained:
        lines.append(f"- **{unexplained} difference{'s have' if unexplained > 1 else ' has'} "
                     "no reason**: see the table.")
    if why:
        lines.append(("- Reasons of the others: " if unexplained
                      else "- Every difference has a reason: ") + why + ".")
    per = table.groupby("source", sort=True)["verdict"]
    lines.append("- Per notebook (agree of published): " + ", ".join(
        f"{source[:2]}: {int((v == 'agrees').sum())} of {len(v)}" for source, v in per) + ".")
    borrowed = int((table["study"] != study).sum())
    if borrowed:
        lines.append(f"- {borrowed} row{'s come' if borrowed > 1 else ' comes'} from the "
                     "reference study's tables: this study has not written them.")
    return "\n".join(lines)
