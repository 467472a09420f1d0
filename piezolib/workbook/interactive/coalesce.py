"""Work for the latest of a stream of values, one run at a time, off the kernel's thread.

A slider moved by the keyboard sends one value per key press.  Drawing every
value in turn, in the kernel's own thread, queues the frames: the figure
lags the hand by the sum of all the draws, and shows values the reader has
already left.  :class:`LatestOnly` keeps only the latest value: a submission
replaces the one still waiting, and a single worker thread runs the work for
the latest value whenever it is free, so the kernel keeps reading messages
(and the slider's newest value) while a frame is drawn.
"""

import threading
import time

from piezolib._checks import check_nonnegative

__all__ = ["LatestOnly"]

#: What ``_pending`` holds when no value waits.
_NOTHING = object()


class LatestOnly:
    """Run ``work(value, superseded)`` for the latest submitted value, in a worker thread.

    :meth:`submit` returns at once.  Values submitted while the worker is
    busy replace each other; when a run ends, the worker runs the latest one
    (if any) and then stops.  The worker waits for ``settle_s`` without a new
    value before it starts a run, but never longer than ``max_wait_s`` after
    the oldest waiting submission: a burst of key presses costs one run, a
    held key still shows frames.

    Parameters
    ----------
    work : callable
        Called as ``work(value, superseded)``; ``superseded()`` is True once a
        newer value waits, so a run in stages can stop early (its result
        would be stale); ``superseded(within=s)`` waits up to s seconds for one.
    settle_s : float, optional
        Quiet time [s] before a run starts (default 0.04 s).
    max_wait_s : float, optional
        Longest wait [s] of a submitted value before its run starts (default
        0.25 s).

    Attributes
    ----------
    runs : int
        Number of runs so far.
    error : Exception or None
        The exception of the latest run that raised (the worker carries on).

    Examples
    --------
    >>> drawn = []
    >>> latest = LatestOnly(lambda value, superseded: drawn.append(value))
    >>> for value in range(20):
    ...     latest.submit(value)
    >>> latest.wait(5.0), drawn
    (True, [19])
    """

    def __init__(self, work, *, settle_s=0.04, max_wait_s=0.25):
        if not callable(work):
            raise TypeError(f"work must be callable as work(value, superseded), got {work!r}")
        self.settle_s = check_nonnegative("settle_s", settle_s)
        self.max_wait_s = max(check_nonnegative("max_wait_s", max_wait_s), self.settle_s)
        self._work = work
        self._lock = threading.Condition()
        self._pending, self._callbacks = _NOTHING, []
        self._first_t = self._last_t = 0.0
        self._thread = None
        self.runs = 0
        self.error = None

    def submit(self, value, then=None):
        """Make ``value`` the one to run next (replacing any still waiting); return at once.

        Parameters
        ----------
        value : object
        then : callable, optional
            Called with no argument in the worker once a run for this value,
            or a later one, has finished without being superseded (e.g. to show
            a "done" line together with the figure it announces).
        """
        if then is not None and not callable(then):
            raise TypeError(f"then must be callable or None, got {then!r}")
        with self._lock:
            now = time.monotonic()
            if self._pending is _NOTHING:
                self._first_t = now
            self._pending, self._last_t = value, now
            if then is not None:
                self._callbacks.append(then)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, daemon=True,
                                                name="piezolib-live-panel")
                self._thread.start()
            self._lock.notify_all()

    def superseded(self, within=0.0):
        """True when a value waits that was submitted after the one running, or arrives
        ``within`` seconds (a run in stages waits so before its slow stage)."""
        deadline = time.monotonic() + within
        with self._lock:
            while self._pending is _NOTHING:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._lock.wait(left)
            return True

    @property
    def busy(self):
        """True while a value waits or a run is under way."""
        with self._lock:
            return self._thread is not None

    def wait(self, timeout=None):
        """Block until nothing waits or runs; True if so within ``timeout`` [s] (None: no limit)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._lock:
            while self._thread is not None:
                left = None if deadline is None else deadline - time.monotonic()
                if left is not None and left <= 0:
                    return False
                self._lock.wait(left)
            return True

    def _take(self):
        """The latest value and the callbacks waiting on it, once it has settled (lock held);
        ``_NOTHING`` when none waits (and the worker is then marked stopped)."""
        while self._pending is not _NOTHING:
            now = time.monotonic()
            start = min(self._last_t + self.settle_s, self._first_t + self.max_wait_s)
            if now >= start:
                value, callbacks = self._pending, self._callbacks
                self._pending, self._callbacks = _NOTHING, []
                return value, callbacks
            self._lock.wait(start - now)
        self._thread = None
        self._lock.notify_all()
        return _NOTHING, []

    def _run(self):
        while True:
            with self._lock:
                value, callbacks = self._take()
            if value is _NOTHING:
                return
            self.runs += 1
            try:
                self._work(value, self.superseded)
            except Exception as exc:        # noqa: BLE001 -- a dead worker would hang the panel
                self.error = exc
            with self._lock:
                if self._pending is not _NOTHING:
                    # stale: what the callbacks announce comes with the next run
                    self._callbacks[:0] = callbacks
                    continue
            for callback in callbacks:
                try:
                    callback()
                except Exception as exc:    # noqa: BLE001
                    self.error = exc
