"""The 10 kHz loop of Fig. 1 (piezolib.workbook.loop): exact open-loop equivalence, linear
closed-loop theory, the discretised controller's response, saturation and bad input.
The cases and experiments of Sec. V are tested in test_experiments.py."""

import warnings

import control as ct
import numpy as np
import pytest

from piezolib import hysteresis, paper, signals
from piezolib.problem.stage import StageSaturationWarning, VirtualStage
from piezolib.robust.discrete import discretize
from piezolib.workbook import loop

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


def reference(peak=3.0, frequency_Hz=20.0, periods=2):
    return signals.triangle(peak, frequency_Hz, FS, periods=periods)[1]


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
    v = reference(frequency_Hz=10.0)
    for ff in (1.0, DAHL):
        a = loop.run_loop(stage, v, feedforward=ff)
        b = loop.run_loop(stage, v, feedforward=ff, controller=ct.ss([], [], [], [[0.0]], 1 / FS))
        assert a.controller is None
        assert np.array_equal(a.v_y_V, b.v_y_V)


def test_feedforward_paths(stage):
    v = reference()
    assert np.all(loop.run_loop(stage, v).u_f_V == 0)                       # none
    assert np.array_equal(loop.run_loop(stage, v, feedforward=2.0).u_f_V, v / 2.0)
    ff = loop.run_loop(stage, v, feedforward=DAHL).u_f_V
    step = hysteresis.DahlFeedforward(DAHL).run(v)                          # eq. 14
    assert np.allclose(ff, step, rtol=0, atol=1e-12)
    pi = hysteresis.PIModel((0.0, 0.4), (0.9, 0.25))                       # any hysteresis model
    run = loop.run_loop(stage, v, feedforward=pi)
    assert np.array_equal(run.u_f_V, pi.feedforward(v)) and run.feedforward == "PIModel.feedforward"


def test_a_model_feedforward_must_give_one_finite_input_per_sample(stage):
    class Broken:
        def simulate(self, v):
            return v

        def feedforward(self, x_r):
            return x_r[:-1]
    with pytest.raises(ValueError, match=r"Broken.feedforward\(v_r\)"):
        loop.run_loop(stage, reference(), feedforward=Broken())


def test_peak_to_peak_error_is_the_literal_reading_over_the_steady_state(stage):
    run = loop.run_loop(stage, reference(periods=3), feedforward=1.0)
    s = run.steady_state(20.0)
    e = run.x_r_um[s] - run.x_um[s]
    assert run.peak_to_peak_error_percent(20.0, range_um=12.0) == pytest.approx(
        100 * np.ptp(e) / 12.0, rel=1e-12)


# --- linear closed loop: the LTI theory, sample for sample ---------------------------
@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("which", ["published", "integrator"])
def test_linear_stage_closed_loop_matches_lti_theory(linear_stage, which, delay):
    Ts = 1 / FS
    if which == "published":
        Kd = loop.discrete_controller(paper.controller())
    else:   # a slow discrete integrator, u_b[k] = u_b[k-1] + 40 T v_e[k]
        Kd = ct.ss(ct.tf([40 * Ts, 0], [1, -1], Ts))
    v = reference(peak=2.0, frequency_Hz=20.0, periods=2)
    g = 0.9
    got = loop.run_loop(linear_stage, v, feedforward=g, controller=Kd, delay_samples=delay)
    assert got.delay_samples == delay
    Gd = ct.ss(ct.tf(linear_stage.b, linear_stage.a, Ts))
    KD = Kd * ct.ss(ct.tf([1], [1] + [0] * delay, Ts))     # z^-d after the controller
    L = Gd * KD
    T = ct.feedback(L, 1)                   # v_r -> v_y
    SG = ct.feedback(Gd, KD)                # u_f -> v_y
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
    dc = discretize(paper.controller(), FS)
    z = np.exp(1j * 2 * np.pi * 50.0 / FS)
    assert np.allclose(loop.discrete_controller(dc)(z), dc.K(z))


# --- saturation ------------------------------------------------------------------------
def test_saturation_is_counted_and_warned(stage):
    v = reference(peak=14.0, frequency_Hz=10.0, periods=1)    # u_c up to 14 V > 12 V
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


