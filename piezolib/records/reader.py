"""The strict CSV reader: a record from a delimited text file of any column layout, encoding
and number format (pandas' C parser, a line-by-line reader naming the offending line), every
error a :class:`~piezolib.records.RecordError` naming the file and the line.
"""

import codecs
import csv
import functools
import math
import re
from array import array
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from piezolib._checks import check_integer, check_positive
from piezolib.records.record import RATE_TOLERANCE, Record, RecordError, _rate_of

__all__ = ["read_table", "load_csv", "MIN_SAMPLES"]

#: Fewest samples :func:`load_csv` accepts by default.
MIN_SAMPLES = 16


# --- reading -----------------------------------------------------------------------------
# How read_table works: Python reads the top of the file line by line (comments, header, first
# data row), then surveys the rest in large chunks (line counts, comment markers and, when
# only some columns are read, delimiters per line: all at C speed), and pandas' C parser
# reads the needed columns as floats.  Whenever pandas fails or finds a NaN or inf, or the
# survey shows anything the fast read could get wrong (blank or comment lines among the
# data, rows of another length), the reference reader reads the file line by line instead:
# it names the first offending line, or returns what pandas would have returned.

#: Characters read at a time by the survey (1 MB: as fast as one pass over the whole text,
#: while memory stays flat for any file size).
_CHUNK = 1 << 20

# A byte-order mark names its encoding; UTF-32's marks begin like UTF-16's, so they come first.
_BOMS = ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"),
         (codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"),
         (codecs.BOM_UTF16_BE, "utf-16"))

# Decimal marks and thousands separators of common locales, tried on a cell that does not
# read, to say what it looks like (NBSP and narrow NBSP group thousands in French and SI).
_DECIMALS = (".", ",")
_SEPARATORS = (None, ",", ".", " ", "'", "\u00a0", "\u202f")


@dataclass(frozen=True)
class _Head:
    """The top of a file, up to and including its first data row."""

    metadata: dict
    names: list | None        # header names (None without a header)
    header_line: int | None   # 1-based file line of the header
    first_line: int | None    # 1-based file line of the first data row (None: no data)
    first_text: str           # that line as read (with its "\n")
    n_fields: int             # fields per row: the header's, else the first data row's


@dataclass(frozen=True)
class _Survey:
    """Counts over the data region (first data row to the end of the file)."""

    lines: int                # lines, not counting blank lines at the very end
    comment_seen: bool        # the comment marker occurs somewhere in the region
    uneven: int | None        # those lines with another number of delimiters than a full
                              # row (None: not counted)


def _check_format(delimiter, comment, decimal, thousands):
    if not isinstance(delimiter, str) or not delimiter or "\n" in delimiter or "\r" in delimiter:
        raise ValueError(f"delimiter must be a non-empty string without line ends, got "
                         f"{delimiter!r}")
    if comment is not None and not isinstance(comment, str):
        raise TypeError(f"comment must be a string or None, got {comment!r}")
    if decimal not in _DECIMALS:
        raise ValueError(f"decimal must be '.' or ',', got {decimal!r}")
    if thousands is not None and not (isinstance(thousands, str) and len(thousands) == 1
                                      and not thousands.isdigit() and thousands not in "+-eE"
                                      and thousands != decimal):
        raise ValueError(f"thousands must be None or one character other than a digit, a "
                         f"sign, 'e' and the decimal mark {decimal!r}, got {thousands!r}")
    if delimiter in (decimal, thousands):
        raise ValueError(f"delimiter {delimiter!r} cannot also be the decimal mark or the "
                         "thousands separator")


def _codec_of(path, encoding):
    """The codec to read ``path`` with: ``encoding``, or found from a byte-order mark."""
    try:
        with open(path, "rb") as f:
            start = f.read(4)
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such file") from None
    if encoding is not None:
        try:
            name = codecs.lookup(encoding).name
        except (LookupError, TypeError):
            raise ValueError(f"unknown encoding {encoding!r}") from None
        # "utf-8" on Excel's "CSV UTF-8" would keep its BOM as a character of the first line
        return "utf-8-sig" if name == "utf-8" and start.startswith(codecs.BOM_UTF8) else encoding
    return next((codec for bom, codec in _BOMS if start.startswith(bom)), "utf-8")


