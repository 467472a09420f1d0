"""Figures of notebook 01: drawn, saved under their names, returned."""

import control as ct
import numpy as np
import pytest

from piezolib import identification, paper
from piezolib.workbook import plotting
from piezolib.workbook.figures import identification as F

FS = paper.SAMPLING_FREQUENCY_HZ


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


def test_bode_overlay_draws_continuous_discrete_and_measured():
    G = paper.plant()
    omega = np.logspace(2, 4.5, 50)
    sampled = ct.c2d(ct.ss(G), 1 / FS, "zoh")
    fig, (ax_mag, ax_phase) = F.bode_overlay({"G": G, "G sampled": sampled}, omega,
                                             measured=(omega, G(1j * omega)))
    assert len(ax_mag.lines) == 3 and len(ax_phase.lines) == 3
    assert ax_mag.lines[1].get_label() == "G" and ax_mag.lines[2].get_linestyle() == "--"
    # the dB magnitude of the continuous model at the grid
    assert np.allclose(ax_mag.lines[1].get_ydata(), 20 * np.log10(np.abs(G(1j * omega))))
    with pytest.raises(ValueError, match="omega"):
        F.bode_overlay({"G": G}, [1.0])


def test_fig04_is_saved_under_the_paper_number(figures_dir):
    u = np.random.default_rng(0).standard_normal(8000) * 0.05
    y = identification.zoh_simulate(paper.plant(), u, FS)
    y_sim = y + 1e-4 * np.random.default_rng(1).standard_normal(len(y))
    fig = F.fig04_chirp_validation(y, y_sim, 1000, FS, zoom_s=(0.2, 0.22))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig04_chirp_validation.png"
    fit = identification.fit_percent(y[1000:], y_sim[1000:])
    ax_full, ax_zoom, ax_res = fig.axes
    assert ax_full.get_title().endswith(f"fit {fit:.1f} %")
    # every panel has its x label; both traces are visible (envelopes, then the traces)
    assert all(ax.get_xlabel() for ax in fig.axes)
    assert len(ax_full.lines) == 4 and len(ax_zoom.lines) == 2
    measured, simulated = ax_zoom.lines
    assert measured.get_linewidth() > simulated.get_linewidth()
    assert measured.get_linestyle() != simulated.get_linestyle()
    np.testing.assert_allclose(ax_res.lines[0].get_ydata(),
                               1e3 * (measured.get_ydata() - simulated.get_ydata()))
    with pytest.raises(ValueError, match="y_sim"):
        F.fig04_chirp_validation(y, y_sim[:-1], 1000, FS)


def test_fig13_marks_the_quantities_of_eq_25_26(figures_dir):
    from piezolib.hysteresis import hysteresis_measure
    t = np.arange(3001) / FS
    v = 20 * (1 - np.abs(((10 * t) % 1) * 2 - 1))       # three 10 Hz triangles, 0 ... 20 V
    rising = np.gradient(v) > 0
    x = 0.3 * v + np.where(rising, -0.4, 0.4) * np.sin(np.pi * v / 20)  # a loop 0.8 um wide
    measure = hysteresis_measure(v, x)
    fig = F.fig13_hysteresis_measure(v, x, measure, 20.0)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig13_hysteresis_measure.png"
    ax = fig.axes[0]
    assert f"{measure.percent:.2f} %" in ax.get_title()
    dots = [line for line in ax.lines if line.get_marker() == "o"][0]
    np.testing.assert_allclose(dots.get_xdata(), [measure.v_mid] * 2)
    np.testing.assert_allclose(sorted(dots.get_ydata()), sorted([measure.x_up, measure.x_lo]))
    assert {"X_UP", "X_LO", "X_MAX", "X_MIN"} <= {t.get_text() for t in ax.texts}
    assert ax.get_ylabel().endswith("[µm]")                   # the units rule was applied


def test_residual_whiteness_figure(figures_dir):
    white = identification.whiteness(np.random.default_rng(2).standard_normal(5000))
    fig = F.extra_residual_whiteness(white)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_residual_whiteness.png"
    assert f"p = {white.p_value:.2f}" in fig.axes[0].get_title()