def test_bad_stage_and_too_short_run(stage):
    v = reference()
    with pytest.raises(TypeError, match="stage must be a VirtualStage"):
        loop.run_loop("stage", v)
    with pytest.raises(ValueError, match="leaves no samples"):
        loop.run_loop(stage, v).steady_state(20.0, discard_periods=2)


def test_bad_feedforward_tuple(stage):
    with pytest.raises(TypeError, match="feedforward must be"):
        loop.run_loop(stage, reference(), feedforward=(1.0, 2.0, 3.0))


def test_default_delay_is_one_sample(stage):
    assert loop.COMPUTATION_DELAY_SAMPLES == 1
    v = reference(frequency_Hz=10.0)
    Kd = loop.discrete_controller(paper.controller())
    a = loop.run_loop(stage, v, feedforward=DAHL, controller=Kd)
    b = loop.run_loop(stage, v, feedforward=DAHL, controller=Kd, delay_samples=1)
    assert a.delay_samples == 1 and np.array_equal(a.v_y_V, b.v_y_V)
    # what reached the DAC is u_f[k] + u_b[k - 1]
    assert np.allclose(a.u_c_requested_V[1:], a.u_f_V[1:] + a.u_b_V[:-1], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="delay_samples"):
        loop.run_loop(stage, v, controller=Kd, delay_samples=-1)


def test_exported_sections_run_like_the_model(stage):
    from piezolib.robust.export import controller_sos
    v = reference(frequency_Hz=10.0)
    Kd = loop.discrete_controller(paper.controller())
    sos = controller_sos(Kd, "K_pub")
    model = loop.run_loop(stage, v, feedforward=DAHL, controller=Kd)
    f64 = loop.run_loop(stage, v, feedforward=DAHL, controller=sos, sections_dtype="float64")
    f32 = loop.run_loop(stage, v, feedforward=DAHL, controller=sos)
    assert np.max(np.abs(f64.u_b_V - model.u_b_V)) < 1e-9
    # float32 sections: the measured output stays within a few ADC steps of the model's
    assert np.max(np.abs(f32.v_y_V - model.v_y_V)) < 5e-3
    with pytest.raises(ValueError, match="Hz"):
        loop.run_loop(stage, v, controller=controller_sos(
            ct.tf([0.1], [1, -0.5], 1e-3), "K_slow"))


# --- N noise seeds at once: member i is the single run with seed i, bit for bit -------
SEEDS = [3, 0, 11]


def sections():
    from piezolib.robust.export import controller_sos
    return controller_sos(loop.discrete_controller(paper.controller()), "K_pub")


def assert_same_run(one, member):
    for name in ("t_s", "u_c_V", "v_a_V", "x_um", "v_y_V"):
        assert np.array_equal(getattr(one.record, name), getattr(member.record, name)), name
    for name in ("v_r_V", "u_f_V", "u_b_V"):
        assert np.array_equal(getattr(one, name), getattr(member, name)), name
    assert one.saturation == member.saturation and one.delay_samples == member.delay_samples
    assert one.feedforward == member.feedforward


@pytest.mark.parametrize("delay", [0, 1, 2])
@pytest.mark.parametrize("kind", ["sections float32", "sections float64", "state space"])
def test_batched_closed_loop_member_is_the_single_run_with_its_seed(stage, kind, delay):
    v = reference(frequency_Hz=10.0)
    controller, dtype = ((loop.discrete_controller(paper.controller()), "float32")
                         if kind == "state space" else (sections(), kind.split()[1]))
    runs = loop.run_loop(stage, v, feedforward=DAHL, controller=controller,
                         delay_samples=delay, sections_dtype=dtype, seeds=SEEDS)
    assert isinstance(runs, list) and len(runs) == len(SEEDS)
    for seed, member in zip(SEEDS, runs):
        one = loop.run_loop(stage.replace(seed=seed), v, feedforward=DAHL,
                            controller=controller, delay_samples=delay, sections_dtype=dtype)
        assert member.record.seed == seed
        assert_same_run(one, member)
    assert not np.array_equal(runs[0].v_y_V, runs[1].v_y_V)      # the noise differs


