"""Prandtl-Ishlinskii model: play operators, NNLS fit, exact inverse feedforward."""

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import signals

FS = 10_000.0
R = tuple(0.3 * np.arange(6))
W = (0.8, 0.2, 0.0, 0.15, 0.1, 0.05)


def minor_loops(n=4001):
    t = np.linspace(0, 1, n)
    return 1.6 + 1.2 * np.sin(2 * np.pi * 3 * t) + 0.4 * np.sin(2 * np.pi * 17 * t)


def test_play_operator_is_backlash():
    v = np.array([0.0, 1.0, 2.0, 1.5, 1.0, 0.5, 1.0])
    y = hy.play_outputs(v, np.array([0.0, 0.5]), np.array([0.0, 0.0]))
    np.testing.assert_allclose(y[:, 0], v)
    np.testing.assert_allclose(y[:, 1], [0.0, 0.5, 1.5, 1.5, 1.5, 1.0, 1.0])


@pytest.mark.parametrize("start", hy.PI_STARTS)
def test_fit_recovers_known_weights_exactly(start):
    true = hy.PIModel(R, W, x0=-0.1, start=start)
    loops = [(v, true.simulate(v)) for v in
             (signals.triangle(A, 10.0, fs=FS, periods=2)[1] for A in (1.0, 2.0, 3.0))]
    loops.append((minor_loops(), true.simulate(minor_loops())))
    fit = hy.fit_pi(loops, thresholds=R, start=start)
    np.testing.assert_allclose(fit.model.weights, W, rtol=0, atol=1e-10)
    assert fit.model.x0 == pytest.approx(-0.1, abs=1e-10)
    assert fit.worst_rms_percent < 1e-8
    table = fit.parameter_table()
    assert table["at_bound"].tolist() == [False, False, True, False, False, False, False]
    assert table.loc["w_1 (r = 0.3)", "identifiable"]


@pytest.mark.parametrize("start", hy.PI_STARTS)
def test_inverse_composed_with_model_is_the_identity(start):
    m = hy.PIModel(R, W, x0=0.3, start=start)
    x_r = minor_loops()
    np.testing.assert_allclose(m.simulate(m.feedforward(x_r)), x_r, rtol=0, atol=1e-12)
    v = minor_loops()[::-1].copy()
    inverse, state = m.inverse(v[0])
    np.testing.assert_allclose(inverse.simulate(m.simulate(v) - m.x0, state=state), v,
                               rtol=0, atol=1e-12)
    assert isinstance(m, hy.HysteresisModel)


def test_static_part_is_the_line_the_major_loop_is_centred_on():
    m = hy.PIModel(R, W, x0=0.3)
    gain, offset = m.static_part
    assert gain == pytest.approx(sum(W)) and offset == 0.3
    # beyond 2 r_max every play moves: the branches are the line -+ sum w_i r_i
    v = np.r_[np.linspace(0.0, 6.0, 601), np.linspace(6.0, 0.0, 601)[1:]]
    x = m.simulate(v)
    rising, falling = x[300], x[-301]                      # both at v = 3
    assert (rising + falling) / 2 == pytest.approx(gain * 3.0 + offset, abs=1e-12)


def test_not_invertible_and_bad_input_raise_clearly():
    flat = hy.PIModel(R, (0.0,) + W[1:])
    assert not flat.invertible
    with pytest.raises(hy.NotInvertibleError, match="w_0 > 0"):
        flat.feedforward(minor_loops())
    with pytest.raises(ValueError, match="start at 0"):
        hy.PIModel((0.1, 0.2), (1.0, 1.0))
    with pytest.raises(ValueError, match="one weight per threshold"):
        hy.PIModel(R, (1.0,))
    with pytest.raises(TypeError, match="must be real"):
        hy.PIModel(R, W).simulate(minor_loops() + 1j)
    with pytest.raises(ValueError, match="start must be one of"):
        hy.PIModel(R, W, start="lowered")


def test_zero_linear_weight_is_reported():
    """Data with a dead zone after every reversal: w_0 ends on its bound, with a warning."""
    true = hy.PIModel((0.0, 0.4), (0.0, 1.0))
    t, v = signals.triangle(2.0, 10.0, fs=FS, periods=2)
    with pytest.warns(hy.FitWarning, match="w_0"):
        fit = hy.fit_pi([(v, true.simulate(v))], thresholds=(0.0, 0.4))
    assert fit.parameter_table()["at_bound"].iloc[0]


def test_every_weight_on_its_bound_is_named_in_a_warning():
    """docs/hysteresis.md: a FitWarning names every parameter on a bound, not only w_0."""
    true = hy.PIModel(R, W, x0=-0.1)
    loops = [(v, true.simulate(v)) for v in
             (signals.triangle(A, 10.0, fs=FS, periods=2)[1] for A in (1.0, 2.0, 3.0))]
    zero = [i for i, w in enumerate(W) if w == 0]
    assert zero and zero[0] > 0
    with pytest.warns(hy.FitWarning, match=f"w_{zero[0]} "):
        hy.fit_pi(loops, thresholds=R, start="rest")


@pytest.mark.parametrize("start", hy.PI_STARTS)
def test_the_default_start_is_the_one_the_data_support(start):
    """Data from either initial state: the default fit finds it (exactly), not always "rest"."""
    true = hy.PIModel(R, W, x0=-0.1, start=start)
    v = np.r_[minor_loops(), signals.triangle(3.0, 10.0, fs=FS, periods=2)[1]]
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hy.FitWarning)
        fit = hy.fit_pi([(v, true.simulate(v))], thresholds=R)
    assert fit.model.start == start
    assert fit.worst_rms_percent < 1e-8
    assert set(fit.start_scores) == set(hy.PI_STARTS)
