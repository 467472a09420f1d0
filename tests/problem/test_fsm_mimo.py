"""The 3 x 3 mirror controller: the committed record, the verification's pieces on small
plants with known answers, bad input."""

from types import SimpleNamespace

import control as ct
import numpy as np
import pytest

from piezolib import robust
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_mimo, fsm_models

FS = fsm.SAMPLING_FREQUENCY_HZ
T = 1 / FS
F_HZ = np.linspace(2.0, 1500.0, 200)


def _diag_plant(poles=(0.9, 0.8, 0.7), gain=1.0):
    A = np.diag(poles)
    return ct.ss(A, gain * np.eye(3), np.eye(3), np.zeros((3, 3)), T)


def _integrators(k=0.05, n=3):
    return ct.ss(np.eye(n), k * np.eye(n), np.eye(n), np.zeros((n, n)), T)


def test_relative_spread_is_the_largest_singular_value_of_the_output_error():
    G = np.tile(np.diag([1.0, 2.0]), (3, 1, 1)).astype(complex)
    G_l = G.copy()
    G_l[:, 0, 1] = 0.5                         # (G_l - G) G^-1 = [[0, 0.25], [0, 0]]
    assert fsm_mimo.relative_spread([G_l, G], G) == pytest.approx([0.25] * 3)


def test_sampled_radius_of_decoupled_loops_is_the_worst_siso_loop():
    G = _diag_plant()
    K = ct.ss([], [], [], 0.05 * np.eye(3), T)
    r3 = fsm_mimo.sampled_radius(G, K)
    r_siso = max(fsm_mimo.sampled_radius(ct.ss(p, 1.0, 1.0, 0.0, T), ct.ss([], [], [], 0.05, T))
                 for p in (0.9, 0.8, 0.7))
    assert r3 == pytest.approx(r_siso, rel=1e-12)
    assert 0 < r3 < 1


def test_step_crosstalk_of_a_coupled_static_plant_matches_its_dc_gain():
    # plant G = C (zI - A)^-1 B with a constant mixing: with integral control the loop's T -> I,
    # so the off-diagonal steps end at 0 and their peak is the transient only; a decoupled
    # plant has none at all
    x = fsm_mimo.step_crosstalk(_diag_plant(), _integrators())
    assert np.all(x[~np.eye(3, dtype=bool)] == 0.0)
    assert np.all(np.diag(x) >= 1.0 - 1e-9)
    mix = np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    G = ct.ss(np.diag([0.9, 0.9, 0.9]), mix, np.eye(3), np.zeros((3, 3)), T)
    x = fsm_mimo.step_crosstalk(G, _integrators(0.02))
    assert x[0, 1] > 0.01 and x[1, 0] == 0.0          # input 2 reaches output 1, not the reverse


def test_step_crosstalk_refuses_an_unstable_loop():
    with pytest.raises(ValueError, match="unstable"):
        fsm_mimo.step_crosstalk(_diag_plant(), ct.ss([], [], [], -5 * np.eye(3), T))


