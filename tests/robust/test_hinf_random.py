"""hinfsyn against independent references on seeded random well-posed plants.

Two references: the optimum of the classical two-Riccati test
(``riccati_reference.py`` next to this file: numpy/scipy only, no code shared
with hinfsyn), and python-control's hinfsyn (SLICOT SB10AD), whose controller's
recomputed closed-loop norm is the reference (its reported gamma is not
trusted).  The 50-plant sweep with both is ``benchmarks/bench_hinf_random.py``.
"""

import control as ct
import numpy as np
import pytest
import riccati_reference as riccati
from scipy.optimize import brentq

from piezolib.robust.hinf import HinfSynthesisError, hinfsyn
from piezolib.robust.lft import lower_lft
from piezolib.robust.lti import hinf_norm


def random_well_posed_plant(rng, n):
    """Random P with D12 = [0; 1], D21 = [0, 1], D11 = D22 = 0 (2 w, 1 u, 2 z, 1 y).

    A has random (possibly unstable) modes; (A, B2) and (A, C2) are generic,
    so the standard assumptions hold with probability one.
    """
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, 3))
    C = rng.standard_normal((3, n))
    D = np.array([[0.0, 0, 0], [0, 0, 1], [0, 1, 0]])
    return ct.ss(A, B, C, D, inputs=["w1", "w2", "u"], outputs=["z1", "z2", "y"])


def reference_norm(P):
    """||F_l(P, K_SB10AD)||_inf recomputed, or None when SB10AD fails."""
    try:
        K, _, _, _ = ct.hinfsyn(P, 1, 1)
    except Exception:
        return None
    M = lower_lft(P, K)
    if np.any(ct.poles(M).real >= 0):
        return None
    return hinf_norm(M, omega=np.logspace(-4, 4, 4000))[0]


# a sweep (SLICOT comparison on ten plants): the two-Riccati test below covers the same paths
@pytest.mark.slow
@pytest.mark.parametrize("seed", range(10))
def test_random_plant_matches_python_control(seed):
    rng = np.random.default_rng(1000 + seed)
    P = random_well_posed_plant(rng, int(rng.integers(2, 6)))
    ref = reference_norm(P)
    res = hinfsyn(P, 1, 1, rtol=1e-4)
    # verified: stable, and the recomputed norm is within the reported gamma
    assert np.all(res.closed_loop_poles.real < 0)
    assert res.converged and res.regularization == ""
    assert res.norm <= res.gamma * (1 + 1e-3)
    assert res.gamma_infeasible < res.gamma
    if ref is not None:
        # no better verified controller exists than our gamma (0.1 %), and
        # our infeasibility claim is not contradicted by SB10AD's controller
        assert res.gamma <= ref * (1 + 1e-3)
        assert res.gamma_infeasible <= ref * (1 + 1e-6)


@pytest.mark.parametrize("seed", range(12))
def test_random_plant_matches_the_two_riccati_optimum(seed):
    # A's scale spans four decades, so gamma ranges over about 1 ... 1e5
    rng = np.random.default_rng(2000 + seed)
    P = random_well_posed_plant(rng, int(rng.integers(2, 9)))
    P = ct.ss(P.A * 10 ** rng.uniform(-2, 2), P.B, P.C, P.D)
    reference = riccati.riccati_optimal_gamma(P)
    res = hinfsyn(P, 1, 1, rtol=1e-4)
    assert res.converged and res.norm <= res.gamma * (1 + 1e-3)
    assert abs(res.gamma / reference - 1) <= 1e-3
    # the infeasible end of our bracket is below the optimum (up to the bisection's accuracy)
    assert res.gamma_infeasible <= reference * (1 + 1e-4)


def test_riccati_reference_and_hinfsyn_on_a_scalar_problem():
    # xdot = x + 2 w1 + u, z = (x, u), y = x + w2: the Riccati equations are scalar,
    # 2 x + x^2 (4 / g^2 - 1) + 1 = 0 and 2 y + y^2 (1 / g^2 - 1) + 4 = 0, and the optimum
    # solves x(g) y(g) = g^2 (a root found here by brentq: 1 + sqrt(6))
    def root(g, b2, c2):
        k = 1 - b2 / g**2
        return (1 + np.sqrt(1 + c2 * k)) / k

    optimum = brentq(lambda g: root(g, 4, 1) * root(g, 1, 4) - g**2, 2.01, 50, xtol=1e-14)
    P = ct.ss([[1.0]], [[2.0, 0, 1]], [[1.0], [0], [1]], [[0, 0, 0], [0, 0, 1], [0, 1, 0]])
    assert abs(riccati.riccati_optimal_gamma(P) / optimum - 1) <= 1e-6
    assert riccati.riccati_gamma_feasible(P, optimum * (1 + 1e-6))
    assert not riccati.riccati_gamma_feasible(P, optimum * (1 - 1e-6))
    assert abs(hinfsyn(P, 1, 1, rtol=1e-6).gamma / optimum - 1) <= 1e-5


