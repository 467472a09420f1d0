"""Fixed-pole basis models on synthetic MIMO systems with a known nonlinearity."""

import control as ct
import numpy as np
import pytest

from piezolib import identification as ident
from piezolib.identification import basis_model as bm

RNG = np.random.default_rng(7)
N = 2000
POLES = np.array([0.95, 0.8 * np.exp(0.6j), 0.9 * np.exp(1.4j)])     # one real, two pairs


def _records(count, rms, n_u=2, seed=0):
    rng = np.random.default_rng(seed)
    return [rms * rng.standard_normal((N, n_u)) for _ in range(count)]


def _two_by_two():
    """A 2 x 2 discrete system with the poles of POLES (known)."""
    den = np.real(np.poly([POLES[0], POLES[1], POLES[1].conj(), POLES[2], POLES[2].conj()]))
    nums = [[[0.0, 0.3, -0.1, 0.05], [0.0, 0.1, 0.02]], [[0.0, -0.2, 0.1], [0.0, 0.4, 0.0, 0.1]]]
    return ct.ss(ct.tf(nums, [[den, den], [den, den]], 1.0))


def test_static_polynomial_before_a_known_filter_is_recovered():
    """y = G(q) [u + c u|u|] on 2 inputs: the fit on the filter's poles predicts fresh data to
    the noise level and returns c as the ratio of the branches' coefficients."""
    G, c, noise = _two_by_two(), 0.4, 1e-3
    truth = lambda u: ident.simulate_discrete(G, u + c * u * np.abs(u))
    u_fit, u_new = _records(4, 1.0, seed=1), _records(2, 1.0, seed=2)
    y_fit = [truth(u) + noise * RNG.standard_normal((N, 2)) for u in u_fit]
    branches = [("u", 0), ("u|u|", 0)]
    model = ident.fit_basis_model(u_fit, y_fit, ident.basis_poles([G]), branches, 50.0, 1.0)
    for u in u_new:
        y = truth(u)
        rms_err = np.sqrt(np.mean((model.simulate(u) - y) ** 2, axis=0))
        # noise 1e-3 on 8000 samples: coefficient error ~ noise / sqrt(N) per regressor; the
        # prediction error on fresh data is then a fraction of the noise level
        assert np.all(rms_err < noise), rms_err
    half = model.theta.shape[1] // 2
    lin, quad = model.theta[:, :half], model.theta[:, half:]
    big = np.abs(lin) > 0.05 * np.abs(lin).max()
    # c is the same for every regressor of the u|u| branch: within 1 % where the linear one is
    # not small (a relative error of noise / signal ~ 1e-3 per coefficient, times 10 margin)
    assert np.allclose(quad[big] / lin[big], c, rtol=1e-2)


def test_amplitude_scheduled_resonance_needs_the_schedule():
    """A 2 x 2 system whose resonance moves with the input's level (truth: each record's own
    pole, pole angle falling with the RMS): the model with the poles of the end levels and a
    quadratic schedule predicts an intermediate level far better than the one without."""
    def system(rms):
        p = 0.95 * np.exp(1j * (0.8 - 0.05 * rms))        # resonance 6 % lower at the top level
        den = np.real(np.poly([p, p.conj(), 0.7]))
        return ct.ss(ct.tf([[[0.0, 0.2, 0.1], [0.0, 0.1]], [[0.0, 0.05], [0.0, 0.3, -0.1]]],
                           [[den, den], [den, den]], 1.0))

    levels = (0.5, 1.0, 1.5)
    u_fit = [u for i, lv in enumerate(levels) for u in _records(2, lv, seed=10 + i)]
    y_fit = [ident.simulate_discrete(system(lv), u) for lv in levels
             for u in u_fit[2 * levels.index(lv):2 * levels.index(lv) + 2]]
    poles = ident.basis_poles([system(lv) for lv in levels])
    u_new = _records(1, 1.25, seed=20)[0]
    y_new = ident.simulate_discrete(system(1.25), u_new)

    def error(branches):
        m = ident.fit_basis_model(u_fit, y_fit, poles, branches, 100.0, 1.0, n_init=100)
        e = m.simulate(u_new)[100:] - y_new[100:]
        return float(np.mean(np.sqrt(np.mean(e ** 2, axis=0)) / np.std(y_new[100:], axis=0)))

    plain, scheduled = error([("u", 0)]), error([("u", 0), ("u", 1), ("u", 2)])
    # the unscheduled model is one LTI compromise of the three levels; the scheduled one
    # interpolates in the running RMS between the levels' poles (the pole at 1.25 is not in
    # the basis, and the RMS of a 100-sample window fluctuates by ~7 %: what keeps it above 0)
    assert scheduled < 0.25 * plain, (plain, scheduled)      # measured 0.185 and 0.029
    assert scheduled < 0.05


