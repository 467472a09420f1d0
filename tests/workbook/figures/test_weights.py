"""Figures of notebook 04: drawn, saved under their names, returned."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.workbook import plotting
from piezolib.workbook.figures import weights as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


def test_weight_templates_vary_the_corner(figures_dir):
    omega = np.logspace(-1, 9, 60)
    fig = F.extra_weight_templates(paper.ERROR_WEIGHT, paper.OUTPUT_WEIGHT, omega)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_weight_templates.png"
    ax_e, ax_y = fig.axes
    assert [line.get_label() for line in ax_e.lines] == [f"omega_e x {f:g}" for f in (0.5, 1, 2)]
    # the middle curve is the published template; at DC it sits at eps_e
    middle = ax_e.lines[1].get_ydata()
    assert middle[0] == pytest.approx(20 * np.log10(paper.ERROR_WEIGHT.eps_e), abs=0.01)
    assert ax_y.get_ylim() == (-200, 20)
    plt.close(fig)


def test_fig11_for_several_designs(figures_dir):
    G, K = paper.plant(), paper.controller()
    loops = {"published": robust.loop_functions(G, K), "half": robust.loop_functions(G, 0.5 * K)}
    fig = F.fig11_sensitivity_templates_designs(loops, paper.error_weight(),
                                                paper.output_weight(), np.logspace(0, 7, 40))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig11_sensitivity_templates_designs.png"
    ax_s, _ = fig.axes
    assert [line.get_label() for line in ax_s.lines] == ["|S|, published", "|S|, half", "1/|H_e|"]
    plt.close(fig)
