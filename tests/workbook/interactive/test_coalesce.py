"""Coalescing slider values: only the latest is drawn, by one worker, and stale frames are
dropped rather than queued (no browser: a fake slow draw)."""

import threading
import time

import pytest

from piezolib.workbook.interactive import LatestOnly


class SlowDraw:
    """A draw that takes ``seconds`` and records what it drew, and from which thread."""

    def __init__(self, seconds):
        self.seconds, self.drawn, self.threads = seconds, [], set()
        self.started = threading.Event()

    def __call__(self, value, superseded):
        self.started.set()
        self.threads.add(threading.get_ident())
        time.sleep(self.seconds)
        self.drawn.append(value)


def test_twenty_rapid_values_cost_at_most_two_draws_the_last_drawn_last():
    draw = SlowDraw(0.3)
    latest = LatestOnly(draw, settle_s=0.0)
    for value in range(20):
        latest.submit(value)
        time.sleep(0.001)                  # key presses a millisecond apart
    assert latest.wait(5.0)
    assert len(draw.drawn) <= 2 and draw.drawn[-1] == 19
    assert latest.runs == len(draw.drawn)


def test_values_sent_during_a_draw_are_coalesced_into_one():
    draw = SlowDraw(0.1)
    latest = LatestOnly(draw, settle_s=0.0)
    latest.submit("first")
    assert draw.started.wait(2.0)          # the first draw is under way
    for value in range(20):
        latest.submit(value)
    assert latest.busy
    assert latest.wait(5.0) and not latest.busy
    assert draw.drawn == ["first", 19]
    assert draw.threads.isdisjoint({threading.get_ident()})   # never on the caller's thread


def test_submit_returns_before_the_draw_ends():
    draw = SlowDraw(0.3)
    latest = LatestOnly(draw)
    start = time.monotonic()
    latest.submit(1)
    assert time.monotonic() - start < 0.2 and draw.drawn == []
    assert latest.wait(5.0) and draw.drawn == [1]


def test_settling_turns_a_burst_into_one_draw():
    draw = SlowDraw(0.01)
    latest = LatestOnly(draw, settle_s=0.05)
    for value in range(20):
        latest.submit(value)
    assert latest.wait(5.0) and draw.drawn == [19]


def test_a_held_key_still_shows_frames():
    """Values 10 ms apart for 0.4 s never settle for 50 ms; max_wait_s still starts runs."""
    draw = SlowDraw(0.0)
    latest = LatestOnly(draw, settle_s=0.05, max_wait_s=0.1)
    for value in range(40):
        latest.submit(value)
        time.sleep(0.01)
    assert latest.wait(5.0)
    assert len(draw.drawn) >= 2 and draw.drawn[-1] == 39


def test_a_stage_can_see_it_is_superseded():
    seen = []

    def work(value, superseded):
        seen.append((value, superseded()))
        if value == "first":
            latest.submit("second")
            seen.append(("after", superseded()))

    latest = LatestOnly(work, settle_s=0.0)
    latest.submit("first")
    assert latest.wait(5.0)
    assert seen == [("first", False), ("after", True), ("second", False)]


def test_a_stage_can_wait_for_a_newer_value():
    seen = []

    def work(value, superseded):
        if value == "first":
            threading.Timer(0.05, latest.submit, ["second"]).start()
            seen.append(superseded(within=2.0))
        else:
            seen.append(superseded(within=0.05))

    latest = LatestOnly(work, settle_s=0.0)
    latest.submit("first")
    assert latest.wait(5.0)
    assert seen == [True, False]           # "second" came within 2 s; nothing after it


def test_then_runs_after_the_frame_it_waits_for_not_before():
    events = []
    draw_started = threading.Event()
    release = threading.Event()

    def work(value, superseded):
        draw_started.set()
        release.wait(2.0)
        events.append(f"drew {value}")

    latest = LatestOnly(work, settle_s=0.0)
    latest.submit("old")
    assert draw_started.wait(2.0)
    latest.submit("new", then=lambda: events.append("done"))
    release.set()
    assert latest.wait(5.0)
    assert events == ["drew old", "drew new", "done"]


def test_then_of_a_superseded_run_waits_for_the_next():
    events = []

    def work(value, superseded):
        events.append(f"drew {value}")
        if value == 1:
            latest.submit(2)               # a newer value arrives while 1 is drawn

    latest = LatestOnly(work, settle_s=0.0)
    latest.submit(1, then=lambda: events.append("done"))
    assert latest.wait(5.0)
    assert events == ["drew 1", "drew 2", "done"]


def test_a_failing_run_does_not_stop_the_worker():
    drawn = []

    def work(value, superseded):
        if value == "bad":
            raise RuntimeError("boom")
        drawn.append(value)

    latest = LatestOnly(work, settle_s=0.0)
    latest.submit("bad")
    assert latest.wait(5.0)
    assert isinstance(latest.error, RuntimeError)
    latest.submit("good")
    assert latest.wait(5.0) and drawn == ["good"]


def test_wait_times_out_while_busy():
    release = threading.Event()
    latest = LatestOnly(lambda value, superseded: release.wait(2.0), settle_s=0.0)
    latest.submit(1)
    assert latest.wait(0.05) is False
    release.set()
    assert latest.wait(5.0) is True


def test_arguments_are_checked():
    with pytest.raises(TypeError, match="work"):
        LatestOnly("draw")
    with pytest.raises(ValueError, match="settle_s"):
        LatestOnly(print, settle_s=-1)
    with pytest.raises(TypeError, match="then"):
        LatestOnly(print).submit(1, then="done")
