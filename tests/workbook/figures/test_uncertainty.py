"""Figures of notebook 02: Fig. 6 on log axes, with the refined peak and the weight's excess."""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib import paper
from piezolib.workbook import plotting
from piezolib.workbook.figures import uncertainty as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


def test_fig06_log_axes_refined_peak_and_weight_excess(figures_dir):
    omega = np.logspace(0, 6, 200)
    G = paper.plant()
    H_m = paper.uncertainty_weight()
    members = [G * (1 + 0.05 * k) for k in (-1, 1)] + [G * ct.tf([1], [1e-4, 1])]
    errors = np.array([np.abs(np.ravel(Gk(1j * omega)) / np.ravel(G(1j * omega)) - 1)
                       for Gk in members])
    errors = np.maximum(errors, 1e-9)
    envelope = errors.max(axis=0)
    W_fit = ct.tf([0.2, 20.0], [1e-4, 200.0])          # 0.1 at DC, 2000 at high frequency
    fig = F.fig06_relative_error(omega, errors, envelope, H_m, W_fit, 0.05,
                                 peak=(497.0, 5774.0))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig06_relative_error.png"
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    excess = np.max(np.abs(np.ravel(W_fit(1j * omega))) / envelope)
    assert any(f"up to {excess:.0f}x" in label for label in labels)
    assert any("refined peak of E_m: 497 at 5774 rad/s" in label for label in labels)
    assert any(f"grid maximum {envelope.max():.0f}" in label for label in labels)
    plt.close(fig)

