"""Progress bars for the long computations: one mechanism for the whole library.

:func:`progress` returns a bar that fits where the code runs:

* in a notebook (an IPython kernel, under JupyterLab or a headless client
  such as nbclient, papermill, ``jupyter nbconvert --execute`` or nbval): a
  :class:`~piezolib.notebook_display.CellBar`, one output redrawn in place
  (HTML with a plain-text twin).  It ends on one line that says how the work
  ended: green "✔ done" with the reason it stopped (:func:`finish`), however
  many of its ``total`` steps it took, or red "✘ FAILED" when an exception
  left the bar.  A saved notebook keeps that final line, never a stale
  frame or a widget without state.
* elsewhere: a ``tqdm`` text bar on ``file`` (default stderr), transient
  (``leave=False``): it disappears when the loop ends, so logs keep only
  the results and the INFO lines the solvers write anyway.

The bar is extra information; nothing a solver returns depends on it.

The environment variable ``PIEZOLIB_PROGRESS`` switches the bars:

====================  =====================================================
``0`` (off, no, ...)  no bar anywhere (nothing is written)
``1`` (on, yes, ...)  a bar even when stderr is not a terminal (logs, CI)
unset or ``auto``     a bar in a notebook or on a terminal, none when stderr
                      is redirected to a file or captured
====================  =====================================================

:func:`postfix` sets the short status text after the bar (e.g. the current
mu peak), :func:`finish` says why a search stopped, and :func:`write`
prints a line without tearing an active text bar (for per-step report lines
of a runner).  :class:`StatusLine` keeps one line of status current while
work runs elsewhere (the points of a sweep on worker processes).  On a terminal, INFO logging lines and a bar share stderr;
wrap the call in ``tqdm.contrib.logging.logging_redirect_tqdm()`` to route
the log lines around the bar.  In a notebook, :func:`route_logs` shows a
logger's records under the running bar instead of on stderr, and
:func:`shown_in` draws bars into a widget (work started by a button).

tqdm and IPython are imported on first use, so importing a module that
uses this one stays cheap.
"""

import os
import sys
import threading
import time

import numpy as np

from piezolib import notebook_display
from piezolib._checks import check_integer, check_positive
from piezolib.notebook_display import route_logs, shown_in

__all__ = ["ENV_VARIABLE", "progress", "progress_enabled", "postfix", "finish", "write",
           "route_logs", "shown_in", "StatusLine"]

#: Environment variable that switches the bars on (1), off (0) or to auto.
ENV_VARIABLE = "PIEZOLIB_PROGRESS"

_OFF = ("0", "false", "no", "off")
_ON = ("1", "true", "yes", "on")


def progress_enabled():
    """Whether bars are shown, from ``PIEZOLIB_PROGRESS``.

    Returns
    -------
    bool or None
        False (off), True (on, even on a non-terminal stream) or None (auto:
        on in a notebook or on a terminal).

    Raises
    ------
    ValueError
        ``PIEZOLIB_PROGRESS`` holds something other than 0/1, on/off,
        yes/no, true/false or auto.

    Examples
    --------
    >>> import os
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, {ENV_VARIABLE: "off"}):
    ...     progress_enabled()
    False
    >>> with mock.patch.dict(os.environ, {ENV_VARIABLE: "auto"}):
    ...     print(progress_enabled())
    None
    """
    value = os.environ.get(ENV_VARIABLE, "").strip().lower()
    if value in ("", "auto"):
        return None
    if value in _OFF:
        return False
    if value in _ON:
        return True
    raise ValueError(f"environment variable {ENV_VARIABLE} must be 0 (off), 1 (on) or auto, "
                     f"got {os.environ[ENV_VARIABLE]!r}")