def _decode_error(path, codec, encoding):
    """A RecordError naming the line of the first byte ``codec`` cannot decode."""
    data = Path(path).read_bytes()
    try:
        data.decode(codec)
    except UnicodeDecodeError as exc:
        before = exc.object[:exc.start].decode(codec, errors="replace")
        line = len(re.findall(r"\r\n|\r|\n", before)) + 1
        what = "UTF-8" if encoding is None and codec.startswith("utf-8") else repr(codec)
        return RecordError(f"byte 0x{exc.object[exc.start]:02x} is not {what} text "
                           f"({exc.reason}); if the file is text, pass its encoding, e.g. "
                           "encoding='latin-1' (or 'cp1252' for Windows files)", path, line)
    return RecordError(f"the file changed while it was read as {codec!r}", path)


def _nul_error(path, line):
    return RecordError("NUL character: not a text file, or UTF-16/UTF-32 text without a "
                       "byte-order mark (then pass its encoding, e.g. encoding='utf-16-le')",
                       path, line)


def _add_metadata(metadata, body):
    """Store a ``key = value`` comment (``body`` without the comment marker)."""
    body = body.strip()
    if " = " in body:
        key, value = body.split(" = ", 1)
        metadata[key.strip()] = _parse_value(value.strip())


def _is_data(line, comment, metadata):
    """False for a blank line or a comment (whose ``key = value`` goes into ``metadata``);
    True for a line of fields.  Both readers classify lines by this one rule."""
    stripped = line.strip()
    if not stripped:
        return False
    if comment and stripped.startswith(comment):
        _add_metadata(metadata, stripped[len(comment):])
        return False
    return True


def _read_head(stream, path, header, delimiter, comment):
    """Read comments, blank lines and the header up to the first data row (see _Head)."""
    metadata, names, header_line, number = {}, None, None, 0
    while line := stream.readline():
        number += 1
        if "\x00" in line:
            raise _nul_error(path, number)
        if not _is_data(line, comment, metadata):
            continue
        fields = line.rstrip("\n").split(delimiter)
        if header and names is None:
            names, header_line = [name.strip() for name in fields], number
            continue
        n_fields = len(fields) if names is None else len(names)
        return _Head(metadata, names, header_line, number, line, n_fields)
    return _Head(metadata, names, header_line, None, "", 0 if names is None else len(names))


def _survey(stream, path, head, delimiter, comment, count_fields):
    """Count the lines of the data region and look for comments (see _Survey).

    ``stream`` is positioned after the first data row.  Counting in chunks runs at C speed;
    the counts are what lets read_table trust pandas: as many rows as lines (no blank line
    was skipped), no comment marker (no comment line was read as data) and, with
    ``count_fields`` (pandas reads only some columns and ignores extra fields), the same
    number of fields on every line.
    """
    lines, comment_seen, uneven, carry = 0, False, 0, 0
    keep = len(comment) - 1 if comment else 0      # a marker may straddle two chunks
    separators = head.n_fields - 1
    if count_fields and (len(delimiter) != 1 or not delimiter.isascii()):
        count_fields = False                        # (the fast read declines such files)
    previous, trailing, text = "", "", head.first_text
    while text:
        if "\x00" in text:
            before = text[:text.index("\x00")]
            raise _nul_error(path, head.first_line + lines + before.count("\n"))
        lines += text.count("\n")
        if comment and not comment_seen:
            comment_seen = comment in previous[len(previous) - keep:] + text
        if count_fields:
            more, carry = _uneven_lines(text, delimiter, separators, carry)
            uneven += more
        trailing = _trailing_blanks(text, trailing)
        previous, text = text, stream.read(_CHUNK)
    if not previous.endswith("\n"):
        lines += 1                                 # the last line has no line end
        uneven += carry != separators
    # blank lines at the end are common and harmless: pandas skips them, so do not count them
    # (the text before the first line end in ``trailing`` ends the last data row)
    blank = trailing.split("\n")[1:]
    if blank and not blank[-1]:
        blank.pop()                                # after the last line end: no line
    uneven -= sum(line.count(delimiter) != separators for line in blank)
    return _Survey(lines - len(blank), comment_seen, uneven if count_fields else None)


