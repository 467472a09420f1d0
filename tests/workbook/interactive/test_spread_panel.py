"""The spread control (notebook 02): its callback on the paper's plant, its figure, the static
fallback and the widget."""

import sys

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

from figure_checks import text_overlaps
from piezolib import uncertainty as unc
from piezolib.workbook import interactive as I

SPREAD_GRID = np.logspace(0, 6, 2000)


@pytest.fixture(scope="module")
def spread_5(problem):
    return I.spread_view(problem.G, 0.05, SPREAD_GRID)


def test_forced_widget_without_ipywidgets_says_what_to_install(problem, monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)      # import fails
    with pytest.raises(ImportError, match="ipywidgets"):
        I.spread_control(problem.G, problem.H_m, interactive=True)


def test_spread_of_5_percent(problem, spread_5):
    G = problem.G
    view = spread_5
    mset = unc.model_set(G, 0.05, 3)
    assert view.members == 729 and view.n_unstable == 42
    np.testing.assert_array_equal(view.unstable, unc.unstable_members(mset))
    np.testing.assert_allclose(view.envelope,
                               unc.relative_error_envelope(mset, SPREAD_GRID, "stable"),
                               rtol=1e-12)
    np.testing.assert_allclose(view.envelope_all,
                               unc.relative_error_envelope(mset, SPREAD_GRID, "all"), rtol=1e-12)
    assert np.all(view.envelope_all >= view.envelope)
    assert view.envelope_all.max() > view.envelope.max()     # the unstable ones reach higher
    W = view.weight
    assert len(ct.poles(W)) == 5
    assert np.all(ct.poles(W).real < 0) and np.all(ct.zeros(W).real < 0)
    assert view.coverage.covers
    assert np.all(np.abs(np.ravel(W(1j * SPREAD_GRID))) >= view.envelope * (1 - 1e-9))
    assert 0 < view.member_errors.shape[0] <= 60
    assert np.all(view.member_errors <= view.envelope * (1 + 1e-12))


def test_spread_of_3_percent_has_no_unstable_member(problem):
    view = I.spread_view(problem.G, 0.03, SPREAD_GRID)
    assert view.members == 729 and view.n_unstable == 0
    np.testing.assert_array_equal(view.envelope_all, view.envelope)


def test_spread_arguments_are_checked(problem):
    with pytest.raises(ValueError, match="spread"):
        I.spread_view(problem.G, 1.5, SPREAD_GRID)
    with pytest.raises(ValueError, match="omega"):
        I.spread_view(problem.G, 0.05, SPREAD_GRID[::-1])
    with pytest.raises(ValueError, match="levels"):
        I.spread_view(problem.G, 0.05, SPREAD_GRID, levels=1)


def test_spread_figure(problem, spread_5):
    fig = I.draw_spread(spread_5, H_m=problem.H_m)
    (ax,) = fig.axes
    assert text_overlaps(fig) == []
    labels = [line.get_label() for line in ax.lines if not line.get_label().startswith("_")]
    assert labels == ["stable members (a selection)", "envelope incl. 42 unstable members",
                      "envelope E_m (stable members)", "fitted weight, order 5", "|H_m| (Table 2)"]
    assert ax.get_ylabel() == "relative error |G_k/G - 1| [dB]"
    assert "729 models, 42 unstable" in ax.get_title()
    assert "does not cover" in ax.get_title()      # the published H_m at +-5 % (notebook 02)
    without = I.draw_spread(spread_5)
    assert "|H_m| (Table 2)" not in [line.get_label() for line in without.axes[0].lines]


def test_headless_entry_point_returns_the_static_figure(problem, headless):
    before = plt.get_fignums()
    fig = I.spread_control(problem.G, problem.H_m, SPREAD_GRID, spread=0.03)
    assert isinstance(fig, Figure)
    assert plt.get_fignums() == before       # pyplot does not show it a second time
    assert "±3 %" in fig.axes[0].get_title()


def test_spread_widget_follows_its_slider(problem, widgets):
    box = I.spread_control(problem.G, problem.H_m, SPREAD_GRID, interactive=True)
    slider = box.controls["spread"]
    assert (slider.min, slider.max, slider.value) == (0.5, 10.0, 5.0)
    assert box.panel.view.n_unstable == 42
    summaries = []
    box.panel.summary.observe(lambda change: summaries.append(change.new), "value")
    slider.value = 3.0
    assert box.panel.wait(60)
    # the set and its envelope are drawn before the weight is fitted to them
    assert len(summaries) == 2 and "fitting an order-5 weight" in summaries[0]
    assert "fitted order-5 weight exceeds" in summaries[1]
    assert box.panel.view.spread == pytest.approx(0.03) and box.panel.view.n_unstable == 0
    assert "0 unstable" in box.panel.summary.value


def _marginal_set():
    """s^3 + s^2 + 1.02 s + 1 at +-5 %: some members unstable, and its cover (order 1)."""
    from piezolib.problem import coefficient_set as cs
    G = ct.tf([1.0], [1.0, 1.0, 1.02, 1.0])
    omega = np.logspace(-2, 2, 64)
    survey = cs.survey_model_set(G, 0.05, 3)
    return G, omega, survey, cs.cover_envelope(survey, omega, ct.tf([0.5], [1.0]), order=1)


def test_a_view_from_a_survey_and_its_cover_is_not_fitted_again(monkeypatch, headless):
    G, omega, survey, cover = _marginal_set()
    view = I.spread_view_from(survey, cover)
    assert view.n_unstable == survey.unstable.size > 0
    assert np.array_equal(view.envelope, cover.envelope) and view.weight is cover.weight
    assert np.all(view.envelope_all >= view.envelope)
    assert 0 < len(view.member_errors) <= 60
    monkeypatch.setattr(I.spread_panel, "spread_view",
                        lambda *args, **kwargs: pytest.fail("fitted again"))
    fig = I.spread_control(G, None, omega, spread=0.05, start=view)
    assert isinstance(fig, Figure)


def test_a_start_of_another_spread_or_grid_is_refused():
    G, omega, survey, cover = _marginal_set()
    view = I.spread_view_from(survey, cover)
    with pytest.raises(ValueError, match="start"):
        I.spread_control(G, None, omega, spread=0.03, start=view, interactive=False)
    with pytest.raises(ValueError, match="start"):
        I.spread_control(G, None, omega[::2], spread=0.05, start=view, interactive=False)
    with pytest.raises(TypeError, match="start"):
        I.spread_control(G, None, omega, spread=0.05, start="view", interactive=False)
    with pytest.raises(TypeError, match="cover"):
        I.spread_view_from(survey, "cover")
