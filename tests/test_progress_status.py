"""progress.StatusLine: a status line kept current on a terminal, printed when quiet elsewhere."""

import io

import pytest

from piezolib import progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_on_a_terminal_the_status_is_redrawn_below_the_written_lines():
    stream = Terminal()
    count = iter(range(100))
    with progress.StatusLine(lambda: f"status {next(count)}", file=stream,
                             refresh_s=1e6) as line:            # no timer tick in the test
        line.write("first")
        line.refresh()
    text = stream.getvalue()
    assert text == "first\n\rstatus 0\x1b[K\r\x1b[K\rstatus 1\x1b[K\r\x1b[K"


def test_elsewhere_the_status_is_a_line_of_its_own_when_nothing_was_printed_for_a_while():
    stream = io.StringIO()
    with progress.StatusLine(lambda: "3 done", file=stream, refresh_s=1e6,
                             every_s=1e-9) as line:
        line.write("[1/3] point")
        line.refresh()                                  # quiet for longer than every_s
    # the status follows as a line of its own; every_s is all but zero here, so the line's
    # own thread may also print it before the write or once more after it
    lines = stream.getvalue().splitlines()
    assert lines.count("[1/3] point") == 1 and set(lines) == {"[1/3] point", "3 done"}
    assert lines[lines.index("[1/3] point") + 1:], "no status after the written line"
    quiet = io.StringIO()
    with progress.StatusLine(lambda: "3 done", file=quiet, every_s=1e6) as line:
        line.write("[1/3] point")
        line.refresh()                                  # something was printed just now
    assert quiet.getvalue() == "[1/3] point\n"


def test_switched_off_the_status_is_never_shown(monkeypatch):
    monkeypatch.setenv(progress.ENV_VARIABLE, "0")
    stream = Terminal()
    with progress.StatusLine(lambda: "status", file=stream) as line:
        line.write("kept")
        line.refresh()
    assert stream.getvalue() == "kept\n"


@pytest.mark.parametrize("options, said", [
    ({"status": "text"}, "status must be a callable"),
    ({"status": str, "refresh_s": 0}, "refresh_s"),
    ({"status": str, "every_s": float("nan")}, "every_s"),
])
def test_bad_arguments_are_named(options, said):
    with pytest.raises((TypeError, ValueError), match=said):
        progress.StatusLine(**options)
