"""The 10 kHz loop of Fig. 1 (piezolib.workbook.loop): exact open-loop equivalence, linear
closed-loop theory, the discretised controller's response, saturation and bad input."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib import hysteresis, paper, signals
from piezolib.workbook import loop
from piezolib.problem.stage import StageSaturationWarning, VirtualStage

FS = paper.SAMPLING_FREQUENCY_HZ
#: A Dahl model in the workbook convention (u_c -> v_y, volts), well damped.
DAHL = hysteresis.DahlModel(alpha1=200.0, alpha2=600.0, beta1=0.0, beta2=1.9, gamma_a=30.0,
                            g_a=1.12, form="bliman_sorine")


@pytest.fixture(scope="module")
def stage():
    return VirtualStage(seed=3)


@pytest.fixture(scope="module")
def linear_stage():
    # no hysteresis, no noise, converters fine enough not to matter: the stage
    # is then exactly the ZOH-discretised G, b(z)/a(z)
    return VirtualStage(seed=0, hysteresis=None, noise_rms_V=0.0, dac_bits=48, adc_bits=48)


def reference(peak=3.0, frequency_hz=20.0, periods=2):
    return signals.triangle(peak, frequency_hz, periods=periods, fs=FS)[1]


# --- K = 0 and no compensation: the open-loop stage run, exactly -------------------
def test_zero_controller_without_compensation_is_the_open_loop_run(stage):
    v = reference()
    closed = loop.run_loop(stage, v, feedforward=1.0, controller=0.0)
    direct = stage.run(v)
    for name in ("t_s", "u_c_V", "v_a_V", "x_um", "v_y_V"):
        assert np.array_equal(getattr(closed.record, name), getattr(direct, name)), name
    assert np.all(closed.u_b_V == 0)
    assert closed.controller is not None            # the sample-by-sample path ran


def test_zero_controller_and_no_feedforward_applies_nothing(stage):
    v = reference()
    r = loop.run_loop(stage, v, feedforward=None, controller=0.0)
    assert np.array_equal(r.v_y_V, stage.run(np.zeros_like(v)).v_y_V)


def test_open_loop_path_equals_zero_controller_path(stage):
    v = reference(frequency_hz=10.0)
    for ff in (1.0, DAHL):
        a = loop.run_loop(stage, v, feedforward=ff)
        b = loop.run_loop(stage, v, feedforward=ff, controller=ct.ss([], [], [], [[0.0]], 1 / FS))
        assert a.controller is None
        assert np.array_equal(a.v_y_V, b.v_y_V)


def test_default_feedforward_is_the_workbook_model(stage):
    v = reference()
    shared = hysteresis.workbook_dahl_fit().model
    assert np.array_equal(loop.run_case("II", stage, v, None).u_f_V,
                          hysteresis.feedforward(shared, v))
    with pytest.raises(TypeError, match="feedforward must be"):
        loop.run_loop(stage, v, feedforward=(1.0, 2.0, 3.0))


def test_feedforward_paths(stage):
    v = reference()
    assert np.all(loop.run_loop(stage, v).u_f_V == 0)                       # none
    assert np.array_equal(loop.run_loop(stage, v, feedforward=2.0).u_f_V, v / 2.0)
    ff = loop.run_loop(stage, v, feedforward=DAHL).u_f_V
    step = hysteresis.DahlFeedforward(DAHL).run(v)                          # eq. 14
    assert np.allclose(ff, step, rtol=0, atol=1e-12)


def test_cases_apply_what_the_module_says(stage):
    v = reference()
    I = loop.run_case("I", stage, v, DAHL)
    assert np.array_equal(I.u_f_V, v / DAHL.g_a) and np.all(I.u_b_V == 0)
    # with an offset model, Case I is its static part and Case II adds exactly H / g_a
    shifted = DAHL.with_offset(-0.15)
    I, II = (loop.run_case(c, stage, v, shifted) for c in ("I", "II"))
    np.testing.assert_allclose(I.u_f_V, (v + 0.15) / DAHL.g_a, rtol=0, atol=1e-15)
    np.testing.assert_allclose(II.u_f_V - I.u_f_V,
                               hysteresis.dahl_hysteresis(shifted, v) / DAHL.g_a,
                               rtol=0, atol=1e-14)
    assert np.array_equal(loop.run_case("I", stage, v, shifted, case_I_gain=1.0).u_f_V, v)
    assert np.array_equal(loop.run_case("I", stage, v, DAHL, case_I_gain=1.0).u_f_V, v)
    II = loop.run_case("II", stage, v, DAHL)
    assert np.array_equal(II.u_f_V, hysteresis.feedforward(DAHL, v))
    III = loop.run_case("III", stage, v, DAHL, controller=paper.controller())
    assert np.array_equal(III.u_f_V, II.u_f_V) and np.any(III.u_b_V != 0)
    # the stage receives u_f + u_b (quantised by the DAC)
    lsb = stage.dac.lsb
    assert np.max(np.abs(III.record.u_c_V - III.u_c_requested_V)) <= lsb / 2 + 1e-15


# --- linear closed loop: the LTI theory, sample for sample ---------------------------
@pytest.mark.parametrize("which", ["published", "integrator"])
def test_linear_stage_closed_loop_matches_lti_theory(linear_stage, which):
    Ts = 1 / FS
    if which == "published":
        Kd = loop.discrete_controller(paper.controller())
    else:   # a slow discrete integrator, u_b[k] = u_b[k-1] + 40 T v_e[k]
        Kd = ct.ss(ct.tf([40 * Ts, 0], [1, -1], Ts))
    v = reference(peak=2.0, frequency_hz=20.0, periods=2)
    g = 0.9
    got = loop.run_loop(linear_stage, v, feedforward=g, controller=Kd)
    Gd = ct.ss(ct.tf(linear_stage.b, linear_stage.a, Ts))
    L = Gd * Kd
    T = ct.feedback(L, 1)                   # v_r -> v_y
    SG = ct.feedback(Gd, Kd)                # u_f -> v_y
    t = np.arange(v.size) * Ts
    want = (ct.forced_response(T, t, v).outputs
            + ct.forced_response(SG, t, v / g).outputs)
    assert np.max(np.abs(got.v_y_V - want)) < 1e-9 * np.max(np.abs(want))
    # and the error signal is the one the loop sees
    assert np.allclose(got.error_um, paper.UM_PER_VOLT * (v - got.v_y_V))


# --- the discretised controller ------------------------------------------------------
def test_continuous_controller_is_discretised_to_match_below_1kHz():
    K = paper.controller()
    Kd = loop.discrete_controller(K)
    assert Kd.dt == pytest.approx(1 / FS)
    omega = np.linspace(2 * np.pi * 1.0, 2 * np.pi * 1000.0, 2000)
    kc = np.ravel(K(1j * omega))
    kd = np.ravel(Kd(np.exp(1j * omega / FS)))
    assert np.max(np.abs(kd / kc - 1)) < 0.05


def test_controller_forms():
    Ts = 1 / FS
    static = loop.discrete_controller(2.5)
    assert static.nstates == 0 and float(static.D[0, 0]) == 2.5 and static.dt == Ts
    assert loop.discrete_controller(None) is None
    Kd = ct.tf([1.0, 0.5], [1.0, -0.5], Ts)
    assert np.allclose(ct.ss(loop.discrete_controller(Kd))(1.0), Kd(1.0))
    from piezolib.robust.discrete import discretize
    dc = discretize(paper.controller())
    z = np.exp(1j * 2 * np.pi * 50.0 / FS)
    assert np.allclose(loop.discrete_controller(dc)(z), dc.K(z))


# --- saturation ------------------------------------------------------------------------
def test_saturation_is_counted_and_warned(stage):
    v = reference(peak=14.0, frequency_hz=10.0, periods=1)    # u_c up to 14 V > 12 V
    with pytest.warns(StageSaturationWarning):
        r = loop.run_loop(stage, v, feedforward=1.0, controller=0.0)
    n_over = int(np.count_nonzero(v > paper.AMPLIFIER_INPUT_RANGE_V[1]))
    assert r.record.input_saturation.count == n_over
    assert r.saturation_count >= n_over
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert loop.run_loop(stage, reference(), feedforward=1.0).saturation_count == 0


def test_unstable_loop_raises_instead_of_nan(stage):
    K = ct.tf([1.0], [1.0, -2.0], 1 / FS)     # output doubles every sample
    with pytest.raises(ValueError, match="diverged"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loop.run_loop(stage, reference(periods=4), feedforward=1.0, controller=K)


# --- experiments ---------------------------------------------------------------------
def test_tracking_periods_and_reference():
    assert loop.tracking_periods(1.0, discard_periods=2) == 3
    assert loop.tracking_periods(50.0, discard_periods=2) == 2 + 5
    assert loop.tracking_periods(10.0, discard_periods=0) == 1
    t, v = loop.tracking_reference(10.0, 2)
    assert v.max() == pytest.approx(paper.TRACKING_TEST["amplitude_um"] / paper.UM_PER_VOLT)
    assert v.min() == 0.0 and t.size == 2001


def test_small_experiments_have_the_table_layout(stage):
    K = paper.controller()
    h = loop.hysteresis_test(stage, DAHL, K, amplitudes_V=[20.0])
    tr = loop.tracking_test(stage, DAHL, K, frequencies_Hz=[25.0])
    for res, col in ((h, 20.0), (tr, 25.0)):
        assert list(res.table.index) == list(paper.table4().index)
        assert list(res.table.columns) == [col]
        I, II, III = (res.table.loc[f"case_{c}", col] for c in ("I", "II", "III"))
        assert res.table.loc["improvement_III_vs_II", col] == pytest.approx(100 * (II - III) / II)
        assert set(res.runs) == {(c, col) for c in loop.CASES}
        assert (res.saturation.values == 0).all()
    # Case III tracks a 25 Hz triangle on the linear-in-the-small loop better than open loop
    assert tr.table.loc["case_III", 25.0] < tr.table.loc["case_I", 25.0]
    # the tracking error is the metric over whole periods after the discarded ones
    run = tr.runs[("III", 25.0)]
    s = run.steady_state(25.0, loop.DISCARD_PERIODS)
    assert s.start == 2 * 400 and len(run) == 400 * loop.tracking_periods(25.0) + 1


# --- bad input ----------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, error, match", [
    (dict(v_r=np.r_[0.0, np.nan, 1.0]), ValueError, "v_r contains"),
    (dict(v_r=np.ones((3, 3))), ValueError, "v_r must be 1-dimensional"),
    (dict(feedforward=-1.0), ValueError, "feedforward must be positive"),
    (dict(feedforward="dahl"), TypeError, "feedforward must be"),
    (dict(controller="K"), TypeError, "controller must be"),
    (dict(controller=np.nan), ValueError, "controller must be finite"),
    (dict(controller=ct.tf([1.0], [1.0, 0.5], 1e-3)), ValueError, "sample time"),
    (dict(controller=ct.tf([1.0, 0.0, 1.0], [1.0, 1.0])), ValueError, "proper"),
    (dict(controller=ct.ss(np.zeros((1, 1)), np.zeros((1, 2)), np.zeros((1, 1)),
                           np.zeros((1, 2)))), ValueError, "SISO"),
])
def test_run_loop_bad_input(stage, kwargs, error, match):
    args = dict(v_r=reference(), feedforward=1.0, controller=None)
    args.update(kwargs)
    v_r = args.pop("v_r")
    with pytest.raises(error, match=match):
        loop.run_loop(stage, v_r, **args)


def test_bad_stage_case_and_missing_controller(stage):
    v = reference()
    with pytest.raises(TypeError, match="stage must be a VirtualStage"):
        loop.run_loop("stage", v)
    with pytest.raises(ValueError, match="case must be one of"):
        loop.run_case("IV", stage, v, DAHL)
    with pytest.raises(ValueError, match="case III needs a controller"):
        loop.run_case("III", stage, v, DAHL)
    with pytest.raises(TypeError, match="dahl must be"):
        loop.run_case("II", stage, v, paper.DAHL)
    with pytest.raises(ValueError, match="controller must be given"):
        loop.tracking_test(stage, DAHL, None)
    with pytest.raises(ValueError, match="leaves no samples"):
        loop.run_loop(stage, v).steady_state(20.0, discard_periods=2)