def _trailing_blanks(text, before):
    """The whitespace that ends ``before + text`` (``before``: that of the text so far)."""
    tail = text[-256:]                # rstrip of the whole chunk would copy a megabyte
    body = tail.rstrip()
    if body:
        return tail[len(body):]
    body = text.rstrip()
    return text[len(body):] if body else before + text


def _uneven_lines(text, delimiter, separators, carry):
    """How many lines ending in ``text`` have other than ``separators`` delimiters.

    ``carry`` is the number of delimiters of the chunk before after its last line end (they
    belong to the first line here); returns the count and the new carry.
    """
    codes = np.frombuffer(text.encode("utf-8", "surrogatepass"), dtype=np.uint8)
    ends = np.flatnonzero(codes == 10)
    places = np.flatnonzero(codes == ord(delimiter))
    if not ends.size:
        return 0, carry + places.size
    before = np.searchsorted(places, ends)         # delimiters before each line end
    per_line = np.diff(before, prepend=0)
    per_line[0] += carry
    return int(np.count_nonzero(per_line != separators)), int(places.size - before[-1])


@functools.lru_cache(maxsize=None)
def _number_pattern(decimal, thousands, grouped=False):
    """Regular expression of a number cell as pandas' C parser reads it.

    An optional sign, a digit followed by digits and ``thousands`` separators in any order
    (pandas does not check the grouping), an optional decimal mark with digits, an optional
    exponent, spaces or tabs around.  ``grouped`` asks for groups of three digits instead
    (used only to say what a cell looks like).
    """
    if thousands is None:
        integer = "[0-9]+"
    elif grouped:
        integer = f"[0-9]{{1,3}}(?:{re.escape(thousands)}[0-9]{{3}})+"
    else:
        integer = f"[0-9][0-9{re.escape(thousands)}]*"
    mark = re.escape(decimal)
    return re.compile(rf"[ \t\v\f]*[+-]?(?:{integer}(?:{mark}[0-9]*)?|{mark}[0-9]+)"
                      rf"(?:[eE][+-]?[0-9]+)?[ \t\v\f]*")


def _cell_value(cell, decimal=".", thousands=None):
    """The number in a cell (inf and nan included), or None where pandas reads none."""
    if decimal == "." and thousands is None:
        # float() takes all pandas takes, and also digit underscores and non-ASCII digits
        if not cell.isascii() or "_" in cell:
            return None
        try:
            return float(cell)
        except ValueError:
            return None
    if _number_pattern(decimal, thousands).fullmatch(cell):
        if thousands is not None and thousands in cell \
                and not _number_pattern(decimal, thousands, grouped=True).fullmatch(cell):
            return None      # a separator that does not group thousands: not this number
        text = cell.strip() if thousands is None else cell.strip().replace(thousands, "")
        return float(text.replace(decimal, "."))
    word = cell.strip().lstrip("+-").lower()
    return float(cell.strip()) if word in ("inf", "infinity", "nan") else None


def _style_hint(cell, decimal, thousands):
    """'it looks like ...: pass ...' when another locale's number format reads ``cell``."""
    text = cell.strip()
    fits = [(d, t) for d in _DECIMALS for t in _SEPARATORS
            if (d, t) != (decimal, thousands) and t != d and (t is None or t in text)
            and _number_pattern(d, t, grouped=True).fullmatch(text)]
    if not fits:
        return ""
    looks, fixes = [], []
    for d, t in fits:
        mark = "a decimal comma" if d == "," else "a decimal point"
        separator = f"a thousands separator {t!r}"
        looks.append(mark if t is None else separator if d == "." else f"{mark} and {separator}")
        fixes.append(", ".join([f"decimal={d!r}"] * (d != decimal)
                               + [f"thousands={t!r}"] * (t != thousands)))
    return f"it looks like {' or '.join(looks)}: pass {' or '.join(fixes)}"


