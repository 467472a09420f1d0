"""Mixed-mu synthesis (D,G-K iteration) on textbook problems with known answers.

The problems, their closed forms and sources are in ``textbook_problems.py``:

* gain-margin optimisation of P0 = (s - z)/((s - p)(s + a)) (p = 1, z = 2) with the gain
  in [0.5, 1.5] (ratio 3): no controller stabilises a ratio of (z/p)^2 = 4 or more, a
  complex disc certifies less than z/p = 2 [T80, KT85, DFT92];
* the ACC benchmark's two carts with the spring 0.5 <= k <= 2 [WB92]: controllers
  stabilising the whole interval exist.

mixed_musyn's default start (the complex DK design) does not leave the complex optimum on
the gain problem (strict xfail, reported); started from the closed-form controller of
:func:`tp.gain_margin_controller` its D,G-K steps certify the target.  The carts' mixed
design takes 20-45 s and is marked slow.

Every verdict on a controller is computed from the physical loop (plant and K, not the
LFT the design saw) by the exact crossing gains of :func:`tp.real_stability_interval`
and a root locus on a fine grid of the parameter (numpy/scipy only), never by
piezolib's margin code.  ``benchmarks/bench_mixed_musyn.py`` prints the same designs
as a table, with times and dkpy's complex DK beside them.
"""

import control as ct
import numpy as np
import pytest

import textbook_problems as tp
from piezolib.robust.dgk import mixed_musyn
from piezolib.robust.dk import musyn
from piezolib.robust.mu import mussv

# design grids [rad/s]: 200 points cover the gain problem's p, z and the wide
# bandwidth its high-gain controllers need, and the carts' rigid body and flexible mode
GAIN_GRID = np.logspace(-3, 3, 200)
ACC_GRID = np.logspace(-3, 2, 200)
# root-locus points per unit of the parameter interval (the exact crossings decide; the
# grid is a second, independent route)
LOCUS_POINTS = 2001


def design_mixed(P, blk, omega, **options):
    """mixed_musyn (SISO controller) with its defaults unless given (the API in one place)."""
    return mixed_musyn(P, blk, omega, **options)


def exact_range(loop):
    """(k_lo, k_hi): the exact stable interval of the physical parameter around k0.

    Its finite ends are checked to be tight: 1e-4 (relative to k - k0) beyond each, the
    loop has a right-half-plane eigenvalue (an eigenvalue crosses the axis there, so the
    interval is not shortened by a spurious candidate; crossings are transversal).
    """
    A0, b, c, k0 = loop
    t_lo, t_hi = tp.real_stability_interval(A0, b, c)
    ends = [t for t in (t_lo, t_hi) if np.isfinite(t)]
    assert np.all(tp.stable_on_grid(A0, b, c, np.array(ends) * (1 + 1e-4)) > 0)
    return k0 + t_lo, k0 + t_hi


def assert_locus_stable(loop, k_lo, k_hi):
    """Every closed loop on a fine grid of [k_lo, k_hi] is Hurwitz (an independent route)."""
    A0, b, c, k0 = loop
    k = np.linspace(k_lo, k_hi, LOCUS_POINTS)
    worst = tp.stable_on_grid(A0, b, c, k - k0)
    assert worst.max() < 0, f"unstable at k = {k[np.argmax(worst)]:.6g}"


def certified_interval(prob_k0, r, mu, additive):
    """The parameter interval a mu upper bound certifies: |delta| < 1/mu with
    k = k0 (1 + r delta) (gain problem; the lower end clipped at 0) or k = k0 + r delta
    (carts)."""
    rho = r / mu
    if additive:
        return prob_k0 - rho, prob_k0 + rho
    return prob_k0 * (1 - min(rho, 1.0)), prob_k0 * (1 + rho)


# --- 1. gain-margin optimisation -----------------------------------------------------------

@pytest.fixture(scope="module")
def gain():
    return tp.gain_margin()


@pytest.fixture(scope="module")
def gain_mixed(gain):
    return design_mixed(gain.P, gain.blk_mixed, GAIN_GRID)


def witness_controller(gain, ratio=3.5, alpha=30.0):
    """The closed-form controller for [1, ratio], rescaled by (1 + ratio)/2 so that its
    interval is centred on k0 = 1 (u = K y convention)."""
    return -ct.ss(tp.gain_margin_controller(gain.p, gain.z, 1.0, ratio, alpha)) * ((1 + ratio) / 2)


@pytest.fixture(scope="module")
def gain_mixed_from_witness(gain):
    return design_mixed(gain.P, gain.blk_mixed, GAIN_GRID, K0=witness_controller(gain),
                        dg_steps=6, refinements=1)


