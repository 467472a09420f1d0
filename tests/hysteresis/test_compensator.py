"""Dahl feedforward compensator of eq. 14 sample by sample: equals the record-level inverse."""

import numpy as np
import pytest

from piezolib import hysteresis as hy

# a well-damped model whose loops look like a piezo's (x-unit: sensor V, v-unit: u_c V)
PARAMS = dict(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4.0 / 30.0, gamma_a=30.0, g_a=0.95)


def model(form="bliman_sorine", **overrides):
    return hy.DahlModel(**{**PARAMS, **overrides}, form=form)


def minor_loop_reference(n=6001):
    """A reference with reversals at several levels (nested minor loops)."""
    t = np.linspace(0, 1, n)
    return 2.0 + 1.5 * np.sin(2 * np.pi * 3 * t) + 0.5 * np.sin(2 * np.pi * 17 * t)


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


def test_bad_feedforward_inputs_raise():
    with pytest.raises(ValueError, match="x_r must be finite"):
        hy.DahlFeedforward(model()).step(float("nan"))
    with pytest.raises(TypeError, match="model must be a DahlModel"):
        hy.DahlFeedforward(PARAMS)                       # the parameters, not a model
