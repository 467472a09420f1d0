"""H-infinity synthesis wrapper: textbook optima, verification, failures."""

import time

import control as ct
import numpy as np
import pytest
import scipy.optimize as opt

import textbook_problems as tp
from piezolib import paper, robust
from piezolib.problem import genplant
from piezolib.robust.hinf import HinfSynthesisError, hinfsyn


def scalar_plant(a):
    """x' = a x + w1 + u, z = [x; u], y = x + w2 (inputs w1, w2, u; outputs z1, z2, y)."""
    A = [[a]]
    B = [[1.0, 0.0, 1.0]]
    C = [[1.0], [0.0], [1.0]]
    D = [[0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]]
    return ct.ss(A, B, C, D)


def scalar_optimum(a):
    """gamma_opt of :func:`scalar_plant`, derived by hand.

    Both Riccati equations reduce to 2 a X - q X^2 + 1 = 0 with q = 1 - g^-2,
    whose stabilising root is X = Y = 1 / (sqrt(a^2 + q) - a); it needs
    a^2 + q > 0, and X >= 0 needs q > 0 when a >= 0.  The coupling condition
    rho(XY) < g^2 reads X < g.
    """
    def excess(g):
        return 1.0 / (np.sqrt(a * a + 1 - g ** -2) - a) - g
    lowest = 1.0 if a >= 0 else 1 / np.sqrt(1 + a * a)
    return opt.brentq(excess, lowest + 1e-9, 1e3)


@pytest.mark.parametrize("a", [0.0, 1.0, -1.0, 3.0])
def test_scalar_textbook_optimum(a):
    res = hinfsyn(scalar_plant(a), 1, 1, rtol=1e-5)
    g_opt = scalar_optimum(a)
    if a == 0.0:
        assert g_opt == pytest.approx(np.sqrt(2), rel=1e-9)
    assert res.gamma == pytest.approx(g_opt, rel=1e-3)
    assert res.gamma_infeasible <= g_opt * (1 + 1e-6)
    # the recomputed closed-loop norm is what gamma promises
    assert res.norm <= res.gamma * (1 + 1e-3)
    assert res.norm >= g_opt * (1 - 1e-6)
    assert np.all(res.closed_loop_poles.real < 0)
    assert res.regularization == "" and res.converged


def _sb10ad_reference(P):
    """gamma of SLICOT SB10AD when its own controller verifies, else None."""
    try:
        K, CL, gam, _ = ct.hinfsyn(P, 1, 1)
    except Exception:
        return None
    if np.any(ct.poles(CL).real >= 0):
        return None
    norm = robust.hinf_norm(CL, omega=np.logspace(-4, 4, 4000))[0]
    return gam if abs(norm - gam) <= 1e-4 * gam else None


def random_plant(rng, n=4):
    """Stable random plant with D11 != 0, full-rank D12 and D21, D22 = 0 (2+1 in, 2+1 out)."""
    A = rng.standard_normal((n, n))
    A -= (np.linalg.eigvals(A).real.max() + 0.5) * np.eye(n)
    B, C = rng.standard_normal((n, 3)), rng.standard_normal((3, n))
    D = np.zeros((3, 3))
    D[:2, :2] = 0.4 * rng.standard_normal((2, 2))
    D[:2, 2:] = rng.standard_normal((2, 1))
    D[2:, :2] = rng.standard_normal((1, 2))
    return ct.ss(A, B, C, D)


def test_matches_slicot_on_random_plants_where_slicot_verifies():
    rng = np.random.default_rng(7)
    compared = 0
    for _ in range(5):
        P = random_plant(rng)
        ref = _sb10ad_reference(P)
        if ref is None:
            continue
        res = hinfsyn(P, 1, 1, rtol=1e-5)
        assert res.gamma == pytest.approx(ref, rel=2e-3)
        assert res.norm <= res.gamma * (1 + 1e-3)
        compared += 1
    assert compared >= 3       # SB10AD's own result verifies on most of these plants


def test_d22_loop_shift_keeps_the_optimum():
    P = scalar_plant(1.0)
    D = np.asarray(P.D).copy()
    D[2, 2] = 0.5
    res = hinfsyn(ct.ss(P.A, P.B, P.C, D), 1, 1, rtol=1e-5)
    # the closed loop is recomputed on the plant with D22, so this checks the shift
    assert res.gamma == pytest.approx(scalar_optimum(1.0), rel=1e-3)
    assert res.norm <= res.gamma * (1 + 1e-3)