@pytest.fixture(scope="module")
def gain_complex(gain):
    return musyn(gain.P, gain.blk_complex, 1, 1, GAIN_GRID, d_order=2)


def test_crossing_gains_of_a_static_controller_are_exact():
    """u = kappa y on (s - z)/((s - p)(s + a)): the closed loop is
    s^2 + (a - p - k kappa) s + (k kappa z - a p), Hurwitz iff a p / z < k kappa < a - p
    (one crossing at s = 0, one on the imaginary axis)."""
    prob = tp.gain_margin(p=1.0, z=2.0, a=3.0, k_lo=1.6, k_hi=1.9)
    kappa = 1.0
    K = ct.ss([], [], [], [[kappa]])
    k_lo, k_hi = exact_range(tp.gain_loop(prob, K))
    assert k_lo == pytest.approx(3.0 * 1.0 / 2.0 / kappa, rel=1e-12)
    assert k_hi == pytest.approx((3.0 - 1.0) / kappa, rel=1e-12)


def test_closed_forms_of_the_gain_problem(gain):
    p, z = gain.p, gain.z
    assert tp.gain_ratio_sup_real(p, z) == 4.0
    assert tp.gain_ratio_sup_complex(p, z) == 2.0
    # the complex disc of radius (z - p)/(z + p) holds exactly the real ratio z/p
    assert tp.ratio_of_radius((z - p) / (z + p)) == pytest.approx(z / p, rel=1e-15)
    assert (gain.k_lo, gain.k_hi) == (gain.k0 * (1 - gain.r), gain.k0 * (1 + gain.r))
    assert tp.ratio_of_radius(gain.r) == pytest.approx(3.0, rel=1e-15)


@pytest.mark.parametrize("ratio, alpha", [(3.0, 10.0), (3.5, 30.0), (3.9, 200.0)])
def test_explicit_controllers_approach_the_real_supremum(gain, ratio, alpha):
    """The closed-form controllers of :func:`tp.gain_margin_controller` (order 3) stabilise
    [1, ratio] for ratios up to (z/p)^2 = 4 and never beyond: the supremum is approached.
    T = c (w^2 - 1) keeps off the slit including its end, so the interval is open around
    [1, ratio] (strict inequalities, no tolerance)."""
    C = tp.gain_margin_controller(gain.p, gain.z, 1.0, ratio, alpha)
    prob = tp.gain_margin(p=gain.p, z=gain.z, a=1.0, k_lo=1.0, k_hi=ratio)
    loop = tp.gain_loop(prob, -ct.ss(C))
    k_lo, k_hi = exact_range(loop)
    assert k_lo < 1.0 and k_hi > ratio
    assert k_hi / k_lo < tp.gain_ratio_sup_real(gain.p, gain.z)
    assert_locus_stable(loop, 1.0, ratio)
    with pytest.raises(ValueError, match="too small"):
        tp.gain_margin_controller(gain.p, gain.z, 1.0, ratio, alpha / 10)


def test_design_target_is_attainable_in_mixed_mu(gain):
    """A witness for the mixed design's target: the closed-form controller for the ratio 3.5,
    rescaled so that its interval is centred on k0 = 1, has mixed mu < 1 on the design
    structure (the regularising channels included), so mixed_musyn missing mu < 1 would be
    the synthesis' shortfall, not the problem's."""
    K = witness_controller(gain)
    k_lo, k_hi = exact_range(tp.gain_loop(gain, K))
    assert k_lo < gain.k_lo and k_hi > gain.k_hi
    N = tp.pointwise_lft(gain.P, K, GAIN_GRID)
    assert mussv(N, gain.blk_mixed).upper.max() < 1


def check_mixed_gain_design(gain, res):
    """The design interval (ratio 3) is certified: beyond z/p = 2, below (z/p)^2 = 4."""
    loop = tp.gain_loop(gain, res.K)
    k_lo, k_hi = exact_range(loop)
    ratio = k_hi / k_lo
    # the theorem: no controller reaches (z/p)^2, whatever mixed_musyn reports
    assert ratio < tp.gain_ratio_sup_real(gain.p, gain.z)
    # mu < 1 certifies the design interval [0.5, 1.5], which no complex disc can (z/p = 2)
    assert res.mu_peak < 1
    assert k_lo <= gain.k_lo and k_hi >= gain.k_hi
    assert ratio > tp.gain_ratio_sup_complex(gain.p, gain.z)
    assert_locus_stable(loop, gain.k_lo, gain.k_hi)
    # the certificate of the dense verification grid holds in the exact loop
    cert_lo, cert_hi = certified_interval(gain.k0, gain.r, res.verified_peak, additive=False)
    assert k_lo <= cert_lo and k_hi >= cert_hi


