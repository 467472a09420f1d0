"""piezolib.progress: the one progress-bar mechanism (tqdm), switched by PIEZOLIB_PROGRESS."""

import io
import sys
import types

import numpy as np
import pytest

from piezolib.progress import ENV_VARIABLE, postfix, progress, progress_enabled, write


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


def test_no_widget_bar_in_a_headless_kernel(monkeypatch):
    """nbclient / nbval kernels (PIEZOLIB_STATIC=1) get no bar unless asked explicitly."""
    monkeypatch.delenv(ENV_VARIABLE, raising=False)
    monkeypatch.setenv("PIEZOLIB_STATIC", "1")
    fake_ipython = types.ModuleType("IPython")
    fake_ipython.get_ipython = lambda: types.SimpleNamespace(kernel=object())
    monkeypatch.setitem(sys.modules, "IPython", fake_ipython)
    tty = Terminal()
    bar = progress(range(3), desc="kernel", file=tty)
    assert bar.disable and list(bar) == [0, 1, 2] and tty.getvalue() == ""
    monkeypatch.setenv(ENV_VARIABLE, "1")                 # explicit: shown all the same
    assert not progress(range(3), file=tty).disable
    monkeypatch.delenv(ENV_VARIABLE)
    monkeypatch.setenv("PIEZOLIB_STATIC", "0")            # an interactive kernel
    assert not progress(range(3), file=tty).disable
    monkeypatch.setenv("PIEZOLIB_STATIC", "1")
    fake_ipython.get_ipython = lambda: None               # a plain script: terminal rules
    assert not progress(range(3), file=tty).disable


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
