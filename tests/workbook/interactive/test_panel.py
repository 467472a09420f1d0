"""The controls' plumbing: widget or static figure, and the static figure shown as a PNG."""

import sys
import types

import pytest
from matplotlib.figure import Figure

from piezolib.workbook.interactive import _panel


@pytest.fixture
def fake_kernel(monkeypatch):
    """IPython's shell has a kernel, as inside Jupyter."""
    ipython = pytest.importorskip("IPython")
    monkeypatch.setattr(ipython, "get_ipython", lambda: types.SimpleNamespace(kernel=object()))
    monkeypatch.delenv(_panel.STATIC_ENV, raising=False)


def test_no_frontend_outside_a_kernel(monkeypatch):
    monkeypatch.delenv(_panel.STATIC_ENV, raising=False)
    ipython = pytest.importorskip("IPython")
    assert ipython.get_ipython() is None            # pytest runs no IPython shell
    assert _panel.interactive_available() is False
    monkeypatch.delitem(sys.modules, "IPython")
    assert _panel.interactive_available() is False


def test_kernel_is_interactive_unless_static_is_set(fake_kernel, monkeypatch):
    pytest.importorskip("ipywidgets")
    assert _panel.interactive_available() is True
    for value in ("1", "true", "YES", "on"):
        monkeypatch.setenv(_panel.STATIC_ENV, value)
        assert _panel.interactive_available() is False, value
    for value in ("0", "false", "", "off"):
        monkeypatch.setenv(_panel.STATIC_ENV, value)
        assert _panel.interactive_available() is True, value


def test_kernel_without_ipywidgets_is_static(fake_kernel, monkeypatch):
    monkeypatch.setattr(_panel.importlib.util, "find_spec",
                        lambda name: None if name == "ipywidgets" else object())
    assert _panel.interactive_available() is False


def test_interactive_argument_is_checked(monkeypatch):
    monkeypatch.setenv(_panel.STATIC_ENV, "1")
    assert _panel.want_widget(None) is False                  # interactive_available decides
    assert _panel.want_widget(True) is True and _panel.want_widget(False) is False
    with pytest.raises(TypeError, match="interactive"):
        _panel.want_widget("yes")


def test_missing_ipywidgets_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)      # import fails
    with pytest.raises(ImportError, match="ipywidgets"):
        _panel.import_ipywidgets()


def test_static_figure_shows_as_png_in_ipython(monkeypatch):
    """Without a resolved pyplot backend (MPLBACKEND=Agg) IPython would show '<Figure ...>'."""
    ipython = pytest.importorskip("IPython")
    from IPython.core.formatters import PNGFormatter
    png = PNGFormatter()
    shell = types.SimpleNamespace(
        display_formatter=types.SimpleNamespace(formatters={"image/png": png}))
    monkeypatch.setattr(ipython, "get_ipython", lambda: shell)
    fig, (ax,) = _panel.panel_figure(None, 1, (3.0, 2.0))
    ax.plot([0, 1], [0, 1])
    assert _panel.static_figure(fig) is fig
    assert png(fig).startswith(b"\x89PNG")
    # a formatter already there (the inline backend's) is kept
    mine = png.lookup_by_type(Figure)
    png.for_type(Figure, lambda f: b"\x89PNG inline")
    _panel.static_figure(fig)
    assert png(fig) == b"\x89PNG inline" and png.lookup_by_type(Figure) is not mine
