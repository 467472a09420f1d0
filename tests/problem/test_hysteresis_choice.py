"""The Dahl candidates compared and the model chosen (notebook 03, sections 3 and 6).

The full-size fits run in notebook 03; here every result type is built from small
synthetic loops and fits, so that each statement is seen holding and failing.
"""

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from piezolib import hysteresis as hy
from piezolib import paper, signals
from piezolib.problem import hysteresis_choice as hc
from piezolib.problem.hysteresis_fits import CASE_I_CANDIDATES, WORKBOOK_DAHL

FS = paper.SAMPLING_FREQUENCY_HZ
AMPLITUDES = paper.HYSTERESIS_TEST["actuator_amplitudes_V"]
WORKBOOK = hy.DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0,
                        g_a=1.28, form="bliman_sorine", x0=-0.15, start="rest")


def _loops():
    """Four triangles of three 10 Hz periods: v_y back at 0 at every lower reversal."""
    out = {}
    for A in AMPLITUDES:
        t, u = signals.triangle(A / paper.AMPLIFIER_GAIN, 10.0, FS, periods=3)
        out[A] = SimpleNamespace(u_c_V=u, v_y_V=0.9 * u)
    return out


def _fit(model, rms, x_model, mask=(0, 0, 0, 0)):
    rms = np.asarray(rms, dtype=float)
    return hy.DahlFit(model=model, x_model=x_model, residuals=[], rms=rms / 100,
                      rms_percent=rms, max_percent=2 * rms, initial=model,
                      result=SimpleNamespace(active_mask=np.array(mask)))


def _case_I(bs_offset=0.1):
    loops = _loops()
    fits = {}
    for k, key in enumerate(CASE_I_CANDIDATES):
        form, offset, start = key
        x0 = (WORKBOOK.x0 if form == "bliman_sorine" else 0.001) if offset else 0.0
        model = replace(WORKBOOK, form=form, start=start, x0=x0)
        x_model = [rec.v_y_V + (bs_offset if key == hc.BLIMAN_SORINE_PAPER else 0.0)
                   for rec in loops.values()]
        rms = [1.0, 2.0, 0.9, 2.0] if key == WORKBOOK_DAHL else [3.0 + k] * 4
        mask = (0, 1, 0, 0) if key == hc.BLIMAN_SORINE_PAPER else (0, 0, 0, 0)
        if key == hc.PAPER_FORM:
            model = replace(model, g_a=0.93, alpha1=2 * paper.DAHL.alpha1,
                            alpha2=4 * paper.DAHL.alpha2)
        fits[key] = _fit(model, rms, x_model, mask)
    return hc.CaseIFits(loops, fits, hy.choose_fit(fits), fits[WORKBOOK_DAHL])


def test_candidate_label():
    assert hc.candidate_label(WORKBOOK_DAHL) == "bliman-sorine, offset, rest"
    with pytest.raises(TypeError, match="key"):
        hc.candidate_label("printed")


def test_the_rule_picks_the_smallest_pooled_rms_and_the_checks_hold():
    case_I = _case_I()
    assert case_I.choice == WORKBOOK_DAHL
    assert case_I.amplitudes == AMPLITUDES and len(case_I.fit_data) == 4
    table = case_I.parameter_table()
    assert list(table.index) == [hc.candidate_label(k) for k in CASE_I_CANDIDATES]
    assert table.loc["bliman-sorine, offset, rest", "pooled RMS %"] == pytest.approx(
        np.sqrt(np.mean(np.array([1.0, 2.0, 0.9, 2.0]) ** 2)))
    assert all(case_I.selection_checks.values()) and all(case_I.gain_checks.values())


def test_a_workbook_fit_on_a_bound_fails_its_check():
    case_I = _case_I()
    on_bound = replace(case_I, workbook=replace(case_I.workbook,
                                                result=SimpleNamespace(active_mask=np.ones(4))))
    checks = on_bound.selection_checks
    assert not checks["the workbook model is an interior optimum"]


def test_lower_reversals_hold_and_fail():
    assert all(hc.lower_reversals(_case_I()).checks.values())
    tips = hc.lower_reversals(_case_I(bs_offset=0.0))       # the Dahl fit at 0, not at +h
    assert not all(tips.checks.values())
    np.testing.assert_allclose(tips.table["stage: x at v = 0 [V]"], 0.0, atol=1e-12)


def test_start_effect_and_implied_scale():
    case_I = _case_I()
    effect = hc.start_effect(case_I)
    assert list(effect.table.columns) == [f"{A:.0f} V" for A in AMPLITUDES]
    assert (effect.table.values >= 0).all()
    scale = hc.implied_unit_scale(case_I)
    np.testing.assert_allclose(scale["printed, no offset, virgin"], 2.0)


def test_per_amplitude_checks_fail_when_a_single_loop_fits_worse():
    table = pd.DataFrame({"joint fit RMS %": [1.0, 2.0], "fit per amplitude RMS %": [0.2, 0.3],
                          "g_a per amplitude": [1.1, 1.4], "x0 per amplitude [V]": [0.0, -0.5]})
    assert all(hc.PerAmplitudeFits({}, table).checks.values())
    worse = table.assign(**{"fit per amplitude RMS %": [0.2, 2.5]})
    assert not all(hc.PerAmplitudeFits({}, worse).checks.values())


def test_validation_checks():
    index = pd.MultiIndex.from_product([[hc.PI_NAME, hc.DAHL_NAME, hc.PRINTED_NAME], ["a"]],
                                       names=["model", "record"])
    table = pd.DataFrame({"max %": [1.0, 3.0, 8.0], "pooled RMS %": [0.4, 1.4, 3.8]},
                         index=index)
    comparison = hc.ModelComparison(SimpleNamespace(rms_percent=np.ones(4)), _case_I().workbook,
                                    {}, {}, table)
    assert comparison.pooled.to_dict() == {hc.PI_NAME: 0.4, hc.DAHL_NAME: 1.4,
                                           hc.PRINTED_NAME: 3.8}
    assert all(comparison.validation_checks.values())
    assert list(comparison.case_I_rms.columns) == [hc.PI_NAME, hc.DAHL_NAME]
    swapped = replace(comparison, validation=table.assign(**{"pooled RMS %": [1.5, 1.4, 3.8]}))
    assert not all(swapped.validation_checks.values())


@pytest.mark.parametrize("function", [hc.lower_reversals, hc.start_effect,
                                      hc.implied_unit_scale, hc.per_amplitude_fits,
                                      hc.compare_models])
def test_a_wrong_case_I_is_named(function):
    with pytest.raises(TypeError, match="case_I"):
        function({"fits": {}})
