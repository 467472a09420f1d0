"""The one call that starts a notebook: its study, its claim table and its figure style.

::

    from piezolib.workbook import session

    nb = session.start(study, claims="tracking")
    fig = nb.save(figures.fig15_tracking_error(...))   # figures/fig15_tracking_error.png
    nb.check("Table 5", "mean error, Case III, 1 Hz", 0.43, value, rtol=0.3,
             expect="agrees")                           # recorded, and asserted
    nb.require(checks)                                  # named checks of the library, asserted
    nb.show(table)                                      # every number in the one format
    nb.summary()                                        # the closing summary, from the claims
    nb.claims.save()                                    # data/results/tracking.csv

Everything a notebook writes goes through its session, to the folders of the
session's study (``figures/`` and ``data/results/`` for the reference study,
``runs/<study>/`` for any other): the study is passed, never looked up.

In a notebook kernel the session also shows the library's log records in
the cell (:func:`piezolib.progress.route_logs`): a solver's INFO lines
(when the notebook sets ``logging.getLogger("piezolib").setLevel(logging.INFO)``)
appear in a collapsed log under its progress bar, not as stderr blocks.
"""

import re
import time
from collections.abc import Mapping

import control as ct
import pandas as pd
from joblib.hashing import NumpyHasher

from piezolib import notebook_display, progress
from piezolib.problem.hysteresis_fits import share_stored_model_check
from piezolib.workbook import plotting, report, style, tables
from piezolib.workbook import study as studies

__all__ = ["Session", "start", "DISPLAY_OPTIONS", "CheckFailed", "claim_lines"]

class CheckFailed(AssertionError):
    """A notebook's check does not hold (an ``AssertionError``, so nbval reports the cell).

    Examples
    --------
    >>> issubclass(CheckFailed, AssertionError)     # nbval reports the failing cell
    True
    """


#: pandas display options every notebook starts with (tables of claims and numbers).
DISPLAY_OPTIONS = {"display.precision": 4, "display.max_colwidth": 90,
                   "display.max_rows": 400}


