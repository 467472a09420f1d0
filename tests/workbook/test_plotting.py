"""The workbook's figure style and figure naming."""

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib.workbook import plotting


def test_figure_names(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1])
    assert plotting.save_figure(fig, 10, "step_responses").name == "fig10_step_responses.png"
    assert plotting.save_figure(fig, None, "extra_view").name == "extra_extra_view.png"
    assert (tmp_path / "figures" / "fig10_step_responses.png").is_file()
    plt.close(fig)
    with pytest.raises(ValueError, match="what"):
        plotting.figure_path(4, "Bad Name")
    with pytest.raises(ValueError, match="number"):
        plotting.figure_path(0, "ok")
    with pytest.raises(TypeError, match="Figure"):
        plotting.save_figure("figure", 1, "ok")


def test_style_and_helpers():
    fig, ax = plotting.new_figure()
    assert mpl.rcParams["savefig.dpi"] == plotting.STYLE["savefig.dpi"]
    assert plotting.db(10.0) == pytest.approx(20.0)
    line = plotting.plot_magnitude(ax, np.array([1.0, 10.0]), np.array([1.0, 0.1]), label="x")
    np.testing.assert_allclose(line.get_ydata(), [0.0, -20.0])
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "frequency [rad/s]"
    plt.close(fig)


def test_block_diagram_draws_boxes_junctions_and_wires():
    fig, ax = plotting.new_figure()
    plotting.block_diagram(ax, {"a": (0.0, 0.0, "A"), "s": (2.0, 0.0, "o")},
                           [("a", "s", "x [V]"), ((-1.0, 0.0), "a", "")], title="t")
    assert ax.get_title() == "t"
    assert len(ax.patches) == 2 and any(t.get_text() == "x [V]" for t in ax.texts)
    plt.close(fig)
