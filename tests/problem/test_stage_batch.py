"""N virtual stages at once: each member float for float its stage alone, the batch's checks."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib import identification, paper
from piezolib.problem import stage as S
from piezolib.problem.stage_batch import StageBatch, check_seeds
from piezolib.problem.stage_calibration import case_I_input
from piezolib.problem.stage_data import IDENTIFICATION_CHIRP, chirp_input
from piezolib.problem.stage_hysteresis import PlayHysteresis

FS = paper.SAMPLING_FREQUENCY_HZ


@pytest.fixture(scope="module")
def stage():
    return S.VirtualStage(seed=0)


def chirp_u():
    return chirp_input(IDENTIFICATION_CHIRP)[0][:6000]


def saturating_u():
    return np.r_[np.linspace(0, 13, 300), np.linspace(13, -3, 300), np.linspace(-3, 4, 400)]


def members_of(stage, seeds):
    return [stage.replace(seed=s) for s in seeds]


@pytest.mark.parametrize("make_u", [chirp_u, saturating_u])
def test_batch_run_is_each_members_run_exactly(stage, make_u):
    u, seeds = make_u(), [0, 5, 2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        batch = StageBatch.of_seeds(stage, seeds).run(u)
        single = [st.run(u) for st in members_of(stage, seeds)]
    for one, member in zip(single, batch):
        for name in S.RECORD_COLUMNS:
            assert np.array_equal(getattr(one, name), getattr(member, name)), name
        assert (one.input_saturation, one.output_saturation, one.adc_saturation) == (
            member.input_saturation, member.output_saturation, member.adc_saturation)
        assert one.seed == member.seed
    # one warning per place of the chain for the batch, naming its members
    n_places = sum(any(getattr(r, p).occurred for r in single)
                   for p in ("input_saturation", "output_saturation", "adc_saturation"))
    batch_warnings = [str(w.message) for w in caught if "batch members" in str(w.message)]
    assert len(batch_warnings) == n_places
    assert all("seeds 0, 5, 2" in m for m in batch_warnings)


@pytest.mark.parametrize("make_u", [chirp_u, saturating_u,
                                    lambda: case_I_input(40.0, periods=1)])
def test_batch_steps_are_each_members_simulation_exactly(stage, make_u):
    u, seeds = make_u(), [4, 0, 9]
    offsets = np.array([0.0, 1e-3, -0.37])      # a different input per member
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", S.StageSaturationWarning)
        sim = StageBatch.of_seeds(stage, seeds).start()
        measured = [sim.v_y_V]
        for u_k in u:
            measured.append(sim.step(u_k + offsets))
        records = sim.records()
        for i, st in enumerate(members_of(stage, seeds)):
            one = st.start()
            mine = [one.v_y_V] + [one.step(u_k + offsets[i]) for u_k in u]
            rec = one.record()
            for name in S.RECORD_COLUMNS:
                assert np.array_equal(getattr(rec, name), getattr(records[i], name)), name
            assert (rec.input_saturation, rec.output_saturation, rec.adc_saturation) == (
                records[i].input_saturation, records[i].output_saturation,
                records[i].adc_saturation)
            assert np.array_equal(np.array(measured)[:, i], mine)
            assert np.array_equal(sim.state[0][i], one.state[0])
            assert np.array_equal(sim.state[1][i], one.state[1])
    assert sim.k == len(u) and sim.seeds == tuple(seeds)
    # the signals by sample (across blocks for the chirp) and the counts, without records
    for name, column in (("v_y", "v_y_V"), ("u_dac", "u_c_V")):
        assert np.array_equal(sim.samples(name), np.array([getattr(r, column) for r in records]).T)
    assert sim.saturation_counts().tolist() == [
        sum(s.count for s in (r.input_saturation, r.output_saturation, r.adc_saturation))
        for r in records]
    with pytest.raises(ValueError, match="name must be one of"):
        sim.samples("x_um")


def test_batch_members_may_differ_in_noise_plant_and_hysteresis():
    base = S.VirtualStage(seed=1)
    members = [base, base.replace(noise_rms_V=0.0),
               base.replace(seed=2, plant=0.9 * paper.plant()),
               base.replace(seed=3, hysteresis=PlayHysteresis((0.5, 2.0, 9.0),
                                                                (0.05, 0.02, 0.01)))]
    with pytest.raises(ValueError, match="same number of plays"):
        StageBatch(members)
    members = members[:3]
    batch = StageBatch(members)
    assert batch.b.shape == (3, len(base.b)) and batch.noise_rms_V[1] == 0.0
    u = case_I_input(30.0, periods=1)[:3000]
    sim = batch.start()
    for u_k in u:
        sim.step(u_k)
    for st, rec, run in zip(members, sim.records(), batch.run(u)):
        one = st.start()
        for u_k in u:
            one.step(u_k)
        assert np.array_equal(one.record().v_y_V, rec.v_y_V)
        assert np.array_equal(st.run(u).v_y_V, run.v_y_V)
    assert np.array_equal(sim.records()[1].v_y_V, members[1].run(u).v_y_V)


@pytest.mark.parametrize("seeds, match", [
    ([], r"seeds must hold at least 1 seed\(s\), got 0"),
    ([1, 2.5], "seeds must be integers, got 2.5"),
    ([True], "seeds must be integers"),
    ([3, -1], "seeds must be non-negative, got -1"),
    ([1, 2, 1], r"seeds must be distinct, got \[1\] more than once"),
    ("012", "seeds must be a sequence of non-negative integers"),
    (5, "seeds must be a sequence of non-negative integers"),
])
def test_batch_rejects_bad_seeds(stage, seeds, match):
    with pytest.raises(ValueError, match=match):
        StageBatch.of_seeds(stage, seeds)


def test_check_seeds_says_why_a_minimum_applies():
    assert check_seeds(np.arange(3)) == (0, 1, 2)
    with pytest.raises(ValueError, match="at least 2 seed.*got 1: N >= 2 for an interval"):
        check_seeds([4], min_count=2, why="N >= 2 for an interval")


def test_batch_rejects_incompatible_stages_and_bad_steps(stage):
    with pytest.raises(ValueError, match="at least one"):
        StageBatch([])
    with pytest.raises(TypeError, match=r"stages\[1\] must be a VirtualStage"):
        StageBatch([stage, "stage"])
    with pytest.raises(ValueError, match="converters"):
        StageBatch([stage, S.VirtualStage(adc_bits=12)])
    with pytest.raises(ValueError, match="one order"):
        StageBatch([stage, S.VirtualStage(plant=ct.tf([1.0], [1.0, 1.0]))])
    sim = StageBatch.of_seeds(stage, [0, 1]).start()
    with pytest.raises(ValueError, match="u_c must be finite"):
        sim.step([1.0, np.nan])
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        sim.step(np.ones(3))
    v_y = sim.step(0.5)                              # a scalar is applied to every member
    assert np.array_equal(v_y, sim.v_y_V)
    assert sim.record(1).u_c_V[0] == sim.record(0).u_c_V[0] == stage.run([0.5]).u_c_V[0]
    with pytest.raises(ValueError, match="batch size"):
        sim.record(2)


def test_a_model_set_batch_has_each_members_exact_zoh_plant_and_the_stages_rest(stage):
    from piezolib.uncertainty import model_set
    mset = model_set(stage.settings.plant, 0.05)
    members = [0, 364, 728]                          # a corner, the nominal, the other corner
    batch = StageBatch.over_model_set(stage, type(mset)(mset.plant, 0.05, 3, mset.offsets[members]))
    for member, k in zip(batch.stages, members):
        b, a = identification.zoh_coefficients(mset.member(k), 1.0 / stage.fs)
        np.testing.assert_allclose(member.a, a, rtol=0, atol=1e-12 * np.abs(a).max())
        np.testing.assert_allclose(member.b, b, rtol=0, atol=1e-12 * np.abs(a).max())
        assert member.seed == stage.seed and member.hysteresis is stage.hysteresis
        assert member.settings.unstable_plant_ok
    # members that share the hysteresis: the batch run is still each member's own run
    u = 0.5 + 0.4 * np.sin(np.linspace(0, 30, 3000))
    for record, member in zip(batch.run(u), batch.stages):
        np.testing.assert_array_equal(record.v_y_V, member.run(u).v_y_V)


def test_a_model_set_batch_checks_its_seeds(stage):
    from piezolib.uncertainty import model_set
    mset = model_set(stage.settings.plant, 0.05, 2)
    with pytest.raises(ValueError, match="one seed per member"):
        StageBatch.over_model_set(stage, mset, seeds=[1, 2])
    with pytest.raises(TypeError, match="mset"):
        StageBatch.over_model_set(stage, stage.settings.plant)
    assert StageBatch.over_model_set(stage, mset, seeds=range(mset.size)).seeds == tuple(range(mset.size))


def test_a_batch_is_made_from_a_stage_only(stage):
    with pytest.raises(TypeError, match="stage must be a VirtualStage"):
        StageBatch.of_seeds("stage", [0, 1])
    from piezolib.uncertainty import model_set
    with pytest.raises(TypeError, match="stage must be a VirtualStage"):
        StageBatch.over_model_set(None, model_set(stage.settings.plant, 0.05, 2))
