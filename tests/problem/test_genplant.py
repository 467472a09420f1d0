"""Generalized plant P of eq. 16, the synthesis plant and M = F_l(P, K) of eq. 17-18."""

import control as ct
import numpy as np
import pytest

from piezolib import paper, robust
from piezolib.problem import genplant

OMEGA = np.logspace(0, 6, 300)


def response(sys, omega=OMEGA):
    return np.moveaxis(sys(1j * omega, squeeze=False), -1, 0)


def test_generalized_plant_entries_are_eq16(models):
    G, H_m, H_e, H_y, _ = models
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    assert P.input_labels == ["u_Delta", "v_r", "u_b"] == list(genplant.PLANT_INPUTS)
    assert P.output_labels == ["y_Delta", "y1", "y2", "v_e"] == list(genplant.PLANT_OUTPUTS)
    assert P.nstates == 14 and P.name == "P" and P.isctime(strict=True)
    s = 1j * OMEGA
    g, hm, he, hy = (np.ravel(f(s)) for f in (G, H_m, H_e, H_y))
    zero = np.zeros_like(g)
    expected = np.stack([np.stack([zero, zero, hm], -1),
                         np.stack([-he * g, he, -he * g], -1),
                         np.stack([hy * g, zero, hy * g], -1),
                         np.stack([-g, np.ones_like(g), -g], -1)], 1)
    got = response(P)
    scale = np.maximum(np.abs(expected), 1e-300)
    nonzero = np.abs(expected) > 0
    assert np.max(np.abs(got - expected)[nonzero] / scale[nonzero]) < 1e-8
    assert np.max(np.abs(got[~nonzero])) < 1e-9


def test_time_scale_only_conditions_the_realisation(models):
    G, H_m, H_e, H_y, _ = models
    default = response(genplant.generalized_plant(G, H_m, H_e, H_y))
    for omega_s in (3e3, 1e4, 1e5):
        other = response(genplant.generalized_plant(G, H_m, H_e, H_y, omega_s=omega_s))
        np.testing.assert_allclose(other, default, rtol=1e-7, atol=1e-12)


def test_effort_output_and_design_plant(models):
    G, H_m, H_e, H_y, _ = models
    P = genplant.design_plant(G, H_m, H_e, H_y)
    assert P.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"]
    resp = response(P)
    np.testing.assert_allclose(resp[:, 3, 2], genplant.DESIGN_EFFORT_WEIGHT, rtol=1e-12)
    np.testing.assert_allclose(resp[:, 3, :2], 0, atol=1e-14)
    assert genplant.DESIGN_BLOCK_STRUCTURE == ((1, 1), (1, 3))
    assert genplant.BLOCK_STRUCTURE == ((1, 1), (1, 2))
    # the other entries are those of the exact P
    exact = response(genplant.generalized_plant(G, H_m, H_e, H_y))
    np.testing.assert_allclose(resp[:, [0, 1, 2, 4], :], exact, rtol=1e-7, atol=1e-12)
    rho = genplant.design_plant(G, H_m, H_e, H_y, effort_weight=0.1)
    np.testing.assert_allclose(response(rho)[:, 3, 2], 0.1, rtol=1e-12)


def test_lower_lft_is_eq18(models):
    G, H_m, H_e, H_y, K = models
    M = genplant.closed_loop_matrix(K, G, H_m, H_e, H_y)
    assert M.input_labels == ["u_Delta", "v_r"]
    assert M.output_labels == ["y_Delta", "y1", "y2"]
    lf = robust.loop_functions(G, K)
    s = 1j * OMEGA
    S, T, KS, GS = (np.ravel(f(s)) for f in lf)
    hm, he, hy = (np.ravel(f(s)) for f in (H_m, H_e, H_y))
    expected = np.stack([np.stack([-hm * T, hm * KS], -1),
                         np.stack([-he * GS, he * S], -1),
                         np.stack([hy * GS, hy * T], -1)], 1)
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    for got in (response(M), robust.lft_response(P, K, OMEGA)):
        np.testing.assert_allclose(got, expected, rtol=1e-7, atol=1e-12)


def test_other_weights_enter_where_eq16_says(models):
    G, H_m, _, _, _ = models
    H_e, H_y = paper.error_weight(omega_e=2e3), paper.output_weight(M_y=2.0)
    P = genplant.generalized_plant(G, H_m, H_e, H_y)
    s = 1j * OMEGA
    got = response(P)
    np.testing.assert_allclose(got[:, 1, 1], np.ravel(H_e(s)), rtol=1e-8)
    np.testing.assert_allclose(got[:, 2, 2], np.ravel(H_y(s)) * np.ravel(G(s)), rtol=1e-8)