def progress(iterable=None, *, total=None, desc=None, unit="step", leave=False, file=None):
    """A progress bar over ``iterable`` or over ``total`` manual updates.

    Use it as an iterable wrapper (``for x in progress(items, desc=...)``)
    or as a context manager that is advanced by hand::

        with progress(total=n, desc="DK", unit="iter") as bar:
            for k in range(n):
                ...
                postfix(bar, mu=peak)
                bar.update()

    Parameters
    ----------
    iterable : iterable, optional
        Items to wrap; ``total`` defaults to its length when it has one.
    total : int, optional
        Expected number of steps, or an upper bound (a search that stops
        early still ends as done, see :func:`finish`); None shows a counter
        without a percentage.
    desc : str, optional
        Label in front of the bar.
    unit : str
        Name of one step.
    leave : bool
        Keep a finished text bar on screen (default False: it disappears).
        A notebook bar always keeps its one final line.
    file : file-like, optional
        Stream of a text bar; default ``sys.stderr``, or in a notebook
        kernel the cell, inside :func:`shown_in` its callback (a
        :class:`~piezolib.notebook_display.CellBar`).  Given explicitly, the
        text bar is drawn there even in a kernel.

    Returns
    -------
    tqdm.tqdm or piezolib.notebook_display.CellBar
        The bar; ``bar.n`` counts the steps done.  A disabled bar writes
        nothing and still iterates.

    Raises
    ------
    ValueError, TypeError
        ``total`` not a non-negative integer, or a bad ``PIEZOLIB_PROGRESS``.

    Examples
    --------
    A bar on a non-terminal stream is disabled (writes nothing) but still iterates:

    >>> import io
    >>> sum(progress(range(4), desc="demo", file=io.StringIO()))
    6
    >>> with progress(total=3, file=io.StringIO()) as bar:    # advanced by hand
    ...     for k in range(3):
    ...         bar.update()
    """
    from tqdm import tqdm

    if total is not None:
        total = check_integer("total", total, minimum=0)
    if not isinstance(unit, str) or not unit:
        raise TypeError(f"unit must be a non-empty string, got {unit!r}")
    enabled = progress_enabled()
    if enabled is not False and file is None and (notebook_display.in_kernel()
                                                  or notebook_display.redirected()):
        return notebook_display.CellBar(iterable, total=total, desc=desc, unit=unit)
    # disable=None is tqdm's "off unless the stream is a terminal"
    return tqdm(iterable, total=total, desc=desc, unit=unit, leave=bool(leave),
                file=sys.stderr if file is None else file,
                disable=None if enabled is None else not enabled, dynamic_ncols=True)


def postfix(bar, text=None, *, refresh=False, **values):
    """Set the status text after ``bar``: ``text`` and/or ``name value`` pairs.

    Floats are shown with 4 significant digits (``mu 0.9402``), which tqdm's
    own ``set_postfix`` (3 digits) does not give.

    Parameters
    ----------
    bar : tqdm.tqdm or piezolib.notebook_display.CellBar
        A bar from :func:`progress` (disabled bars ignore the call).
    text : str, optional
        Free text put first.
    refresh : bool
        Redraw now (for a status shown during a long step); default False:
        the text appears with the next ``bar.update()``.
    **values
        Named values, in the order given.

    Examples
    --------
    >>> import io, os
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, {ENV_VARIABLE: "1"}):     # force a text bar
    ...     bar = progress(total=5, desc="DK", file=io.StringIO())
    >>> postfix(bar, "iter 1", mu=0.94023)
    >>> bar.postfix
    'iter 1, mu 0.9402'
    >>> bar.close()
    """
    parts = [] if text is None else [str(text)]
    for name, value in values.items():
        shown = f"{value:.4g}" if isinstance(value, (float, np.floating)) else str(value)
        parts.append(f"{name} {shown}")
    bar.set_postfix_str(", ".join(parts), refresh=bool(refresh))


def finish(bar, reason):
    """Say why the work of ``bar`` ended: it succeeded, after however many steps.

    Call it before the bar closes (inside its ``with`` block).  A search
    that stops before ``total`` (converged, no more improvement) is not a
    failure, and the bar must not read as one:

    * a notebook bar ends on a green line with the reason, e.g.
      ``✔ musyn DK: done: no improvement > 0.005 in 2 iterations · 5 of at
      most 8 iter in 41.2 s · mu 0.8003``;
    * a text bar is completed (its total becomes the steps done, so a kept
      bar reads 100 %) with the reason as its status text.

    Parameters
    ----------
    bar : tqdm.tqdm or piezolib.notebook_display.CellBar
        A bar from :func:`progress` (disabled bars ignore the call).
    reason : str
        Why the work stopped, e.g. ``"converged"``, ``"no improvement > 0.005
        in 2 iterations"`` or ``"max_iter reached"``.

    Examples
    --------
    >>> import io, os
    >>> from unittest import mock
    >>> with mock.patch.dict(os.environ, {ENV_VARIABLE: "1"}):
    ...     bar = progress(total=8, file=io.StringIO())
    >>> bar.update(3)
    >>> finish(bar, "converged")                 # stopped early: 3 of 3, not 3 of 8
    >>> bar.n, bar.total, bar.postfix
    (3, 3, 'converged')
    >>> bar.close()
    """
    if not isinstance(reason, str) or not reason:
        raise TypeError(f"reason must be a non-empty string, got {reason!r}")
    if isinstance(bar, notebook_display.CellBar):
        bar.finish(reason)
        return
    if getattr(bar, "disable", True):
        return
    if bar.total is not None and bar.n < bar.total:
        bar.total = bar.n
    bar.set_postfix_str(reason, refresh=False)