def _looks_numeric(text, decimal, thousands):
    return _cell_value(text, decimal, thousands) is not None or bool(
        _style_hint(text, decimal, thousands))


def _column_index(spec, names, what, path, line):
    if isinstance(spec, str):
        if names is None:
            raise ValueError(f"{what}={spec!r} names a column but header=False; give a "
                             "0-based column number or set header=True")
        if spec not in names:
            raise RecordError(f"missing column {spec!r} ({what}); the header has {names}",
                              path, line)
        places = [k for k, name in enumerate(names) if name == spec]
        if len(places) > 1:
            # taking the first would silently read the wrong signal half the time
            raise RecordError(f"column name {spec!r} ({what}) appears {len(places)} times in "
                              f"the header (columns {', '.join(map(str, places))}): rename "
                              "the columns or give the 0-based column number", path, line)
        return places[0]
    return check_integer(what, spec, minimum=0)


def _columns_of(columns, head, header, path, decimal, thousands, distinct):
    """``{key: column number}`` and ``{key: label for messages}``, checking the header."""
    if header and head.names is None:
        raise RecordError("no header line and no data", path)
    # empty fields (a trailing delimiter, runs of spaces) are no names: a row of numbers
    # with them is still data
    named = [n for n in head.names or () if n != ""]
    if named and all(_looks_numeric(n, decimal, thousands) for n in named):
        shown = ", ".join(repr(n) for n in named[:4]) + (", ..." if len(named) > 4 else "")
        raise RecordError(f"the header line holds only numbers ({shown}): it looks like data; "
                          "pass header=False (and the columns by number)", path,
                          head.header_line)
    index = {key: _column_index(spec, head.names, f"columns[{key!r}]", path, head.header_line)
             for key, spec in columns.items()}
    taken = {}
    for key, col in index.items():
        if distinct and col in taken:
            # one signal in two roles would fit x against itself without a word
            shown = f"{col} ({head.names[col]!r})" if head.names and col < len(head.names) \
                else f"{col}"
            raise ValueError(f"{taken[col]} and {key} name the same column {shown}: each "
                             "signal needs a column of its own")
        taken[col] = key
    labels = {}
    for key, col in index.items():
        # (a column number past the header's names is reported by the rows that lack it)
        shown = head.names[col] if head.names and col < len(head.names) else col
        labels[key] = repr(shown) if str(shown) == str(key) else f"{shown!r} ({key})"
    return index, labels


def _every_column(index, head):
    """Whether the columns asked for are all the columns (then pandas checks row lengths)."""
    return sorted(set(index.values())) == list(range(head.n_fields))


def _read_fast(path, codec, head, index, survey, delimiter, decimal, thousands):
    """``(data, lines)`` read by pandas' C parser, or None where the slow reader must decide."""
    needed, every = sorted(set(index.values())), _every_column(index, head)
    # pandas takes a thousands separator anywhere in a number ('1234.35' read as 123435 with
    # thousands='.'); the slow reader accepts it only between groups of three digits
    if len(delimiter) != 1 or survey.comment_seen or thousands is not None:
        return None
    # pandas checks the length of every row when it reads every column; reading some, it
    # ignores extra fields: then every line must have as many delimiters as a full row
    if not every and survey.uneven != 0:
        return None
    # here, not at the top: the toolkit imports no pandas at module level
    # (tests/test_architecture.py), and importing it takes longer than most reads
    import pandas as pd

    with open(path, encoding=codec, newline=None) as stream:
        for _ in range(head.first_line - 1):
            stream.readline()
        # an open stream past the head, not the path: pandas (3.1) then keeps one array per
        # column, where from a path it also joins them into one 2-D block (2.3x the peak
        # memory); and skipping the head here, not by skiprows, saves a third of the time
        try:
            frame = pd.read_csv(stream, sep=delimiter, header=None,
                                usecols=None if every else needed, dtype=np.float64,
                                decimal=decimal, thousands=thousands, quoting=csv.QUOTE_NONE,
                                na_filter=False, skip_blank_lines=True, engine="c")
        except ValueError:   # text in a number column, a short or long row, ...
            return None
    # pandas skips blank lines (the counts differ) and takes the first row's width (the
    # columns differ when it is not the header's)
    if len(frame) != survey.lines or list(frame.columns) != needed:
        return None
    # one column at a time out of the frame, so that at most one extra column is held
    columns = {col: frame.pop(col).to_numpy(dtype=np.float64, copy=True) for col in needed}
    del frame
    if not all(np.isfinite(values).all() for values in columns.values()):
        return None          # the slow reader names the line
    data, taken = {}, set()
    for key, col in index.items():  # a column read for two keys: each gets its own array
        data[key] = columns[col].copy() if col in taken else columns[col]
        taken.add(col)
    return data, np.arange(head.first_line, head.first_line + survey.lines)


