"""Notebook 04's closing findings."""

import numpy as np
import pandas as pd
import pytest

from piezolib import paper
from piezolib.problem import weighting
from piezolib.workbook.weighting_findings import findings


def _met(S_dB):
    table = pd.DataFrame([("our K", False, True, S_dB, 4.0, 372.0)],
                         columns=["controller", "|S| < 1/|H_e|", "|T| < 1/|H_y|",
                                  "||S|| [dB]", "||T|| [dB]", "bandwidth of T [Hz]"])
    return weighting.TemplatesMet({"our K": None}, table, {"our K": True})


def test_findings_say_what_fails():
    templates = weighting.template_asymptotes(paper.ERROR_WEIGHT, paper.OUTPUT_WEIGHT)
    entries = weighting.Eq16Entries(pd.DataFrame({"max relative error": [1e-10, np.nan],
                                                  "max |P| (zero entries)": [np.nan, 0.0]}),
                                    np.logspace(0, 6, 50))
    lines = findings(entries, 3e-11, templates, paper.ERROR_WEIGHT, _met(7.0))
    assert len(lines) == 3
    assert "(50 frequencies)" in lines[0] and "1e-10" in lines[0]
    assert f"{templates.crossing_rad_s:.4g} rad/s" in lines[1]
    assert "|S| under 1/|H_e| **no**" in lines[2]
    assert "(limit 6 dB: **not met**)" in lines[2] and "(limit 3.5 dB: **not met**)" in lines[2]


def test_findings_name_a_wrong_argument():
    with pytest.raises(TypeError, match="entries"):
        findings(None, 0.0, None, paper.ERROR_WEIGHT, _met(1.0))