@pytest.mark.xfail(strict=True, reason="mixed_musyn's start, the complex DK design (mu 1.507, "
                   "|T0| flat, the real worst case at DC), is a point the local D,G-K steps "
                   "do not leave: no step is accepted and mu stays 1.507 (reported to the lead)")
def test_mixed_design_certifies_more_than_any_complex_disc(gain, gain_mixed):
    check_mixed_gain_design(gain, gain_mixed)


def test_mixed_steps_from_a_good_start_keep_and_improve_the_certificate(gain,
                                                                         gain_mixed_from_witness):
    """Started from the closed-form controller (mixed mu 0.90), the D,G-K steps may only
    lower the mixed bound, and the result passes every check of the known answer."""
    res = gain_mixed_from_witness
    assert res.mu_peak <= res.start_mu_peak
    check_mixed_gain_design(gain, res)


def test_complex_design_cannot_certify_more_than_z_over_p(gain, gain_complex):
    """Nevanlinna-Pick: sup |r T0| >= r (z + p)/(z - p) = 1.5 for every stabilising K, so a
    complex certificate stays below z/p; musyn's mu bounds |r T0| from above."""
    res = gain_complex
    bound = tp.complex_mu_bound(gain.p, gain.z, gain.r)
    T_design = np.abs(tp.gain_T0(gain, res.K, GAIN_GRID))
    # mu of the whole loop >= mu of its 1 x 1 delta channel = |r T0| at each grid point
    assert np.all(res.mu_upper >= gain.r * T_design * (1 - 1e-9))
    # the theorem on this controller: the peak of |T0| (dense grid) reaches the bound
    dense = np.logspace(-4, 4, 20001)
    assert gain.r * np.abs(tp.gain_T0(gain, res.K, dense)).max() >= bound * (1 - 1e-6)
    # the exact loop is stable over what its mu certifies
    loop = tp.gain_loop(gain, res.K)
    k_lo, k_hi = exact_range(loop)
    cert_lo, cert_hi = certified_interval(gain.k0, gain.r, res.mu_peak, additive=False)
    assert k_lo <= cert_lo and k_hi >= cert_hi
    # so musyn's grid bound certifies no more than z/p, up to the sampling of the peak of
    # |T0|, which a near-optimal complex design makes flat (T0 ~ all-pass times 1.5/r)
    assert tp.ratio_of_radius(gain.r / res.mu_peak) < tp.gain_ratio_sup_complex(gain.p, gain.z) \
        * (1 + 1e-2)


@pytest.mark.xfail(strict=True, reason="see test_mixed_design_certifies_more_than_any_complex_disc")
def test_mixed_certificate_beats_the_complex_one(gain, gain_mixed, gain_complex):
    """Same plant, same grid: the real-parameter certificate is strictly wider (ratio 3
    against below 2): mixed mu < 1 < 1.5 <= complex mu (up to the grid's sampling of the
    flat complex peak, 1 %)."""
    assert gain_mixed.mu_peak < 1 < tp.complex_mu_bound(gain.p, gain.z, gain.r) \
        <= gain_complex.mu_peak * (1 + 1e-2)


# --- 2. ACC benchmark: two carts, uncertain spring -----------------------------------------

@pytest.fixture(scope="module")
def carts():
    return tp.acc_benchmark()


@pytest.fixture(scope="module")
def carts_mixed(carts):
    return design_mixed(carts.P, carts.blk_mixed, ACC_GRID)


@pytest.fixture(scope="module")
def carts_complex(carts):
    return musyn(carts.P, carts.blk_complex, 1, 1, ACC_GRID, d_order=2)


def test_spring_loop_matches_the_lft(carts):
    """The physical model of :func:`tp.spring_loop` at k is the LFT P closed by
    delta = (k - k0)/r (a check of both builders against each other, with K = 0: the
    open-loop state matrices are compared)."""
    K = ct.ss([], [], [], [[0.0]])
    A0, b, c, k0 = tp.spring_loop(carts, K)
    for k in (0.5, 1.0, 2.0):
        delta = (k - carts.k0) / carts.r
        A_lft = carts.P.A + delta * carts.P.B[:, :1] @ carts.P.C[:1]
        A_phys = (A0 + (k - k0) * b @ c)[:4, :4]
        np.testing.assert_allclose(A_phys, A_lft, rtol=0, atol=1e-15)
        # the undamped mode sqrt(2 k) rad/s (m1 = m2 = 1) and the rigid body at 0
        w = np.sort(np.abs(np.linalg.eigvals(A_phys)))
        np.testing.assert_allclose(w, [0, 0, np.sqrt(2 * k), np.sqrt(2 * k)], atol=1e-7)


