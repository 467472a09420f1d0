"""Notebook 08's control stages (piezolib.workbook.your_stage_control): what they refuse and
how they pass on a stage not run (the full-size design and experiments run in the notebook)."""

import control as ct
import numpy as np
import pytest

from piezolib.workbook import your_stage as own
from piezolib.workbook import your_stage_control as own_control

PLANT = ct.tf([800.0], [1.0, 1000.0])           # first order, DC gain 0.8, 159 Hz


def test_the_stages_that_need_the_plant_pass_a_skip_on():
    skipped = own.Skipped(own.NO_PLANT_NOTE)
    assert own_control.design_for_loop(skipped, skipped, {}, {}, {}, order=6, d_order=2,
                                       iterations=1, fs=1e4, delay_samples=1) is skipped
    assert own_control.verify_design(skipped, skipped, skipped) is skipped
    assert own_control.run_experiments(skipped, None, seed=1, noise_rms_V=0.0,
                                       amplitudes_V=(1.0,), periods=2, frequencies_Hz=(1.0,),
                                       amplitude_um=1.0, delay_samples=1,
                                       loop_rate_Hz=1e4) is skipped


def test_design_for_loop_refuses_a_rolloff_above_the_loops_nyquist_frequency():
    model = own.Identification(None, None, PLANT, np.zeros(1), 100.0, 100.0, 70.0, 0.0,
                               (np.array([1.0]), np.array([1.0 + 0j])))
    H_e = dict(low_frequency_bound=0.003, high_frequency_bound=2.0, bandwidth_rad_s=1260.0)
    H_y = dict(low_frequency_bound=1.5, high_frequency_bound=1e-4, bandwidth_rad_s=7500.0)
    rolloff = dict(hf_gain=10.0, lf_gain=1e4, frequency=4e4, order=2)     # pi 1e4 = 31416
    with pytest.raises(ValueError, match="rolloff"):
        weight = object.__new__(own.UncertaintyWeight)     # not read: the roll-off fails first
        own_control.design_for_loop(model, weight, H_e, H_y, rolloff, order=6, d_order=2,
                                    iterations=1, fs=1e4, delay_samples=1)
