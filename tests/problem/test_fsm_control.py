"""One mirror axis: the nominal entry, the verification's checks, the coupling one loop leaves."""

from types import SimpleNamespace

import control as ct
import numpy as np
import pandas as pd
import pytest

from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_control, fsm_models

FS = fsm.SAMPLING_FREQUENCY_HZ
F_HZ = np.linspace(2.0, 1500.0, 300)
ZL = np.exp(2j * np.pi * F_HZ / FS)


def _mimo():
    """3 x 3 discrete model [m/V] whose every entry is one minimal 3-state system."""
    A = np.diag([0.9, 0.5, -0.3])
    return ct.ss(A, np.ones((3, 3)), 1e-6 * np.ones((3, 3)), np.zeros((3, 3)), 1 / FS)


def _linear(model, G_all):
    models = {f"ours, order chosen (3), trained at {lv} mV": (lv, model) for lv in fsm.LEVELS_MV}
    models["ours, one model for all levels (order 3)"] = ("all", model)
    return fsm_models.LinearModels(models=models, selections={lv: SimpleNamespace(order=3)
                                                              for lv in fsm.LEVELS_MV},
                                   baseline_order=28, G_all=G_all)


def test_the_full_order_entry_reproduces_its_own_response():
    model = _mimo()
    G_all = np.asarray(model(ZL))                                # (3, 3, F)
    nominal = fsm_control.axis_nominal(_linear(model, G_all), F_HZ, 2, orders=(1,))
    assert list(nominal.reduction.index) == [1, 2, 3]
    assert nominal.reduction.loc[3, "rms error < 100 Hz [%]"] < 1e-8
    assert nominal.reduction.loc[3, "levels' spread, peak 500-1100 Hz"] < 1e-12
    assert nominal.g_nominal.nstates == 2 and nominal.g_nominal.D[0, 0] == 0.0
    assert nominal.hankel_relative[0] == pytest.approx(1.0)
    assert np.all(np.diff(nominal.hankel_relative) <= 0)
    # truncation to one state keeps the DC gain (matchdc) but not the response
    assert nominal.reduction.loc[1, "rms error < 1100 Hz [%]"] > 1e-3


def test_axis_entry_is_in_um_per_volt():
    g = fsm_control.axis_entry(_mimo(), (2, 2))
    assert np.allclose(np.ravel(g(ZL)), 1e6 * np.asarray(_mimo()(ZL))[2, 2])


def test_hz_of_w_plane_inverts_the_warping():
    f = np.array([1.0, 100.0, 3000.0])
    nu = 2 * FS * np.tan(np.pi * f / FS)
    assert [fsm_control.hz_of_w_plane(x) for x in nu] == pytest.approx(f)


def _verification(mu_upper=0.8, radius=0.99, gain_margin=3.0):
    loops = pd.DataFrame({"sampled loop: largest |pole|": [radius], "stable": [radius < 1],
                          "gain margin [x]": [gain_margin], "phase margin [deg]": [60.0],
                          "disk margin": [1.0]}, index=["nominal (reduced)"])
    mu = SimpleNamespace(upper=np.array([0.5, mu_upper]), lower=np.array([0.4, mu_upper]))
    return fsm_control.AxisVerification(mu=mu, mu_upper=mu_upper, mu_lower=mu_upper, peak_Hz=1.0,
                                        wplane_max_real=-1.0,
                                        delay_radius=np.array([radius] * 4), loops=loops)


def test_the_verification_checks_can_fail():
    assert all(_verification().checks.values())
    assert not _verification(mu_upper=1.2).checks["robust performance: mu_RP upper bound < 1"]
    failed = _verification(radius=1.001).checks
    assert not failed["the sampled loop is stable with 0-3 samples of delay"]
    assert not failed["the sampled loop is stable with the nominal and each level's model"]
    assert not _verification(gain_margin=0.9).checks[
        "gain margins > 1 and phase margins > 0 with every model"]


def test_a_loop_without_gain_moves_nothing_and_the_coupling_is_relative_to_the_diagonal():
    G = np.ones((3, 3, F_HZ.size), dtype=complex)
    G[np.arange(3), np.arange(3)] = 2.0
    blas = fsm_models.LevelBLAs(train={}, blas={lv: SimpleNamespace(G=G, frequency_Hz=F_HZ)
                                                for lv in fsm.LEVELS_MV}, file_problems={})
    zero = ct.ss([], [], [], [[0.0]], 1 / FS)
    design = fsm_control.AxisDesign(G_w=None, spread=None, hull=None, W_m=None, coverage=None,
                                    plant=None, dk=None, K_w=None, K_d=zero, zinv=None,
                                    bandwidth_Hz=20.0)
    coupling = fsm_control.axis_coupling(blas, _linear(_mimo(), 1e-6 * G), design)
    assert np.allclose(coupling.off_diagonal, 0.5)
    assert np.allclose(np.diag(coupling.band.values), 1.0)
    assert np.allclose(coupling.moves.values, 0.0)
    # a static gain k on the BLA: |d_i / r_3| = |G_i3 k / (1 + z^-1 G_33 k)|
    k = ct.ss([], [], [], [[0.1]], 1 / FS)
    design = fsm_control.AxisDesign(**{**design.__dict__, "K_d": k})
    moves = fsm_control.axis_coupling(blas, _linear(_mimo(), 1e-6 * G), design).moves
    at10 = int(np.argmin(np.abs(F_HZ - 10)))
    expected = abs(1.0 * 0.1 / (1 + ZL[at10] ** -1 * 2.0 * 0.1))
    assert moves.loc["d_1", "|d_i / r_3| at 10 Hz"] == pytest.approx(expected)


def test_design_and_verify_refuse_what_is_not_their_input():
    with pytest.raises(TypeError, match="nominal"):
        fsm_control.design_axis(None, bandwidth_Hz=20.0, error_weight={}, output_weight={},
                                output_corner=5.0, rolloff={}, dk_iterations=1)
    with pytest.raises(ValueError, match="nominal_order"):
        fsm_control.axis_nominal(None, F_HZ, 0)