class Session:
    """A notebook's study and where its outputs go; made by :func:`start`.

    Attributes
    ----------
    study : piezolib.workbook.study.Study
        The study the notebook works on.
    claims : piezolib.workbook.report.ClaimTable or None
        The notebook's paper-versus-reproduced table, written to the study's
        results folder by ``claims.save()``.
    started : float
        :func:`time.perf_counter` at the start (see :meth:`elapsed`).

    Examples
    --------
    >>> nb = Session(studies.Study().replace(name="explore"), claims="weights")
    >>> nb, nb.reference
    (Session(study='explore', claims='weights'), False)
    >>> row = nb.check("eq. 15", "omega_e", 1260.0, 1260.0, rtol=0.01)
    >>> row["verdict"], len(nb.claims.rows)
    ('agrees', 1)
    """

    def __init__(self, study, claims=None):
        self.study = studies.load(study)
        if claims is not None and not (isinstance(claims, str) and claims.isidentifier()):
            raise ValueError(f"claims must be the name of the notebook's claim table, e.g. "
                             f"'tracking', got {claims!r}")
        self.claims = None if claims is None else report.ClaimTable(claims, self.study.name)
        self.started = time.perf_counter()

    def __repr__(self):
        table = "" if self.claims is None else f", claims={self.claims.name!r}"
        return f"Session(study={self.study.name!r}{table})"

    @property
    def reference(self):
        """True for the paper's reproduction, the one study whose numbers the notebooks assert."""
        return self.study.is_reference

    def save(self, fig):
        """Save a figure drawn by a figure function to the study's figures and return it.

        Parameters
        ----------
        fig : matplotlib.figure.Figure
            Named by its figure function (:func:`piezolib.workbook.plotting.name_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            ``fig``, so that ``fig = nb.save(figures.fig04_...(...))`` keeps it.
        """
        plotting.save_figure(fig, self.study.figures_dir)
        return fig

    def save_table(self, frame, name):
        """Write a table of claims to the study's results folder
        (:func:`piezolib.workbook.report.save_results`); return its path."""
        return report.save_results(frame, name, self.study.name)

    @staticmethod
    def cached(func, *args):
        """``func(*args)`` through the workbook's disk cache, keyed on the arguments, the
        function's source and the library's (:func:`piezolib.workbook.pipeline.checked_cache_call`):
        a product computed by an earlier run of the notebook is read, not computed again.

        Examples
        --------
        >>> import os, tempfile
        >>> from unittest import mock
        >>> with (tempfile.TemporaryDirectory() as folder,
        ...       mock.patch.dict(os.environ, {"PIEZOLIB_CACHE": folder})):
        ...     first, again = Session.cached(divmod, 7, 2), Session.cached(divmod, 7, 2)
        >>> first, again
        ((3, 1), (3, 1))
        """
        if not callable(func):
            raise TypeError(f"func must be a callable, got {func!r}")
        return _disk_cached(_call, func, _Arguments(args))

    def elapsed(self):
        """Seconds since the session started."""
        return time.perf_counter() - self.started

    @staticmethod
    def markdown(text):
        """Render Markdown text computed by the library (e.g. a report's summary) under the cell."""
        from IPython.display import Markdown

        if not isinstance(text, str):
            raise TypeError(f"text must be a str of Markdown, got {type(text).__name__}")
        return Markdown(text)

    def figure(self, name, width=None):
        """Show a figure file the workbook wrote (``figures/`` of the study, else the
        reference's): an IPython image, e.g. for the report's sections.

        Parameters
        ----------
        name : str
            File name, e.g. ``"extra_fsm_scores.png"``.
        width : int, optional
            Display width [px].
        """
        from IPython.display import Image

        return Image(filename=str(report.figure_path(name, self.study.name)), width=width)

    def _asserts(self, every_study):
        """True when a check of this session is asserted (the reference asserts all)."""
        return self.reference or every_study

    def check(self, section, quantity, paper, ours, *, expect=None, holds=None,
              every_study=False, **claim):
        """Record one claim in the claim table and assert what the notebook states of it.

        Parameters
        ----------
        section, quantity, paper, ours
            As :meth:`piezolib.workbook.report.ClaimTable.add`.
        expect : {"agrees", "differs"}, optional
            The verdict the notebook states (asserted): a published number that
            the workbook reproduces, or one it shows to differ.
        holds : bool, optional
            A condition the notebook states of ``ours`` (asserted), e.g.
            ``holds=mu < 1`` for a claim without a published number.
        every_study : bool
            Assert in every study, not only in the reference (a check that must
            hold whatever the study's choices).
        **claim
            ``unit``, ``rtol``, ``atol``, ``interval``, ``precision``, ``reason``,
            ``note`` of :meth:`~piezolib.workbook.report.ClaimTable.add`.

        Returns
        -------
        dict
            The recorded row.

        Raises
        ------
        CheckFailed
            When the stated verdict or condition does not hold (in the reference
            study, or in every study with ``every_study=True``).

        Examples
        --------
        >>> nb = Session.__new__(Session)                # a session without a study folder
        >>> nb.study = studies.Study(); nb.claims = report.ClaimTable("demo", "reference")
        >>> row = nb.check("IV-C", "||H_e S||_inf", 0.81, 0.808, rtol=0.01, expect="agrees")
        >>> row["verdict"]
        'agrees'
        >>> nb.check("IV-C", "mu_RP", 0.71, 1.45, rtol=0.05, expect="agrees")
        Traceback (most recent call last):
        ...
        piezolib.workbook.session.CheckFailed: IV-C, mu_RP: the verdict is 'differs', the notebook states 'agrees' (ours 1.45, paper 0.71, tolerance +-5%)
        """
        if self.claims is None:
            raise ValueError("this session has no claim table: start it with "
                             "session.start(study, claims='<name>')")
        if expect not in (None, "agrees", "differs"):
            raise ValueError(f"expect must be 'agrees', 'differs' or None, got {expect!r}")
        if expect is not None and paper is None:
            raise ValueError(f"expect={expect!r} needs a published value: paper is None "
                             "(state a condition with holds=... instead)")
        if holds is not None and not isinstance(holds, bool) and not hasattr(holds, "__bool__"):
            raise TypeError(f"holds must be a condition (bool), got {type(holds).__name__}")
        self.claims.add(section, quantity, paper, ours, **claim)
        row = self.claims.rows[-1]
        if self._asserts(every_study):
            where = f"{section}, {quantity}"
            if expect is not None and row["verdict"] != expect:
                raise CheckFailed(
                    f"{where}: the verdict is {row['verdict']!r}, the notebook states "
                    f"{expect!r} (ours {tables.format_number(row['ours'])}, paper "
                    f"{tables.format_number(paper)}, tolerance {row['tolerance']})")
            if holds is not None and not bool(holds):
                raise CheckFailed(f"{where}: the stated condition does not hold "
                                  f"(ours {tables.format_number(row['ours'])})"
                                  + (f"; {row['note']}" if row["note"] else ""))
        return row

    def require(self, checks, every_study=True):
        """Assert named checks computed by the library; return them as a table.

        Parameters
        ----------
        checks : mapping of str to bool
            What each check states (its name) and whether it holds, e.g. the
            ``checks`` of a library result.
        every_study : bool
            Assert in every study (default) or only in the reference.

        Returns
        -------
        pandas.DataFrame
            One row per check (``check``, ``holds``), to show under the cell.

        Raises
        ------
        CheckFailed
            Naming every check that does not hold.

        Examples
        --------
        >>> nb = Session.__new__(Session); nb.study = studies.Study()
        >>> bool(nb.require({"lower <= upper": True, "closed loop stable": True}).holds.all())
        True
        >>> nb.require({"closed loop stable": False})
        Traceback (most recent call last):
        ...
        piezolib.workbook.session.CheckFailed: does not hold: closed loop stable
        """
        if not isinstance(checks, Mapping) or not checks:
            raise TypeError(f"checks must be a non-empty mapping of check names to bools, "
                            f"got {checks!r}")
        frame = pd.DataFrame({"check": list(checks), "holds": [bool(v) for v in checks.values()]})
        failed = frame.check[~frame.holds].tolist()
        if failed and self._asserts(every_study):
            raise CheckFailed("does not hold: " + "; ".join(failed))
        return frame

    @staticmethod
    def show(frame, **options):
        """``frame`` styled for reading: every number in the one format of the report
        (:func:`piezolib.workbook.tables.readable`, whose options it takes)."""
        if isinstance(frame, pd.Series):
            frame = frame.to_frame()
            options.setdefault("index", True)
        return tables.readable(frame, **options)

    def summary(self, title="What holds", lines=()):
        """The notebook's closing summary (Markdown): its claims, one line each.

        Parameters
        ----------
        title : str
            The heading line.
        lines : sequence of str, optional
            Findings computed by the library that are not claims of the table,
            written first.

        Returns
        -------
        IPython.display.Markdown
            Rendered under the cell (its ``data`` is the Markdown text).
        """
        from IPython.display import Markdown

        rows = [] if self.claims is None else self.claims.rows
        text = [f"**{title}** (study `{self.study.name}`)", ""]
        text += [f"* {line}" for line in lines] + [f"* {line}" for line in claim_lines(rows)]
        return Markdown("\n".join(text))


