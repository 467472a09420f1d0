"""The Table 4 Case I experiment and the calibration of the stage's hysteresis on it."""

import numpy as np
import pytest

from piezolib import paper
from piezolib.problem import stage_calibration as C
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_hysteresis import CALIBRATED_HYSTERESIS


def test_calibration_rederives_the_stored_parameters():
    law, achieved = C.calibrate_hysteresis()
    assert law.density_per_V == pytest.approx(CALIBRATED_HYSTERESIS.density_per_V, rel=1e-3)
    assert law.decay_V == pytest.approx(CALIBRATED_HYSTERESIS.decay_V, rel=1e-3)
    target = paper.table4().loc["case_I"]
    assert all(abs(achieved[A] - target[A]) <= 0.5 for A in achieved)


@pytest.mark.parametrize("targets, match", [({5.0: -1.0}, r"targets\[5.0\]"),
                                            ({-5.0: 1.0}, "targets"),
                                            ({5.0: np.nan}, r"targets\[5.0\]"),
                                            ([1.0], "targets"), ({}, "targets")])
def test_calibration_refuses_impossible_targets(targets, match):
    # a negative target used to be fitted (to whatever least squares found)
    with pytest.raises((TypeError, ValueError), match=match):
        C.calibrate_hysteresis(targets=targets)


def test_calibration_targets_hold_on_the_default_stage():
    got = C.case_I_hysteresis(C.run_case_I(VirtualStage(seed=0)))
    target = paper.table4().loc["case_I"]
    for A, value in got.items():
        assert abs(value - target[A]) <= 0.5, (A, value)
