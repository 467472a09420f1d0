"""The virtual stage's calibration and identification checks (notebook 01), on small inputs."""

import control as ct
import numpy as np
import pytest

from piezolib.problem import paper, stage_data
from piezolib.problem import stage_identification as sid
from piezolib.problem.stage import VirtualStage


@pytest.fixture(scope="module")
def stage():
    return VirtualStage(seed=0)


def _two_pairs(scale=1.0):
    """A model with two lightly damped pole pairs at 10 and 100 rad/s (times ``scale``)."""
    w1, w2 = 10.0 * scale, 100.0 * scale
    return ct.tf([w1 ** 2 * w2 ** 2], np.polymul([1.0, 0.2 * w1, w1 ** 2], [1.0, 0.1 * w2, w2 ** 2]))


def test_pole_pair_frequencies_in_hz():
    assert sid.pole_pair_frequencies_Hz(_two_pairs()) == pytest.approx(
        [10 / (2 * np.pi), 100 / (2 * np.pi)])


def test_compare_with_truth_accepts_one_percent_and_refuses_five():
    truth = _two_pairs()
    close = sid.compare_with_truth(_two_pairs(1.01), truth)
    assert all(close.checks.values())
    assert close.f_Hz == pytest.approx(1.01 * sid.pole_pair_frequencies_Hz(truth))
    far = sid.compare_with_truth(_two_pairs(1.05), truth)
    assert far.checks == {"DC gain within 2% of the truth": True,
                          "natural frequencies within 2% of the truth": False}
    assert far.table.shape == (5, 3)


def test_compare_with_truth_refuses_models_of_other_orders():
    with pytest.raises(ValueError, match="pole pairs"):
        sid.compare_with_truth(_two_pairs(), ct.tf([100.0], [1.0, 1.0, 100.0]))


def test_coefficient_table_of_the_published_plant_is_eq4():
    table = sid.coefficient_table(paper.plant())
    assert list(table.index) == [f"a{i}" for i in range(6)] + [f"b{i}" for i in range(4)]
    assert np.abs(table["relative error"]).max() < 1e-9
    assert table["published (eq. 4)"].tolist() == list(paper.PLANT.a + paper.PLANT.b)


def test_case_i_calibration_holds_on_the_recorded_loops(stage):
    calibration = sid.case_I_calibration(stage, stage_data.load_hysteresis_loops())
    assert all(calibration.checks.values())
    assert calibration.widest == 40.0
    assert list(calibration.table.columns) == ["paper Case I [%]", "virtual stage [%]",
                                               "chord gain of the loop"]


def test_the_truth_validates_the_validation_chirp_up_to_the_noise(stage):
    chirps = {which: stage_data.load_chirp(which) for which in ("identification", "validation")}
    assert all(sid.chirp_checks(chirps, stage).values())
    assert sid.chirp_settings_table(chirps).shape[1] == 2
    validation = sid.validate_on_chirp(stage.small_signal_model(), chirps["validation"], stage)
    assert validation.fit_percent == validation.fit_truth_percent      # the model is the truth
    assert 0.9 < validation.noise_ratio < 1.1                          # the rest is sensor noise


@pytest.mark.parametrize("call", [
    lambda st: sid.case_I_calibration(st, {}),
    lambda st: sid.case_I_calibration(object(), {10.0: None}),
    lambda st: sid.chirp_checks({"x": object()}, st),
    lambda st: sid.identify_chirp("chirp", st),
    lambda st: sid.validate_on_chirp(paper.plant(), None, st),
])
def test_bad_input_names_the_argument(call, stage):
    with pytest.raises((TypeError, ValueError), match="loops|stage|chirp"):
        call(stage)
