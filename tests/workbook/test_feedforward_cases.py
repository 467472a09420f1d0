"""The Dahl feedforward on the model, Case II on the virtual stage, the cross-check."""

from dataclasses import replace
from types import SimpleNamespace

import pandas as pd
import pytest

from piezolib import hysteresis as hy
from piezolib import paper
from piezolib.problem import hysteresis_choice as hc
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments
from piezolib.workbook import feedforward_cases as fc

DAHL = hy.DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0, g_a=1.28,
                    form="bliman_sorine", x0=-0.15, start="rest")
PRINTED = hy.DahlModel(alpha1=80.0, alpha2=900.0, beta1=0.0, beta2=0.5, gamma_a=30.0,
                       g_a=0.93, form="printed")
STAGE = VirtualStage(seed=0)


def test_the_feedforward_makes_the_model_an_identity():
    result = fc.feedforward_on_model(DAHL, PRINTED)
    assert result.identity and all(result.checks.values())
    assert result.x_r.shape == result.x_comp.shape == result.t.shape
    assert result.numbers.size == 4 and "V" in result.note
    # a round-off error is stated as a bound: its digits differ between BLAS kernels
    assert result.note.startswith(f"max |x - x_r| < {fc.ROUND_OFF_V:.0e} V (round-off)")
    assert "= 2.0e-09 V" in replace(result, error_V=2e-9, error_paper_form_V=0.0).note
    with pytest.raises(TypeError, match="paper_form"):
        fc.feedforward_on_model(DAHL, "printed")


@pytest.fixture(scope="module")
def case():
    loops = {A: STAGE.run(experiments.table4_reference(A)[1])
             for A in paper.HYSTERESIS_TEST["actuator_amplitudes_V"]}
    return fc.case_II(loops, DAHL, PRINTED, stage=STAGE)


def test_case_II_measures_as_table4(case):
    run = case.runs[fc.WORKBOOK_MODEL][40.0]
    assert case.percent[fc.WORKBOOK_MODEL][40.0] == pytest.approx(
        experiments.table4_measure(run.v_r_V, run.v_y_V, discard_periods=2).percent)
    assert list(case.table["paper Case II"]) == list(paper.table4().loc["case_II"])
    assert fc.PER_AMPLITUDE not in case.percent
    assert set(case.checks) and set(case.actuator_range_V) == set(case.case_I)


def test_case_II_checks_fail_when_the_contrast_is_better(case):
    worse = replace(case, percent={**case.percent,
                                   fc.PRINTED_MODEL: {A: 0.0 for A in case.case_I}})
    assert not worse.checks[
        "workbook model: less hysteresis than eq. 10-13 as printed at every amplitude"]


def test_cross_check_on_the_stage(case):
    comparison = hc.ModelComparison(None, None, {hc.PI_NAME: PRINTED, hc.DAHL_NAME: DAHL}, {},
                                    pd.DataFrame())
    cross = fc.cross_check_on_stage(comparison, case)
    assert cross.on_stage.index.tolist() == [hc.PI_NAME, hc.DAHL_NAME]
    checks = cross.checks
    assert checks["every feedforward is exact on its own model (RMS < 1e-8 %)"]
    assert checks["the workbook Dahl feedforward on the stage is the 40 V Case II"]
    with pytest.raises(TypeError, match="case"):
        fc.cross_check_on_stage(comparison, SimpleNamespace())
    with pytest.raises(TypeError, match="loops"):
        fc.case_II([], DAHL, PRINTED)