# the carts' mixed design takes 20-45 s on the 2-core machine (20 D,G-K steps on 200
# frequencies; on 100 it stalls at mu 1.08), so its tests run with `pytest -m slow`
@pytest.mark.slow
def test_mixed_design_stabilises_the_benchmark_interval(carts, carts_mixed):
    """[WB92]: one controller stabilises 0.5 <= k <= 2 (exact crossings and root locus)."""
    res = carts_mixed
    loop = tp.spring_loop(carts, res.K)
    k_lo, k_hi = exact_range(loop)
    assert k_lo < tp.ACC_K_RANGE[0] and k_hi > tp.ACC_K_RANGE[1]
    assert_locus_stable(loop, *tp.ACC_K_RANGE)
    assert res.mu_peak < 1
    cert_lo, cert_hi = certified_interval(carts.k0, carts.r, res.verified_peak, additive=True)
    assert k_lo <= cert_lo and k_hi >= cert_hi


@pytest.mark.slow
def test_carts_mixed_certificate_is_no_worse_than_complex(carts, carts_mixed, carts_complex):
    """Mixed mu of a loop never exceeds its complex mu, and mixed_musyn starts from a complex
    DK design and keeps a step only when the mixed bound drops; so the mixed design certifies
    at least the complex design's range (both DK iterations stop within rtol = 5e-3 of their
    best, twice over: the start and our musyn differ in their D-fit orders)."""
    assert carts_mixed.mu_peak <= carts_mixed.start_mu_peak
    assert carts_mixed.mu_peak <= carts_complex.mu_peak * (1 + 2 * 5e-3)


def test_carts_complex_certificate_holds_in_the_exact_loop(carts, carts_complex):
    """What musyn's complex mu certifies (a disc of springs) holds for the real spring."""
    loop = tp.spring_loop(carts, carts_complex.K)
    k_lo, k_hi = exact_range(loop)
    cert_lo, cert_hi = certified_interval(carts.k0, carts.r, carts_complex.mu_peak,
                                          additive=True)
    assert k_lo <= cert_lo and k_hi >= cert_hi


# --- 3. bad input ------------------------------------------------------------------------------

def two_by_two_plant():
    """Inputs [w1, w2, u], outputs [z1, z2, y]: a 2 x 2 uncertainty/performance channel."""
    return ct.ss(-np.eye(2), np.array([[1.0, 0, 1], [0, 1, 1]]),
                 np.array([[1.0, 0], [0, 1], [1, 1]]),
                 np.array([[0, 0, 1.0], [0, 0, 1], [0, 1, 0]]))


@pytest.mark.parametrize("blk", [[(-2, 0)], [(2, 0)]])     # repeated real / complex scalar
def test_mixed_musyn_refuses_repeated_scalars(blk):
    with pytest.raises(ValueError, match="repeated"):
        mixed_musyn(two_by_two_plant(), blk, GAIN_GRID)


def test_mixed_musyn_refuses_a_real_last_block():
    with pytest.raises(ValueError, match="last block"):
        mixed_musyn(two_by_two_plant(), [(1, 1), (-1, 0)], GAIN_GRID)


@pytest.mark.parametrize("blk", [[(-1, 0), (2, 2)], [(-1, 0)], [(1, 2)]])
def test_mixed_musyn_refuses_a_structure_not_fitting_p(gain, blk):
    with pytest.raises(ValueError):
        mixed_musyn(gain.P, blk, GAIN_GRID)          # P's channel is 2 x 2


@pytest.mark.parametrize("option", [dict(dg_steps=0), dict(dk_iterations=0), dict(order=0),
                                    dict(refinements=-1), dict(d_order=-1),
                                    dict(dk_options={"no_such_option": 1})])
def test_mixed_musyn_refuses_bad_options(gain, option):
    with pytest.raises((ValueError, TypeError)):
        mixed_musyn(gain.P, gain.blk_mixed, GAIN_GRID, **option)


@pytest.mark.parametrize("K0, match", [
    (ct.ss([], [], [], [[-1.5]], dt=0), "does not stabilise"),     # P0 has a pole at +1
    (ct.ss(ct.tf([1.0], [1, 1])), "does not stabilise"),
    (ct.ss([], [], [], [[1.0, 1.0]], dt=0), "SISO"),
    (ct.ss(-0.5, 1, 1, 0, 0.1), "continuous"),
])
def test_mixed_musyn_refuses_a_bad_start(gain, K0, match):
    with pytest.raises(ValueError, match=match):
        mixed_musyn(gain.P, gain.blk_mixed, GAIN_GRID, K0=K0)
