"""The experiments of Sec. V: the Table 4 triangle and its measurement, Cases I-III and the
Table 4 / Table 5 experiments on the virtual stage."""

import numpy as np
import pandas as pd
import pytest

from piezolib import hysteresis as hy
from piezolib import metrics, paper, signals
from piezolib.problem.hysteresis_fits import workbook_dahl_fit
from piezolib.problem.stage import VirtualStage
from piezolib.workbook import experiments as ex
from piezolib.workbook import loop, report

PARAMS = dict(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4.0 / 30.0, gamma_a=30.0, g_a=0.95)


class DahlStage:
    """A 'stage' that is the Dahl model itself: v_y = x of the voltage-driven model."""

    def __init__(self, model):
        self.model = model

    def run(self, u_c):
        return type("Record", (), {"v_y_V": hy.simulate_dahl(self.model, u_c).x,
                                   "u_c_V": np.asarray(u_c)})


def test_table4_reference_is_case_I_triangle():
    t, v_r = ex.table4_reference(40.0)
    assert v_r.max() == pytest.approx(40.0 / paper.AMPLIFIER_GAIN) and v_r.min() == 0.0
    assert t[-1] == pytest.approx(3 / paper.HYSTERESIS_TEST["frequency_Hz"])


def test_table4_measure_scales_axes_and_discards_start():
    t, v_r = ex.table4_reference(20.0)
    v_y = 0.9 * v_r - 0.05 * np.sign(np.gradient(v_r))       # branches 0.1 V apart
    v_y[:1000] += 0.3 * np.sin(np.linspace(0, 30, 1000))     # start-up junk, discarded
    m = ex.table4_measure(v_r, v_y)
    assert m.v_mid == pytest.approx(10.0)                    # actuator volts
    assert m.x_lo - m.x_up == pytest.approx(paper.UM_PER_VOLT * 0.1, rel=1e-9)   # um
    assert m.percent == pytest.approx(hy.hysteresis_percent(v_r[1000:], v_y[1000:]), rel=1e-12)
    with pytest.raises(ValueError, match="equal lengths"):
        ex.table4_measure(v_r, v_y[:-1])
    with pytest.raises(ValueError, match="leaves no record"):
        ex.table4_measure(v_r, v_y, discard_periods=3)


@pytest.mark.parametrize("m", [
    hy.DahlModel(**PARAMS, form="bliman_sorine"),
    hy.DahlModel(0.1, 0.3, 0.0, -0.01, 30.0, 0.93, form="printed"),   # long transients
])
def test_case_II_on_the_model_itself_removes_the_loop(m):
    plain = DahlStage(m).run(ex.table4_reference(30.0)[1])
    assert ex.table4_measure(plain.u_c_V, plain.v_y_V).percent > 1.0
    for A in (10.0, 30.0):
        t, v_r = ex.table4_reference(A)
        run = DahlStage(m).run(hy.feedforward(m, v_r))        # Case II: u_c = u_f (eq. 14)
        np.testing.assert_allclose(run.v_y_V, v_r, atol=1e-9)
        assert ex.table4_measure(v_r, run.v_y_V).percent < 1e-6


# --- Cases I-III and the Table 4 / Table 5 experiments on the virtual stage ----------
#: A Dahl model in the workbook convention (u_c -> v_y, volts), well damped.
DAHL = hy.DahlModel(alpha1=200.0, alpha2=600.0, beta1=0.0, beta2=1.9, gamma_a=30.0,
                    g_a=1.12, form="bliman_sorine")
FS = paper.SAMPLING_FREQUENCY_HZ


@pytest.fixture(scope="module")
def stage():
    return VirtualStage(seed=3)


def reference(peak=3.0, frequency_Hz=20.0, periods=2):
    return signals.triangle(peak, frequency_Hz, FS, periods=periods)[1]


def test_default_feedforward_is_the_workbook_model(stage):
    v = reference()
    shared = workbook_dahl_fit().model
    assert np.array_equal(ex.run_case("II", stage, v, None).u_f_V, hy.feedforward(shared, v))


