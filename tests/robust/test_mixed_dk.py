"""Mixed mu-synthesis (real scalar + complex full blocks), verified by recomputation."""

import control as ct
import numpy as np
import pytest

from piezolib import robust
from piezolib.robust.mixed_dk import complex_relaxation, mixed_musyn, real_block_shrink

OMEGA = np.logspace(-2, 2, 40)
BLK = [(-1, 0), (1, 2)]          # real input-gain offset, then the 1 x 2 performance block


def _plant():
    """G = 200/((10s+1)(0.05s+1)^2) (Skogestad & Postlethwaite's disturbance process) with a
    real +-60 % input-gain offset, W_P on the error and 0.1 on the control."""
    s = ct.tf("s")
    G = 200 / ((10 * s + 1) * (0.05 * s + 1) ** 2)
    parts = [ct.ss(G, inputs="u_p", outputs="y", name="G"),
             ct.ss(ct.tf([0.6], [1]), inputs="u", outputs="z", name="W_I"),
             ct.ss((s / 2 + 0.5) / (s + 5e-3), inputs="e", outputs="z1", name="W_P"),
             ct.ss(ct.tf([0.1], [1]), inputs="u", outputs="z2", name="W_u"),
             ct.summing_junction(["u", "w"], "u_p"),
             ct.summing_junction(["r", "-y"], "e")]
    return ct.ss(ct.interconnect(parts, inputs=["w", "r", "u"], outputs=["z", "z1", "z2", "e"]))


@pytest.fixture(scope="module")
def design():
    P = _plant()
    return P, mixed_musyn(P, BLK, 1, 1, OMEGA, max_iter=4)


def test_result_is_recomputed_from_P_and_K(design):
    P, res = design
    M = robust.lft_response(P, res.K, OMEGA)
    again = robust.mussv(M, BLK, OMEGA)
    assert again.upper.max() == pytest.approx(res.mu_peak, rel=1e-6)
    assert np.all(again.lower <= again.upper)
    assert res.mu_lower_peak <= res.mu_peak and res.mu_lower_peak > 0.9 * res.mu_peak
    # closed loop recomputed: stable, and the reported poles are its poles
    poles = robust.lower_lft(P, res.K).poles()
    assert np.all(poles.real < 0)
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(res.closed_loop_poles),
                               rtol=1e-6)
    assert res.mu_peak == min(r["mu_upper"] for r in res.records)
    assert res.K.input_labels == ["e"] and res.K.output_labels == ["u"]


def test_real_blocks_never_worse_than_complex_ones(design):
    P, res = design
    M = robust.lft_response(P, res.K, OMEGA)
    cplx = robust.mussv(M, complex_relaxation(BLK), OMEGA, lower=False)
    assert res.mu_peak <= cplx.upper.max() * (1 + 1e-9)
    assert res.mu_complex_peak == pytest.approx(cplx.upper.max(), rel=1e-6)
    # the first K-step is the unscaled H-infinity design
    assert res.records[0]["gamma"] == pytest.approx(robust.hinfsyn(P, 1, 1).gamma, rel=2e-3)


def test_shrink_matches_the_target_bound(design):
    P, res = design
    M = robust.lft_response(P, res.K, OMEGA)
    target = res.mu.upper
    alpha, Dl, Dr = real_block_shrink(M, BLK, target)
    assert np.all((alpha > 0) & (alpha <= 1))
    A = Dl @ M @ np.linalg.inv(Dr)
    A[:, 0, :] *= alpha[:, None]                       # the real block's output row
    sig = np.linalg.norm(A, 2, axis=(1, 2))
    inside = (alpha < 1) & (alpha > 1.001e-3)
    np.testing.assert_allclose(sig[inside], target[inside], rtol=1e-5)
    assert np.all(sig[alpha == 1] <= target[alpha == 1] * (1 + 1e-9))


def test_bad_structures_and_options():
    P = _plant()
    with pytest.raises(ValueError, match="last block"):
        mixed_musyn(P, [(1, 2), (-1, 0)], max_iter=1)
    with pytest.raises(ValueError, match="repeated scalar"):
        mixed_musyn(P, [(1, 0), (1, 2)], max_iter=1)
    with pytest.raises(ValueError, match="alpha_power"):
        mixed_musyn(P, BLK, omega=OMEGA, alpha_power=2.0)
    with pytest.raises(ValueError, match="increasing"):
        mixed_musyn(P, BLK, omega=OMEGA[::-1])
    with pytest.raises(ValueError, match="target"):
        real_block_shrink(np.ones((2, 3, 2)), BLK, [1.0, -1.0])
    with pytest.raises(ValueError, match="max_iter must be >= 1"):
        mixed_musyn(P, BLK, omega=OMEGA, max_iter=0)
    with pytest.raises(TypeError, match="time_budget"):
        mixed_musyn(P, BLK, omega=OMEGA, time_budget=120.0)
    with pytest.raises(TypeError, match=r"hinfsyn does not take: \['time_budget'\]"):
        mixed_musyn(P, BLK, omega=OMEGA, hinf_options={"time_budget": 30.0})
