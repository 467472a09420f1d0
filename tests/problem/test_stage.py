"""Virtual stage simulator: determinism, step == run, causality, saturation, settings."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib import identification, paper
from piezolib.problem import stage as S
from piezolib.problem.stage_calibration import case_I_input
from piezolib.problem.stage_data import IDENTIFICATION_CHIRP, chirp_input

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
    lambda: case_I_input(40.0, periods=1),
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
    u = case_I_input(30.0, periods=1)[:700]         # up, then partly down again
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


def test_an_unstable_plant_is_accepted_only_when_asked_for():
    with pytest.raises(ValueError, match="plant must be stable"):
        S.VirtualStage(plant=ct.tf([1.0], [1.0, 0.5, -1.0]))
    unstable = ct.tf([1.0], [1.0, 0.5, -1.0])
    stage = S.VirtualStage(plant=unstable, unstable_plant_ok=True)
    b, a = identification.zoh_coefficients(unstable, 1.0 / stage.fs)
    np.testing.assert_array_equal(stage.a, a)
