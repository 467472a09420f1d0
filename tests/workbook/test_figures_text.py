"""No text of a workbook figure collides: with another text, a diagram's wires and boxes, or a
curve under a legend (renderer-based: :func:`figure_checks.text_overlaps`).

Each case draws one figure function on small inputs of the notebook's kind (the committed
experiment files and result tables where the figure needs them) and checks the saved figure.
The block diagrams are checked in tests/workbook/figures/test_diagrams.py; the figures of
notebooks 05 and 06 that need a μ design or closed-loop runs are checked in their own files.
"""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib import hysteresis, identification, paper, robust
from piezolib.problem import stage_data
from piezolib.workbook import plotting, report
from piezolib.workbook.figures import audit
from piezolib.workbook.figures import hysteresis as hyst_figures
from piezolib.workbook.figures import identification as ident_figures
from piezolib.workbook.figures import mu as mu_figures
from piezolib.workbook.figures import scorecard as report_figures
from piezolib.workbook.figures import uncertainty as unc_figures
from piezolib.workbook.figures import weights
from piezolib.workbook.style import unit_text

FS = paper.SAMPLING_FREQUENCY_HZ
# read from the repository before any test points PIEZOLIB_ROOT elsewhere
LOOPS = stage_data.load_hysteresis_loops()
TABLE = report.reproduction_table(report.load_claims())


@pytest.fixture(autouse=True)
def figures_dir(tmp_path):
    yield tmp_path / "figures"
    plt.close("all")


def _loop():
    return robust.loop_functions(paper.plant(), paper.controller())


def _chirp():
    rng = np.random.default_rng(0)
    u = 0.05 * np.sin(2 * np.pi * np.cumsum(np.linspace(20, 2000, 6000)) / FS)
    y = identification.zoh_simulate(paper.plant(), u, FS)
    return y, y + 3e-4 * rng.standard_normal(y.size)


def _fig06():
    omega = np.logspace(0, 6, 150)
    G = paper.plant()
    members = [ct.tf(G.num[0][0], np.asarray(G.den[0][0]) * (1 + 0.05 * q))
               for q in (-1.0, 1.0)]
    errors = np.array([np.abs(np.ravel(Gk(1j * omega)) / np.ravel(G(1j * omega)) - 1)
                       for Gk in members])
    return unc_figures.fig06_relative_error(
        omega, np.maximum(errors, 1e-12), errors.max(axis=0), paper.uncertainty_weight(),
        paper.uncertainty_weight() * 2, 0.05, peak=(float(errors.max()) * 1.5, 6e3))


def _fig08(exact):
    t = np.arange(1001) / FS
    x_r = 2 * (1 - np.abs((10 * t) % 1 * 2 - 1))
    x_comp = x_r + (1e-17 if exact else 1e-3) * np.sin(50 * t)
    return hyst_figures.fig08_feedforward_on_model(t, x_r, 1.05 * x_r, x_comp)


def _fig13():
    record = LOOPS[max(LOOPS)]
    measure = hysteresis.hysteresis_measure(record.v_a_V, record.x_measured_um)
    return ident_figures.fig13_hysteresis_measure(record.v_a_V, record.x_measured_um,
                                                  measure, max(LOOPS))


CASES = {
    "fig10_step_responses": lambda: audit.fig10_step_responses(_loop()),
    "fig11_sensitivity_templates": lambda: audit.fig11_sensitivity_templates(
        _loop(), paper.error_weight(), paper.output_weight(), np.logspace(0, 7, 200)),
    "extra_weight_templates": lambda: weights.extra_weight_templates(
        paper.ERROR_WEIGHT, paper.OUTPUT_WEIGHT, np.logspace(-1, 9, 200)),
    "fig10_step_responses_designs": lambda: mu_figures.fig10_step_responses_designs(
        paper.plant(), {"published K": paper.controller(), "0.8 K": 0.8 * paper.controller()},
        np.linspace(0, 0.004, 401)),
    "fig04_chirp_validation": lambda: ident_figures.fig04_chirp_validation(
        *_chirp(), 500, FS, zoom_s=(0.2, 0.21)),
    "fig13_hysteresis_measure": _fig13,
    "extra_stage_case_i_loops": lambda: ident_figures.extra_stage_case_i_loops(
        LOOPS, {A: 6.0 for A in LOOPS}, paper.table4().loc["case_I"]),
    "fig06_relative_error": _fig06,
    "fig08_exact": lambda: _fig08(True),
    "fig08_error": lambda: _fig08(False),
    "extra_reproduction_scorecard": lambda: report_figures.extra_reproduction_scorecard(TABLE),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_no_text_collides(name, figures_dir):
    fig = CASES[name]()
    plotting.save_figure(fig, figures_dir)          # the texts as saved, through the units rule
    assert text_overlaps(fig) == []


def test_every_saved_label_follows_the_units_rule(figures_dir):
    fig = CASES["fig13_hysteresis_measure"]()
    plotting.save_figure(fig, figures_dir)
    texts = [t.get_text() for t in fig.findobj(plt.Text)]
    assert any("µm" in t for t in texts)
    assert not any(unit_text(t) != t for t in texts)


def test_fig08_says_exact_to_round_off_only_when_it_is():
    exact = _fig08(True).axes[1]
    assert any(t.get_text().startswith("exact to round-off") for t in exact.texts)
    assert exact.get_ylim() == (-1, 1)
    error = _fig08(False).axes[1]
    assert not error.texts and np.ptp(error.lines[0].get_ydata()) > 1   # nm of real error
