"""Interactive controls: the callbacks on the paper's problem, the static fallback, the widgets."""

import sys
import types
import warnings
from dataclasses import replace

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

from piezolib import paper
from piezolib import uncertainty as unc
from piezolib.hysteresis import FitWarning
from piezolib.problem import analysis, stage_data
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.robust.lti import is_stable
from piezolib.workbook import interactive as I
from piezolib.workbook.plotting import text_overlaps

PUBLISHED = {"M_e": 2.0, "eps_e": 0.003, "omega_e": 1.26e3,
             "M_y": 1.5, "eps_y": 1e-4, "omega_y": 7.5e3}
SPREAD_GRID = np.logspace(0, 6, 2000)


@pytest.fixture(scope="module")
def problem():
    return paper.problem()


@pytest.fixture(scope="module")
def published_analysis(problem):
    G, H_m, H_e, H_y, K = problem
    return analysis.analyze(K, G, H_m, H_e, H_y)


@pytest.fixture(scope="module")
def spread_5(problem):
    return I.spread_view(problem.G, 0.05, SPREAD_GRID)


@pytest.fixture(scope="module")
def dahl():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)    # alpha's not identifiable: known, notebook 03
        fit = workbook_dahl_fit()
    return fit, list(stage_data.load_hysteresis_loops().values())


@pytest.fixture
def headless(monkeypatch):
    monkeypatch.setenv(I.STATIC_ENV, "1")


@pytest.fixture
def fake_kernel(monkeypatch):
    """IPython's shell has a kernel, as inside Jupyter."""
    ipython = pytest.importorskip("IPython")
    monkeypatch.setattr(ipython, "get_ipython", lambda: types.SimpleNamespace(kernel=object()))
    monkeypatch.delenv(I.STATIC_ENV, raising=False)


# --------------------------------------------------------------------------- headless or not
def test_no_frontend_outside_a_kernel(monkeypatch):
    monkeypatch.delenv(I.STATIC_ENV, raising=False)
    ipython = pytest.importorskip("IPython")
    assert ipython.get_ipython() is None            # pytest runs no IPython shell
    assert I.interactive_available() is False
    monkeypatch.delitem(sys.modules, "IPython")
    assert I.interactive_available() is False


def test_kernel_is_interactive_unless_static_is_set(fake_kernel, monkeypatch):
    pytest.importorskip("ipywidgets")
    assert I.interactive_available() is True
    for value in ("1", "true", "YES", "on"):
        monkeypatch.setenv(I.STATIC_ENV, value)
        assert I.interactive_available() is False, value
    for value in ("0", "false", "", "off"):
        monkeypatch.setenv(I.STATIC_ENV, value)
        assert I.interactive_available() is True, value


def test_kernel_without_ipywidgets_is_static(fake_kernel, monkeypatch):
    monkeypatch.setattr(I.importlib.util, "find_spec",
                        lambda name: None if name == "ipywidgets" else object())
    assert I.interactive_available() is False


def test_interactive_argument_is_checked(problem):
    with pytest.raises(TypeError, match="interactive"):
        I.weight_design_control(problem.G, problem.H_m, problem.K, interactive="yes")


def test_forced_widget_without_ipywidgets_says_what_to_install(problem, monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)      # import fails
    with pytest.raises(ImportError, match="ipywidgets"):
        I.spread_control(problem.G, problem.H_m, interactive=True)


# --------------------------------------------------------------------------- (a) weights
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


# --------------------------------------------------------------------------- (b) spread
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


# --------------------------------------------------------------------------- (c) Dahl
def test_dahl_view_reproduces_the_fit(dahl):
    fit, loops = dahl
    for k, record in enumerate(loops):
        view = I.dahl_view(fit.model, record)
        assert view.discard == 1000
        assert view.rms_percent == pytest.approx(fit.rms_percent[k], rel=1e-12)
        assert view.max_percent == pytest.approx(fit.max_percent[k], rel=1e-12)
        np.testing.assert_allclose(view.x_model, fit.x_model[k], rtol=0, atol=1e-12)
    # a (v, x) pair and the model's fields as a dict give the same view
    record = loops[-1]
    fields = {f: getattr(fit.model, f) for f in fit.model.__dataclass_fields__}
    pair = I.dahl_view(fields, (record.u_c_V, record.v_y_V))
    assert pair.rms_percent == pytest.approx(fit.rms_percent[-1], rel=1e-12)


@pytest.mark.parametrize("name, change", [("g_a", lambda g: 1.05 * g),
                                          ("beta2", lambda b: 1.5 * b),
                                          ("x0", lambda x0: x0 + 0.05)])
def test_perturbed_dahl_parameters_fit_worse(dahl, name, change):
    fit, loops = dahl
    perturbed = replace(fit.model, **{name: change(getattr(fit.model, name))})
    rms = np.array([I.dahl_view(perturbed, record).rms_percent for record in loops])
    # the fit minimises the pooled RMS of the four loops (one loop alone may gain)
    assert np.sqrt(np.mean(rms ** 2)) > fit.pooled_rms_percent + 0.05


def test_dahl_arguments_are_checked(dahl):
    fit, loops = dahl
    with pytest.raises(TypeError, match="loop"):
        I.dahl_view(fit.model, loops[0].u_c_V)
    with pytest.raises(ValueError, match="loop"):
        I.dahl_view(fit.model, (np.arange(10.0), np.arange(9.0)))
    with pytest.raises(ValueError, match="discard"):
        I.dahl_view(fit.model, loops[0], discard=loops[0].u_c_V.size)
    with pytest.raises(TypeError, match="model_params"):
        I.dahl_view("bliman_sorine", loops[0])
    with pytest.raises(ValueError, match="gamma"):
        I.dahl_view({"gamma": 1.0}, loops[0])


