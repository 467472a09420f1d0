"""Progress bars for the long computations: one mechanism for the whole library (tqdm).

:func:`progress` returns a :class:`tqdm.auto.tqdm` bar: a widget in a
Jupyter notebook, a text bar on a terminal (written to stderr).  Bars are
transient (``leave=False``): they disappear when the loop ends, so saved
notebooks and logs keep only the results and the INFO logging lines the
solvers write anyway.  The bar is extra information; nothing a solver
returns depends on it.

The environment variable ``PIEZOLIB_PROGRESS`` switches the bars:

====================  =====================================================
``0`` (off, no, ...)  no bar anywhere (nothing is written)
``1`` (on, yes, ...)  a bar even when stderr is not a terminal (logs, CI)
unset or ``auto``     a bar in a notebook or on a terminal, none when stderr
                      is redirected to a file or captured, and none in a
                      notebook kernel run headless (``PIEZOLIB_STATIC=1``)
====================  =====================================================

A kernel run by nbclient, nbval or ``python -m piezolib reproduce`` has no
frontend to draw a widget: the bar would only leave a dead output in the
saved notebook.  Those runners set ``PIEZOLIB_STATIC=1`` (the switch the
workbook's interactive controls read for the same reason), and in a kernel
auto mode takes it as "no bars".

:func:`postfix` sets the short status text after the bar (e.g. the current
mu peak) and :func:`write` prints a line without tearing an active bar
(for per-step report lines of a runner).  On a terminal, INFO logging lines
and a bar share stderr; wrap the call in
``tqdm.contrib.logging.logging_redirect_tqdm()`` to route the log lines
around the bar.

tqdm is imported on first use, so importing a module that uses this one
stays cheap.
"""

import os
import sys

import numpy as np

from piezolib._checks import check_integer

__all__ = ["ENV_VARIABLE", "progress", "progress_enabled", "postfix", "write"]

#: Environment variable that switches the bars on (1), off (0) or to auto.
ENV_VARIABLE = "PIEZOLIB_PROGRESS"
#: Set (true) by the headless notebook runners: no widget frontend exists.
_HEADLESS_VARIABLE = "PIEZOLIB_STATIC"

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


def _headless_kernel():
    """True in an IPython kernel that a headless runner started (``PIEZOLIB_STATIC`` true)."""
    if os.environ.get(_HEADLESS_VARIABLE, "").strip().lower() in ("",) + _OFF:
        return False
    # a kernel's shell has a .kernel; merely importing ipykernel (pytest plugins do) is not one
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if hasattr(ipython, "get_ipython") else None
    return getattr(shell, "kernel", None) is not None


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
        Expected number of steps (an upper bound is fine: the bar vanishes
        when closed); None shows a counter without a percentage.
    desc : str, optional
        Label in front of the bar.
    unit : str
        Name of one step.
    leave : bool
        Keep the finished bar on screen (default False: it disappears).
    file : file-like, optional
        Stream of a text bar; default ``sys.stderr`` (a notebook shows a
        widget instead).

    Returns
    -------
    tqdm.auto.tqdm
        The bar; ``bar.n`` counts the steps done.  A disabled bar writes
        nothing and still iterates.

    Raises
    ------
    ValueError, TypeError
        ``total`` not a non-negative integer, or a bad ``PIEZOLIB_PROGRESS``.
    """
    from tqdm.auto import tqdm

    if total is not None:
        total = check_integer("total", total, minimum=0)
    if not isinstance(unit, str) or not unit:
        raise TypeError(f"unit must be a non-empty string, got {unit!r}")
    enabled = progress_enabled()
    if enabled is None and _headless_kernel():
        enabled = False
    # disable=None is tqdm's "off unless the stream is a terminal" (a notebook bar is shown)
    return tqdm(iterable, total=total, desc=desc, unit=unit, leave=bool(leave),
                file=sys.stderr if file is None else file,
                disable=None if enabled is None else not enabled, dynamic_ncols=True)


def postfix(bar, text=None, *, refresh=False, **values):
    """Set the status text after ``bar``: ``text`` and/or ``name value`` pairs.

    Floats are shown with 4 significant digits (``mu 0.9402``), which tqdm's
    own ``set_postfix`` (3 digits) does not give.

    Parameters
    ----------
    bar : tqdm.tqdm
        A bar from :func:`progress` (disabled bars ignore the call).
    text : str, optional
        Free text put first.
    refresh : bool
        Redraw now (for a status shown during a long step); default False:
        the text appears with the next ``bar.update()``.
    **values
        Named values, in the order given.
    """
    parts = [] if text is None else [str(text)]
    for name, value in values.items():
        shown = f"{value:.4g}" if isinstance(value, (float, np.floating)) else str(value)
        parts.append(f"{name} {shown}")
    bar.set_postfix_str(", ".join(parts), refresh=bool(refresh))


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
    """
    from tqdm.auto import tqdm

    stream = sys.stdout if file is None else file
    tqdm.write(str(line), file=stream)
    if hasattr(stream, "flush"):
        stream.flush()
