"""Figures of notebook 05: drawn, saved under their names, returned."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib import paper
from piezolib.problem import analysis, design
from piezolib.workbook import plotting
from piezolib.workbook.figures import mu as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


@pytest.fixture(scope="module")
def result():
    G, H_m, H_e, H_y, _ = paper.problem()
    # two DK steps (a fitted D-scaling to draw) and no fixed-order search: these figures
    # draw the DK run and the reduced K, whose full-size design notebook 05 shows
    return design.design_controller(G, H_m, H_e, H_y, max_iter=2, fixed_order=False)


def test_d_scaling_and_hankel_values(figures_dir, result):
    fig = F.extra_d_scaling_fit(result.musyn)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_d_scaling_fit.png"
    assert len(fig.axes[0].lines) == 2
    plt.close(fig)
    hsv = result.reduction.hsv
    fig = F.extra_hankel_singular_values(hsv, order=6)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_hankel_singular_values.png"
    dots, cut = fig.axes[0].lines
    np.testing.assert_array_equal(dots.get_ydata(), hsv)
    assert cut.get_xdata()[0] == 6.5
    plt.close(fig)


def test_step_responses_and_mu_bounds(figures_dir, result):
    G, H_m, H_e, H_y, K = paper.problem()
    controllers = {"published": K, "ours": result.K_reduced}
    fig = F.fig10_step_responses_designs(G, controllers, np.linspace(0, 0.002, 101))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig10_step_responses_designs.png"
    assert all(len(ax.lines) == 2 for ax in fig.axes)
    ks = fig.axes[2]
    # KS is not clipped: a symmetric log axis holds its whole range, K(inf) spike included
    assert ks.get_yscale() == "symlog"
    peak = max(np.abs(line.get_ydata()).max() for line in ks.lines)
    assert ks.get_ylim()[1] >= peak and ks.get_ylim()[0] <= -min(1.0, peak)
    # overlapping designs stay visible: each controller has its own line style
    assert len({str(line.get_linestyle()) for line in fig.axes[0].lines}) == 2
    plt.close(fig)
    omega = np.logspace(-2, 8, 100)
    results = {name: analysis.analyze(K_, G, H_m, H_e, H_y, omega=omega, name=name)
               for name, K_ in controllers.items()}
    fig = F.fig12_mu_bounds(results)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig12_mu_bounds.png"
    ax_rs, ax_rp = fig.axes
    assert len(ax_rs.lines) == 2 + 1 and len(ax_rp.lines) == 4 + 1    # + the mu = 1 line
    np.testing.assert_array_equal(ax_rs.lines[0].get_ydata(), results["published"].mu_RS_curve)
    upper, lower = ax_rp.lines[0], ax_rp.lines[1]               # published K: distinct styles
    assert upper.get_linestyle() != lower.get_linestyle()
    assert upper.get_linewidth() > lower.get_linewidth()
    assert ax_rs.get_ylabel() == "μ"
    plt.close(fig)


def test_mu_bounds_legend_sits_below_the_panels(figures_dir, result):
    G, H_m, H_e, H_y, K = paper.problem()
    omega = np.logspace(0, 7, 120)
    results = {name: analysis.analyze(K_, G, H_m, H_e, H_y, omega=omega, name=name)
               for name, K_ in {"published": K, "ours": result.K_reduced}.items()}
    fig = F.fig12_mu_bounds(results)
    plotting.save_figure(fig, figures_dir)
    assert all(ax.get_legend() is None for ax in fig.axes)        # none inside a panel
    legend, = fig.legends
    labels = [t.get_text() for t in legend.get_texts()]
    assert labels == ["published", "ours", "(b) upper bound", "(b) lower bound"]
    box = legend.get_window_extent()
    assert all(box.y1 <= ax.get_window_extent().y0 for ax in fig.axes)   # below both panels
    assert text_overlaps(fig) == []
    plt.close(fig)
