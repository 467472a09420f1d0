"""Dahl model (eq. 10-13) and its exact integration."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from piezolib import hysteresis as hy
from piezolib import signals

FS = 10_000.0
# a well-damped model whose loops look like a piezo's (x-unit: sensor V, v-unit: u_c V)
PARAMS = dict(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4.0 / 30.0, gamma_a=30.0, g_a=0.95)


def model(form="bliman_sorine", **overrides):
    return hy.DahlModel(**{**PARAMS, **overrides}, form=form)


def triangle(peak, frequency_Hz, periods):
    return signals.triangle(peak, frequency_Hz, fs=FS, periods=periods)


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
    m = model("printed", alpha1=200.0, alpha2=1e4)      # transient 0.01 x-units
    expected = m.beta2 * m.gamma_a / m.alpha2
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
    t1, v1 = triangle(4.0, 1.0, periods=2)      # 10 000 samples per period
    t50, v50 = triangle(4.0, 50.0, periods=2)   # 200 samples per period
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


@pytest.mark.parametrize("form", hy.FORMS)
def test_several_records_equal_one_simulation_each(form):
    m = model(form, x0=-0.1, start="rest" if form == "bliman_sorine" else "virgin")
    records = [triangle(A, 10.0, periods=2)[1] for A in (1.0, 2.5, 4.0)]
    records.append(minor_loop_reference(1501) / m.g_a)
    for sim, v in zip(hy.simulate_dahl_records(m, records), records):
        one = hy.simulate_dahl(m, v)
        np.testing.assert_array_equal(sim.v, v)
        np.testing.assert_allclose(sim.x, one.x, rtol=0, atol=1e-13)
        np.testing.assert_allclose(sim.H, one.H, rtol=0, atol=1e-13)
    with pytest.raises(ValueError, match="at least one"):
        hy.simulate_dahl_records(m, [])
    with pytest.raises(ValueError, match="beta1 = 0"):
        hy.simulate_dahl_records(model(beta1=0.1), records)


def test_directions_from_another_record():
    """H driven by a noisy x with the stroke directions of the clean input v.

    Along a stroke of v the state depends only on x[k] - x[stroke start], not
    on the wiggles in between: where the noise is zero, H is that of v itself.
    """
    m = model("bliman_sorine")
    v = minor_loop_reference(2001)
    noise = np.random.default_rng(3).normal(0, 2e-2, v.size)
    noise[::2] = 0.0                                       # clean at even samples ...
    noise[[start for start, stop, s in hy.strokes(v)]] = 0.0   # ... and at the turning points
    H_clean = hy.dahl_hysteresis(m, v)
    H = hy.dahl_hysteresis(m, v + noise, directions=v)
    np.testing.assert_allclose(H[::2], H_clean[::2], rtol=0, atol=1e-13)
    # without them the noise reverses the motion: H depends on the wiggles
    assert np.max(np.abs(hy.dahl_hysteresis(m, v + noise)[::2] - H_clean[::2])) > 1e-3
    np.testing.assert_array_equal(hy.dahl_hysteresis(m, v, directions=v), H_clean)
    with pytest.raises(ValueError, match="equal lengths"):
        hy.dahl_hysteresis(m, v, directions=v[:-1])


def test_bliman_sorine_loop_width_known():
    """With a short transient the branches are g_a v -+ h: hysteresis % = 2h/(g dv - 2h)."""
    m = model("bliman_sorine", alpha1=2000.0, alpha2=1e6, beta2=0.2 * 1e6 / 30.0)
    h = m.steady_state(1)
    assert h == pytest.approx(0.2)
    t, v = triangle(4.0, 10.0, periods=2)
    x = hy.simulate_dahl(m, v).x
    width = 2 * h / (m.g_a * 4.0 - 2 * h) * 100
    # X_MAX, X_MIN are averages over the samples next to the turning points (measure.py)
    assert hy.hysteresis_percent(v[1000:], x[1000:]) == pytest.approx(width, rel=2e-3)


def test_printed_form_has_no_loop_after_long_strokes():
    m = model("printed", alpha1=200.0, alpha2=1e4)      # transient 0.01 x-units << 4
    t, v = triangle(4.0, 10.0, periods=2)
    x = hy.simulate_dahl(m, v).x
    assert hy.hysteresis_percent(v[1000:], x[1000:]) == pytest.approx(0.0, abs=1e-9)


# --- output offset x0 and initial state (workbook extensions) --------------------
@pytest.mark.parametrize("form", hy.FORMS)
def test_offset_only_shifts_the_output(form):
    m = model(form)
    v = minor_loop_reference() / m.g_a
    plain, shifted = hy.simulate_dahl(m, v), hy.simulate_dahl(m.with_offset(-0.15), v)
    np.testing.assert_allclose(shifted.x, plain.x - 0.15, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shifted.H, plain.H, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shifted.x + shifted.H, m.g_a * v - 0.15, rtol=0, atol=1e-12)
    assert model(form).x0 == 0.0                                          # eq. 13
    assert m.with_offset(-0.15).static_part == (m.g_a, -0.15)            # x + H = g_a v + x0


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


# --- invertibility of the voltage-driven model -------------------------------------
def test_monotonicity_check_is_exact():
    """The closed-form minimum of d(x + H)/dx along a stroke equals a dense-grid minimum.

    The dense minimum uses the states of :func:`dahl_hysteresis` on the grid and
    eq. 10 for the slope: with beta1 = 0, H = beta2 z1 and dz1/dx = z2 (printed)
    or sgn(x') z2 (Bliman-Sorine).
    """
    rng = np.random.default_rng(0)
    for trial in range(200):
        a2, zeta = 10 ** rng.uniform(-1, 3), [0.1, 0.5, 1.0, 3.0][trial % 4]
        m = hy.DahlModel(2 * zeta * math.sqrt(a2), a2, 0.0, rng.normal(), 30.0, 1.0,
                         form=hy.FORMS[trial % 2])
        s = int(rng.choice([1, -1]))
        bs = m.form == "bliman_sorine"
        z_ss = np.array([m.gamma_a / a2 * (s if bs else 1), 0.0])    # steady state of the stroke
        z0 = z_ss + rng.normal(size=2) * [1 / a2, 1]
        sigma_max = 10 ** rng.uniform(-2, 1)
        sig = np.linspace(0, sigma_max, 20001)
        H, z = hy.dahl_hysteresis(m, s * sig, z0=z0, direction0=s, return_state=True)
        dense = np.min(1 + m.beta2 * z[:, 1] * (s if bs else 1))
        exact = hy.min_stroke_slope(m, z0, s, sigma_max)
        assert exact <= dense + 1e-12 and exact == pytest.approx(dense, abs=1e-3 * (1 + abs(dense)))


def test_not_invertible_exactly_when_the_slope_turns_negative():
    """simulate_dahl raises where min_stroke_slope <= 0, and only there."""
    t, v = triangle(4.0, 10.0, periods=1)
    for zeta, invertible in ((0.15, False), (1.0, True)):
        m = model("bliman_sorine", alpha1=2 * zeta * math.sqrt(1e4), alpha2=1e4,
                  beta2=0.2 * 1e4 / 30.0)
        slope = hy.min_stroke_slope(m, *m.initial_state(), length=4.0)
        assert (slope > 0) == invertible
        if invertible:
            hy.simulate_dahl(m, v)
        else:
            with pytest.raises(hy.NotInvertibleError, match="not increasing") as err:
                hy.simulate_dahl(m, v)
            # the message names the damping and what to do with a raw record
            assert "0.15" in str(err.value)
            assert "skip_transient=True" in str(err.value) and "fit_hammerstein" in str(err.value)


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
    with pytest.raises(ValueError, match="direction must be"):
        hy.min_stroke_slope(model(), [0.0, 0.0], 0, 1.0)
    with pytest.raises(ValueError, match="length must be positive"):
        hy.min_stroke_slope(model(), [0.0, 0.0], 1, 0.0)


def test_bad_records_raise():
    m = model()
    with pytest.raises(ValueError, match="x contains 1 non-finite"):
        hy.dahl_hysteresis(m, [0.0, np.nan, 1.0])
    with pytest.raises(ValueError, match="v contains 1 non-finite"):
        hy.simulate_dahl(m, [0.0, 1.0, np.nan])
    with pytest.raises(ValueError, match="beta1 = 0"):
        hy.simulate_dahl(model(beta1=0.1), [0.0, 1.0])


@pytest.mark.parametrize("alpha1, alpha2", [(1e30, 1e30), (1e30, 1e40)])
def test_extreme_alpha_gives_the_first_order_limit(alpha1, alpha2):
    """alpha1 = 1e30: the first-order Dahl limit, H = s h (1 - e^(-rate sigma)) from z = 0,
    rate alpha2/alpha1 and h = beta2 gamma_a / alpha2 (the steady state) exactly."""
    h = 0.1
    m = hy.DahlModel(alpha1, alpha2, 0.0, h * alpha2 / 30.0, 30.0, 1.0, form="bliman_sorine")
    rate = alpha2 / alpha1
    x = np.linspace(0.0, 2.0, 201)
    expected = h * (1.0 - np.exp(-rate * x))
    np.testing.assert_allclose(hy.dahl_hysteresis(m, x), expected, rtol=1e-9, atol=1e-12)
    v = np.r_[np.linspace(0.0, 2.0, 101), np.linspace(2.0, 0.0, 101)[1:]]
    sim = hy.simulate_dahl(m, v)
    np.testing.assert_allclose(sim.x + sim.H, v, rtol=0, atol=1e-12)     # eq. 13 holds
    if rate < 1e6:          # (at rate 1e10, dH/dx = 1e9 h at a reversal: x's rounding shows)
        np.testing.assert_allclose(sim.H, hy.dahl_hysteresis(m, sim.x), rtol=0, atol=1e-12)
    else:
        np.testing.assert_allclose(sim.H[20:100], h, rtol=1e-12)           # steady state
        np.testing.assert_allclose(sim.H[120:], -h, rtol=1e-12)


def test_complex_input_is_a_clear_error():
    # complex x used to end in a bare KeyError: 0
    x = np.sin(np.linspace(0, 6, 200)) * (1 + 0.5j)
    with pytest.raises(TypeError, match="x must be real-valued"):
        hy.dahl_hysteresis(model(), x)
    with pytest.raises(TypeError, match="v must be real-valued"):
        hy.simulate_dahl(model(), x)


# --- the feedforward of eq. 14 on a record: the model's inverse -------------------

@pytest.mark.parametrize("form", hy.FORMS)
@pytest.mark.parametrize("alpha1", [3.0, 4.0, 10.0])   # oscillatory, critical, overdamped
def test_feedforward_inverts_the_model(form, alpha1):
    m = model(form, alpha1=alpha1)
    x_r = minor_loop_reference()
    u_f = hy.feedforward(m, x_r)
    x = hy.simulate_dahl(m, u_f).x
    np.testing.assert_allclose(x, x_r, rtol=0, atol=1e-9)


def test_feedforward_of_printed_model_is_offset_only():
    """Printed form, long strokes: after the first transient u_f = (x_r + H_ss)/g_a."""
    m = model("printed", alpha1=200.0, alpha2=1e4)
    t, x_r = signals.triangle(3.6, 10.0, fs=FS, periods=2)
    u_f = hy.feedforward(m, x_r)
    np.testing.assert_allclose(u_f[100:], (x_r[100:] + m.steady_state(1)) / m.g_a, rtol=1e-9)


def test_bad_feedforward_inputs_raise():
    with pytest.raises(ValueError, match="x_r contains"):
        hy.feedforward(model(), [0.0, np.inf])
    with pytest.raises(TypeError, match="model must be a DahlModel"):
        hy.feedforward(PARAMS, [0.0, 1.0])              # the parameters, not a model


@pytest.mark.parametrize("overrides, name", [(dict(alpha2=1e-300), "alpha2"),
                                             (dict(alpha1=1e-300), "alpha1"),
                                             (dict(alpha2=1e300), "alpha2"),
                                             (dict(gamma_a=1e200, alpha2=1e-10), "gamma_a")])
def test_parameters_beyond_double_precision_are_refused(overrides, name):
    # alpha2 = 1e-300 simulated to x ~ 1e301 (overflowing products) instead of the model
    with pytest.raises(ValueError, match=name):
        model(**overrides)
    model(gamma_a=1e-300)                   # a vanishing hysteresis is only weak: accepted


def test_a_record_changed_in_place_is_simulated_anew():
    # the strokes of a record are remembered by its content, never by the array object
    m = model()
    v = np.r_[np.linspace(0.0, 3.0, 31), np.linspace(2.9, 1.0, 20), np.linspace(1.1, 2.0, 10)]
    first = hy.simulate_dahl_records(m, [v])[0].x
    v[35:] = v[35]                              # a rest, then nothing moves: other strokes
    again = hy.simulate_dahl_records(m, [v])[0].x
    fresh = hy.simulate_dahl(m, v.copy()).x
    assert np.array_equal(again, fresh) and not np.array_equal(again, first)


def test_oscillatory_and_overdamped_strokes_match_the_closed_form():
    # parts(): the sinc-like and the sinh-like term against expm(N sigma) = ec I + es P
    from scipy.linalg import expm
    for a1, a2 in ((3.0, 2.0), (1.0, 4.0), (2.0, 1.0)):   # over-, under-, critically damped
        dyn = hy.StrokeDynamics(hy.DahlModel(a1, a2, 0.0, 1.0, 1.0, 1.0, form="bliman_sorine"))
        sigma = np.array([0.0, 1e-6, 0.3, 2.0])
        ec, es = dyn.parts(sigma)
        for k, sg in enumerate(sigma):
            E = expm(dyn.N[1] * sg)
            assert np.allclose(ec[k] * np.eye(2) + es[k] * dyn.P[1], E, rtol=1e-12, atol=1e-14)
