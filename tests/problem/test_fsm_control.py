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


PARAMS = dict(bandwidth_Hz=20.0,
              error_weight=dict(low_frequency_bound=0.01, high_frequency_bound=2.0),
              output_weight=dict(low_frequency_bound=5.0, high_frequency_bound=0.1),
              output_corner=5.0,
              rolloff=dict(hf_gain=0.1, lf_gain=1e3, frequency=2 * np.pi * 2000.0, order=2),
              dk_iterations=1)


def _small_nominal(scale=(0.9, 1.0, 1.1)):
    """A 2-state axis nominal with the levels' models a gain apart."""
    model = _mimo()
    G_all = np.asarray(model(ZL))
    linear = _linear(model, G_all)
    models = dict(linear.models)
    for lv, s in zip(fsm.LEVELS_MV, scale):
        models[f"ours, order chosen (3), trained at {lv} mV"] = (lv, model * s)
    linear = fsm_models.LinearModels(models=models, selections=linear.selections,
                                     baseline_order=28, G_all=G_all)
    return fsm_control.axis_nominal(linear, F_HZ, 2, orders=(1,))


def test_the_axis_record_gives_back_its_design_and_refuses_other_parameters_or_nominals(tmp_path):
    nominal = _small_nominal()
    design = fsm_control.design_axis(nominal, **PARAMS)
    path = fsm_control.write_axis_design(design, nominal, tmp_path / "axis.json")
    back = fsm_control.read_axis_design(nominal, **PARAMS, path=path)
    omega = np.logspace(0, 4, 30)
    assert np.allclose(np.ravel(back.K_w(1j * omega)), np.ravel(design.K_w(1j * omega)))
    assert back.dk.mu_peak == design.dk.mu_peak
    assert list(back.dk.history.columns) == list(design.dk.history.columns)
    assert np.allclose(np.ravel(back.W_m(1j * omega)), np.ravel(design.W_m(1j * omega)))
    assert back.coverage.covers == design.coverage.covers
    # the loop rebuilt from the record is the designed one
    mu_back = fsm_control.verify_axis(nominal, back).mu_upper
    assert mu_back == pytest.approx(fsm_control.verify_axis(nominal, design).mu_upper, rel=1e-9)
    with pytest.raises(ValueError, match="designed with"):
        fsm_control.read_axis_design(nominal, **{**PARAMS, "bandwidth_Hz": 25.0}, path=path)
    with pytest.raises(ValueError, match="nominal: .*another nominal"):
        other = fsm_control.axis_nominal(_linear(_mimo() * 1.01, np.asarray(_mimo()(ZL))), F_HZ,
                                         2, orders=(1,))
        fsm_control.read_axis_design(other, **PARAMS, path=path)
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(ValueError, match="path: .*not an axis design record"):
        fsm_control.read_axis_design(nominal, **PARAMS, path=tmp_path / "bad.json")


def test_the_committed_axis_record_is_the_notebooks_design():
    import json

    doc = json.loads(fsm_control.axis_record_path().read_text())
    assert doc["pair"] == [2, 2] and doc["nominal_order"] == 12
    assert doc["params"]["dk_iterations"] == 8 and doc["params"]["bandwidth_Hz"] == 20.0
    assert doc["mu_lower_peak"] <= doc["mu_peak"] * (1 + 1e-6) and doc["mu_peak"] < 1


@pytest.mark.slow
def test_rederived_axis_design_lands_on_the_committed_record():
    """design_axis from scratch (the notebook's parameters) against the committed record:
    the same order, mu_RP within the claim's precision 0.002, the same verification."""
    import json

    doc = json.loads(fsm_control.axis_record_path().read_text())
    params = doc["params"]
    data = fsm_models.level_blas()
    linear = fsm_models.fit_linear_models(data, (24, 32, 40, 48), 28,
                                          curve=fsm_models.read_order_curve())
    nominal = fsm_control.axis_nominal(linear, data.frequency_Hz, doc["nominal_order"],
                                       pair=tuple(doc["pair"]))
    fresh = fsm_control.design_axis(nominal, **params)
    committed = fsm_control.read_axis_design(nominal, **params)
    assert abs(fresh.dk.mu_peak - committed.dk.mu_peak) < 0.002
    assert abs(fresh.K_w.nstates - committed.K_w.nstates) <= 2
    v_fresh = fsm_control.verify_axis(nominal, fresh)
    v_committed = fsm_control.verify_axis(nominal, committed)
    assert abs(v_fresh.mu_upper - v_committed.mu_upper) < 0.002
    assert v_fresh.loops["stable"].all() and v_committed.loops["stable"].all()


def test_the_committed_axis_controller_is_the_3x3_records_siso_loop_on_axis_3():
    """Both records ran design_axis with the same parameters on the same nominal."""
    import json

    from piezolib.problem import fsm_mimo

    doc = json.loads(fsm_control.axis_record_path().read_text())
    mimo = fsm_mimo.read_mirror_record()
    assert doc["params"]["dk_iterations"] == mimo.params["siso_dk_iterations"]
    assert doc["nominal_order"] == mimo.params["siso_nominal_order"]
    omega = np.logspace(0, 5, 50)
    K, K_mimo = fsm_control._ss_of(doc["K_w"]), mimo.siso_K_w[2]
    assert np.allclose(np.ravel(K(1j * omega)), np.ravel(K_mimo(1j * omega)), rtol=1e-6)
    assert doc["mu_peak"] == pytest.approx(mimo.siso_mu[2], abs=1e-6)