def test_unstabilisable_plant_raises_quickly():
    # unstable mode at +1 not reachable from u
    A = np.diag([1.0, -1.0])
    B = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])     # w1, w2, u
    C = np.array([[1.0, 1.0], [0.0, 0.0], [1.0, 1.0]])
    D = np.array([[0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]])
    t0 = time.perf_counter()
    with pytest.raises(HinfSynthesisError, match="not controllable"):
        hinfsyn(ct.ss(A, B, C, D), 1, 1)
    assert time.perf_counter() - t0 < 10       # bounded: never a hang


def test_undetectable_plant_raises():
    A = np.diag([1.0, -1.0])
    B = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    C = np.array([[1.0, 1.0], [0.0, 0.0], [0.0, 1.0]])    # y does not see the +1 mode
    D = np.array([[0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]])
    with pytest.raises(HinfSynthesisError, match="not observable"):
        hinfsyn(ct.ss(A, B, C, D), 1, 1)


def test_rank_deficient_d12_is_regularised_and_reported():
    P = scalar_plant(-1.0)
    A, B, C = P.A, P.B, P.C[[0, 2]]
    D = np.asarray(P.D)[[0, 2]]                           # drop the u output: D12 = 0
    res = hinfsyn(ct.ss(A, B, C, D), 1, 1)
    assert "effort" in res.regularization and res.effort_weight == 1e-3
    assert res.norm <= res.gamma * (1 + 1e-3)
    with pytest.raises(HinfSynthesisError, match="D12 is rank deficient"):
        hinfsyn(ct.ss(A, B, C, D), 1, 1, effort_weight=None)


def test_published_plant_regularisation_and_verification():
    G, H_m, H_e, H_y, _ = paper.problem()
    P = genplant.generalized_plant(G, H_m, H_e, H_y)      # exact eq. 16, D12 = 2e-10
    res = hinfsyn(P, 1, 1)
    assert "D12 rank deficient" in res.regularization
    assert res.norm <= res.gamma * (1 + 1e-3)
    assert res.K.input_labels == ["v_e"] and res.K.output_labels == ["u_b"]
    assert robust.is_stable(G, res.K)
    # the default time scale is chosen from P (time_scale_of)
    assert res.time_scale == pytest.approx(robust.time_scale_of(P))
    # the same gamma from the plant given in a different time unit
    res2 = hinfsyn(P, 1, 1, time_scale=1e3)
    assert res2.gamma == pytest.approx(res.gamma, rel=5e-3)


def test_controller_and_closed_loop_are_in_ordinary_time():
    P = random_plant(np.random.default_rng(8))
    P = ct.ss(P.A * 1e3, P.B * 1e3, P.C, P.D, inputs=["w1", "w2", "u"],
              outputs=["z1", "z2", "y"])                  # poles ~1e3 rad/s
    res = hinfsyn(P, 1, 1)
    assert res.K.input_labels == ["y"] and res.K.output_labels == ["u"]
    assert res.closed_loop.input_labels == ["w1", "w2"] and res.closed_loop.name == "closed_loop"
    w = np.logspace(1, 5, 60)
    np.testing.assert_allclose(res.closed_loop(1j * w), robust.lower_lft(P, res.K)(1j * w),
                               rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(np.sort_complex(ct.poles(res.closed_loop)),
                               res.closed_loop_poles, rtol=1e-6)


def test_bad_arguments():
    P = scalar_plant(0.0)
    with pytest.raises(ValueError, match="nmeas=3 leaves no performance output"):
        hinfsyn(P, 3, 1)
    with pytest.raises(TypeError, match="nmeas must be an integer"):
        hinfsyn(P, 1.5, 1)
    with pytest.raises(TypeError):
        hinfsyn("P", 1, 1)
    with pytest.raises(ValueError, match="continuous-time"):
        hinfsyn(ct.c2d(P, 0.1), 1, 1)


def test_budget_stops_the_search_and_says_so():
    res = hinfsyn(scalar_plant(1.0), 1, 1, rtol=1e-9, max_iter=6)
    assert not res.converged and res.iterations <= 7
    assert res.norm <= res.gamma * (1 + 1e-3)          # still a verified controller
    assert res.gamma >= scalar_optimum(1.0)


def test_result_does_not_depend_on_the_clock(monkeypatch, slow_clock):
    """A machine so slow that every step seems to take 1000 s gets the same controller."""
    P = genplant.design_plant(*paper.problem()[:4])
    normal = hinfsyn(P, 1, 1)
    monkeypatch.setattr(robust.hinf, "time", slow_clock)
    slow = hinfsyn(P, 1, 1)
    assert slow.attempts == normal.attempts and slow.gamma == normal.gamma
    assert slow.converged == normal.converged and slow.iterations == normal.iterations
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(slow.K, name), getattr(normal.K, name))
    assert slow.elapsed >= 1000.0                        # the time is still reported


