"""Tables as a reader sees them: every number in one format, every text whole.

The notebooks' result tables hold numbers as the CSV files keep them (4
significant digits, as text) and notes of any length.  pandas shows such a
column as it finds it: ``9.148`` beside ``1.834e+23`` or ``9.15e+00``, and a
note cut at ``display.max_colwidth``.  :func:`readable` returns a styled
table for a notebook (and so for the report document) in which each number is
written by :func:`format_number` and each text is whole, wrapped in its cell.

::

    from piezolib.workbook import tables

    tables.readable(claims[["quantity", "paper", "ours", "note"]])
"""

import html
import math
import numbers

import numpy as np
import pandas as pd

from piezolib._checks import check_type
from piezolib.workbook.style import unit_text

__all__ = ["FIXED_RANGE", "DIGITS", "UNITS_COLUMNS", "format_number", "readable"]

#: Magnitudes written in fixed notation (low inclusive, high exclusive); a number
#: outside is written as a power of ten, ``1.834×10²³``, never as ``1.834e+23``.
FIXED_RANGE = (1e-3, 1e6)

#: Significant digits a table shows: those the committed result files keep.
DIGITS = 4

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def format_number(value, digits=DIGITS):
    """One table cell as text: a number in the workbook's one format, anything else as it is.

    Parameters
    ----------
    value : number, str or None
        A number, or the text of a cell read from a result file (``"9.148"``,
        ``"1.834e+23"``, ``"True"``, ``"differs"``, ``""``).
    digits : int
        Significant digits kept.

    Returns
    -------
    str
        A number of magnitude in :data:`FIXED_RANGE` (or zero) in fixed notation,
        rounded to ``digits`` significant digits without trailing zeros; any
        other finite number as ``m×10ᵉ``; text (booleans included) unchanged;
        ``None`` and NaN as ``""``.

    Examples
    --------
    >>> [format_number(x) for x in (9.148, "2100.0", "1.834e+23", 3.027e-11, 0.0, "True")]
    ['9.148', '2100', '1.834×10²³', '3.027×10⁻¹¹', '0', 'True']
    """
    if isinstance(digits, bool) or not isinstance(digits, numbers.Integral) or digits < 1:
        raise ValueError(f"digits must be a positive integer, got {digits!r}")
    number = _as_number(value)
    if number is None:
        return "" if value is None else str(value)
    if math.isnan(number):
        return ""
    if math.isinf(number):
        return "∞" if number > 0 else "−∞"
    rounded = float(f"{number:.{digits}g}")        # the magnitude after rounding decides
    if rounded == 0 or FIXED_RANGE[0] <= abs(rounded) < FIXED_RANGE[1]:
        return np.format_float_positional(rounded, precision=digits, unique=False,
                                          fractional=False, trim="-")
    mantissa, exponent = f"{number:.{digits - 1}e}".split("e")
    mantissa = mantissa.rstrip("0").rstrip(".") if "." in mantissa else mantissa
    return f"{mantissa}×10{str(int(exponent)).translate(_SUPERSCRIPT)}"


def _as_number(value):
    """``value`` as a float when it is a real number or the text of one, else None.

    Booleans are text here: ``True`` is a verdict-like value, not the number 1.
    """
    if isinstance(value, (bool, np.bool_)):
        return None
    if isinstance(value, numbers.Real):
        return float(value)
    if isinstance(value, str):
        text = value.strip()
        if text.lower() in ("", "true", "false", "nan", "inf", "-inf", "infinity"):
            return float("nan") if text.lower() == "nan" else None
        try:
            return float(text)
        except ValueError:
            return None
    return None


#: Columns of a claim table whose text follows the units rule (``mu_RP`` → ``μ_RP``);
#: names such as the notebook's ``05_mu_synthesis`` are left as they are.
UNITS_COLUMNS = ("quantity", "unit", "tolerance", "note")


def readable(frame, digits=DIGITS, index=False, units=UNITS_COLUMNS):
    """A table styled for reading: numbers by :func:`format_number`, texts whole and wrapped.

    Parameters
    ----------
    frame : pandas.DataFrame
        Any table; cells may be numbers or text (as :func:`~piezolib.workbook.report.load_claims`
        reads them).
    digits : int
        Significant digits of the numbers.
    index : bool
        Show the index (e.g. the notebook names of a count table); default False
        (a claim table's row numbers mean nothing to a reader).
    units : str or sequence of str
        Columns whose text is spelled by :func:`~piezolib.workbook.style.unit_text`
        (default :data:`UNITS_COLUMNS`); other text is shown as it is.

    Returns
    -------
    pandas.io.formats.style.Styler
        Renders as HTML in a notebook (and in the exported report): numbers
        right-aligned on one line, text left-aligned and wrapped instead of cut.

    Examples
    --------
    >>> frame = pd.DataFrame({"quantity": ["mu_RP"], "ours": [1.448321], "paper": [0.71]})
    >>> html_text = readable(frame).to_html()
    >>> "μ_RP" in html_text, "1.448" in html_text
    (True, True)
    """
    check_type("frame", frame, pd.DataFrame, "a pandas DataFrame")
    format_number(0.0, digits)                               # a bad ``digits`` fails here
    spell = _units_columns(frame, units)
    styler = frame.style.format(lambda v: html.escape(format_number(v, digits)))
    if spell:
        styler = styler.format(lambda v: html.escape(_spelled(v, digits)), subset=spell)
    for axis in (0, 1):          # labels too: an amplitude 10.0 reads "10", not "10.000000"
        styler = styler.format_index(lambda v: html.escape(format_number(v, digits)), axis=axis)
    if not index:
        styler = styler.hide(axis="index")
    styler = styler.set_table_styles([
        {"selector": "td, th", "props": "vertical-align: top; overflow-wrap: break-word;"},
        {"selector": "th", "props": "text-align: left;"},
    ])
    # a number reads best right-aligned and on one line; a text wraps (cell rules: they
    # outrank the table's own)
    return styler.map(lambda v: "text-align: left; white-space: normal;"
                      if _as_number(v) is None else "text-align: right; white-space: nowrap;")


def _spelled(value, digits):
    """A number formatted, a text spelled with the units rule."""
    text = format_number(value, digits)
    return text if _as_number(value) is not None else unit_text(text)


def _units_columns(frame, units):
    """The columns of ``frame`` among ``units`` (a column name or names)."""
    units = [units] if isinstance(units, str) else list(units)
    return [col for col in frame.columns if col in units]
