"""The one call that starts a notebook: its study, its claim table and its figure style.

::

    from piezolib.workbook import session

    nb = session.start(study, claims="tracking")
    fig = nb.save(figures.fig15_tracking_error(...))   # figures/fig15_tracking_error.png
    nb.claims.add("Table 5", ...)
    nb.claims.save()                                    # data/results/tracking.csv

Everything a notebook writes goes through its session, to the folders of the
session's study (``figures/`` and ``data/results/`` for the reference study,
``runs/<study>/`` for any other): the study is passed, never looked up.

In a notebook kernel the session also shows the library's log records in
the cell (:func:`piezolib.progress.route_logs`): a solver's INFO lines
(when the notebook sets ``logging.getLogger("piezolib").setLevel(logging.INFO)``)
appear in a collapsed log under its progress bar, not as stderr blocks.
"""

import time

import pandas as pd

from piezolib import notebook_display, progress
from piezolib.workbook import plotting, report, style
from piezolib.workbook import study as studies

__all__ = ["Session", "start", "DISPLAY_OPTIONS"]

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

    def elapsed(self):
        """Seconds since the session started."""
        return time.perf_counter() - self.started


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
    """
    session = Session(study, claims)
    style.use_style()
    if notebook_display.in_kernel():        # a script or test keeps its own logging set-up
        progress.route_logs("piezolib")
    for option, value in DISPLAY_OPTIONS.items():
        pd.set_option(option, value)
    return session