def test_trial_limit_is_validated_and_wall_time_is_not_an_option():
    P = scalar_plant(1.0)
    with pytest.raises(ValueError, match="max_iter must be >= 2"):
        hinfsyn(P, 1, 1, max_iter=1)
    with pytest.raises(TypeError, match="max_iter must be an integer"):
        hinfsyn(P, 1, 1, max_iter=10.0)
    with pytest.raises(TypeError, match="time_budget"):
        hinfsyn(P, 1, 1, time_budget=30.0)


# --- regressions: false verdicts from scale-dependent thresholds ---

def _s_ks_plant(G, W1):
    """S/KS mixed sensitivity: inputs [w, u], outputs [W1 (w - G u), u, w - G u]."""
    Gs, Ws = ct.ss(G), ct.ss(W1)
    Gn = ct.ss(Gs.A, Gs.B, Gs.C, Gs.D, inputs=["u"], outputs=["y"])
    Wn = ct.ss(Ws.A, Ws.B, Ws.C, Ws.D, inputs=["e"], outputs=["z1"])
    effort = ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]],
                   inputs=["u"], outputs=["z2"])
    return ct.interconnect([Gn, Wn, effort, ct.summing_junction(["w", "-y"], "e")],
                           inputs=["w", "u"], outputs=["z1", "z2", "e"])


def _verified_sb10ad(P):
    """Recomputed norm of python-control's (SB10AD) controller."""
    K, _, _, _ = ct.hinfsyn(P, 1, 1)
    M = robust.lower_lft(P, K)
    assert np.all(ct.poles(M).real < 0)
    return robust.hinf_norm(M, omega=np.logspace(-6, 11, 6000))[0]


@pytest.mark.parametrize("fast", [1e7, 1e8])
@pytest.mark.parametrize("assembly", ["own", "augw"])
def test_wide_pole_spread_s_ks_reaches_the_optimum(fast, assembly):
    # reproducer: gamma 4.718 claimed optimal (own), 7681.8 (augw) and "no gamma <= 1e6
    # feasible" (fast pole 1e8), while SB10AD's controller verifies at 3.2751
    s = ct.tf("s")
    G = 1 / (s + 1) * fast / (s + fast)
    W1 = (s / 1.5 + 10) / (s + 1e-3)
    P = _s_ks_plant(G, W1) if assembly == "own" else ct.augw(G, W1, ct.tf(1, 1))
    res = hinfsyn(P, 1, 1)
    # the optimum does not depend on the realisation; SB10AD itself is wrong on the
    # augw realisation with the pole at 1e8 (reports 3.023, its controller gives 9.32)
    ref = _verified_sb10ad(_s_ks_plant(G, W1))
    assert res.converged and res.regularization == ""
    assert res.gamma == pytest.approx(ref, rel=1e-3)
    assert res.gamma_infeasible <= ref          # no false infeasibility claim
    assert res.norm <= res.gamma * (1 + 1e-3)


def test_stable_weight_pole_far_below_a_fast_plant_is_not_called_uncontrollable():
    # reproducer: "mode at -0.001 rad/s is not controllable" for G = 1e30/(s+1e10)^3.  Over
    # this 13-decade spread the Riccati verdicts are unreliable, but scipy's solver (the
    # second opinion) gives a verified controller; the verdicts it beats are not kept
    s = ct.tf("s")
    P = _s_ks_plant(1e30 / (s + 1e10) ** 3, (s / 1.5 + 10) / (s + 1e-3))
    res = hinfsyn(P, 1, 1)
    assert np.all(res.closed_loop_poles.real < 0)
    M = robust.lower_lft(P, res.K)
    assert np.all(ct.poles(M).real < 0)
    assert res.gamma_infeasible < res.norm <= res.gamma * (1 + 1e-3)


