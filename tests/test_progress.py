"""piezolib.progress: the one progress-bar mechanism (text bar or cell output), switched by
PIEZOLIB_PROGRESS."""

import io

import numpy as np
import pytest

from piezolib import notebook_display
from piezolib.notebook_display import CellBar
from piezolib.progress import (ENV_VARIABLE, finish, postfix, progress, progress_enabled,
                               shown_in, write)


class Terminal(io.StringIO):
    """A text stream that says it is a terminal (where auto mode shows bars)."""

    def isatty(self):
        return True


@pytest.mark.parametrize("value, expected", [
    (None, None), ("auto", None), ("", None), ("0", False), ("off", False), ("No", False),
    ("1", True), ("on", True), (" TRUE ", True),
])
def test_environment_switch(monkeypatch, value, expected):
    if value is None:
        monkeypatch.delenv(ENV_VARIABLE, raising=False)
    else:
        monkeypatch.setenv(ENV_VARIABLE, value)
    assert progress_enabled() is expected


def test_bad_environment_value_is_named(monkeypatch):
    monkeypatch.setenv(ENV_VARIABLE, "maybe")
    with pytest.raises(ValueError, match="PIEZOLIB_PROGRESS.*'maybe'"):
        progress_enabled()
    with pytest.raises(ValueError, match="PIEZOLIB_PROGRESS"):
        progress(range(3))


def test_disabled_by_environment_writes_nothing(monkeypatch, capsys):
    monkeypatch.setenv(ENV_VARIABLE, "0")
    tty = Terminal()
    items = list(progress(range(5), desc="quiet", file=tty))
    with progress(total=4, desc="quiet") as bar:        # default stream: stderr
        for _ in range(4):
            postfix(bar, mu=0.5)
            bar.update()
    write("a line", file=io.StringIO())
    assert items == [0, 1, 2, 3, 4]                     # still iterates
    assert tty.getvalue() == ""
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_enabled_counts_the_steps_and_writes_the_label(monkeypatch):
    monkeypatch.setenv(ENV_VARIABLE, "1")
    stream = io.StringIO()                              # not a terminal: 1 forces the bar
    bar = progress(range(7), desc="sweep", unit="point", file=stream)
    assert list(bar) == list(range(7))
    assert bar.n == 7 and bar.total == 7
    text = stream.getvalue()                            # drawn at the start, cleared at the end
    assert "sweep" in text and "0/7" in text and "point" in text
    assert text.endswith("\r")                          # leave=False: the line is wiped
    with progress(total=3, desc="manual", file=stream) as manual:
        manual.update()
        manual.update(2)
        assert manual.n == 3
    assert manual.leave is False                        # transient: cleared when closed


def test_auto_mode_shows_bars_on_terminals_only(monkeypatch):
    monkeypatch.delenv(ENV_VARIABLE, raising=False)
    tty, log = Terminal(), io.StringIO()
    on = progress(range(2), desc="tty", file=tty)
    off = progress(range(2), desc="log", file=log)
    assert not on.disable and off.disable               # (a closed bar counts as disabled)
    assert list(on) == list(off) == [0, 1]
    assert on.n == 2 and "tty" in tty.getvalue()
    assert log.getvalue() == ""


@pytest.fixture
def kernel_cell(monkeypatch):
    """A kernel whose cell outputs are recorded: [(bundle, display_id or None)] per call."""
    from IPython import display as ipython_display

    shown = []

    class Handle:
        def update(self, bundle, raw=False):
            shown.append(("update", bundle))

    def display(bundle, raw=False, display_id=False):
        shown.append(("display", bundle))
        return Handle() if display_id else None

    monkeypatch.setattr(notebook_display, "in_kernel", lambda: True)
    monkeypatch.setattr(ipython_display, "display", display)
    monkeypatch.delenv(ENV_VARIABLE, raising=False)
    return shown


def test_a_kernel_gets_a_cell_output_that_ends_done_with_the_reason(kernel_cell):
    """Stopped after 5 of at most 8 steps: the final output reads as success, says why."""
    with progress(total=8, desc="musyn DK", unit="iter") as bar:
        assert isinstance(bar, CellBar)
        for _ in range(5):
            bar.update()
            postfix(bar, mu=0.80031)
        finish(bar, "no improvement > 0.005 in 2 iterations")
    kinds = [kind for kind, _ in kernel_cell]
    assert kinds[0] == "display" and set(kinds[1:]) == {"update"}    # one output, redrawn
    final = kernel_cell[-1][1]
    assert set(final) == {"text/html", "text/plain"}
    text, html_text = final["text/plain"], final["text/html"]
    assert text.startswith("✔ musyn DK: done: no improvement > 0.005 in 2 iterations")
    assert "5 of at most 8 iter" in text and "mu 0.8003" in text
    assert "piezolib-progress-done" in html_text
    assert "failed" not in html_text and "danger" not in html_text and "5/8" not in text


