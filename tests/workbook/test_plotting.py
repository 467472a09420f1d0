"""Saving figures: names after the paper's numbering, the units rule, rewrites only on change."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure


def test_figure_names(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    fig, ax = new_figure()
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


def test_save_figure_applies_the_units_rule(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1], label="+-1 um")
    ax.set(xlabel="x [um]", title="mu bound")
    ax.legend()
    plotting.save_figure(fig, None, "units")
    assert ax.get_xlabel() == "x [µm]" and ax.get_title() == "μ bound"
    assert ax.get_legend().get_texts()[0].get_text() == "±1 µm"
    plt.close(fig)


def test_a_figure_is_rewritten_only_when_it_visibly_changed(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    x = np.linspace(0.0, 1.0, 50)

    def draw(shift):
        fig, ax = plt.subplots(figsize=(3, 2), dpi=100)
        ax.plot(x, x ** 2 + shift)
        ax.set_xlim(0, 1)
        ax.set_ylim(-0.1, 1.1)
        path = plotting.save_figure(fig, None, "rewrite")
        plt.close(fig)
        return path.read_bytes()

    first = draw(0.0)
    # 1e-9 of the axis: the rounding of another machine, far below a pixel
    assert draw(1e-9) == first
    # a tenth of the axis: about 14 pixels, a change a reader sees
    moved = draw(0.1)
    assert moved != first and not plotting.same_picture(first, moved)
    assert plotting.same_picture(first, first)
