"""Progress bars and log lines as outputs of a notebook cell that redraw in place.

Inside an IPython kernel :func:`piezolib.progress.progress` returns a
:class:`CellBar`: one output, shown with
``IPython.display.display(..., display_id=True)`` and redrawn with the
handle's ``update``, as HTML with a plain-text twin.  JupyterLab applies the
updates live; the headless runners (nbclient, papermill,
``jupyter nbconvert --execute``, nbval) apply them to the saved notebook, so
it keeps the bar's final line, not a stale first frame and no widget state.

A bar ends in one of two states, and its final line says which and why:

* **done** (green ✔): the loop ended without an exception, however many
  of its ``total`` steps it took (``total`` is an upper bound, a search
  may stop early).  :meth:`CellBar.finish` (or
  :func:`piezolib.progress.finish`) gives the reason (``"no improvement
  > 0.005 in 2 iterations"``), which the final line shows.
* **failed** (red ✘): an exception left the ``with`` block of the bar.

Log lines: :class:`CellLogHandler` (attached by :func:`route_logs`) shows
the records of a logger in the cell instead of on stderr: under the bar
that is running, in a collapsed "log" section of its output, or when no
bar runs, in a small grey block of their own (growing, until the next bar
of the cell starts).

Where the outputs go: the running cell, or inside :func:`shown_in`, a
callback such as a widget's HTML value.  A widget's callback (a button's
``on_click``) runs outside any cell; what it displays reaches no cell
output in JupyterLab, only the hidden log console.

IPython is imported only when a bar or log block is first drawn; importing
this module stays cheap and usable outside a kernel.
"""

import contextlib
import contextvars
import html
import logging
import sys
import time

__all__ = ["CellBar", "CellLogHandler", "ipython_shell", "in_kernel", "frontend_cell_id",
           "shown_in", "redirected", "route_logs"]

#: Least time between two redraws of a running bar [s] (the final one is always drawn).
_MIN_INTERVAL_S = 0.2
#: Log lines a bar or log block keeps (the oldest are dropped, and counted).
_MAX_LOG_LINES = 400
#: Width of the drawn bar [characters].
_BAR_WIDTH = 24

# colours of the states (JupyterLab's success/error palette, readable on light and dark)
_COLOURS = {"running": "#1976d2", "done": "#2e7d32", "failed": "#c62828"}
_SYMBOLS = {"running": "…", "done": "✔", "failed": "✘"}

# the callback of the innermost shown_in block, or None: draw in the cell
_SINK = contextvars.ContextVar("piezolib_display_sink", default=None)
# open bars, innermost last: log records go under the innermost one
_ACTIVE = []
# bars made so far: a log block drawn before a bar is not continued after it (order kept)
_BARS_MADE = [0]


# --------------------------------------------------------------------------- kernel
def ipython_shell():
    """The running IPython shell, or None (IPython is not imported unless it already is)."""
    ipython = sys.modules.get("IPython")
    return ipython.get_ipython() if hasattr(ipython, "get_ipython") else None


def in_kernel():
    """True when the code runs in an IPython kernel (a notebook, under any client).

    Returns
    -------
    bool
        False in plain Python and terminal IPython (no cell to draw in).
    """
    return getattr(ipython_shell(), "kernel", None) is not None


def frontend_cell_id():
    """The cell id an interactive frontend sent with the running request, or None.

    JupyterLab and Notebook 7 put ``cellId`` in the metadata of every
    execute request; the headless clients (nbclient, and so papermill,
    ``jupyter nbconvert --execute`` and nbval) send no metadata.  A cell id
    therefore means someone is looking at the output and a live widget can
    be drawn.

    Returns
    -------
    str or None
    """
    kernel = getattr(ipython_shell(), "kernel", None)
    get_parent = getattr(kernel, "get_parent", None)
    if get_parent is None:
        return None
    parent = get_parent("shell") or {}
    cell_id = (parent.get("metadata") or {}).get("cellId")
    return str(cell_id) if cell_id else None


def _request_id():
    """Message id of the request being run (one per cell), or None outside a kernel."""
    header = getattr(ipython_shell(), "parent_header", None) or {}
    return (header.get("header") or {}).get("msg_id")