def test_cases_apply_what_the_module_says(stage):
    v = reference()
    I = ex.run_case("I", stage, v, DAHL)
    assert np.array_equal(I.u_f_V, v / DAHL.g_a) and np.all(I.u_b_V == 0)
    # with an offset model, Case I is its static part and Case II adds exactly H / g_a
    shifted = DAHL.with_offset(-0.15)
    I, II = (ex.run_case(c, stage, v, shifted) for c in ("I", "II"))
    np.testing.assert_allclose(I.u_f_V, (v + 0.15) / DAHL.g_a, rtol=0, atol=1e-15)
    np.testing.assert_allclose(II.u_f_V - I.u_f_V,
                               hy.dahl_hysteresis(shifted, v) / DAHL.g_a,
                               rtol=0, atol=1e-14)
    assert np.array_equal(ex.run_case("I", stage, v, shifted, case_I_gain=1.0).u_f_V, v)
    assert np.array_equal(ex.run_case("I", stage, v, DAHL, case_I_gain=1.0).u_f_V, v)
    II = ex.run_case("II", stage, v, DAHL)
    assert np.array_equal(II.u_f_V, hy.feedforward(DAHL, v))
    III = ex.run_case("III", stage, v, DAHL, controller=paper.controller())
    assert np.array_equal(III.u_f_V, II.u_f_V) and np.any(III.u_b_V != 0)
    # the stage receives u_f + u_b (quantised by the DAC)
    lsb = stage.dac.lsb
    assert np.max(np.abs(III.record.u_c_V - III.u_c_requested_V)) <= lsb / 2 + 1e-15


#: A Prandtl-Ishlinskii model in the same convention, invertible.
PI = hy.PIModel((0.0, 0.3, 0.6), (0.8, 0.2, 0.1), x0=-0.05)


def test_a_PI_model_runs_through_the_cases(stage):
    v = reference()
    I, II, III = (ex.run_case(c, stage, v, PI, controller=paper.controller())
                  for c in ("I", "II", "III"))
    np.testing.assert_allclose(I.u_f_V, (v + 0.05) / 1.1, rtol=0, atol=1e-15)   # static part
    assert np.array_equal(II.u_f_V, PI.feedforward(v)) and np.all(II.u_b_V == 0)
    assert np.array_equal(III.u_f_V, II.u_f_V) and np.any(III.u_b_V != 0)
    h = ex.hysteresis_test(stage, PI, paper.controller(), amplitudes_V=[20.0])
    assert h.runs[("II", 20.0)].feedforward == "PIModel.feedforward"
    assert np.array_equal(h.runs[("I", 20.0)].u_f_V, h.runs[("I", 20.0)].v_r_V)    # g = 1
    assert h.table.loc["case_III", 20.0] < h.table.loc["case_I", 20.0]


def test_the_model_argument_is_checked_by_name(stage):
    v = reference()
    for bad in (object(), (1.0, 0.0), "dahl"):
        with pytest.raises(TypeError, match=r"^model must be a hysteresis model.* got "):
            ex.run_case("II", stage, v, bad)
    with pytest.raises(TypeError, match="^model must be"):
        ex.hysteresis_test(stage, object(), paper.controller(), amplitudes_V=[20.0])

    class Plain:                       # a hysteresis model of one's own, without a static part
        def simulate(self, v):
            return v

        def feedforward(self, x_r):
            return np.asarray(x_r, dtype=float)
    assert np.array_equal(ex.run_case("II", stage, v, Plain()).u_f_V, v)
    with pytest.raises(ValueError, match="case I needs case_I_gain: a Plain has no static_part"):
        ex.run_case("I", stage, v, Plain())
    assert np.array_equal(ex.run_case("I", stage, v, Plain(), case_I_gain=2.0).u_f_V, v / 2.0)


def test_tracking_periods_and_reference():
    assert ex.tracking_periods(1.0, discard_periods=2) == 3
    assert ex.tracking_periods(50.0, discard_periods=2) == 2 + 5
    assert ex.tracking_periods(10.0, discard_periods=0) == 1
    assert ex.tracking_periods(10.0) == loop.DISCARD_PERIODS + 1          # 0.1 s = one period
    t, v = ex.tracking_reference(10.0, 2)
    assert v.max() == pytest.approx(paper.TRACKING_TEST["amplitude_um"] / paper.UM_PER_VOLT)
    assert v.min() == 0.0 and t.size == 2001


def test_references_are_built_once_and_read_only():
    t, v = ex.tracking_reference(10.0, 2)
    again = ex.tracking_reference(10.0, 2, amplitude_um=paper.TRACKING_TEST["amplitude_um"])
    assert again[1] is v and again[0] is t
    assert not v.flags.writeable and not t.flags.writeable
    with pytest.raises(ValueError):
        v[0] = 1.0
    np.testing.assert_array_equal(v, signals.triangle(4.0, 10.0, FS, periods=2)[1])
    with pytest.raises(ValueError, match="amplitude_um"):
        ex.tracking_reference(10.0, 2, amplitude_um=-1.0)