def test_batched_open_loop_and_stage_batch_argument(stage):
    from piezolib.problem.stage_batch import StageBatch
    v = reference()
    runs = loop.run_loop(stage, v, feedforward=DAHL, seeds=SEEDS)
    for seed, member in zip(SEEDS, runs):
        assert member.controller is None
        assert_same_run(loop.run_loop(stage.replace(seed=seed), v, feedforward=DAHL), member)
    # a StageBatch runs its members, which may include the noise-free stage
    batch = StageBatch([stage, stage.replace(noise_rms_V=0.0)])
    quiet = loop.run_loop(batch, v, feedforward=DAHL, controller=sections())[1]
    assert_same_run(loop.run_loop(stage.replace(noise_rms_V=0.0), v, feedforward=DAHL,
                                  controller=sections()), quiet)
    with pytest.raises(ValueError, match="seeds must be None"):
        loop.run_loop(batch, v, seeds=[1, 2])


def test_batched_loop_counts_saturation_per_member_and_warns_once_per_place(stage):
    v = reference(peak=14.0, frequency_Hz=10.0, periods=1)    # u_c up to 14 V > 12 V
    with pytest.warns(StageSaturationWarning) as caught:
        runs = loop.run_loop(stage, v, feedforward=1.0, controller=0.0, seeds=SEEDS)
    n_over = int(np.count_nonzero(v > paper.AMPLIFIER_INPUT_RANGE_V[1]))
    for seed, member in zip(SEEDS, runs):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StageSaturationWarning)
            one = loop.run_loop(stage.replace(seed=seed), v, feedforward=1.0, controller=0.0)
        assert member.record.input_saturation == one.record.input_saturation
        assert member.record.input_saturation.count == n_over
        assert member.saturation_count == one.saturation_count
    inputs = [w for w in caught if "DAC/amplifier input" in str(w.message)]
    assert len(inputs) == 1 and "3 of 3 batch members (seeds 3, 0, 11)" in str(inputs[0].message)


def test_batched_unstable_loop_raises_naming_the_seeds(stage):
    K = ct.tf([1.0], [1.0, -2.0], 1 / FS)
    with pytest.raises(ValueError, match=r"diverged at sample \d+ .* seed\(s\) \[3, 0, 11\]"), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loop.run_loop(stage, reference(periods=4), feedforward=1.0, controller=K, seeds=SEEDS)


@pytest.mark.parametrize("seeds, match", [
    ([], "seeds must hold at least 1"),
    ([0, 0], "seeds must be distinct"),
    ([-2], "seeds must be non-negative"),
    ([0.5], "seeds must be integers"),
])
def test_run_loop_bad_seeds(stage, seeds, match):
    with pytest.raises(ValueError, match=match):
        loop.run_loop(stage, reference(), feedforward=1.0, seeds=seeds)


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_section_filter_batch_is_the_section_filter_per_channel(dtype):
    from piezolib.robust.export import SectionFilter, SectionFilterBatch
    rng = np.random.default_rng(1)
    sos = np.array([[0.3, 0.1, -0.2, 1, -1.2, 0.5], [1.1, -0.4, 0.2, 1, -0.3, 0.1],
                    [0.7, 0.2, 0.1, 1, -1.9, 0.91]])
    x = rng.standard_normal((400, 4)) * np.array([1.0, 1e3, 1e-3, 7.0])   # badly scaled too
    batch = SectionFilterBatch(sos, dtype, size=4)
    y = np.array([batch.step(row) for row in x])
    assert y.dtype == np.float64
    for i in range(4):
        single = SectionFilter(sos, dtype)
        assert np.array_equal(y[:, i], [single.step(v) for v in x[:, i].tolist()])
    batch.reset()
    assert np.array_equal(batch.step(x[0]), y[0])
    with pytest.raises(ValueError, match=r"x must have shape \(4,\)"):
        batch.step(np.ones(3))
    with pytest.raises(ValueError, match="size must be >= 1"):
        SectionFilterBatch(sos, dtype, size=0)