@pytest.mark.parametrize("k", [12, 14])
def test_pole_spread_beyond_double_precision_is_reported_as_such(k):
    # G = 1e(3k)/(s+1e k)^3 beside a weight pole at -1e-3 rad/s: at 15 decades and more the
    # slow mode cannot be told from the axis; the error must say so, never that P cannot
    # be stabilised
    s = ct.tf("s")
    P = _s_ks_plant(10.0 ** (3 * k) / (s + 10.0 ** k) ** 3, (s / 1.5 + 10) / (s + 1e-3))
    with pytest.raises(HinfSynthesisError) as info:
        hinfsyn(P, 1, 1)
    text = str(info.value)
    assert "not a proof" in text and "decades" in text
    assert not text.startswith("P cannot be stabilised") and "+0j" not in text


def test_full_rank_d12_beside_a_large_weight_is_not_regularised():
    # D12 = 1 beside a weight of DC gain 1e7 was labelled "rank deficient (sigma_min 1)"
    s = ct.tf("s")
    res = hinfsyn(_s_ks_plant(1 / (s + 1), (s / 2 + 1e4) / (s + 1e-3)), 1, 1)
    assert res.regularization == "" and res.effort_weight == 0.0
    assert res.norm <= res.gamma * (1 + 1e-3)


def test_zero_of_p21_on_the_axis_is_an_error_not_a_converged_result():
    # P21 with a zero at s = 0 returned converged=True with a closed-loop pole at
    # -7.5e-9 rad/s and an infinite true norm
    s = ct.tf("s")
    Gs, Hs = ct.ss(1 / (s + 1)), ct.ss(s / (s + 1))
    G = ct.ss(Gs.A, Gs.B, Gs.C, Gs.D, inputs=["ug"], outputs=["x"])
    H = ct.ss(Hs.A, Hs.B, Hs.C, Hs.D, inputs=["xm"], outputs=["y"])
    effort = ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]],
                   inputs=["u"], outputs=["z2"])
    P = ct.interconnect([G, H, effort, ct.summing_junction(["w1", "u"], "ug"),
                         ct.summing_junction(["x", "w2"], "xm")],
                        inputs=["w1", "w2", "u"], outputs=["x", "z2", "y"])
    with pytest.raises(HinfSynthesisError, match=r"P21 .* zero at s = 0 rad/s"):
        hinfsyn(P, 1, 1)


@pytest.mark.parametrize("P, exc, match", [
    (ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((2, 0)), np.eye(2)), ValueError,
     "P is static"),
    (ct.ss([[np.nan]], [[1, 1]], [[1], [1]], np.zeros((2, 2))), ValueError,
     r"P\.A contains 1 non-finite"),
    (ct.ss([[-1]], [[1, 1]], [[1], [1]], np.zeros((2, 2)), 0.1), ValueError,
     "continuous-time.*discrete"),
    (ct.tf([[[1, 0, 0], [1]], [[1], [1]]], [[[1, 1], [1, 1]], [[1, 1], [1, 1]]]), ValueError,
     "P must be proper"),
])
def test_unclear_errors_are_now_specific(P, exc, match):
    with pytest.raises(exc, match=match):
        hinfsyn(P, 1, 1)


def test_paper_plant_failure_hint_is_not_misleading():
    # the direct realisation used to suggest "check for jw zeros" on any failure; the
    # axis zeros are checked explicitly now, and a too-small gamma_max says so
    G, H_m, H_e, H_y, _ = paper.problem()
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    with pytest.raises(HinfSynthesisError, match="gamma_max is too small") as info:
        hinfsyn(P, 1, 1, gamma_max=1e-3)
    assert "jw" not in str(info.value) and "imaginary axis and that" not in str(info.value)


# --- faults injected into the private Riccati and peak helpers (book problems) -------------

def assert_verified_below(res, P, weight, level):
    """res.gamma < level, and its K meets gamma on P with the effort output (P_reg)."""
    achieved, _ = robust.lft_hinf_norm(tp.with_effort_output(P, weight, 2, 2), res.K,
                                       np.logspace(-5, 5, 2000))
    assert achieved <= res.gamma * (1 + 1e-3) and res.gamma < level
    assert res.gamma_infeasible < achieved


