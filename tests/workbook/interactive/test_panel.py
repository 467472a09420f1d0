"""The controls' plumbing: widget or static figure, and the static figure shown as a PNG."""

import base64
import sys
import time
import types

import pytest
from matplotlib.figure import Figure

from piezolib.workbook.interactive import _panel


@pytest.fixture
def request_metadata(monkeypatch):
    """IPython's shell has a kernel; the metadata of the request it runs (JupyterLab's: cellId)."""
    ipython = pytest.importorskip("IPython")
    metadata = {"cellId": "0f3c"}
    kernel = types.SimpleNamespace(get_parent=lambda channel: {"metadata": metadata})
    monkeypatch.setattr(ipython, "get_ipython", lambda: types.SimpleNamespace(kernel=kernel))
    monkeypatch.delenv(_panel.STATIC_ENV, raising=False)
    return metadata


@pytest.fixture
def fake_kernel(request_metadata):
    """A kernel with JupyterLab attached, as when a person runs the cell."""


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


def test_a_headless_client_gets_the_static_figure_without_a_setting(request_metadata):
    """nbclient, papermill, nbconvert --execute and nbval name no cell in their requests."""
    pytest.importorskip("ipywidgets")
    request_metadata.clear()
    assert _panel.interactive_available() is False
    request_metadata["cellId"] = "7a"
    assert _panel.interactive_available() is True


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


def test_a_panel_box_is_saved_with_its_figure_as_png(monkeypatch):
    """Where the widget cannot be drawn (no state saved, nbconvert's HTML) the figure shows."""
    widgets = pytest.importorskip("ipywidgets")
    sliders = {"a": _panel.linear_slider(widgets, "a", 1.0, 0.0, 2.0, 0.1)}

    def draw(view, fig=None):
        fig, (ax,) = _panel.panel_figure(fig, 1, (3.0, 2.0))
        ax.plot([0, 1], [0, view])
        return fig

    panel = _panel.LivePanel(widgets, sliders, lambda values: values["a"], _panel.redrawn(draw),
                             lambda view: f"a = {view:.2f} & more")
    box = _panel.finish(panel, panel.box())
    assert isinstance(box, widgets.VBox) and box.panel is panel
    bundle = box._repr_mimebundle_()
    assert set(bundle) == {_panel.WIDGET_VIEW_MIME, "image/png", "text/plain"}
    assert base64.b64decode(bundle["image/png"]) == panel.image.value     # the figure shown
    assert bundle["text/plain"] == ("interactive control (figure for the values shown): "
                                    "a = 1.00 & more")
    assert "VBox(" not in bundle["text/plain"]
    first = panel.image.value
    sliders["a"].value = 2.0                                      # the saved figure follows
    assert panel.wait(10) and panel.image.value != first
    assert base64.b64decode(box._repr_mimebundle_()["image/png"]) == panel.image.value


def _counting_panel(widgets, seconds):
    """A panel whose callback takes ``seconds`` and records the values it was called with."""
    sliders = {"a": _panel.linear_slider(widgets, "a", 1.0, 0.0, 3.0, 0.1)}
    computed = []

    def compute(values):
        computed.append(values["a"])
        time.sleep(seconds)
        return values["a"]

    def draw(view, fig=None):
        fig, (ax,) = _panel.panel_figure(fig, 1, (2.0, 1.5))
        ax.plot([0, 1], [0, view])
        return fig

    panel = _panel.LivePanel(widgets, sliders, compute, _panel.redrawn(draw), str)
    box = _panel.finish(panel, panel.box())
    computed.clear()
    return box, sliders["a"], computed


def test_twenty_key_presses_draw_the_last_value_not_every_one(widgets):
    """A slider moved by 20 key presses while each frame takes 0.1 s: the presses return at
    once, at most two frames are drawn and the last one shows the last value."""
    box, slider, computed = _counting_panel(widgets, 0.1)
    frames = box.panel.frames
    start = time.monotonic()
    for _ in range(20):
        slider.value = round(slider.value + 0.1, 1)
    assert time.monotonic() - start < 1.0                 # 20 synchronous frames take 2 s
    assert box.panel.wait(10)
    assert len(computed) <= 2 and computed[-1] == pytest.approx(3.0)
    assert box.panel.frames - frames == len(computed)
    assert box.panel.view == pytest.approx(3.0) and box.panel.summary.value == "3.0"


def test_a_frame_blitted_over_the_background_is_the_full_figure(widgets):
    """The moving artists are painted over a picture of the rest: no stale curve remains."""
    import io

    import matplotlib
    import numpy as np
    from PIL import Image

    class Plot:
        def __init__(self, view, fig):
            self.figure, (ax,) = _panel.panel_figure(fig, 1, (3.0, 2.0))
            (self.line,) = ax.plot([0, 1], [0, view], lw=3)
            ax.set_ylim(-3, 3)
            self.moving = [self.line, ax.title]

        def show(self, view):
            self.line.set_ydata([0, view])
            self.line.axes.set_title(f"a = {view:.1f}")
            return True

    sliders = {"a": _panel.linear_slider(widgets, "a", 1.0, -2.0, 2.0, 0.1)}
    panel = _panel.LivePanel(widgets, sliders, lambda values: values["a"], Plot, str)
    _panel.finish(panel, panel.box())
    sliders["a"].value = -2.0
    assert panel.wait(10) and panel.frames == 2
    blitted = np.asarray(Image.open(io.BytesIO(panel.image.value)).convert("RGB"), dtype=int)
    # the frames are the whole canvas; png_bytes follows savefig.bbox, which the workbook's
    # style (set by another test in this process) makes "tight"
    with matplotlib.rc_context({"savefig.bbox": None}):
        full = np.asarray(Image.open(io.BytesIO(_panel.png_bytes(panel.figure))).convert("RGB"),
                          dtype=int)
    assert blitted.shape == full.shape
    # the line is drawn after the frame of the axes here, before it in a full draw
    assert np.mean(np.abs(blitted - full).max(axis=2) > 40) < 0.005


class _LinePlot:
    """A small plot of one line whose end follows the view (a float, or (stage, float))."""

    def __init__(self, view, fig):
        self.figure, (ax,) = _panel.panel_figure(fig, 1, (1.0, 1.0))
        (self.line,) = ax.plot([0, 1], [0, 0])
        self.moving = [self.line]
        self.show(view)

    def show(self, view):
        self.line.set_ydata([0, view[-1] if isinstance(view, tuple) else view])
        return True


def test_the_slow_stage_waits_until_the_slider_rests(widgets):
    """Values 0.12 s apart: the quick view follows them, the slow one is computed once."""
    sliders = {"a": _panel.linear_slider(widgets, "a", 1.0, 0.0, 3.0, 0.1)}
    slow = []

    def complete(view):
        slow.append(view[1])
        time.sleep(0.05)
        return ("complete", view[1])

    def compute(values):
        return [lambda _: ("quick", values["a"]), complete]

    panel = _panel.LivePanel(widgets, sliders, compute, _LinePlot, str)
    _panel.finish(panel, panel.box())
    slow.clear()
    for _ in range(4):
        sliders["a"].value = round(sliders["a"].value + 0.1, 1)
        time.sleep(0.12)
    assert panel.wait(10)
    assert slow == [pytest.approx(1.4)] and panel.view == ("complete", pytest.approx(1.4))