def test_small_experiments_have_the_table_layout(stage):
    K = paper.controller()
    h = ex.hysteresis_test(stage, DAHL, K, amplitudes_V=[20.0])
    tr = ex.tracking_test(stage, DAHL, K, frequencies_Hz=[25.0])
    for res, col in ((h, 20.0), (tr, 25.0)):
        assert list(res.table.index) == list(paper.table4().index)
        assert list(res.table.columns) == [col]
        I, II, III = (res.table.loc[f"case_{c}", col] for c in ("I", "II", "III"))
        assert res.table.loc["improvement_III_vs_II", col] == pytest.approx(100 * (II - III) / II)
        assert set(res.runs) == {(c, col) for c in ex.CASES}
        assert (res.saturation.values == 0).all()
    # Case III tracks a 25 Hz triangle on the linear-in-the-small loop better than open loop
    assert tr.table.loc["case_III", 25.0] < tr.table.loc["case_I", 25.0]
    # the tracking error is the metric over whole periods after the discarded ones
    run = tr.runs[("III", 25.0)]
    s = run.steady_state(25.0, loop.DISCARD_PERIODS)
    assert s.start == 2 * 400 and len(run) == 400 * ex.tracking_periods(25.0) + 1
    # the Table 4 loops are measured on the shared triangle, the same in every case
    for case in ex.CASES:
        np.testing.assert_array_equal(h.runs[(case, 20.0)].v_r_V,
                                      ex.table4_reference(20.0, periods=4)[1])
        assert h.table.loc[f"case_{case}", 20.0] == pytest.approx(ex.table4_measure(
            h.runs[(case, 20.0)].v_r_V, h.runs[(case, 20.0)].v_y_V, discard_periods=2).percent)


def test_the_hysteresis_test_uses_the_stages_amplifier_gain():
    # a stage with a x20 amplifier reaches the same actuator amplitude with half the input
    stage = VirtualStage(seed=3, amplifier_gain=20.0)
    h = ex.hysteresis_test(stage, DAHL, paper.controller(), amplitudes_V=[20.0], periods=2,
                           discard_periods=1)
    v_r = h.runs[("I", 20.0)].v_r_V
    assert v_r.max() == pytest.approx(20.0 / 20.0)
    assert h.table.loc["case_I", 20.0] == pytest.approx(ex.table4_measure(
        v_r, h.runs[("I", 20.0)].v_y_V, discard_periods=1, amplifier_gain=20.0).percent)


def test_case_table_layout():
    cols = pd.Index([1.0, 2.0], name="frequency_Hz")
    table = ex.case_table({"I": [10.0, 8.0], "II": [5.0, 4.0], "III": [1.0, 2.0]}, cols)
    assert table.index.equals(paper.case_rows_index()) and table.columns.equals(cols)
    np.testing.assert_allclose(table.loc["improvement_II_vs_I"], [50.0, 50.0])
    np.testing.assert_allclose(table.loc["improvement_III_vs_I"], [90.0, 75.0])
    np.testing.assert_allclose(table.loc["improvement_III_vs_II"], [80.0, 50.0])


def test_bad_case_and_missing_controller(stage):
    v = reference()
    with pytest.raises(ValueError, match="case must be one of"):
        ex.run_case("IV", stage, v, DAHL)
    with pytest.raises(ValueError, match="case III needs a controller"):
        ex.run_case("III", stage, v, DAHL)
    with pytest.raises(TypeError, match="model must be a hysteresis model"):
        ex.run_case("II", stage, v, paper.DAHL)
    with pytest.raises(ValueError, match="controller must be given"):
        ex.tracking_test(stage, DAHL, None)
    with pytest.raises(ValueError, match="controller must be given"):
        ex.hysteresis_test(stage, DAHL, None)


# --- the experiments over N noise seeds ------------------------------------------------
@pytest.fixture(scope="module")
def seeded(stage):
    from piezolib.robust.export import controller_sos
    K = controller_sos(loop.discrete_controller(paper.controller()), "K_pub")
    seeds = [3, 8, 1]
    return K, seeds, (ex.hysteresis_test(stage, DAHL, K, amplitudes_V=[20.0], seeds=seeds),
                      ex.tracking_test(stage, DAHL, K, frequencies_Hz=[25.0], seeds=seeds))


