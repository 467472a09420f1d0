"""Saving figures: names after the paper's numbering, the units rule, rewrites only on change."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure


def test_figures_are_named_then_saved_where_the_caller_says(tmp_path):
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    with pytest.raises(ValueError, match="no file name"):
        plotting.save_figure(fig, tmp_path)           # a figure no figure function named
    assert plotting.name_figure(fig, 10, "step_responses") is fig
    path = plotting.save_figure(fig, tmp_path / "figures")
    assert path == tmp_path / "figures" / "fig10_step_responses.png" and path.is_file()
    plotting.name_figure(fig, None, "view")
    assert plotting.save_figure(fig, str(tmp_path)).name == "extra_view.png"
    plt.close(fig)
    with pytest.raises(ValueError, match="what"):
        plotting.figure_name(4, "Bad Name")
    with pytest.raises(ValueError, match="number"):
        plotting.figure_name(0, "ok")
    with pytest.raises(TypeError, match="Figure"):
        plotting.name_figure("figure", 1, "ok")
    with pytest.raises(TypeError, match="Figure"):
        plotting.save_figure("figure", tmp_path)
    with pytest.raises(TypeError, match="directory"):
        plotting.save_figure(fig, None)


def test_save_figure_applies_the_units_rule(tmp_path):
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1], label="+-1 um")
    ax.set(xlabel="x [um]", title="mu bound")
    ax.legend()
    plotting.save_figure(plotting.name_figure(fig, None, "units"), tmp_path)
    assert ax.get_xlabel() == "x [µm]" and ax.get_title() == "μ bound"
    assert ax.get_legend().get_texts()[0].get_text() == "±1 µm"
    plt.close(fig)


def test_a_figure_is_rewritten_only_when_it_visibly_changed(tmp_path):
    x = np.linspace(0.0, 1.0, 50)

    def draw(shift):
        fig, ax = plt.subplots(figsize=(3, 2), dpi=100)
        ax.plot(x, x ** 2 + shift)
        ax.set_xlim(0, 1)
        ax.set_ylim(-0.1, 1.1)
        path = plotting.save_figure(plotting.name_figure(fig, None, "rewrite"), tmp_path)
        plt.close(fig)
        return path.read_bytes()

    first = draw(0.0)
    # 1e-9 of the axis: the rounding of another machine, far below a pixel
    assert draw(1e-9) == first
    # a tenth of the axis: about 14 pixels, a change a reader sees
    moved = draw(0.1)
    assert moved != first and not plotting.same_picture(first, moved)
    assert plotting.same_picture(first, first)
