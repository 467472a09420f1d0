"""The weight-design control (notebook 04): its callbacks on the paper's problem, its figure,
the static fallback and the widget."""

import types

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

from figure_checks import text_overlaps
from piezolib import paper
from piezolib.problem import analysis
from piezolib.robust.lti import is_stable
from piezolib.workbook import interactive as I

PUBLISHED = {"M_e": 2.0, "eps_e": 0.003, "omega_e": 1.26e3,
             "M_y": 1.5, "eps_y": 1e-4, "omega_y": 7.5e3}


@pytest.fixture(scope="module")
def published_analysis(problem):
    G, H_m, H_e, H_y, K = problem
    return analysis.analyze(K, G, H_m, H_e, H_y)


def test_interactive_argument_is_checked(problem):
    with pytest.raises(TypeError, match="interactive"):
        I.weight_design_control(problem.G, problem.H_m, problem.K, interactive="yes")


def test_published_weights_give_the_peaks_of_analyze(problem, published_analysis):
    G, H_m, H_e, H_y, K = problem
    view = I.weight_design_view(G, H_m, K, PUBLISHED)
    a = published_analysis
    assert view.stable
    assert view.norm_He_S == pytest.approx(a.norm_He_S, rel=1e-12)
    assert view.norm_Hy_T == pytest.approx(a.norm_Hy_T, rel=1e-12)
    assert view.mu_RS == pytest.approx(a.mu_RS, rel=1e-12)
    assert view.mu_RP == pytest.approx(a.mu_RP, rel=1e-12)
    assert round(view.norm_He_S, 2) == paper.FIGURES_OF_MERIT["norm_He_S"]
    # the curves are those of the loop and the weights
    s = 1j * view.omega
    S = 1 / (1 + np.ravel(G(s)) * np.ravel(K(s)))
    np.testing.assert_allclose(view.S, np.abs(S), rtol=1e-8)
    np.testing.assert_allclose(view.inv_Hy, 1 / np.abs(np.ravel(H_y(s))), rtol=1e-12)
    # default params are the published ones; an object with the attributes works too
    assert I.weight_design_view(G, H_m, K).params == PUBLISHED
    as_object = I.weight_design_view(G, H_m, K, types.SimpleNamespace(**PUBLISHED),
                                     omega=np.logspace(0, 6, 50))
    assert as_object.peaks() == pytest.approx(view.peaks(), rel=1e-12)


def test_omega_e_moves_the_template_crossing(problem):
    G, H_m, _, _, K = problem
    base = I.weight_design_view(G, H_m, K, PUBLISHED)
    faster = I.weight_design_view(G, H_m, K, {**PUBLISHED, "omega_e": 2 * PUBLISHED["omega_e"]})
    p = PUBLISHED
    exact = p["omega_e"] * np.sqrt((1 - p["eps_e"] ** 2) / (1 - 1 / p["M_e"] ** 2))
    assert base.crossing_He == pytest.approx(exact, rel=2e-3)
    assert faster.crossing_He / base.crossing_He == pytest.approx(2.0, rel=5e-3)
    assert faster.crossing_Hy == pytest.approx(base.crossing_Hy, rel=1e-9)     # H_y untouched
    # a faster template on S is harder to meet: the NP peak on S grows
    assert faster.norm_He_S > base.norm_He_S
    assert faster.norm_Hy_T == pytest.approx(base.norm_Hy_T, rel=1e-12)


def test_destabilising_controller_gives_infinite_peaks(problem):
    G, H_m, _, _, K = problem
    view = I.weight_design_view(G, H_m, -K)
    assert not view.stable
    assert all(np.isinf(v) for v in view.peaks().values())
    fig = I.draw_weight_design(view)
    assert "does not stabilise" in fig.get_suptitle()


@pytest.mark.parametrize("params, match", [
    ({k: v for k, v in PUBLISHED.items() if k != "eps_y"}, "eps_y"),
    ({**PUBLISHED, "omega_e": -1.0}, "omega_e"),
    ({**PUBLISHED, "M_x": 1.0}, "M_x"),
    (types.SimpleNamespace(M_e=2.0), "eps_e"),
])
def test_bad_weight_params_are_named(problem, params, match):
    G, H_m, _, _, K = problem
    with pytest.raises(ValueError, match=match):
        I.weight_design_view(G, H_m, K, params)


def test_weight_figure_is_readable_and_reusable(problem):
    G, H_m, _, _, K = problem
    view = I.weight_design_view(G, H_m, K, PUBLISHED, omega=np.logspace(0, 7, 300))
    fig = I.draw_weight_design(view)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    assert text_overlaps(fig) == []
    for ax in fig.axes:
        assert ax.get_xlabel() == "frequency ω [rad/s]" and ax.get_ylabel() == "magnitude [dB]"
    labels = [line.get_label() for line in fig.axes[0].lines]
    assert labels[:2] == ["|S| (K)", "template 1/|H_e|"]
    assert "μ = 1.448" in fig.get_suptitle()
    # not attached to pyplot: a notebook shows it once, as the cell's value
    assert fig not in [plt.figure(n) for n in plt.get_fignums()]
    again = I.draw_weight_design(view, fig=fig)
    assert again is fig and len(fig.axes) == 2
    with pytest.raises(TypeError, match="view"):
        I.draw_weight_design(view.analysis)