def start(study=studies.REFERENCE, claims=None):
    """Start a notebook: load its study, open its claim table, apply the figure style.

    In a notebook kernel, the records of the ``piezolib`` loggers are shown
    in the cells (under the running progress bar) rather than on stderr.

    Parameters
    ----------
    study : str, path or Study
        A study name in ``studies/``, a TOML path or a :class:`~piezolib.workbook.study.Study`.
    claims : str, optional
        File stem of the notebook's claim table (e.g. ``"tracking"``); none
        for a notebook that only reads tables.

    Returns
    -------
    Session

    Examples
    --------
    >>> import os, tempfile
    >>> import matplotlib
    >>> from unittest import mock
    >>> with (tempfile.TemporaryDirectory() as root,                # a temporary checkout
    ...       mock.patch.dict(os.environ, {"PIEZOLIB_ROOT": root}),
    ...       pd.option_context(*sum(DISPLAY_OPTIONS.items(), ())),  # restored after
    ...       matplotlib.rc_context()):
    ...     nb = start("reference", claims="demo")
    ...     _ = nb.check("IV-C", "||H_e S||_inf", 0.81, 0.808, rtol=0.01, expect="agrees")
    ...     print(nb, nb.claims.save().relative_to(os.path.realpath(root)).as_posix())
    Session(study='reference', claims='demo') data/results/demo.csv
    """
    session = Session(study, claims)
    style.use_style()
    # the notebooks of a run check the committed Dahl model's refit once, not once each
    share_stored_model_check(_disk_cached)
    if notebook_display.in_kernel():        # a script or test keeps its own logging set-up
        progress.route_logs("piezolib")
    for option, value in DISPLAY_OPTIONS.items():
        pd.set_option(option, value)
    return session