def test_selection_picks_the_true_structure_on_held_out_records():
    G = _two_by_two()
    truth = lambda u: ident.simulate_discrete(G, u + 0.3 * u ** 3)
    u = _records(4, 0.8, seed=3)
    y = [truth(x) + 1e-3 * RNG.standard_normal((N, 2)) for x in u]
    sel = ident.select_basis_model(u[:3], y[:3], u[3:], y[3:], ident.basis_poles([G]),
                                   [[("u", 0)], [("u", 0), ("u|u|", 0)], [("u", 0), ("u^3", 0)]],
                                   [20.0, 200.0], 1.0)
    assert sel.branches == (("u", 0), ("u^3", 0))
    assert sel.validation_nrmse.shape == (2, 3, 1)
    assert sel.mean_validation_nrmse.min() < 0.01
    # the window does not matter to unscheduled branches: same error at both
    assert np.allclose(sel.validation_nrmse[0], sel.validation_nrmse[1])


def test_model_is_causal_and_starts_from_rest():
    G = _two_by_two()
    u = _records(1, 1.0, seed=4)[0]
    y = ident.simulate_discrete(G, u)
    model = ident.fit_basis_model([u], [y], ident.basis_poles([G]),
                                  [("u", 0), ("u", 1), ("u|u|", 1)], 30.0, 1.0)
    v = u.copy()
    v[1000:] = 5 * RNG.standard_normal(v[1000:].shape)       # change the future only
    assert np.array_equal(model.simulate(u)[:1000], model.simulate(v)[:1000])
    assert np.all(model.simulate(np.zeros((50, 2))) == 0)


def test_gram_matches_the_product():
    X = RNG.standard_normal((300, 17))
    assert np.allclose(bm._gram(X), X.T @ X)


def test_running_rms_growing_then_exponential_window():
    u = np.ones((10, 3, 2))
    u[:, :, 1] *= 2
    a = ident.running_rms(u, 4.0)
    assert a.shape == (10, 2) and np.allclose(a[:, 0], 1) and np.allclose(a[:, 1], 2)
    u = np.r_[np.ones((4, 1)), np.zeros((6, 1))]
    a2 = ident.running_rms(u, 4.0) ** 2
    assert np.allclose(a2[:4], 1) and np.allclose(a2[4:], 0.75 ** np.arange(1, 7))


def test_model_round_trip_and_shapes():
    G = _two_by_two()
    u = _records(2, 1.0, seed=5)
    arr = np.stack(u, axis=2)[..., None]                       # (N, 2, 2 records, 1)
    y = ident.simulate_discrete(G, arr)
    model = ident.fit_basis_model(arr, y, ident.basis_poles([G]), [("u", 0), ("u", 1)], 30.0, 1.0)
    again = ident.BasisModel.from_arrays(model.to_arrays())
    assert again.branches == model.branches and np.array_equal(again.simulate(arr), model.simulate(arr))
    assert model.simulate(arr).shape == y.shape
    assert model.n_regressors == 2 * (5 + 1) * 2


@pytest.mark.parametrize("kwargs, name", [
    (dict(poles=[1.0]), "poles"), (dict(poles=[0.5 - 0.2j]), "poles"),
    (dict(branches=[("tanh", 0)]), "branches"), (dict(branches=[("u", -1)]), "power"),
    (dict(branches=[("u", 0), ("u", 0)]), "branches"), (dict(window_samples=0.5), "window_samples"),
    (dict(input_scale=0.0), "input_scale"), (dict(n_init=N), "u"), (dict(ridge=-1.0), "ridge")])
def test_bad_arguments_name_themselves(kwargs, name):
    u = _records(1, 1.0, seed=6)
    args = dict(u=u, y=[x[:, :1] for x in u], poles=[0.5], branches=[("u", 0)],
                window_samples=10.0, input_scale=1.0) | kwargs
    with pytest.raises((ValueError, TypeError), match=name):
        ident.fit_basis_model(**args)


def test_stepper_is_simulate_one_sample_at_a_time():
    # every branch kind, complex and real poles, the window passing from growing to sliding
    rng = np.random.default_rng(4)
    poles = np.array([0.95, 0.6 + 0.3j, -0.2])
    branches = (("u", 0), ("u", 1), ("u|u|", 2), ("u^3", 0))
    n_reg = len(branches) * (bm._n_bank(poles) + 1) * 2
    model = ident.BasisModel(poles, branches, 30.0, 0.7, rng.standard_normal((3, n_reg)), 2)
    u = rng.standard_normal((200, 2))
    run = model.stepper()
    np.testing.assert_allclose([run.step(x) for x in u], model.simulate(u), rtol=1e-11,
                               atol=1e-12)
    with pytest.raises(ValueError, match="u"):
        run.step(np.zeros(3))
    with pytest.raises(ValueError, match="u"):
        run.step([np.nan, 0.0])
    with pytest.raises(TypeError, match="model"):
        ident.BasisStepper("model")
