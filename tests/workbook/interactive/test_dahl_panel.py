"""The Dahl control (notebook 03): its callback on the workbook's fit and the Case I loops, its
figure, the static fallback and the widget."""

import warnings
from dataclasses import replace

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure

from figure_checks import text_overlaps
from piezolib.hysteresis import FitWarning
from piezolib.problem import stage_data
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.workbook import interactive as I


@pytest.fixture(scope="module")
def dahl():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FitWarning)    # alpha's not identifiable: known, notebook 03
        fit = workbook_dahl_fit()
    return fit, list(stage_data.load_hysteresis_loops().values())


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


def test_headless_entry_point_returns_the_static_figure(dahl, headless):
    fit, loops = dahl
    before = plt.get_fignums()
    fig = I.dahl_control(fit.model, loops[0])
    assert isinstance(fig, Figure)
    assert plt.get_fignums() == before       # pyplot does not show it a second time
    assert len(fig.axes) == 2


def test_dahl_widget_follows_its_sliders(dahl, widgets):
    fit, loops = dahl
    box = I.dahl_control(fit.model, loops[-1], interactive=True)
    panel = box.panel
    assert set(box.controls) == set(I.DAHL_SLIDER_PARAMETERS)
    assert panel.view.rms_percent == pytest.approx(fit.rms_percent[-1], rel=1e-12)
    box.controls["g_a"].value = 1.1 * fit.model.g_a
    assert panel.wait(30)
    assert panel.view.model.g_a == pytest.approx(1.1 * fit.model.g_a)
    assert panel.view.rms_percent > fit.rms_percent[-1] + 0.5
    worse = panel.view
    # a model too weakly damped to invert: the message is shown, the last view kept
    box.controls["alpha1"].value = box.controls["alpha1"].min
    assert panel.wait(30)
    assert "NotInvertibleError" in panel.status.value
    assert panel.view is worse