# --------------------------------------------------------------------------- where drawings go
class _CellSlot:
    """One output of the running cell, drawn once and then updated in place."""

    def __init__(self):
        self.handle = None

    def show(self, html_text, plain_text):
        from IPython.display import display

        bundle = {"text/html": html_text, "text/plain": plain_text}
        if self.handle is None:
            self.handle = display(bundle, raw=True, display_id=True)
        else:
            self.handle.update(bundle, raw=True)


class _Sink:
    """The blocks drawn inside one :func:`shown_in`, joined and passed to its callback."""

    def __init__(self, callback):
        self.callback = callback
        self.blocks = []

    def slot(self):
        self.blocks.append(("", ""))
        return _SinkSlot(self, len(self.blocks) - 1)

    def redraw(self):
        self.callback("".join(b[0] for b in self.blocks),
                      "\n".join(b[1] for b in self.blocks if b[1]))


class _SinkSlot:
    """Block ``index`` of a :class:`_Sink`."""

    def __init__(self, sink, index):
        self.sink, self.index = sink, index

    def show(self, html_text, plain_text):
        self.sink.blocks[self.index] = (html_text, plain_text)
        self.sink.redraw()


def redirected():
    """True inside a :func:`shown_in` block (bars and log blocks draw through its callback)."""
    return _SINK.get() is not None


def _new_slot():
    """Where a new bar or log block draws: the innermost :func:`shown_in`, else the cell."""
    sink = _SINK.get()
    return _CellSlot() if sink is None else sink.slot()


@contextlib.contextmanager
def shown_in(callback):
    """Draw the bars and log blocks of the ``with`` block through ``callback``, not the cell.

    For work started by a widget (a button's ``on_click``): its output
    reaches no cell, so the bars are drawn into the widget instead::

        with shown_in(lambda html, text: setattr(status, "value", html)):
            result = long_search(...)

    Inside the block, :func:`piezolib.progress.progress` makes a
    :class:`CellBar` even outside a kernel (the callback is where it draws).

    Parameters
    ----------
    callback : callable
        Called as ``callback(html, text)`` with every bar and log block of
        the block (in order of creation, joined) each time one changes.

    Yields
    ------
    None
    """
    if not callable(callback):
        raise TypeError(f"callback must be callable as callback(html, text), got {callback!r}")
    token = _SINK.set(_Sink(callback))
    try:
        yield
    finally:
        _SINK.reset(token)


# --------------------------------------------------------------------------- formatting
def _duration(seconds):
    """``"41.2 s"``, ``"3 min 05 s"`` or ``"1 h 02 min"``."""
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, sec = divmod(int(round(seconds)), 60)
    if minutes < 60:
        return f"{minutes} min {sec:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"


def _bar_text(n, total):
    """A text bar ``██████░░░░`` for n of total steps ('' without a total)."""
    if not total:
        return ""
    filled = round(_BAR_WIDTH * min(n, total) / total)
    return "█" * filled + "░" * (_BAR_WIDTH - filled)


def _log_html(lines, dropped, warnings, summary_word):
    """The collapsed log section of a bar (open when it holds a warning)."""
    if not lines:
        return ""
    count = len(lines) + dropped
    extra = f", {warnings} warning{'s' * (warnings != 1)}" if warnings else ""
    body = "\n".join(_line_html(text, level) for text, level in lines)
    head = f"({dropped} earlier lines not kept)\n" if dropped else ""
    return (f"<details{' open' if warnings else ''} style='margin:0 0 0 1.6em'>"
            f"<summary style='cursor:pointer;color:#666'>{summary_word} ({count} "
            f"line{'s' * (count != 1)}{extra})</summary>"
            f"<pre style='margin:0;padding:2px 0;color:#555;font-size:11px;"
            f"background:transparent'>{head}{body}</pre></details>")


def _line_html(text, level):
    """One escaped log line, amber from WARNING up."""
    escaped = html.escape(text)
    return escaped if level < logging.WARNING else f"<span style='color:#b26a00'>{escaped}</span>"


