"""Cases I-III with two Case III controllers on a small study (one frequency, one amplitude)."""

import pytest

from piezolib.hysteresis import DahlModel
from piezolib.workbook import case_comparison, pipeline, study


@pytest.fixture(scope="module")
def compared():
    small = study.Study().replace(name="small", experiments={
        "frequencies_Hz": (50.0,), "amplitudes_V": (20.0,), "noise_seeds": 2})
    ours = pipeline.study_sections("reference")["K_ours"]
    dahl = DahlModel(alpha1=236.0, alpha2=335.4, beta1=0.0, beta2=2.56, gamma_a=30.0, g_a=1.28,
                     form="bliman_sorine", x0=-0.15, start="rest")
    return case_comparison.case_III_comparison(small, {"A": ours, "B": ours, "none": None},
                                               model=dahl)


def test_one_row_per_controller_and_cases_I_II_once(compared):
    assert list(compared.tracking.index) == ["Case I", "Case II", "Case III, A", "Case III, B"]
    assert list(compared.tracking.columns) == [50.0]
    assert list(compared.hysteresis.index) == ["A", "B"]
    # the same controller twice: the same Case III numbers
    assert compared.tracking.loc["Case III, A", 50.0] == compared.tracking.loc["Case III, B", 50.0]
    assert compared.tracking.loc["Case III, A", 50.0] < compared.tracking.loc["Case I", 50.0]


@pytest.mark.parametrize("controllers", [[], {}, {"none": None}])
def test_bad_controllers(controllers):
    with pytest.raises(TypeError, match="controllers"):
        case_comparison.case_III_comparison(study.Study(), controllers)