@pytest.mark.parametrize("change, error, match", [
    (dict(G=None), TypeError, "G"),
    (dict(H_e=ct.tf([[[1.0]], [[1.0]]], [[[1.0, 1.0]], [[1.0, 2.0]]])), ValueError, "H_e"),
    (dict(effort_weight=-1.0), ValueError, "effort_weight"),
    (dict(omega_s=0.0), ValueError, "omega_s"),
])
def test_generalized_plant_rejects_bad_arguments(models, change, error, match):
    G, H_m, H_e, H_y, _ = models
    args = dict(G=G, H_m=H_m, H_e=H_e, H_y=H_y)
    args.update(change)
    with pytest.raises(error, match=match):
        genplant.generalized_plant(**args)


def test_improper_output_weight_is_refused(models):
    G, H_m, H_e, _, _ = models
    improper = ct.tf([1.0, 1.0, 1.0, 1.0, 1.0], [1.0])       # 4 excess zeros > G's 3
    with pytest.raises(ValueError, match="proper"):
        genplant.generalized_plant(G, H_m, H_e, improper)
    with pytest.raises(ValueError, match="H_y G is improper"):
        genplant.generalized_plant(G, H_m, H_e, improper, omega_s=1e4)



# --- the delay-aware synthesis plant -------------------------------------------

FS = paper.SAMPLING_FREQUENCY_HZ


def test_effective_delay_is_hold_plus_computation():
    assert genplant.effective_delay(FS, 1) == pytest.approx(1.5e-4)
    assert genplant.effective_delay(FS, 0) == pytest.approx(0.5e-4)
    assert genplant.effective_delay(5e3, 2) == pytest.approx(5e-4)
    with pytest.raises(ValueError, match="delay_samples"):
        genplant.effective_delay(FS, -1)
    with pytest.raises(ValueError, match="fs"):
        genplant.effective_delay(0.0, 1)


def test_delay_channel_matches_the_exact_delay_at_low_frequency(models):
    G, H_m, H_e, H_y, _ = models
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS, delay_samples=1)
    assert P.input_labels == ["u_Delta", "v_r", "u_b"]
    assert P.output_labels == ["y_Delta", "y1", "y2", "y_u", "v_e"] and P.name == "P_delay"
    assert P.nstates == 14 + genplant.DESIGN_PADE_ORDER + genplant.DESIGN_ROLLOFF.order
    tau = 1.5e-4
    omega = np.logspace(0, np.log10(0.5 / tau), 200)          # omega tau <= 0.5
    got = response(P, omega)
    exact = response(genplant.generalized_plant(G, H_m, H_e, H_y), omega)
    delay = np.exp(-1j * omega * tau)
    # every u_b entry is the undelayed one times e^{-j omega tau} (Pade error < 1e-4 here)
    for out, row in ((0, 0), (1, 1), (2, 2), (4, 3)):
        np.testing.assert_allclose(got[:, out, 2], exact[:, row, 2] * delay, rtol=1e-4)
        np.testing.assert_allclose(got[:, out, :2], exact[:, row, :2], rtol=1e-7, atol=1e-12)
    # the delay matters: without it the u_b column is off by omega tau
    assert np.max(np.abs(exact[:, 3, 2] / got[:, 4, 2] - 1)) > 0.4
    W_u = np.ravel(genplant.rolloff_weight()(1j * omega))
    np.testing.assert_allclose(got[:, 3, 2], W_u, rtol=1e-8)
    np.testing.assert_allclose(got[:, 3, :2], 0, atol=1e-12)


def test_exact_delay_response_agrees_with_the_pade_plant(models):
    G, H_m, H_e, H_y, K = models
    omega = np.logspace(0, 3.5, 50)
    P = genplant.delay_aware_plant(G, H_m, H_e, H_y, fs=FS, delay_samples=2, pade_order=3)
    pade = robust.lft_response(P, K, omega)
    exact = genplant.delayed_closed_loop_response(K, G, H_m, H_e, H_y, omega, fs=FS,
                                                  delay_samples=2,
                                                  rolloff=genplant.DESIGN_ROLLOFF)
    np.testing.assert_allclose(exact, pade, rtol=1e-4, atol=1e-9)
    # without the roll-off output it is eq. 18 with the delay; d -> no delay is not eq. 18
    plain = genplant.delayed_closed_loop_response(K, G, H_m, H_e, H_y, omega, fs=FS,
                                                  delay_samples=2)
    np.testing.assert_allclose(plain, exact[:, [0, 1, 2], :], rtol=1e-12)
    M = response(genplant.closed_loop_matrix(K, G, H_m, H_e, H_y), omega)
    assert np.max(np.abs(plain - M)) > 1e-2