# --------------------------------------------------------------------------- the bar
class CellBar:
    """A progress bar drawn as one updatable output (see the module docstring).

    Made by :func:`piezolib.progress.progress` in a kernel; the attributes
    and methods the library uses are those of a ``tqdm`` bar: ``n``,
    ``total``, ``postfix``, ``update``, ``reset``, ``set_postfix_str``,
    ``close``, iteration and use as a context manager.

    Parameters
    ----------
    iterable : iterable, optional
        Items to wrap.
    total : int, optional
        Upper bound on the number of steps.
    desc : str, optional
        Label.
    unit : str
        Name of one step.
    """

    def __init__(self, iterable=None, *, total=None, desc=None, unit="step"):
        if total is None and iterable is not None and hasattr(iterable, "__len__"):
            total = len(iterable)
        self.iterable, self.total, self.desc, self.unit = iterable, total, desc or "", unit
        self.n, self.postfix, self.reason = 0, "", None
        self.state, self.disable, self.leave = "running", False, True
        self.start_t = time.perf_counter()
        self._drawn_t = -float("inf")
        self._log, self._dropped, self._warnings = [], 0, 0
        self._slot = _new_slot()
        _ACTIVE.append(self)
        _BARS_MADE[0] += 1
        self.refresh()

    # tqdm-like use ---------------------------------------------------------
    def __iter__(self):
        try:
            for item in self.iterable:
                yield item
                self.update()
        except GeneratorExit:           # the loop was left early (break): not a failure
            self.close()
            raise
        except BaseException as exc:    # the iterable itself failed
            self._fail(exc)
            self.close()
            raise
        self.close()

    def __len__(self):
        return self.total or 0

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, traceback):
        if exc is not None:
            self._fail(exc)
        self.close()
        return False

    def update(self, n=1):
        """Advance by ``n`` steps; redraw unless the last redraw is very recent."""
        self.n += n
        self._draw()

    def reset(self, total=None):
        """Start counting again from 0, with a new ``total`` if given (tqdm's ``reset``).

        The elapsed time keeps counting from the bar's start: the final line
        says how long the whole work took (e.g. a grid search, then solves).
        """
        self.n = 0
        if total is not None:
            self.total = total
        self.refresh()

    def set_postfix_str(self, s="", refresh=True):
        """Set the status text after the counts (e.g. ``"mu 0.9402"``)."""
        self.postfix = str(s)
        if refresh:
            self.refresh()

    def refresh(self):
        """Redraw now."""
        self._draw(force=True)

    @property
    def elapsed(self):
        """Seconds since the bar was made."""
        return time.perf_counter() - self.start_t

    # end and log -------------------------------------------------------------
    def finish(self, reason):
        """Record why the work ended; it succeeded (see :func:`piezolib.progress.finish`)."""
        self.reason = str(reason)

    def close(self):
        """Draw the final line: done (with the reason), or failed; idempotent."""
        if self.disable:
            return
        if self.state == "running":
            self.state = "done"
        self.disable = True
        if self in _ACTIVE:
            _ACTIVE.remove(self)
        self._draw(force=True)

    def log(self, text, level=logging.INFO):
        """Add a log line under the bar (collapsed; a warning opens the section)."""
        self._log.append((str(text), int(level)))
        if len(self._log) > _MAX_LOG_LINES:
            del self._log[0]
            self._dropped += 1
        if level >= logging.WARNING:
            self._warnings += 1
        self._draw(force=level >= logging.WARNING)

    def _fail(self, exc):
        if self.state == "running":
            self.state = "failed"
            self.reason = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__

    # drawing -----------------------------------------------------------------
    def _draw(self, force=False):
        now = time.perf_counter()
        if not force and now - self._drawn_t < _MIN_INTERVAL_S:
            return
        self._drawn_t = now
        self._slot.show(self.html(), self.text())

    def _counts(self):
        if self.state == "running" or not self.total:
            of = f"/{self.total}" if self.total else ""
            return f"{self.n}{of} {self.unit}"
        return f"{self.n} of at most {self.total} {self.unit}"

    def status_line(self):
        """The line of text the bar shows now (without its log)."""
        head = f"{_SYMBOLS[self.state]} {self.desc}".rstrip()
        parts = [_bar_text(self.n, self.total)] if self.state == "running" else []
        word = {"running": "", "done": "done", "failed": "FAILED"}[self.state]
        why = f"{word}: {self.reason}" if self.reason else word
        parts += [why, f"{self._counts()} in {_duration(self.elapsed)}", self.postfix]
        return f"{head}: " + " · ".join(p for p in parts if p)

    def text(self):
        """text/plain of the output: the status line, then the log lines (indented)."""
        lines = [self.status_line()]
        if self._dropped:
            lines.append(f"    ({self._dropped} earlier log lines not kept)")
        lines += [f"    {text}" for text, _ in self._log]
        return "\n".join(lines)

    def html(self):
        """text/html of the output: the coloured status line and the collapsed log."""
        colour = _COLOURS[self.state]
        line = html.escape(self.status_line())
        return (f"<div class='piezolib-progress piezolib-progress-{self.state}' "
                f"style='font-family:var(--jp-code-font-family,monospace);font-size:12px;"
                f"line-height:1.5;border-left:3px solid {colour};padding-left:6px'>"
                f"<span style='color:{colour}'>{line}</span>"
                f"{_log_html(self._log, self._dropped, self._warnings, 'log')}</div>")