def test_seeded_experiments_are_statistics_of_the_single_runs(stage, seeded):
    from scipy import stats
    K, seeds, (h, tr) = seeded
    single = {3: (ex.hysteresis_test(stage, DAHL, K, amplitudes_V=[20.0]),
                  ex.tracking_test(stage, DAHL, K, frequencies_Hz=[25.0]))}
    quiet_stage = stage.replace(noise_rms_V=0.0)
    quiet = (ex.hysteresis_test(quiet_stage, DAHL, K, amplitudes_V=[20.0]),
             ex.tracking_test(quiet_stage, DAHL, K, frequencies_Hz=[25.0]))
    for res, one, noise_free in ((h, single[3][0], quiet[0]), (tr, single[3][1], quiet[1])):
        assert res.seeds == tuple(seeds)
        # seed 3 is the stage's own seed: its table is the unseeded experiment's, exactly
        pd.testing.assert_frame_equal(res.per_seed.loc[3], one.table)
        pd.testing.assert_frame_equal(res.noise_free, noise_free.table)
        assert list(res.per_seed.index.names) == ["seed", "row"]
        for frame in (res.table, res.low, res.high, res.noise_free):
            assert frame.index.equals(one.table.index)
            assert frame.columns.equals(one.table.columns)
        # mean of every row (improvements per seed, then averaged) and the t interval
        by_seed = np.stack([res.per_seed.loc[s].to_numpy() for s in seeds])
        np.testing.assert_allclose(res.table.to_numpy(), by_seed.mean(axis=0), rtol=1e-12)
        half = stats.t.ppf(0.975, 2) * by_seed.std(axis=0, ddof=1) / np.sqrt(3)
        np.testing.assert_allclose(res.high.to_numpy() - res.table.to_numpy(), half,
                                   rtol=1e-9, atol=1e-12)
        assert (res.low.to_numpy() <= res.table.to_numpy()).all()
        assert (res.table.to_numpy() <= res.high.to_numpy()).all()
        # runs are the first seed's, so the figures keep working
        assert set(res.runs) == set(one.runs)
        assert np.array_equal(res.runs[("III", res.table.columns[0])].v_y_V,
                              one.runs[("III", one.table.columns[0])].v_y_V)
        assert (res.saturation.values == 0).all()
    # the seeds differ where the noise matters: Case III of the tracking test
    assert tr.per_seed.xs("case_III", level="row")[25.0].nunique() == 3


@pytest.mark.parametrize("seeds, match", [
    ([], r"at least 2 seed\(s\), got 0"),
    ([5], r"got 1: N >= 2 seeds are needed for a confidence interval"),
    ([1, 2.0], "seeds must be integers"),
    ([1, -2], "seeds must be non-negative"),
    ([4, 4], "seeds must be distinct"),
    (7, "seeds must be a sequence"),
])
def test_experiments_reject_bad_seeds(stage, seeds, match):
    for test in (ex.hysteresis_test, ex.tracking_test):
        with pytest.raises(ValueError, match=match):
            test(stage, DAHL, paper.controller(), [20.0], seeds=seeds)


def test_unseeded_experiment_has_no_statistics(stage):
    res = ex.tracking_test(stage, DAHL, paper.controller(), frequencies_Hz=[50.0])
    assert res.seeds is None and res.low is None and res.high is None
    assert res.noise_free is None and res.per_seed is None
    for call in (lambda: res.statistics("case_III"), lambda: res.interval("case_III", 50.0),
                 lambda: res.over_seeds("case_III"),
                 lambda: ex.design_goal_table({"K": res})):
        with pytest.raises(ValueError, match="needs a result run with seeds"):
            call()


# --- statistics, claims and goals of seeded results ------------------------------------
def seeded_result(per_seed_rows, columns):
    """An ExperimentResult whose per-seed tables are ``per_seed_rows`` (seed -> {row: values})."""
    tables = {s: pd.DataFrame(rows, index=columns).T.reindex(paper.case_rows_index())
              for s, rows in per_seed_rows.items()}
    per_seed = pd.concat(tables, names=["seed"])
    stack = np.stack([t.to_numpy() for t in tables.values()])
    mean, low, high = metrics.mean_interval(stack, axis=0)

    def like(data):
        return pd.DataFrame(data, index=paper.case_rows_index(), columns=columns)
    return ex.ExperimentResult(like(mean), {}, pd.DataFrame(), like(low), like(high),
                               like(mean - 1.0), per_seed, tuple(tables))


def tracking_like(case_III_by_seed, columns=(1.0, 10.0, 50.0)):
    columns = pd.Index(columns, name="frequency_Hz")
    rows = {s: {r: np.full(len(columns), 1.0 + s) for r in paper.case_rows_index()}
            for s in case_III_by_seed}
    for s, values in case_III_by_seed.items():
        rows[s]["case_III"] = np.asarray(values, dtype=float)
    return seeded_result(rows, columns)