@pytest.mark.parametrize("variant", ["hysteresis, float32", "linear, limited, float64"])
def test_compiled_batch_loop_over_several_noise_blocks_is_the_single_run(stage, variant):
    # 9000 samples: three blocks of the signal log and of the noise streams; the
    # second variant has no plays and an amplifier whose output limits act
    limited = variant.startswith("linear")
    base = (stage.replace(hysteresis=None, amplifier_output_range_V=(-40.0, 40.0))
            if limited else stage)
    v = reference(peak=5.0 if limited else 3.0, frequency_Hz=10.0, periods=9)
    assert v.size > 2 * 4096
    dtype = variant.split(", ")[-1]
    seeds = [5, 8]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StageSaturationWarning)
        runs = loop.run_loop(base, v, feedforward=1.0 if limited else DAHL,
                             controller=sections(), delay_samples=1, sections_dtype=dtype,
                             seeds=seeds)
        for seed, member in zip(seeds, runs):
            one = loop.run_loop(base.replace(seed=seed), v, feedforward=1.0 if limited else DAHL,
                                controller=sections(), delay_samples=1, sections_dtype=dtype)
            assert_same_run(one, member)
    if limited:
        assert runs[0].record.output_saturation.occurred


@pytest.mark.parametrize("kind", ["sections, limited", "state space", "open loop"])
def test_batch_tracking_errors_are_the_per_member_results(stage, kind):
    # the compiled loop's signals read in place (three noise blocks, saturating members)
    # and the other paths: each member's error and count as its LoopResult gives them
    from piezolib.problem.stage_batch import StageBatch
    f, periods = (10.0, 9) if kind.startswith("sections") else (50.0, 4)
    v = reference(peak=14.0 if kind.endswith("limited") else 3.0, frequency_Hz=f,
                  periods=periods)                     # u_c beyond 12 V: limited
    controller = {"sections, limited": sections(), "open loop": None,
                  "state space": loop.discrete_controller(paper.controller())}[kind]
    batch = StageBatch.of_seeds(stage, [5, 8])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StageSaturationWarning)
        runs = loop.run_loop(batch, v, feedforward=DAHL, controller=controller)
        errors, counts = loop.batch_tracking_errors(batch, v, f, feedforward=DAHL,
                                                    controller=controller, range_um=12.0)
    assert errors.tolist() == [r.tracking_error_percent(f, range_um=12.0) for r in runs]
    assert counts.tolist() == [r.saturation_count for r in runs]
    assert (counts > 0).all() if kind.endswith("limited") else not counts.any()
    default = loop.batch_tracking_errors(batch, v, f, feedforward=DAHL, controller=controller,
                                         discard_periods=3)[0]
    assert default.tolist() == [r.tracking_error_percent(f, 3) for r in runs]


def test_batch_tracking_errors_bad_input(stage):
    from piezolib.problem.stage_batch import StageBatch
    batch, v = StageBatch([stage]), reference(periods=4)
    with pytest.raises(TypeError, match="batch must be a StageBatch"):
        loop.batch_tracking_errors(stage, v, 20.0)
    with pytest.raises(ValueError, match="sections_dtype"):
        loop.batch_tracking_errors(batch, v, 20.0, controller=sections(), sections_dtype="f16")
    with pytest.raises(ValueError, match="leaves no samples"):
        loop.batch_tracking_errors(batch, v, 20.0, discard_periods=4)
    with pytest.raises(ValueError, match="frequency_Hz"):
        loop.batch_tracking_errors(batch, v, -1.0)


def test_a_workspace_holds_the_log_and_gives_the_same_numbers(stage):
    from piezolib.problem.stage_batch import StageBatch, StageBatchSimulation
    batch, v = StageBatch.of_seeds(stage, [2, 6]), reference(frequency_Hz=10.0, periods=9)
    kwargs = dict(feedforward=DAHL, controller=sections(), range_um=12.0)
    fresh = loop.batch_tracking_errors(batch, v, 10.0, **kwargs)
    workspace = np.full(StageBatchSimulation.workspace_size(v.size, 2), np.nan)
    for space in (workspace, workspace, np.empty(10)):        # reused, then too small
        again = loop.batch_tracking_errors(batch, v, 10.0, **kwargs, workspace=space)
        assert again[0].tolist() == fresh[0].tolist() and again[1].tolist() == fresh[1].tolist()
    assert np.isfinite(workspace[:v.size]).all()             # the log was kept there
    for bad in (np.empty(10, np.float32), [0.0] * 10, np.empty((2, 5))):
        with pytest.raises(TypeError, match="workspace"):
            loop.batch_tracking_errors(batch, v, 10.0, **kwargs, workspace=bad)
