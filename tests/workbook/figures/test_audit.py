"""Figures of notebook 00: drawn, saved under the paper's numbers, returned."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib import paper, robust
from piezolib.workbook import plotting
from piezolib.workbook.figures import audit as F
from piezolib.workbook.style import unit_text


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


@pytest.fixture(scope="module")
def loop():
    return robust.loop_functions(paper.plant(), paper.controller())


def test_fig10_draws_the_four_step_responses(figures_dir, loop):
    t = np.linspace(0, 0.002, 201)
    fig = F.fig10_step_responses(loop, t)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig10_step_responses.png"
    # titles as saved, through the units rule ("->" becomes an arrow)
    assert [ax.get_title() for ax in fig.axes] == [unit_text(t)
                                                   for t in F.STEP_TITLES.values()]
    assert fig.axes[2].get_yscale() == "symlog"                 # KS: its spike is not clipped
    s_line = fig.axes[0].lines[0]
    assert s_line.get_xdata()[-1] == pytest.approx(2.0)          # ms
    assert s_line.get_ydata()[0] == pytest.approx(1.0)           # S(inf) = 1 for a proper loop
    plt.close(fig)


def test_fig11_draws_s_t_and_templates(figures_dir, loop):
    omega = np.logspace(0, 7, 50)
    fig = F.fig11_sensitivity_templates(loop, paper.error_weight(), paper.output_weight(), omega)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig11_sensitivity_templates.png"
    ax_s, ax_t = fig.axes
    assert [line.get_label() for line in ax_s.lines] == ["|S|", "1/|H_e|"]
    np.testing.assert_allclose(ax_t.lines[0].get_ydata(),
                               20 * np.log10(np.abs(loop.T(1j * omega).ravel())))
    assert text_overlaps(fig) == []                             # no legend over |S| or |T|
    plt.close(fig)