def test_the_design_plant_with_no_controller_is_the_open_weights():
    s = ct.tf("s")
    G = ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)))
    W_m, W_S, W_T, W_u = ct.tf(0.2, 1), 1 / (s + 1), ct.tf(0.3, 1), ct.tf(0.1, 1)
    P = fsm_mimo.mirror_design_plant(G, W_m, W_S, W_T, W_u)
    M = robust.lft_response(P, ct.ss([], [], [], np.zeros((3, 3))), np.array([1.0]))[0]
    # with K = 0: y1 = W_S (v_r - u_Delta), y2 = W_T u_Delta, nothing else
    w_s = complex(np.ravel(W_S(1j))[0])
    assert M.shape == (12, 6)
    np.testing.assert_allclose(M[3:6, 3:6], w_s * np.eye(3), atol=1e-12)
    np.testing.assert_allclose(M[3:6, 0:3], -w_s * np.eye(3), atol=1e-12)
    np.testing.assert_allclose(M[6:9, 0:3], 0.3 * np.eye(3), atol=1e-12)
    np.testing.assert_allclose(M[0:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(M[9:12], 0.0, atol=1e-12)


def test_mirror_nominal_at_full_order_reproduces_the_model():
    B = np.vstack([np.eye(3) + 0.1, 0.5 * np.eye(3)])
    C = 1e-6 * np.hstack([np.eye(3), np.ones((3, 3))])
    model = ct.ss(np.diag([0.9, 0.5, -0.3, 0.8, 0.4, 0.2]), B, C, np.zeros((3, 3)), T)
    zl = np.exp(2j * np.pi * F_HZ / FS)
    G_all = np.asarray(model(zl))
    models = {f"ours, order chosen (6), trained at {lv} mV": (lv, model) for lv in fsm.LEVELS_MV}
    models["ours, one model for all levels (order 6)"] = ("all", model)
    linear = fsm_models.LinearModels(models=models, selections={
        lv: SimpleNamespace(order=6) for lv in fsm.LEVELS_MV}, baseline_order=28, G_all=G_all)
    nominal = fsm_mimo.mirror_nominal(linear, F_HZ, 6, orders=(5,))
    assert list(nominal.reduction.index) == [5, 6]
    assert nominal.reduction.loc[6, "rms error < 100 Hz [%]"] < 1e-8
    assert nominal.reduction.loc[5, "rms error < 100 Hz [%]"] > 1e-6    # truncation costs
    assert np.all(nominal.spread() < 1e-10)                             # levels = nominal
    assert nominal.G_nominal.nstates == 6 and nominal.checks


def test_the_committed_design_record_loads_and_states_its_reduction():
    rec = fsm_mimo.read_mirror_record()
    assert rec.K_w.ninputs == rec.K_w.noutputs == 3
    assert rec.K_w.nstates <= rec.K_full_order
    assert rec.mu_reduced <= rec.mu_dk + rec.params["reduction_precision"] + 1e-12
    assert len(rec.history) >= 1 and sorted(rec.siso_K_w) == [0, 1, 2]
    assert rec.K_d().dt == pytest.approx(T) and rec.siso_K_d().ninputs == 3
    assert set(rec.weights) == {"W_m", "W_S", "W_T", "W_u"}


@pytest.mark.parametrize("call, match", [
    (lambda: fsm_mimo.mirror_model(ct.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], T)), "model"),
    (lambda: fsm_mimo.mirror_model(ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3)))),
     "model"),
    (lambda: fsm_mimo.relative_spread([np.ones((4, 2, 2))], np.ones((4, 3, 3))), "level"),
    (lambda: fsm_mimo.relative_spread([np.ones((4, 2, 2))], np.ones((4, 2, 2))), "invertible"),
    (lambda: fsm_mimo.relative_spread([np.eye(2)[None]], np.full((1, 2, 2), np.nan)),
     "nominal_response"),
    (lambda: fsm_mimo.sampled_radius(_diag_plant(), ct.ss([], [], [], np.eye(2), T)), "K_d"),
    (lambda: fsm_mimo.sampled_radius(_diag_plant(), ct.ss([], [], [], np.eye(3), 1e-3)), "K_d"),
    (lambda: fsm_mimo.sampled_radius(_diag_plant(), ct.ss([], [], [], np.eye(3))), "K_d"),
    (lambda: fsm_mimo.step_crosstalk(_diag_plant(), _integrators(), n_samples=3), "n_samples"),
    (lambda: fsm_mimo.mirror_design_plant(_diag_plant(), 1, 1, 1, 1), "G"),
    (lambda: fsm_mimo.mirror_design_plant(
        ct.ss(-np.eye(3), np.eye(3), np.eye(3), np.zeros((3, 3))), ct.tf(1, [1, -1]), 1, 1, 1),
     "W_m"),
    (lambda: fsm_mimo.block_diagonal([]), "controllers"),
    (lambda: fsm_mimo.block_diagonal([ct.ss([], [], [], np.eye(2))]), "controllers"),
    (lambda: fsm_mimo.delay_matrix(0), "n"),
    (lambda: fsm_mimo.read_mirror_record(3), "path"),
    (lambda: fsm_mimo.mirror_nominal("x", F_HZ, 3), "linear"),
    (lambda: fsm_mimo.verify_mirror("x", None), "nominal"),
])
def test_bad_input_is_refused_naming_the_argument(call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call()


def test_a_file_that_is_no_record_is_refused(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text('{"format": 1}')
    with pytest.raises(ValueError, match="not a 3 x 3 design record"):
        fsm_mimo.read_mirror_record(bad)


def test_the_float32_export_of_the_committed_controller_keeps_its_bounds():
    G = _diag_plant()
    nominal = fsm_mimo.MirrorNominal(G_full=G, G_level={lv: G for lv in fsm.LEVELS_MV},
                                     G_nominal=G, reduction=None, hankel_relative=None,
                                     frequency_Hz=F_HZ, nominal_order=3, bla=None)
    exported = fsm_mimo.export_mirror(nominal, fsm_mimo.read_mirror_record())
    x = exported.export
    assert x.A32.dtype == np.float32 and x.n_states == exported.table()["states"]
    assert x.max_error <= np.nanmax(x.bound) and x.time_error <= x.time_bound
    assert set(exported.radius32) == {"all-levels model (full)", "100 mV model", "200 mV model",
                                      "300 mV model"}
    checks = exported.checks
    assert checks["3 x 3 float32 export: controller stable in float32"]


def _nominal_and_record(G, K_w):
    """(MirrorRecord, MirrorNominal) holding only what nonlinear_loop reads."""
    nominal = fsm_mimo.MirrorNominal(G_full=G, G_level={}, G_nominal=G, reduction=None,
                                     hankel_relative=np.zeros(0), frequency_Hz=F_HZ,
                                     nominal_order=G.nstates, bla=np.zeros((1, 3, 3)))
    record = fsm_mimo.MirrorRecord(K_w=K_w, K_full_order=K_w.nstates, weights={}, params={},
                                   history=None, mu_dk=0.5, mu_reduced=0.5, reduction=None,
                                   siso_K_w={}, siso_mu={})
    return record, nominal


def test_the_nonlinear_loop_with_a_basis_model_equal_to_the_linear_plant_is_the_linear_loop():
    from piezolib.identification import BasisModel

    p, g = 0.9, 2.0                                  # g / (z - p) per axis [um/V]
    G = ct.ss(p * np.eye(3), g * np.eye(3), np.eye(3), np.zeros((3, 3)), T)
    theta = np.zeros((3, 6))
    theta[:, :3] = 1e-6 * g * np.eye(3)              # the filter's state, in m
    model = BasisModel(np.array([p]), (("u", 0),), 50.0, 1.0, theta, 3)
    K_w = ct.ss(np.zeros((3, 3)), np.eye(3), 200.0 * np.eye(3), np.zeros((3, 3)))  # integrators
    loop = fsm_mimo.nonlinear_loop(model, *_nominal_and_record(G, K_w))
    nl = loop.table.xs("causal nonlinear model", axis=1, level=0)
    lin = loop.table.xs("all-levels linear model", axis=1, level=0)
    np.testing.assert_allclose(nl.to_numpy(), lin.to_numpy(), rtol=1e-9, atol=1e-12)
    assert np.allclose(nl["final / reference"], 1, atol=5e-3)      # integral action, 0.25 s
    assert np.all(nl["worst cross-talk"] < 1e-12)                   # decoupled plant
    # the steady actuator voltages have the stated RMS (one axis moves: RMS over the three)
    steady = loop.step_um / g * (1 - p)
    np.testing.assert_allclose(steady / np.sqrt(3), fsm_mimo.NONLINEAR_STEP_RMS_V)
    assert all(loop.checks.values())
    with pytest.raises(ValueError, match="causal_model"):
        fsm_mimo.nonlinear_loop(BasisModel(np.array([p]), (("u", 0),), 50.0, 1.0,
                                           np.zeros((1, 2)), 1), *_nominal_and_record(G, K_w))
