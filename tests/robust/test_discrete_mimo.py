"""Tustin discretisation of MIMO controllers: the response against the bilinear map itself,
python-control's ``sample_system``, pre-warping, and the sampled MIMO loop."""

import control as ct
import numpy as np
import pytest
import scipy.signal as sig

from piezolib.robust.discrete import discretize, least_damped_frequency

FS = 2000.0                       # [Hz]
T = 1 / FS


def stable_system(n_states, n_out, n_in, seed, spread=(10.0, 2000.0)):
    """A random stable continuous system: real poles spread over ``spread`` [rad/s] and one
    lightly damped pair, in a random basis."""
    rng = np.random.default_rng(seed)
    real = -np.geomspace(*spread, n_states - 2)
    wn, zeta = 600.0, 0.05
    pair = np.array([[-zeta * wn, wn * np.sqrt(1 - zeta ** 2)],
                     [-wn * np.sqrt(1 - zeta ** 2), -zeta * wn]])
    A = np.zeros((n_states, n_states))
    A[:n_states - 2, :n_states - 2] = np.diag(real)
    A[n_states - 2:, n_states - 2:] = pair
    V = rng.standard_normal((n_states, n_states)) + 3 * np.eye(n_states)
    A = V @ A @ np.linalg.inv(V)
    return ct.ss(A, rng.standard_normal((n_states, n_in)), rng.standard_normal((n_out, n_states)),
                 rng.standard_normal((n_out, n_in)))


def bilinear_response(K, z, c):
    """K(s) at s = c (z - 1)/(z + 1) straight from the continuous matrices (no discretisation)."""
    A, B, C, D = (np.asarray(x) for x in (K.A, K.B, K.C, K.D))
    out = []
    for zk in np.atleast_1d(z):
        s = c * (zk - 1) / (zk + 1)
        out.append(D + C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B))
    return np.array(out)


def response(sys, z):
    return np.moveaxis(sys(np.atleast_1d(z), squeeze=False), -1, 0)


def sigma_max(M):
    return np.linalg.svd(M, compute_uv=False)[..., 0]


@pytest.mark.parametrize("shape, seed", [((2, 2), 0), ((3, 3), 1), ((2, 3), 2)])
def test_plain_tustin_is_the_bilinear_map(shape, seed):
    K = stable_system(6, *shape, seed)
    d = discretize(K, FS, prewarp=None, check_Hz=200.0)
    assert (d.K.noutputs, d.K.ninputs) == shape and d.K.dt == pytest.approx(T)
    theta = np.linspace(0.01, 0.99 * np.pi, 60)
    z = np.exp(1j * theta)
    exact = bilinear_response(K, z, 2 / T)
    got = response(d.K, z)
    scale = sigma_max(exact)
    assert np.max(sigma_max(got - exact) / scale) < 1e-9
    ref = response(ct.sample_system(K, T, method="tustin"), z)
    assert np.max(sigma_max(got - ref) / scale) < 1e-9


@pytest.mark.parametrize("shape, seed", [((2, 2), 3), ((3, 3), 4)])
def test_reported_error_is_the_singular_value_error(shape, seed):
    K = stable_system(6, *shape, seed)
    d = discretize(K, FS, prewarp=None, check_Hz=300.0, n_check=400)
    omega = np.linspace(2 * np.pi * 300.0 / 400, 2 * np.pi * 300.0, 400)
    kc = response(K, 1j * omega)
    kd = bilinear_response(K, np.exp(1j * omega * T), 2 / T)
    err = sigma_max(kd - kc) / sigma_max(kc)
    assert d.max_relative_error == pytest.approx(err.max(), rel=1e-6)
    assert d.omega_max_error == pytest.approx(omega[np.argmax(err)])
    # Tustin's frequency warping: the error grows with frequency, bounded by the warp of the
    # fastest feature; at 300 Hz and 2 kHz it is percent-level, not negligible
    assert 1e-4 < d.max_relative_error < 1.0
    assert d.matches == (d.max_relative_error <= 0.1)


def test_prewarp_is_exact_at_the_least_damped_pole_of_a_mimo_controller():
    K = stable_system(5, 3, 3, seed=5)
    w0 = least_damped_frequency(K, 1e4)
    assert w0 == pytest.approx(600.0, rel=1e-6)
    d = discretize(K, FS, prewarp="auto", check_Hz=150.0)
    assert d.prewarp_frequency == pytest.approx(600.0, rel=1e-6)
    got = response(d.K, np.exp(1j * w0 * T))[0]
    exact = response(K, 1j * w0)[0]
    assert sigma_max(got - exact) / sigma_max(exact) < 1e-9
    c = w0 / np.tan(w0 * T / 2)
    z = np.exp(1j * np.linspace(0.05, 3.0, 25))
    assert np.max(sigma_max(response(d.K, z) - bilinear_response(K, z, c))
                  / sigma_max(bilinear_response(K, z, c))) < 1e-9


def sampled_loop_radius(G, Kd):
    """Spectral radius of the ZOH plant (scipy) in negative feedback with Kd, by hand."""
    Ag, Bg, Cg, Dg, _ = sig.cont2discrete((G.A, G.B, G.C, G.D), T, method="zoh")
    Ak, Bk, Ck, Dk = (np.asarray(x) for x in (Kd.A, Kd.B, Kd.C, Kd.D))
    assert np.allclose(Dg, 0)                          # strictly proper plant: y = Cg x_g
    # u = Ck x_k + Dk e, e = -y
    A = np.block([[Ag - Bg @ Dk @ Cg, Bg @ Ck], [-Bk @ Cg, Ak]])
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def test_sampled_mimo_loop_rectangular():
    # plant 3 outputs x 2 inputs, controller 2 x 3
    rng = np.random.default_rng(6)
    G = ct.ss(-np.diag([5.0, 20.0, 80.0]), rng.standard_normal((3, 2)),
              rng.standard_normal((3, 3)), np.zeros((3, 2)))
    K = 0.5 * stable_system(4, 2, 3, seed=7, spread=(20.0, 200.0))
    d = discretize(K, FS, check_Hz=100.0, G=G)
    assert d.loop_spectral_radius == pytest.approx(sampled_loop_radius(ct.ss(G), d.K), rel=1e-8)
    assert d.loop_stable == (d.loop_spectral_radius < 1)
    big = discretize(200 * K, FS, check_Hz=100.0, G=G)
    assert big.loop_spectral_radius == pytest.approx(sampled_loop_radius(ct.ss(G), big.K),
                                                     rel=1e-8)
    assert big.loop_spectral_radius > 1 and not big.loop_stable


def test_plant_of_the_wrong_shape_is_refused():
    K = stable_system(4, 2, 3, seed=8)
    with pytest.raises(ValueError, match=r"\bG\b"):
        discretize(K, FS, check_Hz=100.0, G=ct.ss(-np.eye(2), np.eye(2), np.eye(2),
                                                   np.zeros((2, 2))))