def test_rolloff_weight_levels_and_errors():
    params = genplant.RolloffWeight(hf_gain=5.0, lf_gain=1e3, frequency=2e4, order=2)
    W = genplant.rolloff_weight(params)
    assert abs(np.ravel(W(1j * 1e-3))[0]) == pytest.approx(1e-3, rel=1e-6)
    assert abs(np.ravel(W(1j * 1e9))[0]) == pytest.approx(0.2, rel=1e-4)
    mags = np.abs(np.ravel(W(1j * np.logspace(0, 7, 50))))
    assert np.all(np.diff(mags) > 0)                       # rises monotonically
    assert genplant.DESIGN_ROLLOFF.hf_gain == 10.0
    for bad, match in ((dict(hf_gain=0.0), "hf_gain"), (dict(lf_gain=1.0), "lf_gain"),
                       (dict(frequency=-1.0), "frequency"), (dict(order=0), "order")):
        with pytest.raises(ValueError, match=match):
            genplant.rolloff_weight(genplant.RolloffWeight(**bad))
    with pytest.raises(TypeError, match="RolloffWeight"):
        genplant.rolloff_weight(10.0)


@pytest.mark.parametrize("change, match", [
    (dict(fs=0.0), "fs"), (dict(delay_samples=-1), "delay_samples"),
    (dict(pade_order=0), "pade_order"),
])
def test_delay_aware_plant_rejects_bad_arguments(models, change, match):
    G, H_m, H_e, H_y, _ = models
    args = dict(fs=FS, delay_samples=1)
    args.update(change)
    with pytest.raises(ValueError, match=match):
        genplant.delay_aware_plant(G, H_m, H_e, H_y, **args)


def test_discrete_or_nan_plant_is_rejected():
    # a discrete G used to give a continuous generalized plant; a NaN coefficient
    # used to surface as "algebraic loop detected"
    G, H_m, H_e, H_y, _ = paper.problem()
    with pytest.raises(ValueError, match=r"G must be continuous-time.*dt=0\.0001"):
        genplant.generalized_plant(ct.c2d(G, 1e-4), H_m, H_e, H_y)
    with pytest.raises(ValueError, match="G has a NaN coefficient"):
        genplant.generalized_plant(ct.tf([np.nan], [1.0, 1.0]), H_m, H_e, H_y)


def test_improper_plant_is_refused_naming_it(models):
    # an improper G used to be realised without its polynomial part, silently
    G, H_m, H_e, H_y, _ = models
    s = ct.tf("s")
    with pytest.raises(ValueError, match=r"\bG must be proper"):
        genplant.generalized_plant(G * s ** 4, H_m, H_e, H_y)
    with pytest.raises(ValueError, match=r"H_e must be proper"):
        genplant.generalized_plant(G, H_m, H_e * s * s, H_y)


# --- the delay-aware plant with the coefficient box as real blocks ---------------

def test_parametric_design_plant_closed_with_offsets_is_that_member(models):
    from piezolib import uncertainty as unc

    G, _, H_e, H_y, _ = models
    spread, q = 0.05, np.array([0.7, -1.0, 0.3, 1.0, -0.4, 0.0])
    P = genplant.parametric_design_plant(G, H_e, H_y, spread, fs=FS)
    n = len(q)
    assert genplant.parametric_block_structure(n) == ((-1, 0),) * n + ((1, 3),)
    assert P.input_labels == [f"w_{i}" for i in range(n)] + ["v_r", "u_b"]
    assert P.output_labels[n:] == ["y1", "y2", "y_u", "v_e"]
    omega = np.logspace(2, 5, 40)
    R = response(P, omega)
    # close the real channels with diag(q): the u_b -> v_e path is -G_q times the Pade delay
    Q = np.diag(q)
    closed = [r[n:, n:] + r[n:, :n] @ Q @ np.linalg.solve(np.eye(n) - r[:n, :n] @ Q, r[:n, n:])
              for r in R]
    member = np.ravel(unc.perturbed_plant(G, spread, q)(1j * omega))
    num, den = ct.pade(genplant.effective_delay(FS, 1), genplant.DESIGN_PADE_ORDER)
    pade = np.ravel(ct.tf(num, den)(1j * omega))
    got = np.array([c[3, 1] for c in closed])                   # u_b -> v_e
    np.testing.assert_allclose(got, -member * pade, rtol=1e-7)
    # v_r -> y1 is H_e (1 - 0) at the reference input: the error weight sees v_r directly
    h_e = np.ravel(H_e(1j * omega))
    np.testing.assert_allclose([c[0, 0] for c in closed], h_e, rtol=1e-7)