def _check_fields(fields, width, head, delimiter, path, number):
    if len(fields) < width:
        raise RecordError(f"{len(fields)} field(s), need at least {width} (column "
                          f"{width - 1} is used)", path, number)
    if any(field.strip() for field in fields[head.n_fields:]):
        where = (f"the header (line {head.header_line}) names {head.n_fields} columns"
                 if head.names is not None else
                 f"the first data row (line {head.first_line}) has {head.n_fields}")
        message = f"{len(fields)} fields, but {where}"
        if delimiter in _DECIMALS or delimiter in _SEPARATORS:
            message += (f"; with {delimiter!r} also between the columns, a number written "
                        f"with {delimiter!r} as decimal mark or thousands separator splits in "
                        "two: write the file with another delimiter, e.g. ';', and pass "
                        "delimiter=';'")
        raise RecordError(message, path, number)


def _checked_value(cell, label, decimal, thousands, path, number):
    value = _cell_value(cell, decimal, thousands)
    if value is None:
        hint = _style_hint(cell, decimal, thousands)
        raise RecordError(f"column {label}: {cell.strip()!r} is not a number"
                          + (f"; {hint}" if hint else ""), path, number)
    if not math.isfinite(value):
        raise RecordError(f"column {label}: {cell.strip()!r} is not a finite number",
                          path, number)
    return value


def _read_slow(stream, path, head, index, labels, delimiter, comment, decimal, thousands):
    """``(data, metadata, lines)`` read line by line in Python, raising at the first
    offending line: the reference the fast read must agree with."""
    width = max(index.values()) + 1
    columns, numbers, metadata = {key: array("d") for key in index}, array("q"), {}
    for number, line in enumerate(stream, start=1):
        if not _is_data(line, comment, metadata) or number == head.header_line:
            continue
        fields = line.rstrip("\n").split(delimiter)
        _check_fields(fields, width, head, delimiter, path, number)
        for key, col in index.items():
            columns[key].append(_checked_value(fields[col], labels[key], decimal, thousands,
                                               path, number))
        numbers.append(number)
    data = {key: np.frombuffer(values, dtype=np.float64) for key, values in columns.items()}
    return data, metadata, np.frombuffer(numbers, dtype=np.int64)


