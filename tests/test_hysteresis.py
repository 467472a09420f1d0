"""Dahl model (eq. 10-13), its fit and the feedforward of eq. 14."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from piezolib import hysteresis as hy
from piezolib import paper, signals

# a well-damped model whose loops look like a piezo's (x-unit: sensor V, v-unit: u_c V)
PARAMS = dict(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4.0 / 30.0, gamma_a=30.0, g_a=0.95)


def model(form="bliman_sorine", **overrides):
    return hy.DahlModel(**{**PARAMS, **overrides}, form=form)


def minor_loop_reference(n=6001):
    """A reference with reversals at several levels (nested minor loops)."""
    t = np.linspace(0, 1, n)
    return 2.0 + 1.5 * np.sin(2 * np.pi * 3 * t) + 0.5 * np.sin(2 * np.pi * 17 * t)


# --- the model -----------------------------------------------------------------
@pytest.mark.parametrize("form", hy.FORMS)
def test_closed_form_matches_time_domain_ode(form):
    """Integrate eq. 10 in time (solve_ivp, stroke by stroke) for x = 2 sin(wt) and compare."""
    m = model(form, beta1=0.05)
    omega = 2 * np.pi * 5.0
    a1, a2, g = m.alpha1, m.alpha2, m.gamma_a

    def rhs(t, z):
        d = 2.0 * omega * np.cos(omega * t)
        if form == "printed":
            return [z[1] * d, (-a2 * z[0] - a1 * np.sign(d) * z[1]) * d + g * d]
        return [z[1] * abs(d), (-a2 * z[0] - a1 * z[1]) * abs(d) + g * d]

    t = np.arange(3701) * 1e-4                  # reversals at 0.05, 0.15, ... fall on samples
    x = 2.0 * np.sin(omega * t)
    z_ref, z_now = [np.zeros(2)], np.zeros(2)
    for a, b in zip([0, 500, 1500, 2500, 3500], [500, 1500, 2500, 3500, 3700]):
        sol = solve_ivp(rhs, (t[a], t[b]), z_now, t_eval=t[a:b + 1], rtol=1e-12, atol=1e-14)
        z_ref.append(sol.y.T[1:])
        z_now = sol.y[:, -1]
    z_ref = np.vstack(z_ref)
    s = np.sign(np.r_[1.0, np.diff(x)])
    H, z = hy.dahl_hysteresis(m, x, return_state=True)
    np.testing.assert_allclose(z, z_ref, rtol=0, atol=1e-8)
    np.testing.assert_allclose(H, m.beta2 * z_ref[:, 0] + m.beta1 * s * z_ref[:, 1],
                               rtol=0, atol=1e-8)


@pytest.mark.parametrize("direction", [1, -1])
def test_printed_form_settles_to_same_H_both_ways(direction):
    m = hy.DahlModel.published("printed")
    expected = paper.DAHL.beta2 * paper.DAHL.gamma_a / paper.DAHL.alpha2
    assert m.steady_state(direction) == pytest.approx(expected, rel=1e-12)
    # a long stroke either way after a long stroke the other way: H stays at the steady state
    x = np.r_[np.linspace(0, 1, 101), np.linspace(1, -1, 201)[1:]] * direction
    H = hy.dahl_hysteresis(m, x)
    np.testing.assert_allclose(H[50:], expected, rtol=1e-9)


def test_bliman_sorine_saturates_at_plus_minus_h():
    m = model("bliman_sorine", alpha1=400.0, alpha2=1e4)   # transient 0.005 x-units
    h = m.beta2 * m.gamma_a / m.alpha2
    assert (m.steady_state(1), m.steady_state(-1)) == pytest.approx((h, -h))
    x = np.r_[np.linspace(0, 1, 1001), np.linspace(1, 0, 1001)[1:]]
    H = hy.dahl_hysteresis(m, x)
    assert H[1000] == pytest.approx(h, rel=1e-12) and H[-1] == pytest.approx(-h, rel=1e-12)


@pytest.mark.parametrize("form", hy.FORMS)
def test_integration_is_exact_for_any_sampling(form):
    """Splitting every step into six sub-steps along the same path changes nothing."""
    m = model(form)
    x = minor_loop_reference(301)
    refined = np.concatenate([np.linspace(a, b, 7)[:-1] for a, b in zip(x[:-1], x[1:])]
                             + [x[-1:]])
    np.testing.assert_allclose(hy.dahl_hysteresis(m, refined)[::6], hy.dahl_hysteresis(m, x),
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("form", hy.FORMS)
def test_rate_independence_1Hz_vs_50Hz(form):
    m = model(form)
    t1, v1 = signals.triangle(4.0, 1.0, periods=2)      # 10 000 samples per period
    t50, v50 = signals.triangle(4.0, 50.0, periods=2)   # 200 samples per period
    x1, x50 = hy.simulate_dahl(m, v1).x, hy.simulate_dahl(m, v50).x
    # at 10 kHz the 50 Hz samples fall on every 50th sample of the 1 Hz record
    np.testing.assert_allclose(x1[::50], x50, rtol=0, atol=1e-12)
    assert np.ptp(x1 - v1 * m.g_a) > 0.1        # H varies: the comparison is not trivial


@pytest.mark.parametrize("form", hy.FORMS)
def test_voltage_driven_model_satisfies_eq13(form):
    m = model(form)
    v = minor_loop_reference() / m.g_a
    r = hy.simulate_dahl(m, v)
    np.testing.assert_allclose(r.x + r.H, m.g_a * v, rtol=0, atol=1e-12)
    # and H is the displacement-driven H of the solved x
    np.testing.assert_allclose(hy.dahl_hysteresis(m, r.x), r.H, rtol=0, atol=1e-12)


def test_bliman_sorine_loop_width_known():
    """With a short transient the branches are g_a v -+ h: hysteresis % = 2h/(g dv - 2h)."""
    m = model("bliman_sorine", alpha1=2000.0, alpha2=1e6, beta2=0.2 * 1e6 / 30.0)
    h = m.steady_state(1)
    assert h == pytest.approx(0.2)
    t, v = signals.triangle(4.0, 10.0, periods=2)
    x = hy.simulate_dahl(m, v).x
    width = 2 * h / (m.g_a * 4.0 - 2 * h) * 100
    # X_MAX, X_MIN are averages over the samples next to the turning points (metrics.py)
    assert hy.hysteresis_percent(v[1000:], x[1000:]) == pytest.approx(width, rel=2e-3)


def test_printed_form_has_no_loop_after_long_strokes():
    m = model("printed", alpha1=200.0, alpha2=1e4)      # transient 0.01 x-units << 4
    t, v = signals.triangle(4.0, 10.0, periods=2)
    x = hy.simulate_dahl(m, v).x
    assert hy.hysteresis_percent(v[1000:], x[1000:]) == pytest.approx(0.0, abs=1e-9)


def test_hysteresis_percent_when_input_jumps_across_the_window():
    """Coarse strokes with no sample near V_M: the two samples around V_M are used."""
    up = np.array([0.0, 0.7, 1.45, 2.2, 3.0])
    v = np.r_[up, up[::-1][1:], up[1:], up[::-1][1:]]
    descending = np.r_[False, np.diff(v) < 0]
    branch = np.where(descending, 0.1, -0.1)          # branches 0.2 apart ...
    branch[(v == 0) | (v == 3)] = 0.0                 # ... meeting at the turning points
    x = 2 * v + branch
    assert hy.hysteresis_percent(v, x) == pytest.approx(0.2 / 6.0 * 100, rel=1e-12)


# --- feedforward (eq. 14) ------------------------------------------------------
@pytest.mark.parametrize("form", hy.FORMS)
@pytest.mark.parametrize("alpha1", [3.0, 4.0, 10.0])   # oscillatory, critical, overdamped
def test_feedforward_inverts_the_model(form, alpha1):
    m = model(form, alpha1=alpha1)
    x_r = minor_loop_reference()
    u_f = hy.feedforward(m, x_r)
    x = hy.simulate_dahl(m, u_f).x
    np.testing.assert_allclose(x, x_r, rtol=0, atol=1e-9)


@pytest.mark.parametrize("form", hy.FORMS)
@pytest.mark.parametrize("alpha1", [3.0, 4.0, 10.0])
def test_stateful_feedforward_equals_array_version(form, alpha1):
    m = model(form, alpha1=alpha1, beta1=0.02)
    x_r = minor_loop_reference()
    ff = hy.DahlFeedforward(m)
    u_steps = np.array([ff.step(r) for r in x_r[:3000]] + list(ff.run(x_r[3000:])))
    np.testing.assert_allclose(u_steps, hy.feedforward(m, x_r), rtol=0, atol=1e-11)
    assert ff.H == pytest.approx(hy.dahl_hysteresis(m, x_r)[-1], abs=1e-11)
    ff.reset()
    assert ff.state == (0.0, 0.0)
    assert ff.step(x_r[0]) == pytest.approx(x_r[0] / m.g_a)


# --- output offset x0 and initial state (workbook extensions) --------------------
@pytest.mark.parametrize("form", hy.FORMS)
def test_offset_only_shifts_the_output(form):
    m = model(form)
    v = minor_loop_reference() / m.g_a
    plain, shifted = hy.simulate_dahl(m, v), hy.simulate_dahl(m.with_offset(-0.15), v)
    np.testing.assert_allclose(shifted.x, plain.x - 0.15, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shifted.H, plain.H, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shifted.x + shifted.H, m.g_a * v - 0.15, rtol=0, atol=1e-12)
    assert model(form).x0 == 0.0 and hy.DahlModel.published(form).x0 == 0.0   # eq. 13


@pytest.mark.parametrize("form", hy.FORMS)
@pytest.mark.parametrize("start", hy.STARTS)
@pytest.mark.parametrize("alpha1", [3.0, 10.0, 400.0])   # oscillatory, overdamped, first-order-like
def test_feedforward_inverts_the_model_with_offset(form, start, alpha1):
    m = model(form, alpha1=alpha1, x0=-0.153, start=start)
    x_r = minor_loop_reference()
    u_f = hy.feedforward(m, x_r)
    np.testing.assert_allclose(hy.simulate_dahl(m, u_f).x, x_r, rtol=0, atol=1e-9)
    np.testing.assert_allclose(hy.DahlFeedforward(m).run(x_r), u_f, rtol=0, atol=1e-11)
    # u_f = (x_r - x0 + H(x_r)) / g_a, H from the model's start state
    H = hy.dahl_hysteresis(m, x_r)
    np.testing.assert_allclose(u_f, (x_r - m.x0 + H) / m.g_a, rtol=0, atol=1e-15)


def test_rest_start_is_the_state_after_a_long_descending_stroke():
    m = model("bliman_sorine", start="rest")
    z0, s0 = m.initial_state()
    assert s0 == -1
    assert hy.dahl_hysteresis(m, [0.0, 0.0])[0] == pytest.approx(m.steady_state(-1), rel=1e-12)
    # a record from rest equals the virgin model's response after lowering it by 50 x-units
    # (>> the transient length 2/alpha1) onto the record's first sample
    x = minor_loop_reference()
    virgin = model("bliman_sorine")                      # default start: virgin, z = 0
    lowered = np.r_[np.linspace(x[0] + 50.0, x[0], 2001), x[1:]]
    H_virgin = hy.dahl_hysteresis(virgin, lowered, direction0=-1)
    np.testing.assert_allclose(hy.dahl_hysteresis(m, x), H_virgin[2000:], rtol=0, atol=1e-12)
    assert virgin.initial_state()[1] == 1 and np.all(virgin.initial_state()[0] == 0)


def test_feedforward_of_published_model_is_offset_only():
    """Printed form, published numbers: after the first transient u_f = (x_r + 26.97)/g_a."""
    m = hy.DahlModel.published("printed")
    t, x_r = signals.triangle(3.6, 10.0, periods=2)
    u_f = hy.feedforward(m, x_r)
    np.testing.assert_allclose(u_f[100:], (x_r[100:] + m.steady_state(1)) / m.g_a, rtol=1e-9)


# --- fit -----------------------------------------------------------------------
@pytest.mark.parametrize("form", hy.FORMS)
def test_fit_recovers_known_parameters(form):
    true = model(form, alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = []
    for amplitude in (1.0, 2.0, 3.0, 4.0):
        t, v = signals.triangle(amplitude, 10.0, periods=2)
        loops.append((v, hy.simulate_dahl(true, v).x))
    fit = hy.fit_dahl(loops, form=form, stride=5)
    for name in ("alpha1", "alpha2", "beta2", "g_a"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-6), name
    assert fit.model.gamma_a == paper.DAHL.gamma_a and fit.model.beta1 == 0.0
    assert np.all(fit.rms_percent < 1e-6)
    assert len(fit.x_model) == 4 and fit.residuals[0].shape == loops[0][0].shape


@pytest.mark.parametrize("form, start", [("bliman_sorine", "virgin"), ("bliman_sorine", "rest"),
                                         ("printed", "virgin")])
def test_fit_recovers_known_parameters_including_offset(form, start):
    true = model(form, alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9, x0=-0.15,
                 start=start)
    loops = []
    for amplitude in (1.0, 2.0, 3.0, 4.0):
        t, v = signals.triangle(amplitude, 10.0, periods=2)
        loops.append((v, hy.simulate_dahl(true, v).x))
    fit = hy.fit_dahl(loops, form=form, offset=True, start=start, stride=5)
    for name in ("alpha1", "alpha2", "beta2", "g_a", "x0"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-6), name
    assert fit.offset and fit.model.start == start
    assert fit.pooled_rms_percent < 1e-6
    # the paper's form (no offset) cannot represent the shifted loops
    paper_form = hy.fit_dahl(loops, form=form, start=start, stride=5)
    assert paper_form.model.x0 == 0.0 and paper_form.worst_rms_percent > 0.1


def test_fit_reaches_the_first_order_limit():
    """A first-order-like model (alpha1 >> 2 sqrt(alpha2)) is recovered inside the bounds."""
    true = model("bliman_sorine", alpha1=300.0, alpha2=420.0, beta2=0.25 * 420.0 / 30.0,
                 g_a=1.25, x0=-0.15, start="rest")
    loops = [(v, hy.simulate_dahl(true, v).x) for v in
             (signals.triangle(A, 10.0, periods=2)[1] for A in (1.0, 2.0, 3.0, 4.0))]
    fit = hy.fit_dahl(loops, offset=True, start="rest", discard=1000, stride=5)
    assert not np.any(fit.result.active_mask)                 # no parameter on a bound
    assert fit.pooled_rms_percent < 1e-4
    for name in ("g_a", "x0"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-4), name
    # the first-order quantities: rate alpha2/alpha1 and steady state b2 gamma_a / alpha2
    assert fit.model.alpha2 / fit.model.alpha1 == pytest.approx(1.4, rel=1e-3)
    assert fit.model.steady_state(1) == pytest.approx(0.25, rel=1e-4)


def test_choose_fit_takes_the_smallest_pooled_rms():
    fake = {key: type("Fit", (), {"pooled_rms_percent": value})()
            for key, value in (("a", 2.0), ("b", 0.5), ("c", 0.5), ("d", 3.0))}
    assert hy.choose_fit(fake) == "b"
    with pytest.raises(ValueError, match="at least one"):
        hy.choose_fit({})


def test_workbook_fit_is_shared_and_deterministic():
    first = hy.workbook_dahl_fit()
    assert hy.workbook_dahl_fit() is first                    # cached: one model everywhere
    assert hy.fit_case_I_loops(*hy.WORKBOOK_DAHL) is first
    form, offset, start = hy.WORKBOOK_DAHL
    assert (first.model.form, first.offset, first.model.start) == (form, offset, start)
    hy._fit_case_I_loops.cache_clear()
    again = hy.workbook_dahl_fit()
    assert again is not first and again.model == first.model  # refitted: bit-identical
    np.testing.assert_array_equal(again.rms_percent, first.rms_percent)
    with pytest.raises(TypeError, match="offset must be True or False"):
        hy.fit_case_I_loops("bliman_sorine", 1, "rest")
    with pytest.raises(ValueError, match="start must be one of"):
        hy.fit_case_I_loops("bliman_sorine", True, "lowered")


def test_fit_single_loop_and_discard():
    true = model("bliman_sorine")
    t, v = signals.triangle(3.0, 10.0, periods=2)
    x = hy.simulate_dahl(true, v).x
    fit = hy.fit_dahl((v, x), discard=1000)
    assert fit.residuals[0].size == v.size - 1000
    assert fit.model.g_a == pytest.approx(true.g_a, rel=1e-6)


# --- bad input -----------------------------------------------------------------
@pytest.mark.parametrize("overrides, match", [
    (dict(g_a=0.0), "g_a must be positive"),
    (dict(g_a=-0.9), "g_a must be positive"),
    (dict(alpha1=0.0), "alpha1 must be positive"),
    (dict(alpha2=float("nan")), "alpha2 must be finite"),
    (dict(beta2=float("inf")), "beta2 must be finite"),
])
def test_bad_parameters_raise(overrides, match):
    with pytest.raises(ValueError, match=match):
        model(**overrides)


def test_bad_form_and_direction_raise():
    with pytest.raises(ValueError, match="form must be one of"):
        model("first_order")
    with pytest.raises(ValueError, match="direction must be"):
        model().steady_state(0)
    with pytest.raises(ValueError, match="start must be one of"):
        model(start="lowered")
    with pytest.raises(ValueError, match="x0 must be finite"):
        model(x0=float("nan"))
    with pytest.raises(TypeError, match="x0 must be a real number"):
        model(x0="0")


def test_bad_records_raise():
    m = model()
    with pytest.raises(ValueError, match="x contains 1 non-finite"):
        hy.dahl_hysteresis(m, [0.0, np.nan, 1.0])
    with pytest.raises(ValueError, match="v contains 1 non-finite"):
        hy.simulate_dahl(m, [0.0, 1.0, np.nan])
    with pytest.raises(ValueError, match="x_r contains"):
        hy.feedforward(m, [0.0, np.inf])
    with pytest.raises(ValueError, match="x_r must be finite"):
        hy.DahlFeedforward(m).step(float("nan"))
    with pytest.raises(TypeError, match="model must be a DahlModel"):
        hy.feedforward(paper.DAHL, [0.0, 1.0])
    with pytest.raises(ValueError, match="beta1 = 0"):
        hy.simulate_dahl(model(beta1=0.1), [0.0, 1.0])


def test_fit_rejects_records_without_a_full_cycle():
    ramp = np.linspace(0, 4, 500)
    with pytest.raises(ValueError, match="no full cycle"):
        hy.fit_dahl([(ramp, 0.9 * ramp)])
    t, v = signals.triangle(4.0, 10.0, periods=1)
    with pytest.raises(ValueError, match="no full cycle"):
        hy.fit_dahl([(v, 0.9 * v)], discard=600)
    with pytest.raises(ValueError, match="equal lengths"):
        hy.fit_dahl([(v, v[:-1])])
    with pytest.raises(ValueError, match="contains 1 non-finite"):
        hy.fit_dahl([(v, np.r_[np.nan, v[1:]])])
    with pytest.raises(TypeError, match=r"loops\[0\] must be a \(v, x\) pair"):
        hy.fit_dahl({10.0: (v, v)})
    with pytest.raises(ValueError, match="starts must be >= 1"):
        hy.fit_dahl([(v, 0.9 * v)], starts=0)
    with pytest.raises(TypeError, match="offset must be True or False"):
        hy.fit_dahl([(v, 0.9 * v)], offset="yes")
    with pytest.raises(ValueError, match="start must be one of"):
        hy.fit_dahl([(v, 0.9 * v)], start="lowered")


def test_monotonicity_check_is_exact():
    """The closed-form minimum of d(x + H)/dsigma equals a dense-grid minimum."""
    rng = np.random.default_rng(0)
    for trial in range(200):
        a2, zeta = 10 ** rng.uniform(-1, 3), [0.1, 0.5, 1.0, 3.0][trial % 4]
        m = hy.DahlModel(2 * zeta * math.sqrt(a2), a2, 0.0, rng.normal(), 30.0, 1.0,
                         form=hy.FORMS[trial % 2])
        dyn, s = hy._Dynamics(m), int(rng.choice([1, -1]))
        w, sigma_max = rng.normal(size=2) * [1 / a2, 1], 10 ** rng.uniform(-2, 1)
        sig = np.linspace(0, sigma_max, 20001)
        ec, es = dyn.parts(sig)
        C, N, P = dyn.C[s], dyn.N[s], dyn.P[s]
        dense = np.min(1 + s * (ec * (C @ N @ w) + es * (C @ N @ P @ w)))
        exact = hy._min_slope(dyn, s, w, sigma_max)
        assert exact <= dense + 1e-12 and exact == pytest.approx(dense, abs=1e-3 * (1 + abs(dense)))


def test_strongly_underdamped_model_is_not_invertible():
    m = hy.DahlModel.published("bliman_sorine")   # H overshoots: x + H(x) not monotone
    t, v = signals.triangle(4.0, 10.0, periods=1)
    with pytest.raises(hy.NotInvertibleError, match="not increasing"):
        hy.simulate_dahl(m, v)


# --- Table 4 measurement ---------------------------------------------------------
class DahlStage:
    """A 'stage' that is the Dahl model itself: v_y = x of the voltage-driven model."""

    def __init__(self, model):
        self.model = model

    def run(self, u_c):
        return type("Record", (), {"v_y_V": hy.simulate_dahl(self.model, u_c).x,
                                   "u_c_V": np.asarray(u_c)})


def test_table4_reference_is_case_I_triangle():
    t, v_r = hy.table4_reference(40.0)
    assert v_r.max() == pytest.approx(40.0 / paper.AMPLIFIER_GAIN) and v_r.min() == 0.0
    assert t[-1] == pytest.approx(3 / paper.HYSTERESIS_TEST["frequency_Hz"])


def test_table4_measure_scales_axes_and_discards_start():
    t, v_r = hy.table4_reference(20.0)
    v_y = 0.9 * v_r - 0.05 * np.sign(np.gradient(v_r))       # branches 0.1 V apart
    v_y[:1000] += 0.3 * np.sin(np.linspace(0, 30, 1000))     # start-up junk, discarded
    m = hy.table4_measure(v_r, v_y)
    assert m.v_mid == pytest.approx(10.0)                    # actuator volts
    assert m.x_lo - m.x_up == pytest.approx(paper.UM_PER_VOLT * 0.1, rel=1e-9)   # um
    assert m.percent == pytest.approx(hy.hysteresis_percent(v_r[1000:], v_y[1000:]), rel=1e-12)
    with pytest.raises(ValueError, match="equal lengths"):
        hy.table4_measure(v_r, v_y[:-1])
    with pytest.raises(ValueError, match="leaves no record"):
        hy.table4_measure(v_r, v_y, discard_periods=3)


@pytest.mark.parametrize("m", [
    model("bliman_sorine"),
    hy.DahlModel(0.1, 0.3, 0.0, -0.01, 30.0, 0.93, form="printed"),   # long transients
])
def test_case_II_on_the_model_itself_removes_the_loop(m):
    plain = DahlStage(m).run(hy.table4_reference(30.0)[1])
    assert hy.table4_measure(plain.u_c_V, plain.v_y_V).percent > 1.0
    for A in (10.0, 30.0):
        t, v_r = hy.table4_reference(A)
        run = DahlStage(m).run(hy.feedforward(m, v_r))        # Case II: u_c = u_f (eq. 14)
        np.testing.assert_allclose(run.v_y_V, v_r, atol=1e-9)
        assert hy.table4_measure(v_r, run.v_y_V).percent < 1e-6