def test_a_kernel_bar_fails_only_when_an_exception_leaves_it(kernel_cell):
    with pytest.raises(RuntimeError):
        with progress(total=3, desc="search") as bar:
            bar.update()
            raise RuntimeError("K-step diverged")
    final = kernel_cell[-1][1]
    assert "piezolib-progress-failed" in final["text/html"]
    assert final["text/plain"].startswith("✘ search: FAILED: RuntimeError: K-step diverged")


def test_in_a_kernel_the_switch_and_an_explicit_stream_still_rule(kernel_cell, monkeypatch):
    tty = Terminal()
    assert not isinstance(progress(range(2), file=tty), CellBar)     # the stream asked for
    monkeypatch.setenv(ENV_VARIABLE, "0")
    bar = progress(range(3), desc="off")
    assert not isinstance(bar, CellBar) and bar.disable and list(bar) == [0, 1, 2]
    assert kernel_cell == []


def test_shown_in_draws_bars_through_the_callback_outside_a_kernel(monkeypatch):
    monkeypatch.delenv(ENV_VARIABLE, raising=False)
    drawn = []
    with shown_in(lambda html_text, text: drawn.append(text)):
        with progress(total=4, desc="re-design", unit="iter") as bar:
            bar.update(2)
            finish(bar, "max_iter reached")
    assert isinstance(bar, CellBar)
    assert drawn[-1].startswith("✔ re-design: done: max_iter reached")
    assert not isinstance(progress(range(2)), CellBar)               # after the block: text


def test_finish_completes_a_text_bar(monkeypatch):
    monkeypatch.setenv(ENV_VARIABLE, "1")
    kept = io.StringIO()
    with progress(total=8, desc="search", unit="iter", leave=True, file=kept) as bar:
        bar.update(5)
        finish(bar, "converged")
    last = kept.getvalue().rstrip("\n").split("\r")[-1]
    assert "100%" in last and "5/5" in last and "converged" in last     # not a stale 5/8
    gone = io.StringIO()
    with progress(total=8, desc="search", file=gone) as bar:
        bar.update(5)
        finish(bar, "converged")
    assert gone.getvalue().endswith("\r") and gone.getvalue().split("\r")[-2].strip() == ""
    with pytest.raises(TypeError, match="reason"):
        finish(bar, "")
    monkeypatch.setenv(ENV_VARIABLE, "0")
    off = progress(total=3)
    finish(off, "converged")                         # a disabled bar ignores it
    assert off.total == 3


def test_postfix_formats_values_with_four_digits(monkeypatch):
    monkeypatch.setenv(ENV_VARIABLE, "1")
    stream = io.StringIO()
    with progress(total=2, file=stream) as bar:
        postfix(bar, mu=0.940238840, gamma=np.float64(1.86783), grid=300)
        assert bar.postfix == "mu 0.9402, gamma 1.868, grid 300"
        postfix(bar, "start 2/3", refresh=True)
        assert bar.postfix == "start 2/3"
        assert "start 2/3" in stream.getvalue()           # refresh draws it at once
        postfix(bar, "polish", rms=0.5)
        assert bar.postfix == "polish, rms 0.5"


def test_write_keeps_lines_whole_beside_a_bar(monkeypatch):
    monkeypatch.setenv(ENV_VARIABLE, "1")
    stream = io.StringIO()
    with progress(total=2, desc="steps", file=stream) as bar:
        bar.update()
        write("[1/2] first step  0.1 s", file=stream)
        bar.update()
    lines = stream.getvalue().replace("\r", "\n").split("\n")
    assert "[1/2] first step  0.1 s" in lines               # on a line of its own
    other = io.StringIO()
    write("plain", file=other)
    assert other.getvalue() == "plain\n"


@pytest.mark.parametrize("total, exc", [(-1, ValueError), (2.5, TypeError), (True, TypeError)])
def test_bad_total_is_named(total, exc):
    with pytest.raises(exc, match="total"):
        progress(total=total)


def test_bad_unit_is_named():
    with pytest.raises(TypeError, match="unit"):
        progress(range(2), unit="")
