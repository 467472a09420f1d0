"""Figures of notebook 08: each is drawn from small inputs, saved under its name and returned."""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from figure_checks import text_overlaps
from piezolib import robust
from piezolib.hysteresis import PIModel
from piezolib.records import Record
from piezolib.workbook import plotting
from piezolib.workbook.figures import own_stage as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


@pytest.fixture
def plant():
    return ct.tf([1e8], [1, 2e3, 1e8], inputs="u", outputs="y")


def _record(n=400, fs=1000.0):
    t = np.arange(n) / fs
    return Record(np.sin(2 * np.pi * 5 * t), 3 * np.sin(2 * np.pi * 5 * t - 0.2), fs,
                  input_unit="V", output_unit="um", input_name="u_c", output_name="x")


def test_records_one_panel_per_record_with_marks(figures_dir):
    fig = F.extra_own_stage_records({"a": _record(), "b": _record(200)},
                                    marks={"a": [(0.1, "window"), (0.2, "")]})
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_records.png"
    main = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title().split(":")[0] for ax in main] == ["a", "b"]
    assert len(main[0].get_lines()) == 3 and len(main[1].get_lines()) == 1   # signal + 2 marks
    assert main[0].get_ylabel() == "u_c [V]"
    assert text_overlaps(fig) == []                   # the marks' names stay off the curves
    plt.close(fig)


def test_records_rejects_other_types(figures_dir):
    with pytest.raises(TypeError, match="records\\['a'\\]"):
        F.extra_own_stage_records({"a": np.zeros(10)})
    with pytest.raises(ValueError, match="at least one"):
        F.extra_own_stage_records({})


def test_identification_panels_and_zoom(figures_dir, plant):
    t = np.arange(100) / 1e3
    y = np.sin(40 * t)
    omega = np.logspace(0, 4, 50)
    fig = F.extra_own_stage_identification(t, y, y + 0.01, {"model": plant}, omega,
                                           y_truth=y - 0.01, output_label="v_y [V]",
                                           zoom_s=(0.02, 0.05))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_identification.png"
    a, magnitude, errors, phase = fig.axes
    assert a.get_xlim() == pytest.approx((0.02, 0.05))
    assert len(errors.get_lines()) == 2               # model and truth errors
    assert np.allclose(errors.get_lines()[0].get_ydata(), 0.01)
    assert len(magnitude.get_lines()) == 1 and len(phase.get_lines()) == 1
    plt.close(fig)
    with pytest.raises(ValueError, match="equal lengths"):
        F.extra_own_stage_identification(t, y[:-1], y, {"model": plant}, omega)
    with pytest.raises(ValueError, match="zoom_s"):
        F.extra_own_stage_identification(t, y, y, {"model": plant}, omega, zoom_s=(1, 0))


def test_uncertainty_draws_weight_on_grid(figures_dir):
    omega = np.logspace(0, 5, 60)
    W = ct.tf([1, 10], [0.1, 100])
    fig = F.extra_own_stage_uncertainty(omega, np.full(60, 0.05), W, 0.02,
                                        true_error=np.full(60, 0.01))
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_uncertainty.png"
    lines = fig.axes[0].get_lines()
    assert len(lines) == 3
    assert np.allclose(lines[1].get_ydata(), np.abs(np.ravel(W(1j * omega))))
    assert "2 %" in lines[0].get_label()
    plt.close(fig)
    with pytest.raises(ValueError, match="shape of omega"):
        F.extra_own_stage_uncertainty(omega, np.ones(3), W, 0.02)


def test_hysteresis_scales_axes_and_errors(figures_dir):
    v = np.r_[np.linspace(0, 2, 50), np.linspace(2, 0, 50)]
    model = PIModel((0.0, 0.5), (1.0, 0.5))
    x = model.simulate(v) + 0.01
    index = pd.MultiIndex.from_tuples([("PI", "loop")], names=["model", "record"])
    scores = pd.DataFrame({"RMS %": [1.23]}, index=index)
    fig = F.extra_own_stage_hysteresis(v, x, {"PI": model}, scores, input_scale=10.0,
                                       output_scale=3.0, input_label="V", output_label="um")
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_hysteresis.png"
    a, b = fig.axes
    assert "1.23 %" in a.get_lines()[1].get_label()
    assert np.allclose(a.get_lines()[0].get_xdata(), 10 * v)
    assert np.allclose(b.get_lines()[0].get_ydata(), -0.03)     # 3 x (model - measured)
    plt.close(fig)


def test_mu_and_loop_functions(figures_dir, plant):
    omega = np.logspace(0, 5, 40)
    bounds = type("Bounds", (), {"upper": np.full(40, 0.9), "lower": np.full(40, 0.8)})()
    lf = robust.loop_functions(plant, ct.tf([0.5], [1]))
    H = ct.tf([1, 10], [1, 1])
    fig = F.extra_own_stage_mu(omega, {"design": bounds}, {"plant": lf}, omega, H, H)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_mu.png"
    a, b = fig.axes
    assert len(a.get_lines()) == 3                   # upper, lower, the level 1
    assert np.allclose(a.get_lines()[0].get_ydata(), 0.9)
    assert len(b.get_lines()) == 4                   # two templates, |S| and |T|
    plt.close(fig)


def test_experiments_cases_and_extra_rows(figures_dir):
    rows = ["case_I", "case_II", "case_III"]
    t4 = pd.DataFrame([[5.0, 6.0], [1.0, 1.5], [0.1, 0.2]], index=rows,
                      columns=pd.Index([10.0, 20.0], name="amplitude_V"))
    t5 = pd.DataFrame([[9.0], [2.0], [0.5]], index=rows,
                      columns=pd.Index([1.0], name="frequency_Hz"))
    fig = F.extra_own_stage_experiments(t4, t5, {"II: PI": pd.Series({10.0: 0.3, 20.0: 0.4})},
                                        feedforward="Dahl feedforward")
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_own_stage_experiments.png"
    a, b = fig.axes
    labels = [line.get_label() for line in a.get_lines()]
    assert labels == ["I: open loop", "II: Dahl feedforward",
                      "III: Dahl feedforward + mu controller", "II: PI"]
    assert np.allclose(b.get_lines()[2].get_ydata(), [0.5])
    assert len(fig.legends) == 1 and text_overlaps(fig) == []
    plt.close(fig)
