"""Virtual stage simulator: determinism, step == run, causality, saturation, calibration."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib import identification, paper
from piezolib.problem import stage as S
from piezolib.problem.stage_data import IDENTIFICATION_CHIRP, chirp_input
from piezolib.problem.stage_hysteresis import CALIBRATED_HYSTERESIS

FS = paper.SAMPLING_FREQUENCY_HZ


@pytest.fixture(scope="module")
def stage():
    return S.VirtualStage(seed=0)


def chirp_u():
    return chirp_input(IDENTIFICATION_CHIRP)[0][:6000]


def test_same_seed_same_record_other_seed_other_noise(stage):
    u = chirp_u()
    a, b = stage.run(u), S.VirtualStage(seed=0).run(u)
    c = S.VirtualStage(seed=1).run(u)
    for name in ("u_c_V", "v_a_V", "x_um", "v_y_V"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.x_um, c.x_um)             # noise does not touch the truth
    assert not np.array_equal(a.v_y_V, c.v_y_V)


@pytest.mark.parametrize("make_u", [
    chirp_u,
    lambda: S.case_I_input(40.0, periods=1),
    lambda: np.r_[np.linspace(0, 13, 300), np.linspace(13, -3, 300)],   # saturates
])
def test_step_equals_run_exactly(stage, make_u):
    u = make_u()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", S.StageSaturationWarning)
        rec = stage.run(u)
        sim = stage.start()
        measured = [sim.v_y_V]
        for u_k in u:
            measured.append(sim.step(u_k))
    stepped = sim.record()
    for name in ("t_s", "u_c_V", "v_a_V", "x_um", "v_y_V"):
        assert np.array_equal(getattr(rec, name), getattr(stepped, name)), name
    assert np.array_equal(np.array(measured[:-1]), rec.v_y_V)
    assert rec.input_saturation == stepped.input_saturation
    assert rec.adc_saturation == stepped.adc_saturation
    assert sim.k == len(u)


def test_measurement_at_k_does_not_depend_on_input_at_k(stage):
    u = chirp_u()
    changed = u.copy()
    changed[3000:] += 0.05
    a, b = stage.run(u), stage.run(changed)
    assert np.array_equal(a.v_y_V[:3001], b.v_y_V[:3001])   # v_y[3000] uses u[..2999]
    assert not np.array_equal(a.v_y_V[3001:], b.v_y_V[3001:])


def test_linear_part_is_the_exact_zoh_discretisation_of_G():
    quiet = S.VirtualStage(noise_rms_V=0.0, hysteresis=None)
    u = np.full(400, 1.0)
    rec = quiet.run(u)
    t = np.arange(400) / FS
    _, y = ct.forced_response(ct.c2d(ct.ss(paper.plant()), 1e-4, "zoh"), t,
                              quiet.dac.convert(u))
    assert np.allclose(rec.x_um / paper.UM_PER_VOLT, y, rtol=1e-9, atol=1e-12)
    settled = quiet.run(np.full(3000, 2.0))
    assert settled.x_um[-1] / 3 == pytest.approx(
        paper.plant().dcgain() * quiet.dac.convert_scalar(2.0), rel=1e-9)


def test_small_chirp_sees_exactly_the_small_signal_model():
    settings = IDENTIFICATION_CHIRP
    u, start = chirp_input(settings)
    hyst = S.VirtualStage(noise_rms_V=0.0).run(u)
    lin = S.VirtualStage(noise_rms_V=0.0, hysteresis=None).run(u)
    offset = (hyst.x_um - lin.x_um)[start:]
    # during the sweep H is v_a plus a constant: the difference is a constant
    assert np.ptp(offset) < 1e-9 * np.max(np.abs(hyst.x_um))
    assert 2 * settings.amplitude_V < S.VirtualStage().small_signal_limit_V
    assert S.VirtualStage().small_signal_model().dcgain() == pytest.approx(
        paper.plant().dcgain())


def test_out_of_range_input_is_limited_and_reported(stage):
    u = np.r_[np.zeros(10), np.full(20, 13.0), np.full(5, -2.5), np.zeros(10)]
    with pytest.warns(S.StageSaturationWarning) as caught:
        rec = stage.run(u)
    messages = [str(w.message) for w in caught]
    assert any("DAC/amplifier input" in m and "-2 ... 12 V in 25 sample" in m
               for m in messages), messages
    # the 13 V step also overshoots the sensor beyond the ADC's +-10 V: reported too
    assert any(m.startswith("ADC") for m in messages) and rec.adc_saturation.occurred
    sat = rec.input_saturation
    assert (sat.count, sat.first_index, sat.requested_min_V, sat.requested_max_V) == (
        25, 10, -2.5, 13.0)
    assert rec.u_c_V.max() <= 12.0 and rec.u_c_V.min() >= -2.0 and rec.saturated
    sim = stage.start()
    with pytest.warns(S.StageSaturationWarning, match="DAC/amplifier input"):
        sim.step(20.0)
    assert sim.record().input_saturation.count == 1


def test_amplifier_output_limit_is_reported():
    tight = S.VirtualStage(amplifier_output_range_V=(-30.0, 50.0))
    with pytest.warns(S.StageSaturationWarning, match="amplifier output"):
        rec = tight.run(np.full(50, 6.0))
    assert rec.output_saturation.count == 50 and rec.v_a_V.max() == 50.0


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(gain=3), TypeError, "unknown stage setting"),
    (dict(noise_rms_V=-1.0), ValueError, "noise_rms_V"),
    (dict(dac_range_V=(12.0, -2.0)), ValueError, "dac_range_V"),
    (dict(plant=ct.tf([1.0], [1.0, -1.0])), ValueError, "stable"),
    (dict(plant=ct.tf([1.0, 0.0], [1.0, 1.0])), ValueError, "strictly proper"),
    (dict(hysteresis="PI"), TypeError, "hysteresis"),
    (dict(unstable_plant_ok=1), TypeError, "unstable_plant_ok"),
])
def test_bad_settings_raise(kwargs, error, match):
    with pytest.raises(error, match=match):
        S.VirtualStage(**kwargs)


@pytest.mark.parametrize("u, match", [
    (np.r_[0.0, np.nan], "non-finite"),
    (np.zeros((3, 2)), "1-dimensional"),
    (np.array([]), "at least 1"),
])
def test_bad_input_raises(stage, u, match):
    with pytest.raises(ValueError, match=match):
        stage.run(u)


def test_step_rejects_nan(stage):
    with pytest.raises(ValueError, match="u_c must be finite"):
        stage.start().step(float("nan"))


def test_one_step_is_fast_enough_for_closed_loops(stage):
    # not a timing test: only checks the state stays plain Python floats
    sim = stage.start()
    sim.step(1.0)
    filter_state, plays = sim.state
    assert len(filter_state) == len(stage.a) - 1
    assert len(plays) == len(stage.hysteresis.thresholds_V)
    assert all(type(z) is float for z in filter_state) and all(type(y) is float for y in plays)
    assert type(sim.v_y_V) is float


def test_simulation_state_is_the_play_state_of_the_operator(stage):
    u = S.case_I_input(30.0, periods=1)[:700]         # up, then partly down again
    sim = stage.start()
    for u_k in u:
        sim.step(u_k)
    rec = sim.record()
    _, plays = stage.hysteresis.apply(rec.v_a_V)
    assert sim.state[1] == pytest.approx(plays, abs=1e-12)
    assert S.VirtualStage(hysteresis=None).start().state[1] == ()


def test_record_columns_and_segment(stage):
    rec = stage.run(np.full(100, 0.5))
    assert tuple(rec.columns()) == S.RECORD_COLUMNS
    part = rec.segment(10, 30)
    assert len(part) == 20 and np.array_equal(part.v_y_V, rec.v_y_V[10:30])
    assert part.input_saturation == rec.input_saturation


def test_zoh_helper_is_shared_with_identification(stage):
    b, a = identification.zoh_coefficients(paper.plant(), 1e-4)
    assert np.array_equal(b, stage.b) and np.array_equal(a, stage.a)


def test_run_rejects_complex_input(stage):
    # the imaginary part used to be dropped silently
    with pytest.raises(TypeError, match="u_c must be real-valued"):
        stage.run(np.ones(100) * (1 + 1j))


# --- N stages at once: StageBatch and StageBatchSimulation --------------------------
def saturating_u():
    return np.r_[np.linspace(0, 13, 300), np.linspace(13, -3, 300), np.linspace(-3, 4, 400)]


def members_of(stage, seeds):
    return [stage.replace(seed=s) for s in seeds]


@pytest.mark.parametrize("make_u", [chirp_u, saturating_u])
def test_batch_run_is_each_members_run_exactly(stage, make_u):
    u, seeds = make_u(), [0, 5, 2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        batch = stage.batch(seeds).run(u)
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
                                    lambda: S.case_I_input(40.0, periods=1)])
def test_batch_steps_are_each_members_simulation_exactly(stage, make_u):
    u, seeds = make_u(), [4, 0, 9]
    offsets = np.array([0.0, 1e-3, -0.37])      # a different input per member
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", S.StageSaturationWarning)
        sim = stage.batch(seeds).start()
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


def test_batch_members_may_differ_in_noise_plant_and_hysteresis():
    base = S.VirtualStage(seed=1)
    members = [base, base.replace(noise_rms_V=0.0),
               base.replace(seed=2, plant=0.9 * paper.plant()),
               base.replace(seed=3, hysteresis=S.PlayHysteresis((0.5, 2.0, 9.0),
                                                                (0.05, 0.02, 0.01)))]
    with pytest.raises(ValueError, match="same number of plays"):
        S.StageBatch(members)
    members = members[:3]
    batch = S.StageBatch(members)
    assert batch.b.shape == (3, len(base.b)) and batch.noise_rms_V[1] == 0.0
    u = S.case_I_input(30.0, periods=1)[:3000]
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


def test_replace_changes_only_what_it_is_told(stage):
    other = stage.replace(seed=7)
    assert other.seed == 7 and stage.seed == 0 and other.b is stage.b
    quiet = stage.replace(noise_rms_V=0.0)
    assert quiet.noise_rms == 0.0 and quiet.seed == stage.seed
    assert np.array_equal(quiet.b, stage.b) and quiet.hysteresis == stage.hysteresis
    u = np.full(200, 1.0)
    assert np.array_equal(quiet.run(u).x_um, stage.run(u).x_um)
    with pytest.raises(TypeError, match="unknown stage setting"):
        stage.replace(gain=3)


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
        stage.batch(seeds)


def test_check_seeds_says_why_a_minimum_applies():
    assert S.check_seeds(np.arange(3)) == (0, 1, 2)
    with pytest.raises(ValueError, match="at least 2 seed.*got 1: N >= 2 for an interval"):
        S.check_seeds([4], min_count=2, why="N >= 2 for an interval")


def test_batch_rejects_incompatible_stages_and_bad_steps(stage):
    with pytest.raises(ValueError, match="at least one"):
        S.StageBatch([])
    with pytest.raises(TypeError, match=r"stages\[1\] must be a VirtualStage"):
        S.StageBatch([stage, "stage"])
    with pytest.raises(ValueError, match="converters"):
        S.StageBatch([stage, S.VirtualStage(adc_bits=12)])
    with pytest.raises(ValueError, match="one order"):
        S.StageBatch([stage, S.VirtualStage(plant=ct.tf([1.0], [1.0, 1.0]))])
    sim = stage.batch([0, 1]).start()
    with pytest.raises(ValueError, match="u_c must be finite"):
        sim.step([1.0, np.nan])
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        sim.step(np.ones(3))
    v_y = sim.step(0.5)                              # a scalar is applied to every member
    assert np.array_equal(v_y, sim.v_y_V)
    assert sim.record(1).u_c_V[0] == sim.record(0).u_c_V[0] == stage.run([0.5]).u_c_V[0]
    with pytest.raises(ValueError, match="batch size"):
        sim.record(2)


def test_calibration_rederives_the_stored_parameters():
    law, achieved = S.calibrate_hysteresis()
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
        S.calibrate_hysteresis(targets=targets)


def test_an_unstable_plant_is_accepted_only_when_asked_for():
    with pytest.raises(ValueError, match="plant must be stable"):
        S.VirtualStage(plant=ct.tf([1.0], [1.0, 0.5, -1.0]))
    unstable = ct.tf([1.0], [1.0, 0.5, -1.0])
    stage = S.VirtualStage(plant=unstable, unstable_plant_ok=True)
    b, a = identification.zoh_coefficients(unstable, 1.0 / stage.fs)
    np.testing.assert_array_equal(stage.a, a)


def test_a_model_set_batch_has_each_members_exact_zoh_plant_and_the_stages_rest(stage):
    from piezolib.uncertainty import model_set
    mset = model_set(stage.settings.plant, 0.05)
    members = [0, 364, 728]                          # a corner, the nominal, the other corner
    batch = stage.over_model_set(type(mset)(mset.plant, 0.05, 3, mset.offsets[members]))
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
        stage.over_model_set(mset, seeds=[1, 2])
    with pytest.raises(TypeError, match="mset"):
        stage.over_model_set(stage.settings.plant)
    assert stage.over_model_set(mset, seeds=range(mset.size)).seeds == tuple(range(mset.size))
