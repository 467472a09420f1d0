"""Figures of notebook 06: drawn, saved under the paper's numbers, returned."""

import matplotlib.pyplot as plt
import pytest

from piezolib import hysteresis as hy
from piezolib import paper
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments
from piezolib.workbook import plotting
from piezolib.workbook.figures import tracking as F

DAHL = hy.DahlModel(alpha1=200.0, alpha2=600.0, beta1=0.0, beta2=1.9, gamma_a=30.0,
                    g_a=1.12, form="bliman_sorine")


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


@pytest.fixture(scope="module")
def stage():
    return VirtualStage(seed=3)


def test_fig14_one_panel_per_case_and_amplitude(figures_dir, stage):
    result = experiments.hysteresis_test(stage, DAHL, paper.controller(),
                                         amplitudes_V=[10.0, 30.0])
    fig = F.fig14_hysteresis_cases(result)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig14_hysteresis_cases.png"
    axes = fig.axes
    assert len(axes) == 3 * 2
    value = result.table.loc["case_II", 30.0]
    assert axes[3].get_title() == f"(d) Case II, 30 V: {value:.2f} %"
    plt.close(fig)


def test_fig15_draws_the_published_K_dashed_in_case_III(figures_dir, stage):
    ours = experiments.tracking_test(stage, DAHL, paper.controller(), frequencies_Hz=[25.0])
    published = experiments.tracking_test(stage, DAHL, 0.5, frequencies_Hz=[25.0])
    fig = F.fig15_tracking_error(ours, published)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "fig15_tracking_error.png"
    case_I, _, case_III = fig.axes
    assert len(case_I.lines) == 1 and len(case_III.lines) == 2
    assert case_III.lines[1].get_linestyle() == "--"
    # one steady-state period of 25 Hz at 10 kHz: 400 samples + 1
    assert len(case_III.lines[0].get_xdata()) == 401
    plt.close(fig)
