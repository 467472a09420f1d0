"""Tracking over a model set: members run at once, unstable ones named, each member as alone."""

import warnings

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib.hysteresis import PIModel
from piezolib.problem import paper
from piezolib.problem.stage import VirtualStage
from piezolib.problem.stage_batch import StageBatch
from piezolib.robust import controller_sos
from piezolib.uncertainty import model_set, random_model_set, unstable_members
from piezolib.uncertainty.modelset import ModelSet
from piezolib.workbook import experiments, set_tracking
from piezolib.workbook import study as studies
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
    batch = StageBatch.over_model_set(STAGE, mset)
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


# --------------------------------------------------------------------------- a study's set
LABELS = list(set_tracking.CONTROLLER_LABELS.values())


def small_set(offsets=((0,) * 6, (1,) * 6, (-1,) * 6)):
    """A SetTrackingStudy of three grid members and two draws, a PI-type K in its place."""
    Kd = ct.sample_system(K, 1 / STAGE.fs, "tustin")
    sections = {LABELS[0]: controller_sos(Kd, name="ours"),
                LABELS[1]: controller_sos(2 * Kd, name="other")}
    study = studies.Study().replace(name="small", experiments={"frequencies_Hz": (10.0, 50.0)})
    return set_tracking.SetTrackingStudy(
        study, STAGE, paper.plant(), MODEL, MODEL, sections, {LABELS[0]: K, LABELS[1]: 2 * K},
        members_with(offsets), random_model_set(STAGE.settings.plant, 0.05, 2, seed=1), 0)


def test_the_boundary_check_recomputes_the_batched_poles_by_feedback():
    check = small_set().boundary_check(members=2)
    assert all(len(m) == 2 for m in check.members.values())
    assert all(check.checks.values()) and len(check.checks) == 4
    assert max(check.differences().values()) < 1e-9          # the same poles, two ways
    bad = set_tracking.BoundaryCheck(check.members, check.batched,
                                     {k: v + 2.0 for k, v in check.by_feedback.items()})
    assert not any(bad.checks.values())                       # a check that can fail
    assert "nearest the boundary" in str(check)


@pytest.fixture(scope="module")
def runs():
    """The runs of notebook 12 on the small set (one Case III result stands for every run)."""
    over = small_set()
    iii = iv = tracking_over_set(STAGE, over.grid, MODEL, K, frequencies_Hz=[10.0, 50.0])
    draws = tracking_over_set(STAGE, over.draws, MODEL, K, frequencies_Hz=[10.0, 50.0])
    grid = {set_tracking.CASE_II: iii, f"Case III, {LABELS[0]}": iii,
            f"Case III, {LABELS[1]}": iii, f"Case IV (Dahl), {LABELS[0]}": iv,
            f"Case IV (PI), {LABELS[0]}": iv}
    return set_tracking.SetTrackingRuns(over, grid, {f"Case III, {LABELS[0]}": draws}, 1.0)


STABILITY = pd.DataFrame({label: {"exact parametric margin, continuous loop [%]": 4.5,
                                  "unstable of 3, continuous loop": 0,
                                  "unstable of 3, sampled, no delay": 0,
                                  "unstable of 3, sampled, delay 1": 1,
                                  "unstable of 2 random, sampled, delay 1": 0,
                                  "grid spread, sampled, delay 1 [%]": 3.0} for label in LABELS})


def test_the_runs_tables_count_the_members(runs):
    overview = runs.overview()
    assert list(overview.index.levels[0]) == ["grid (3)", "random (2)"] and len(overview) == 6
    assert (overview["members run"] == 3).iloc[:5].all()
    worst = runs.worst_members(count=2)
    assert len(worst) == 2 and worst["error [%]"].is_monotonic_decreasing
    assert list(worst.columns[-6:]) == [f"q{i}" for i in range(6)]
    assert runs.by_damping()["members"].sum() == 3
    assert runs.goal_shares().shape[0] == 6
    assert set(runs.nominal_errors()) == set(runs.over_grid) and runs.worst_frequency == 50.0
    assert "0 unstable members ()" in runs.unstable_lines()
    assert runs.samples == sum(r.samples for r in runs.over_grid.values()) + \
        runs.over_draws[f"Case III, {LABELS[0]}"].samples


def test_the_claims_follow_the_notebooks_order(runs):
    claims = runs.claims(STABILITY)
    assert len(claims) == 2 * 2 + 5 * 2 * 2 + 5
    assert claims[0]["quantity"] == ("our deployed K: members of the 3 set with an unstable "
                                     "sampled loop (delay 1)")
    assert (claims[0]["ours"], claims[0]["expect"]) == (1, "differs")
    assert claims[-1]["quantity"].endswith("stable members meeting both goals")
    assert [c["quantity"] for c in claims[4:6]] == [
        f"{set_tracking.CASE_II}: median tracking error at 10 Hz",
        f"{set_tracking.CASE_II}: worst tracking error at 10 Hz"]


def test_the_reference_checks_can_fail(runs):
    checks = runs.checks(STABILITY)
    assert all(isinstance(v, bool) for v in checks.values()) and len(checks) == 8
    assert all(checks[f"{label}: the sampled loop with delay 1 loses members the continuous "
                      "loop keeps"] for label in LABELS)
    kept = STABILITY.copy()
    kept.loc["unstable of 3, sampled, delay 1"] = 0
    assert not any(v for k, v in runs.checks(kept).items() if "loses members" in k)
    lines = runs.findings(STABILITY)
    assert lines[0].startswith(f"{LABELS[0]}: exact parametric margin of the continuous loop ±4.5 %")
    assert any("stricter goal" in line for line in lines)


def test_a_prebuilt_batch_gives_the_same_runs():
    mset = random_model_set(STAGE.settings.plant, 0.05, 4, seed=2)
    alone = tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[50.0])
    shared = tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[50.0],
                               batch=StageBatch.over_model_set(STAGE, mset))
    pd.testing.assert_frame_equal(alone.errors, shared.errors)
    pd.testing.assert_frame_equal(alone.saturated, shared.saturated)
    with pytest.raises(ValueError, match="one member per member of mset"):
        tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[50.0],
                          batch=StageBatch.of_seeds(STAGE, [1]))
    with pytest.raises(TypeError, match="batch must be a StageBatch"):
        tracking_over_set(STAGE, mset, MODEL, K, frequencies_Hz=[50.0], batch=STAGE)