def test_statistics_interval_and_reductions_over_seeds():
    res = tracking_like({0: [0.5, 0.9, 4.0], 1: [0.7, 0.8, 4.4], 2: [0.6, 1.0, 4.2]})
    stats = res.statistics("case_III")
    assert list(stats.index) == ["mean", "95 % low", "95 % high", "noise-free"]
    np.testing.assert_allclose(stats.loc["mean"], [0.6, 0.9, 4.2])
    np.testing.assert_allclose(stats.loc["noise-free"], stats.loc["mean"] - 1.0)
    assert res.interval("case_III", 50.0) == (res.low.loc["case_III", 50.0],
                                              res.high.loc["case_III", 50.0])
    # each seed's largest error over 1-10 Hz, then the mean of those: not the max of the means
    assert res.over_seeds("case_III", [1.0, 10.0]) == pytest.approx(
        metrics.mean_interval([0.9, 0.8, 1.0]))
    assert res.over_seeds("case_III", how="mean") == pytest.approx(
        metrics.mean_interval([5.4 / 3, 5.9 / 3, 5.8 / 3]))
    with pytest.raises(ValueError, match="how must be"):
        res.over_seeds("case_III", how="median")


def test_design_goals_are_judged_on_the_interval():
    below = tracking_like({0: [0.5, 0.6, 4.0], 1: [0.5, 0.7, 4.1], 2: [0.6, 0.65, 4.05]})
    above = tracking_like({0: [0.5, 1.2, 5.5], 1: [0.5, 1.3, 5.6], 2: [0.6, 1.25, 5.4]})
    across = tracking_like({0: [0.5, 0.5, 4.0], 1: [0.5, 1.5, 6.0], 2: [0.6, 1.0, 5.0]})
    no_50 = tracking_like({0: [0.5, 0.6], 1: [0.5, 0.7], 2: [0.6, 0.65]}, columns=(1.0, 10.0))
    table = ex.design_goal_table({"below": below, "above": above, "across": across,
                                  "no 50 Hz": no_50})
    assert table["goal < 1 % up to 10 Hz"].tolist() == ["met", "missed", "undecided", "met"]
    assert table["goal < 5 % at 50 Hz"].tolist() == ["met", "missed", "undecided", "undecided"]
    assert table.loc["above", "max error up to 10 Hz [%]"] == pytest.approx(1.25)
    assert np.isnan(table.loc["no 50 Hz", "error at 50 Hz [%]"])
    loose = ex.design_goal_table({"above": above}, goals={
        "peak_to_peak_error_pct_up_to_10Hz": 2.0, "peak_to_peak_error_pct_at_50Hz": 6.0})
    assert loose.loc["above", "goal < 2 % up to 10 Hz"] == "met"


def test_table_claims_one_per_published_cell_with_the_tolerances():
    columns = pd.Index([1.0, 10.0, 15.0], name="frequency_Hz")      # 15 Hz: not published
    published = paper.table5()
    rows = {s: {r: published.reindex(columns=columns).loc[r].fillna(1.0).to_numpy() + 0.01 * s
                for r in published.index} for s in range(3)}
    res = seeded_result(rows, columns)
    claims = report.ClaimTable("claims_test", "reference")
    ex.add_table_claims(claims, "Table 5", published, res, "tracking error {row} at {col:g} Hz",
                        notes={"case_I": "calibration"})
    ex.add_table_claims(claims, "Table 5", published, res, "{row} at {col:g} Hz, published K",
                        rows=["case_III"], notes="eq. 24 K", reason="")
    frame = claims.frame()
    assert frame.quantity.tolist()[:3] == ["tracking error case_I at 1 Hz",
                                           "tracking error case_I at 10 Hz",
                                           "tracking error case_II at 1 Hz"]
    assert len(frame) == 6 * 2 + 2 and (frame.verdict == "agrees").all()
    assert frame.note.tolist()[:2] == ["calibration"] * 2
    assert set(frame.note[frame.quantity.str.contains("improvement")]) == {
        "from the case rows above"}
    assert set(frame.note[frame.quantity.str.contains("case_II ")]) == {""}
    assert frame.quantity.iloc[-1] == "case_III at 10 Hz, published K"
    assert frame.note.iloc[-1] == "eq. 24 K"
    case_I = frame.set_index("quantity").loc["tracking error case_I at 1 Hz"]
    assert case_I.tolerance == "+-20%"
    assert case_I.low == pytest.approx(res.low.loc["case_I", 1.0])
    improvement = frame.set_index("quantity").loc["tracking error improvement_II_vs_I at 1 Hz"]
    assert improvement.tolerance == "+-5"
    with pytest.raises(ValueError, match="needs a result run with seeds"):
        ex.add_table_claims(claims, "Table 5", published,
                            ex.ExperimentResult(res.table, {}, pd.DataFrame()), "{row}")