def read_table(path, columns, header=False, delimiter=",", comment="#", *, encoding=None,
               decimal=".", thousands=None, distinct=False):
    """Read numeric columns of a delimited text file, checking every line.

    A clean file is read by pandas' C parser (about the time and memory of
    ``pandas.read_csv``); any doubt sends it through a line-by-line reader
    that names the first offending line.

    Parameters
    ----------
    path : str or Path
    columns : dict
        ``{key: column}`` with a 0-based column number or, with ``header``, a
        column name.
    header : bool, optional
        The first non-comment, non-blank line holds the column names.
    delimiter : str, optional
        Between the fields; one character reads fast, a longer string line by
        line.
    comment : str or None, optional
        Lines starting with it (after blanks) are comments; ``key = value``
        comments are returned in the metadata.  Text after a number is not a
        comment.
    encoding : str, optional
        Text encoding, e.g. ``"latin-1"`` or ``"cp1252"``.  Default: UTF-8,
        or what a byte-order mark says (UTF-8 with a BOM as Excel writes it,
        UTF-16, UTF-32).
    decimal : {".", ","}, optional
        Decimal mark (``","`` for many European instrument exports; the
        delimiter must then be another character, e.g. ``";"``).
    thousands : str, optional
        Thousands separator inside numbers, e.g. ``","`` for ``1,234.5``
        (default: none allowed).
    distinct : bool, optional
        Every key must name a column of its own (as the signals of
        :func:`load_csv`); default False: a column may be read under two keys.

    Returns
    -------
    data : dict
        ``{key: ndarray}`` of floats.
    metadata : dict
        ``key = value`` comment lines (values parsed as int or float when
        possible).
    lines : ndarray of int
        1-based file line of every data row (comment, blank and header lines
        counted).

    Raises
    ------
    FileNotFoundError
        Missing file.
    RecordError
        Undecodable bytes or NUL characters (the message says to pass
        ``encoding``), a header of numbers only, a missing or duplicated
        column name, too few fields or more than the header names, text or
        NaN/inf in a number column (with a hint when it looks like another
        decimal mark or thousands separator); the message names the file,
        the line and the column.
    ValueError
        Bad arguments (an unknown encoding, a delimiter equal to the decimal
        mark, names without ``header``, two keys naming one column with
        ``distinct``).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "log.csv"
    ...     _ = path.write_text("# gain = 2\\ntime,u,y\\n0,1,2\\n0.5,2,4\\n1,3,6\\n")
    ...     data, meta, lines = read_table(path, {"u": "u", "y": 2}, header=True)
    >>> data["y"], meta, lines                     # by name or number; file line of each row
    (array([2., 4., 6.]), {'gain': 2}, array([3, 4, 5]))
    """
    path = Path(path)
    _check_format(delimiter, comment, decimal, thousands)
    codec = _codec_of(path, encoding)
    try:
        with open(path, encoding=codec, newline=None) as stream:
            head = _read_head(stream, path, header, delimiter, comment)
            index, labels = _columns_of(columns, head, header, path, decimal, thousands,
                                        distinct)
            if head.first_line is None:
                return ({key: np.empty(0) for key in index}, head.metadata,
                        np.empty(0, dtype=np.int64))
            survey = _survey(stream, path, head, delimiter, comment,
                             count_fields=not _every_column(index, head))
        fast = _read_fast(path, codec, head, index, survey, delimiter, decimal, thousands)
        if fast is not None:
            return fast[0], head.metadata, fast[1]
        with open(path, encoding=codec, newline=None) as stream:
            return _read_slow(stream, path, head, index, labels, delimiter, comment, decimal,
                              thousands)
    except UnicodeDecodeError:
        raise _decode_error(path, codec, encoding) from None


def _parse_value(text):
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text