def test_dahl_figure(dahl):
    fit, loops = dahl
    view = I.dahl_view(fit.model, loops[-1])
    fig = I.draw_dahl(view)
    ax_loop, ax_err = fig.axes
    assert text_overlaps(fig) == []
    assert ax_loop.get_xlabel() == "u_c (amplifier input) [V]"
    assert ax_loop.get_ylabel() == "v_y (sensor) [V]"
    assert ax_err.get_ylabel() == "model - measured [% of stroke]"
    assert f"RMS {view.rms_percent:.3f} %" in ax_err.get_title()
    # the error curve is the residual after the first period, against time in s
    t, r = ax_err.lines[0].get_data()
    assert t[0] == pytest.approx(0.1) and np.sqrt(np.mean(r ** 2)) == pytest.approx(
        view.rms_percent, rel=1e-12)


# --------------------------------------------------------------------------- entry points
def test_entry_points_headless_return_static_figures(problem, dahl, headless):
    G, H_m, _, _, K = problem
    fit, loops = dahl
    before = plt.get_fignums()
    figs = [I.weight_design_control(G, H_m, K),
            I.spread_control(G, H_m, SPREAD_GRID, spread=0.03),
            I.dahl_control(fit.model, loops[0])]
    assert all(isinstance(f, Figure) for f in figs)
    assert plt.get_fignums() == before       # pyplot does not show them a second time
    assert "μ = 1.448" in figs[0].get_suptitle()           # the published weights
    assert "±3 %" in figs[1].axes[0].get_title()
    assert len(figs[2].axes) == 2


def test_static_figure_shows_as_png_in_ipython(dahl, headless, monkeypatch):
    """Without a resolved pyplot backend (MPLBACKEND=Agg) IPython would show '<Figure ...>'."""
    ipython = pytest.importorskip("IPython")
    from IPython.core.formatters import PNGFormatter
    png = PNGFormatter()
    shell = types.SimpleNamespace(
        display_formatter=types.SimpleNamespace(formatters={"image/png": png}))
    monkeypatch.setattr(ipython, "get_ipython", lambda: shell)
    fit, loops = dahl
    fig = I.dahl_control(fit.model, loops[0])
    assert png(fig).startswith(b"\x89PNG")
    # a formatter already there (the inline backend's) is kept
    mine = png.lookup_by_type(Figure)
    png.for_type(Figure, lambda f: b"\x89PNG inline")
    I.dahl_control(fit.model, loops[0])
    assert png(fig) == b"\x89PNG inline" and png.lookup_by_type(Figure) is not mine


@pytest.fixture
def widgets():
    return pytest.importorskip("ipywidgets")


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

    box.controls["omega_e"].value = 2 * PUBLISHED["omega_e"]       # as a person moving it
    assert panel.view.params["omega_e"] == pytest.approx(2 * PUBLISHED["omega_e"])
    assert panel.view.crossing_He / first_crossing == pytest.approx(2.0, rel=5e-3)
    assert bytes(panel.image.value) != first_image
    assert "NP ||H_e S||" in panel.summary.value and panel.status.value == ""

    box.controls["redesign"].click()
    menu = box.controls["controller"]
    assert menu.value.startswith("re-designed K") and len(menu.options) == 2
    assert "μ_RP" in box.redesign_result.value
    assert panel.view.controller == menu.value
    K_new, mu = I.redesign(G, H_m, panel.values(), max_iter=1)
    assert panel.view.mu_RP == pytest.approx(mu, rel=1e-9)
    assert f"{mu:.3f}" in box.redesign_result.value
    menu.value = menu.options[0]                                    # back to the given K
    assert panel.view.controller == menu.options[0]
    assert panel.view.norm_He_S > published_analysis.norm_He_S      # faster template on S


def test_spread_widget_follows_its_slider(problem, widgets):
    box = I.spread_control(problem.G, problem.H_m, SPREAD_GRID, interactive=True)
    slider = box.controls["spread"]
    assert (slider.min, slider.max, slider.value) == (0.5, 10.0, 5.0)
    assert box.panel.view.n_unstable == 42
    slider.value = 3.0
    assert box.panel.view.spread == pytest.approx(0.03) and box.panel.view.n_unstable == 0
    assert "0 unstable" in box.panel.summary.value


def test_dahl_widget_follows_its_sliders(dahl, widgets):
    fit, loops = dahl
    box = I.dahl_control(fit.model, loops[-1], interactive=True)
    panel = box.panel
    assert set(box.controls) == set(I.DAHL_SLIDER_PARAMETERS)
    assert panel.view.rms_percent == pytest.approx(fit.rms_percent[-1], rel=1e-12)
    box.controls["g_a"].value = 1.1 * fit.model.g_a
    assert panel.view.model.g_a == pytest.approx(1.1 * fit.model.g_a)
    assert panel.view.rms_percent > fit.rms_percent[-1] + 0.5
    worse = panel.view
    # a model too weakly damped to invert: the message is shown, the last view kept
    box.controls["alpha1"].value = box.controls["alpha1"].min
    assert "NotInvertibleError" in panel.status.value
    assert panel.view is worse