def test_lundstrom_k_step_keeps_a_central_controller_that_missed_its_gamma(lundstrom_plant,
                                                                         monkeypatch):
    # near the optimum the central controllers miss their own gamma by 0.1-0.6 % in a
    # pattern set by rounding; here every one misses it by construction (the coarse
    # check sees peaks 0.2 % high, beyond verify_rtol) and scipy's route is off, so only
    # a trial's controller verified at its own peak (on the dense grid) can end the search
    # below the verified gammas far above the optimum
    from piezolib.robust import hinf
    central, peak_gain = hinf._central, hinf._peak_gain

    def pencil_first_only(pl, gamma, scipy_first=False):
        return (None, "switched off") if scipy_first else central(pl, gamma)

    monkeypatch.setattr(hinf, "_central", pencil_first_only)
    monkeypatch.setattr(hinf, "_peak_gain", lambda *args: 1.002 * peak_gain(*args))
    res = robust.hinfsyn(lundstrom_plant, 2, 2, effort_weight=1e-6)
    assert any("verified at its peak" in status for _, status in res.attempts)
    assert_verified_below(res, lundstrom_plant, 1e-6, 0.98)


def test_lundstrom_k_step_retries_a_failed_controller_with_scipy_riccati(lundstrom_plant,
                                                                        monkeypatch):
    # at effort weight 1e-6 the pencil's X, Y gave central controllers 72 % above
    # gamma = 1.0 where scipy's verify (which route fails near the optimum is set by
    # rounding); here the pencil route's controllers are all spoiled (twice the output
    # gain), so every controller verified must come from the retry with scipy's solutions,
    # and the search must still end within rtol of the optimum (0.9733)
    from piezolib.robust import hinf
    central = hinf._central

    def spoiled_pencil(pl, gamma, scipy_first=False):
        K, status = central(pl, gamma, scipy_first=scipy_first)
        if K is None or scipy_first:
            return K, status
        Ak, Bk, Ck, Dk = K
        return (Ak, Bk, 2 * Ck, 2 * Dk), status

    monkeypatch.setattr(hinf, "_central", spoiled_pencil)
    res = robust.hinfsyn(lundstrom_plant, 2, 2, effort_weight=1e-6)
    assert any("scipy's Riccati" in status for _, status in res.attempts)
    assert_verified_below(res, lundstrom_plant, 1e-6, 0.976)


def test_infeasibility_is_never_claimed_below_the_returned_controller(monkeypatch):
    # whatever the Riccati verdicts say, a gamma above the returned controller's own
    # norm is not infeasible: with wrong verdicts injected on (1.5, 2.5) (the optimum
    # is 1.366) the bracket must drop below that norm and the result not be converged
    from piezolib.robust import hinf
    central = hinf._central

    def wrong_verdicts(pl, gamma, **kwargs):
        return (None, "no stabilising Riccati solution") if 1.5 < gamma < 2.5 else \
            central(pl, gamma, **kwargs)

    monkeypatch.setattr(hinf, "_central", wrong_verdicts)
    res = robust.hinfsyn(tp.disturbance_process().P, 1, 1)
    assert res.gamma_infeasible < res.norm <= res.gamma * (1 + 1e-3)
    assert not res.converged


def test_badly_scaled_realisation_of_the_paper_plant_reaches_the_same_optimum():
    # the design plant built by direct interconnection of the transfer functions (companion
    # forms with coefficients to 1e23: A entries up to 4.7e11); its Riccati verdicts said
    # "no gamma <= 1e6 feasible", also after diagonal balancing, where design_plant's
    # realisation of the same system gives 1.868
    G, H_m, H_e, H_y, _ = paper.problem()
    blocks = [ct.ss(G, inputs="u_c", outputs="v_y"), ct.ss(H_y, inputs="v_y", outputs="y2"),
              ct.ss(H_m, inputs="u_b", outputs="y_Delta"), ct.ss(H_e, inputs="v_e", outputs="y1"),
              ct.ss([], [], [], [[genplant.DESIGN_EFFORT_WEIGHT]], inputs="u_b", outputs="y_u"),
              ct.summing_junction(["u_Delta", "u_b"], "u_c"),
              ct.summing_junction(["v_r", "-v_y"], "v_e")]
    direct = ct.interconnect(blocks, inputs=["u_Delta", "v_r", "u_b"],
                             outputs=["y_Delta", "y1", "y2", "y_u", "v_e"])
    assert np.abs(direct.A).max() > 1e11
    reference = hinfsyn(genplant.design_plant(G, H_m, H_e, H_y), 1, 1)
    res = hinfsyn(direct, 1, 1)
    assert res.realization.startswith("block-diagonal")
    assert res.converged and res.gamma <= reference.gamma_infeasible * (1 + 2e-3)
    assert res.gamma >= reference.gamma_infeasible * (1 - 2e-3)
    assert np.all(ct.poles(direct.lft(res.K)).real < 0)
    assert res.norm <= res.gamma * (1 + 1e-3)