# --------------------------------------------------------------------------- logs
class _LogBlock:
    """Log lines of one request (cell) drawn while no bar runs (and none was made since the
    first of them): a small grey block."""

    def __init__(self, request):
        self.request, self.lines = request, []
        self._slot = _new_slot()

    def add(self, text, level):
        self.lines = (self.lines + [(str(text), int(level))])[-_MAX_LOG_LINES:]
        body = "\n".join(_line_html(t, lv) for t, lv in self.lines)
        self._slot.show(f"<pre class='piezolib-log' style='margin:0;color:#555;font-size:11px;"
                        f"background:transparent'>{body}</pre>",
                        "\n".join(t for t, _ in self.lines))


class CellLogHandler(logging.Handler):
    """Shows log records in the notebook: under the running bar, or in a block of the cell.

    Records of WARNING and above are prefixed with their level.  Outside
    a kernel (no cell) a record goes where it would go without this
    handler: to the other handlers of the logger and its parents, or if
    there are none, to :data:`logging.lastResort` (stderr).
    """

    def __init__(self, level=logging.NOTSET):
        super().__init__(level)
        self.setFormatter(logging.Formatter("%(message)s"))
        self._block = None

    def format(self, record):
        text = super().format(record)
        return text if record.levelno < logging.WARNING else f"{record.levelname}: {text}"

    def emit(self, record):
        try:
            if not (in_kernel() or redirected()):
                if not self._others_handle(record) and record.levelno >= logging.lastResort.level:
                    logging.lastResort.handle(record)
                return
            text = self.format(record)
            if _ACTIVE:
                _ACTIVE[-1].log(text, record.levelno)
                return
            # one block per cell and stretch between bars, so lines stay in order with them
            key = (_request_id(), id(_SINK.get()), _BARS_MADE[0])
            if self._block is None or self._block.request != key:
                self._block = _LogBlock(key)
            self._block.add(text, record.levelno)
        except Exception:           # noqa: BLE001 -- logging must never break the computation
            self.handleError(record)

    def _others_handle(self, record):
        """Whether a handler other than this one receives ``record`` (the logging chain)."""
        logger = logging.getLogger(record.name)
        while logger is not None:
            if any(h is not self for h in logger.handlers):
                return True
            logger = logger.parent if logger.propagate else None
        return False


def route_logs(name="piezolib"):
    """Show the records of logger ``name`` in the notebook's cells (idempotent).

    Attaches one :class:`CellLogHandler` to the logger.  The logger's level
    still decides what is shown (``logging.getLogger("piezolib").setLevel
    (logging.INFO)`` shows the solvers' per-iteration lines); records still
    propagate to the root logger's handlers, if any were configured.

    Parameters
    ----------
    name : str
        Logger name (default ``"piezolib"``: every module of the library).

    Returns
    -------
    CellLogHandler
        The handler attached (the existing one on a repeated call).
    """
    if not isinstance(name, str):
        raise TypeError(f"name must be a logger name (str), got {name!r}")
    logger = logging.getLogger(name)
    for handler in logger.handlers:
        if isinstance(handler, CellLogHandler):
            return handler
    handler = CellLogHandler()
    logger.addHandler(handler)
    return handler
