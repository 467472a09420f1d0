"""Tracking over a model set: members run at once, unstable ones named, each member as alone."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib.hysteresis import PIModel
from piezolib.problem import paper
from piezolib.problem.stage import VirtualStage
from piezolib.uncertainty import model_set, random_model_set, unstable_members
from piezolib.uncertainty.modelset import ModelSet
from piezolib.workbook import experiments
from piezolib.workbook.figures.tracking import tracking_over_set as figure
from piezolib.workbook.set_tracking import tracking_over_set
from piezolib.workbook.two_dof import two_dof_feedforward

STAGE = VirtualStage(seed=4)
# a static feedforward through the PI model's exact inverse: one play of zero width, gain 1/G(0)
G0 = float(ct.dcgain(paper.plant()))
MODEL = PIModel(thresholds=(0.0,), weights=(G0,), x0=0.0)
K = ct.tf([0.02, 400.0], [1.0, 0.0]) * ct.tf([1.0], [1 / 6000.0, 1.0])   # PI with roll-off [V/V]


def members_with(offsets):
    return ModelSet(STAGE.settings.plant, 0.05, 0, np.asarray(offsets, dtype=float))


def test_each_member_runs_as_its_stage_would_alone():
    """Member k's error equals Case III run on member k's stage by itself, float for float."""
    mset = random_model_set(STAGE.settings.plant, 0.05, 5, seed=7)
    res = tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[20.0, 50.0])
    batch = STAGE.over_model_set(mset)
    for k in (0, 3):
        for f in (20.0, 50.0):
            v_r = experiments.tracking_reference(f, experiments.tracking_periods(f))[1]
            alone = experiments.run_case("III", batch.stages[k], v_r, MODEL, K)
            assert res.errors.loc[k, f] == alone.tracking_error_percent(f, range_um=12.0)


def test_unstable_members_are_named_and_not_run():
    """The open loop: the set's unstable plants; the closed loop: too much gain for some."""
    mset = model_set(STAGE.settings.plant, 0.05)
    subset = members_with(mset.offsets[np.r_[unstable_members(mset)[:3], 0:700:50]])
    open_loop = tracking_over_set(STAGE, subset, MODEL, case="II", frequencies_Hz=[50.0])
    np.testing.assert_array_equal(open_loop.unstable, unstable_members(subset))
    assert open_loop.unstable.size > 0 and open_loop.spectral_radius is None
    assert open_loop.errors.loc[open_loop.unstable].isna().all().all()
    assert open_loop.errors.loc[open_loop.stable].notna().all().all()
    hot = 14 * K                                       # near the nominal loop's limit
    closed = tracking_over_set(STAGE, subset, MODEL, hot, frequencies_Hz=[50.0])
    assert 0 < closed.unstable.size < subset.size
    assert (closed.spectral_radius[closed.unstable] >= 1).all()
    assert (closed.spectral_radius[closed.stable] < 1).all()


def test_the_nominal_member_tracks_like_the_nominal_stage():
    """The member with zero offsets differs from the stage only by the rounding of its ZOH
    model (10^-13): its error agrees with the nominal stage's to far below the noise."""
    res = tracking_over_set(STAGE, members_with(np.zeros((1, 6))), MODEL, K, frequencies_Hz=[50.0])
    v_r = experiments.tracking_reference(50.0, experiments.tracking_periods(50.0))[1]
    nominal = experiments.run_case("III", STAGE, v_r, MODEL, K)
    assert res.errors.loc[0, 50.0] == pytest.approx(
        nominal.tracking_error_percent(50.0, range_um=12.0), rel=1e-6)


def test_summary_and_figure():
    mset = random_model_set(STAGE.settings.plant, 0.05, 6, seed=1)
    ff = two_dof_feedforward(paper.plant(), MODEL, STAGE.fs)
    results = {"III": tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[10.0, 50.0]),
               "IV": tracking_over_set(STAGE, mset, ff, K, frequencies_Hz=[10.0, 50.0])}
    s = results["IV"].summary()
    assert list(s.index) == [10.0, 50.0]
    assert (s["worst [%]"] >= s["95th percentile [%]"]).all()
    assert (s["95th percentile [%]"] >= s["median [%]"]).all()
    assert (results["IV"].errors.median() < results["III"].errors.median()).all()
    fig = figure(results)
    assert fig.get_label() == "extra_tracking_over_set"
    assert len(fig.axes[0].get_legend().get_texts()) == 3     # two results and the goals


def test_saturation_is_counted_not_warned():
    mset = random_model_set(STAGE.settings.plant, 0.05, 2, seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[50.0], amplitude_um=40.0)
    assert (res.saturated > 0).all().all()


def test_overview_and_goal_shares_count_the_stable_members():
    mset = random_model_set(STAGE.settings.plant, 0.05, 4, seed=2)
    res = tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[10.0, 50.0])
    line = res.overview()
    assert line["members run"] == 4 - len(res.unstable)
    assert line["worst at 50 Hz [%]"] == res.errors[50.0].max()
    shares = res.goal_shares({"peak_to_peak_error_pct_up_to_10Hz": 100.0,
                              "peak_to_peak_error_pct_at_50Hz": 0.0})
    assert shares["meets < 100 % up to 10 Hz [%]"] == 100.0
    assert shares["meets < 0 % at 50 Hz [%]"] == 0.0 == shares["meets both [%]"]