def _disk_cached(func, *args):
    """``func(*args)`` through the pipeline's disk cache, keyed on the library's source too."""
    from piezolib.workbook import pipeline
    return pipeline.checked_cache_call(func, *args, pipeline.library_fingerprint())[0]


_GENERIC_NAME = re.compile(r"sys\[\d+\]")


class _ModelHasher(NumpyHasher):
    """joblib's hasher, blind to the numbers of the generic names python-control gives its
    systems (``sys[41]``, ``sys[41]$sampled``: a counter of the process, so the same model
    would key another entry in another run)."""

    def reducer_override(self, obj):
        if not isinstance(obj, (ct.StateSpace, ct.TransferFunction)):
            return NotImplemented
        name = _GENERIC_NAME.sub("sys[]", obj.name)
        labels = (obj.input_labels, obj.output_labels, name)
        if isinstance(obj, ct.StateSpace):
            return ct.ss, (obj.A, obj.B, obj.C, obj.D, obj.dt, obj.state_labels, *labels)
        return ct.tf, (obj.num_array, obj.den_array, obj.dt, *labels)


class _Arguments:
    """The arguments of a cached call, pickled (so keyed by the cache) as their digest."""

    def __init__(self, args, digest=None):
        self.args = args
        self.digest = _ModelHasher().hash(args) if digest is None else digest

    def __reduce__(self):
        return _Arguments, ((), self.digest)


def _call(func, arguments, fingerprint):
    """``func(*arguments.args)``; the library ``fingerprint`` is part of the key only."""
    return func(*arguments.args)


def claim_lines(rows):
    """One sentence per claim row: the quantity, our value, the paper's and the verdict.

    Parameters
    ----------
    rows : sequence of dict or pandas.DataFrame
        Claim rows (:data:`piezolib.workbook.report.COLUMNS`).

    Returns
    -------
    list of str
        Markdown lines, numbers in the one format of :func:`~piezolib.workbook.tables.format_number`.

    Examples
    --------
    >>> claim_lines([dict(section="IV-C", quantity="mu_RP", unit="", paper=0.71, ours=1.448,
    ...                   low=None, high=None, verdict="differs", reason="typo", note="")])
    ['**μ_RP** (IV-C): 1.448; paper 0.71, *differs* (typo)']
    """
    if isinstance(rows, pd.DataFrame):
        rows = rows.to_dict("records")
    if isinstance(rows, (str, bytes)) or not hasattr(rows, "__iter__"):
        raise TypeError(f"rows must be a DataFrame or a list of claim rows, got "
                        f"{type(rows).__name__}")
    rows = list(rows)
    if not all(isinstance(row, dict) for row in rows):
        raise TypeError("rows must hold claim rows (dicts with 'ours'), got "
                        f"{[type(r).__name__ for r in rows][:5]}")
    out = []
    for row in rows:
        value = tables.format_number(row["ours"])
        unit = row.get("unit") or ""
        if unit and unit != "-":
            value += f" {unit}"
        if str(row.get("low", "") or "") not in ("", "nan"):
            value += (f" (95 % interval {tables.format_number(row['low'])} … "
                      f"{tables.format_number(row['high'])})")
        if row["verdict"] == "not published":
            tail = ""
        else:
            tail = f"; paper {tables.format_number(row['paper'])}, *{row['verdict']}*"
            if row.get("reason"):
                tail += f" ({row['reason']})"
        note = f". {row['note']}" if row.get("note") else ""
        quantity = style.unit_text(str(row["quantity"]))
        out.append(f"**{quantity}** ({row['section']}): {value}{tail}{note}")
    return out