def load_csv(path, *, input, output, time=None, fs=None, header=False, delimiter=",",
             comment="#", encoding=None, decimal=".", thousands=None, input_unit="V",
             output_unit="V", input_scale=1.0, output_scale=1.0, time_scale=1.0,
             input_name="u", output_name="y", rate_tolerance=RATE_TOLERANCE,
             min_samples=MIN_SAMPLES, metadata=None):
    """Load a measured experiment from a delimited text file.

    Parameters
    ----------
    path : str or Path
    input, output : int or str
        Column of the input and of the output: 0-based number, or a name
        from the header line (``header=True``).
    time : int or str, optional
        Column of the sample times; the rate is then taken from it and the
        sampling is checked to be even within ``rate_tolerance``.
    fs : float, optional
        Sampling rate [Hz]; required without a time column.  With both, they
        must agree within ``rate_tolerance``.
    header : bool, optional
        The first non-comment line holds column names.
    delimiter, comment : str, optional
        Field delimiter and comment marker (see :func:`read_table`).
    encoding : str, optional
        Text encoding, e.g. ``"latin-1"``; default UTF-8 or what a
        byte-order mark says (UTF-8 with BOM, UTF-16, UTF-32).
    decimal : {".", ","}, optional
        Decimal mark; ``decimal=","`` (with e.g. ``delimiter=";"``) reads
        European exports such as ``0,0125;1,5``.
    thousands : str, optional
        Thousands separator inside numbers, e.g. ``","`` for ``1,234.5``.
    input_unit, output_unit : str, optional
        Units of the signals after scaling.
    input_scale, output_scale, time_scale : float, optional
        Factors applied to the file's numbers (e.g. ``output_scale=1e6`` for
        metres to micrometres, ``time_scale=1e-3`` for milliseconds).
    input_name, output_name : str, optional
    rate_tolerance : float, optional
        Largest relative deviation of a time step from the median step.
    min_samples : int, optional
        Fewest data rows accepted.
    metadata : dict, optional
        Added to the record's metadata (after the file's ``key = value``
        comments and ``source``).

    Returns
    -------
    Record

    Raises
    ------
    FileNotFoundError
        Missing file.
    RecordError
        Undecodable text, a header of numbers only, a missing or duplicated
        column, text/NaN in a number column (with a hint for thousands
        separators and decimal commas), non-increasing or uneven time, too
        few rows: the message names the file and the line.
    ValueError
        Contradictory arguments (no rate, names without a header, one column
        for two signals, an unknown encoding, a delimiter equal to the
        decimal mark).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     path = Path(folder) / "step.csv"
    ...     rows = "".join(f"{k / 100},{k % 5},{0.5 * (k % 5)}\\n" for k in range(20))
    ...     _ = path.write_text("t,v,x\\n" + rows)
    ...     rec = load_csv(path, time="t", input="v", output="x", header=True, output_unit="um")
    >>> rec, rec.output[:3]
    (Record(20 samples at 100 Hz, u [V] -> y [um]), array([0. , 0.5, 1. ]))
    """
    if time is None and fs is None:
        raise ValueError("give the sampling rate fs [Hz] or a time column (time=...)")
    for name, value in (("input_scale", input_scale), ("output_scale", output_scale)):
        if not (isinstance(value, (int, float, np.number)) and math.isfinite(value)
                and value != 0):
            raise ValueError(f"{name} must be a finite non-zero number, got {value!r}")
    time_scale = check_positive("time_scale", time_scale)
    min_samples = check_integer("min_samples", min_samples, minimum=2)
    rate_tolerance = check_positive("rate_tolerance", rate_tolerance)
    columns = {"input": input, "output": output}
    if time is not None:
        columns["time"] = time
    data, meta, lines = read_table(path, columns, header, delimiter, comment,
                                   encoding=encoding, decimal=decimal, thousands=thousands,
                                   distinct=True)
    if len(lines) < min_samples:
        raise RecordError(f"too short: {len(lines)} data row(s), need at least {min_samples}",
                          path, int(lines[-1]) if len(lines) else None)
    # read_table's arrays are new and ours: scale in place (no copy of a long record)
    for key, scale in (("input", input_scale), ("output", output_scale), ("time", time_scale)):
        if key in data and scale != 1:
            data[key] *= scale
    t0 = 0.0
    if time is not None:
        t = data["time"]
        rate, t0 = _rate_of(t, rate_tolerance,
                            lambda i, msg: RecordError(msg, path, int(lines[i])))
        if fs is not None:
            fs = check_positive("fs", fs)
            if abs(rate - fs) > rate_tolerance * fs:
                raise RecordError(f"the time column gives {rate:.6g} Hz, but fs={fs:g} Hz",
                                  path)
        fs = rate
    meta = {"source": str(path), **meta, **(metadata or {})}
    return Record(data["input"], data["output"], fs, input_unit, output_unit, input_name,
                  output_name, t0, meta)