@pytest.mark.parametrize("seed", [90021, 90052])
def test_ill_conditioned_optimum_backs_off_instead_of_raising(seed):
    # near these optima (gamma 1.4e3 and 3.5e5) a verified central controller, realised
    # for the given plant, can leave a closed-loop pole across the axis (seen at
    # 0.0023 + 0.013j and 0.20 + 207j rad/s; which controllers do is set by rounding) and
    # hinfsyn raised; now such a controller is rejected and another one near the optimum,
    # or a backed-off gamma, stabilises the given plant with a margin
    P, ny, nu = riccati.random_orthonormal_plant(np.random.default_rng(seed))
    res = hinfsyn(P, ny, nu, rtol=1e-4, gamma_max=1e9)
    assert res.gamma <= res.gamma_infeasible * 1.02
    poles = ct.poles(ct.ss(P).lft(res.K, nu=nu, ny=ny))
    assert np.all(poles.real < 0)
    assert res.norm <= res.gamma * (1 + 1e-3)


@pytest.mark.parametrize("seed", [90285, 90333])
def test_optimum_zero_claims_no_positive_infeasible_gamma(seed):
    # one state, square D12 and D21: z and y can be made independent of w, the optimum is
    # 0 (60-digit two-Riccati test: rho(XY) / gamma^2 ~ 0 even at gamma = 1e-9); the search
    # stops at its floor 1e-9 gamma, which was reported as "infeasible"
    P, ny, nu = riccati.random_orthonormal_plant(np.random.default_rng(seed))
    assert P.nstates == 1
    res = hinfsyn(P, ny, nu, rtol=1e-4, gamma_max=1e9)
    assert res.gamma_infeasible == 0.0
    assert res.norm <= res.gamma < 1e-6


@pytest.mark.parametrize("seed", range(8))
def test_rescaled_controls_measurements_and_d22_keep_the_optimum(seed):
    # u -> T u, y -> S y (condition numbers up to 1e3) and a D22 leave the optimum as it is;
    # the reference runs on the plant before the change
    rng = np.random.default_rng(70000 + seed)
    P, ny, nu = riccati.random_orthonormal_plant(rng)
    reference = riccati.riccati_optimal_gamma(P, ny, nu)
    res = hinfsyn(riccati.rescaled_controls_and_measurements(rng, P, ny, nu), ny, nu, rtol=1e-4)
    assert res.norm <= res.gamma * (1 + 1e-3)
    assert abs(res.gamma / reference - 1) <= 1e-3
    assert res.gamma_infeasible <= reference * (1 + 1e-4)


def test_default_regularisation_is_raised_where_no_controller_verifies():
    # a random plant with D12 = 0: with the default effort output 1e-3 u (and 1e-2, 1e-1)
    # X spans 14 decades and no central controller near the optimum verifies (60-digit
    # two-Riccati test: feasible from about 8e6; at 1e-1 every loop unstable up to 1e9
    # under one BLAS kernel, a few verified 8 % above the optimum under another); with
    # 1.0 the search converges
    P, ny, nu = riccati.random_orthonormal_plant(np.random.default_rng(60073))
    D = np.array(P.D)
    D[:-ny, -nu:] = 0
    P = ct.ss(P.A, P.B, P.C, D)
    res = hinfsyn(P, ny, nu, rtol=1e-4, gamma_max=1e9)
    assert res.effort_weight == 1.0 and "raised from the default" in res.regularization
    assert res.converged and res.norm <= res.gamma * (1 + 1e-3)
    assert np.all(ct.poles(P.lft(res.K, nu=nu, ny=ny)).real < 0)
    # with the weight fixed at 1e-3 nothing converges: either no controller verifies at all,
    # or the retry on the modal realisation verifies one short of the optimum, and says so
    try:
        fixed = hinfsyn(P, ny, nu, rtol=1e-4, gamma_max=1e9, effort_weight=1e-3)
    except HinfSynthesisError as exc:
        assert "effort_weight" in str(exc)
    else:
        assert not fixed.converged and fixed.norm <= fixed.gamma * (1 + 1e-3)
        assert np.all(ct.poles(P.lft(fixed.K, nu=nu, ny=ny)).real < 0)