def write(line, file=None):
    """Print ``line`` (and a newline) without tearing the active bars.

    For per-step report lines written while a bar runs (e.g. a runner's
    ``[3/12] step ... 4.1 s``): bars on the same stream are cleared, the
    line printed and the bars redrawn::

        with progress(total=len(steps), desc="reproduce") as bar:
            for k, step in enumerate(steps, 1):
                seconds = run(step)
                write(f"[{k}/{len(steps)}] {step}  {seconds:.1f} s", file=stream)
                bar.update()

    Parameters
    ----------
    line : str
        Text to print.
    file : file-like, optional
        Destination; default ``sys.stdout``.

    Examples
    --------
    >>> import io
    >>> stream = io.StringIO()
    >>> write("[1/2] step done", file=stream)
    >>> print(stream.getvalue(), end="")
    [1/2] step done
    """
    from tqdm import tqdm

    stream = sys.stdout if file is None else file
    tqdm.write(str(line), file=stream)
    if hasattr(stream, "flush"):
        stream.flush()


class StatusLine:
    """One line of status kept current while the work runs elsewhere (other processes).

    ``status()`` is called for the text.  On a terminal the line is redrawn
    in place every ``refresh_s`` seconds, below the lines :meth:`write`
    prints.  On any other stream (a log file, a pipe, a notebook cell) it is
    printed as a line of its own when nothing was printed for ``every_s``
    seconds, so a log shows the run is alive before its first result.
    ``PIEZOLIB_PROGRESS=0`` turns the status off (the written lines stay).

    Parameters
    ----------
    status : callable
        ``status() -> str``, called from a timer thread and after each write.
    file : file-like, optional
        Default ``sys.stdout``.
    refresh_s, every_s : float
        Redraw period on a terminal, and the quiet time after which a line
        is printed elsewhere [s].

    Examples
    --------
    >>> import io
    >>> stream = io.StringIO()                     # not a terminal: no redrawn line
    >>> with StatusLine(lambda: "2 done, 1 running, 0 left", file=stream,
    ...                 every_s=60.0) as line:
    ...     line.write("[2/3] point 2  0.1 s")
    >>> print(stream.getvalue(), end="")
    [2/3] point 2  0.1 s
    """

    def __init__(self, status, file=None, refresh_s=1.0, every_s=10.0):
        if not callable(status):
            raise TypeError(f"status must be a callable returning text, got {status!r}")
        self.refresh_s = check_positive("refresh_s", refresh_s)
        self.every_s = check_positive("every_s", every_s)
        self._status, self.file = status, sys.stdout if file is None else file
        isatty = getattr(self.file, "isatty", None)
        self.live = bool(isatty and isatty())
        self._enabled = progress_enabled() is not False
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._last_print = time.monotonic()
        self._drawn = False
        self._thread = None
        if self._enabled:
            self._thread = threading.Thread(target=self._tick_until_closed, daemon=True,
                                            name="piezolib-status-line")
            self._thread.start()

    def write(self, line):
        """Print ``line`` above the status (which is redrawn after it on a terminal)."""
        with self._lock:
            self._clear()
            self._emit(f"{line}\n")
            if self.live and self._enabled:
                self._draw()

    def refresh(self):
        """Redraw the status now (a terminal), or print it when it is due (elsewhere)."""
        with self._lock:
            if not self._enabled:
                return
            if self.live:
                self._clear()
                self._draw()
            elif time.monotonic() - self._last_print >= self.every_s:
                self._emit(f"{self._status()}\n")

    def close(self):
        """Stop the timer and take the live line off the terminal."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            self._clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _tick_until_closed(self):
        period = self.refresh_s if self.live else min(self.refresh_s, self.every_s)
        while not self._stop.wait(period):
            self.refresh()

    def _draw(self):
        self._emit(f"\r{self._status()}\x1b[K", newline=False)
        self._drawn = True

    def _clear(self):
        if self._drawn:
            self._emit("\r\x1b[K", newline=False)
            self._drawn = False

    def _emit(self, text, newline=True):
        self.file.write(text)
        if hasattr(self.file, "flush"):
            self.file.flush()
        if newline:
            self._last_print = time.monotonic()