def test_redesign_for_the_published_weights(problem):
    G, H_m, H_e, H_y, _ = problem
    K_new, mu = I.redesign(G, H_m, PUBLISHED, max_iter=1)
    assert K_new.nstates == 6
    assert K_new.input_labels == ["v_e"] and K_new.output_labels == ["u_b"]
    assert is_stable(G, K_new)
    mu_check, _ = analysis.robust_performance_peak(K_new, G, H_m, H_e, H_y)
    assert mu == pytest.approx(mu_check, rel=1e-12)
    assert 0.5 < mu < 3.0
    with pytest.raises(ValueError, match="omega_y"):
        I.redesign(G, H_m, {**PUBLISHED, "omega_y": 0.0}, max_iter=1)


def test_headless_entry_point_returns_the_static_figure(problem, headless):
    G, H_m, _, _, K = problem
    before = plt.get_fignums()
    fig = I.weight_design_control(G, H_m, K)
    assert isinstance(fig, Figure)
    assert plt.get_fignums() == before       # pyplot does not show it a second time
    assert "μ = 1.448" in fig.get_suptitle()              # the published weights


def test_weight_widget_follows_its_sliders(problem, published_analysis, widgets):
    G, H_m, _, _, K = problem
    box = I.weight_design_control(G, H_m, K, interactive=True,
                                  design_options={"max_iter": 1})
    assert isinstance(box, widgets.VBox)
    panel = box.panel
    assert set(box.controls) == set(I.WEIGHT_PARAMETERS) | {"redesign", "controller"}
    assert isinstance(box.controls["omega_e"], widgets.FloatLogSlider)
    assert isinstance(box.controls["M_e"], widgets.FloatSlider)
    assert panel.view.mu_RP == pytest.approx(published_analysis.mu_RP, rel=1e-12)
    assert bytes(panel.image.value).startswith(b"\x89PNG")
    first_image, first_crossing = bytes(panel.image.value), panel.view.crossing_He

    summaries = []
    panel.summary.observe(lambda change: summaries.append(change.new), "value")
    box.controls["omega_e"].value = 2 * PUBLISHED["omega_e"]       # as a person moving it
    assert panel.wait(30)
    # the curves under the new template come first, the peaks (the slow part) after
    assert len(summaries) == 2 and "computing the NP, RS and RP peaks" in summaries[0]
    assert panel.view.params["omega_e"] == pytest.approx(2 * PUBLISHED["omega_e"])
    assert panel.view.crossing_He / first_crossing == pytest.approx(2.0, rel=5e-3)
    assert bytes(panel.image.value) != first_image
    assert "NP ||H_e S||" in panel.summary.value and panel.status.value == ""

    events = []          # what the reader sees, in order
    panel.image.observe(lambda change: events.append(("figure", panel.view.controller)), "value")
    box.redesign_progress.observe(lambda change: events.append(
        ("bar", "done" if "piezolib-progress-done" in change.new else "running")), "value")
    box.redesign_result.observe(lambda change: events.append(("result", change.new)), "value")
    box.controls["redesign"].click()
    assert panel.wait(30)
    menu = box.controls["controller"]
    # the done line and the result come with the figure of the new controller, not before it
    # (its curves, then the figure with its peaks)
    new_figure = events.index(("figure", menu.value))
    assert [kind for kind, _ in events[new_figure:]] == ["figure", "figure", "bar", "result"]
    assert events[-2] == ("bar", "done") and "μ_RP" in events[-1][1]
    assert ("bar", "done") not in events[:new_figure]
    assert menu.value.startswith("re-designed K") and len(menu.options) == 2
    assert "μ_RP" in box.redesign_result.value
    # its progress is drawn under the button (a callback's output reaches no cell), finished
    assert "piezolib-progress-done" in box.redesign_progress.value
    assert "musyn DK" in box.redesign_progress.value
    assert "max_iter reached" in box.redesign_progress.value
    assert panel.view.controller == menu.value
    K_new, mu = I.redesign(G, H_m, panel.values(), max_iter=1)
    assert panel.view.mu_RP == pytest.approx(mu, rel=1e-9)
    assert f"{mu:.3f}" in box.redesign_result.value
    menu.value = menu.options[0]                                    # back to the given K
    assert panel.wait(30)
    assert panel.view.controller == menu.options[0]
    assert panel.view.norm_He_S > published_analysis.norm_He_S      # faster template on S


def test_controller_menu_spells_the_name_as_the_text_does(problem, widgets):
    G, H_m, _, _, K = problem
    named = ct.tf(K.num, K.den, name="K_mu6")
    box = I.weight_design_control(G, H_m, named, interactive=True)
    menu = box.controls["controller"]
    assert menu.options == ("given K (K_μ6)",) and menu.value == "given K (K_μ6)"
    assert box.panel.view.controller == menu.value
