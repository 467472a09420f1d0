"""Notebook 10's claim rows and summary lines from (small, synthetic) benchmark results."""

import dataclasses
from types import SimpleNamespace

import control as ct
import numpy as np
import pandas as pd

from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_control, fsm_models
from piezolib.workbook import fsm_findings
from piezolib.workbook.report import ClaimTable

LEVELS = fsm.LEVELS_MV


def _score(level, percent):
    return fsm.Score(level_mV=level, rmse_um=np.full(3, 0.1), nrmse=np.full(3, percent / 100))


def _results():
    names = {lv: f"ours, order chosen (40), trained at {lv} mV" for lv in LEVELS}
    models = {**{n: (lv, None) for lv, n in names.items()},
              **{f"ours, order 28, trained at {lv} mV": (lv, None) for lv in LEVELS},
              "ours, one model for all levels (order 40)": ("all", None)}
    linear = fsm_models.LinearModels(models=models, selections={lv: SimpleNamespace(
                                         order=40, orders=[24, 32, 40, 48]) for lv in LEVELS},
                                     baseline_order=28, G_all=None)
    scores = fsm_models.LinearScores(
        linear=linear, scores={n: {lv: _score(lv, 5.0) for lv in LEVELS} for n in models},
        floors={lv: _score(lv, 1.0) for lv in LEVELS},
        train_floors={lv: _score(lv, 1.0) for lv in LEVELS}, largest_pole_radius=0.9)
    nonlinear = fsm_models.NonlinearModels(
        hammerstein=None, scheduled=None, level_rms_V=[0.1, 0.2, 0.3], blend=None,
        scores={fsm_models.HAMMERSTEIN: {lv: _score(lv, 9.0) for lv in LEVELS},
                fsm_models.SCHEDULED: {lv: _score(lv, 5.0) for lv in LEVELS}})
    f = np.array([10.0, 900.0, 2000.0])
    weight = fsm_models.LevelSpreadWeight(
        pair=(2, 2), coupling=pd.DataFrame(np.ones((3, 3))), relative_errors={},
        envelope=np.array([0.1, 0.5, 0.2]), weight=ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]]),
        coverage=SimpleNamespace(covers=True), weight_magnitude=np.ones(3), frequency_Hz=f,
        pair_is_largest=True, order=4)
    reduction = pd.DataFrame({"rms error < 100 Hz [%]": [6.4512, 4.3]}, index=[12, 48])
    nominal = fsm_control.AxisNominal(
        pair=(2, 2), g_full=SimpleNamespace(nstates=48), g_level={},
        g_nominal=SimpleNamespace(nstates=12), reduction=reduction, hankel_relative=None,
        frequency_Hz=f, nominal_order=12)
    loops = pd.DataFrame({"sampled loop: largest |pole|": [0.99412], "stable": [True],
                          "gain margin [x]": [17.4], "phase margin [deg]": [82.6],
                          "disk margin": [1.6049], "crossover [Hz]": [20.0]},
                         index=["nominal (reduced)"])
    verified = fsm_control.AxisVerification(mu=None, mu_upper=0.76218, mu_lower=0.7615,
                                            peak_Hz=1.0, wplane_max_real=-1.0,
                                            delay_radius=np.ones(4) * 0.99, loops=loops)
    design = fsm_control.AxisDesign(**{f.name: None for f in dataclasses.fields(
        fsm_control.AxisDesign)} | dict(bandwidth_Hz=20.0, K_w=SimpleNamespace(nstates=22)))
    return scores, nonlinear, weight, nominal, verified, design


def test_the_claims_come_in_the_tables_order_with_their_precision():
    rows = fsm_findings.claim_rows(*_results())
    assert len(rows) == 4 * 3 + 2 * 3 + 2 + 4 + 4
    assert rows[0]["quantity"] == ("test NRMSE, working linear model at 100 mV (order 40, best "
                                   "of 24-48)")
    assert rows[0]["note"] == ("the model the scheduled model, the weights and the mu designs "
                               "use; published 28th-order BLA at the same level: 8.38 %; "
                               "lower is better")
    assert rows[18]["quantity"] == "level-spread envelope of v_a3 -> d_3, peak"
    assert rows[18]["ours"] == 0.5 and rows[18]["note"] == "at 900.0 Hz"
    by_quantity = {r["quantity"]: r for r in rows}
    assert by_quantity["mu_RP upper bound, sampled loop (w-plane)"]["ours"] == 0.762
    assert by_quantity["nominal model: rms relative FRF error to the BLA below 100 Hz"][
        "note"] == "full 48-state entry: 4.30 %"
    assert by_quantity["gain margin, nominal (reduced)"]["ours"] == 17.0
    assert by_quantity["phase margin, nominal (reduced)"]["ours"] == 83
    assert by_quantity["disk margin, nominal (reduced)"]["ours"] == 1.6
    table = ClaimTable("demo", "reference")
    for row in rows:
        table.add(**row)
    assert (table.frame().verdict == "not published").all()


def test_the_summary_names_the_levels_where_the_scheduled_model_beats_the_lfr():
    scores, nonlinear, weight, nominal, verified, design = _results()
    G = np.ones((3, 3, 3), dtype=complex)
    var = np.ones(G.shape)
    bla = SimpleNamespace(G=G, frequency_Hz=weight.frequency_Hz, var_noise=var,
                          var_total=2 * var, var_distortion=var)
    blas = fsm_models.LevelBLAs(train={}, blas={lv: bla for lv in LEVELS}, file_problems={})
    change = fsm_models.LevelChange(table=pd.DataFrame(
        {f"{lo}-{hi} Hz": {"share of the change's power [%]": 20.0}
         for lo, hi in fsm_models.BANDS_HZ}), gain_ratio=[1.1, 1.1, 1.1])
    coupling = fsm_control.AxisCoupling(band=pd.DataFrame(np.full((3, 3), 0.5)),
                                        moves=pd.DataFrame([[1.2], [0.8], [1.0]]), pair=(2, 2))
    lines = fsm_findings.summary_lines(blas, scores, change, nonlinear, weight, nominal, design,
                                       verified, coupling)
    assert lines[0].startswith("working linear models per level (orders 40, 40, 40, chosen by "
                               "validation on the other group over 24-48)")
    nonlinear_line = next(x for x in lines if x.startswith("one model for all levels, not"))
    assert "below the LFR at 100 mV; above it at 200 mV, 300 mV" in nonlinear_line
    assert "why the Hammerstein model fails: 60 %" in lines[6]
    assert "envelope peak 0.50 at 900 Hz, covered by an order-4 weight" in lines[7]
    assert lines[-1].startswith("the mirror as a whole: the 3 × 3 μ controller")


def _curve(best_at_end=False):
    orders = (24, 48, 64, 92, 160)
    errors = {100: [0.09, 0.06, 0.055, 0.057, 0.06], 200: [0.09, 0.046, 0.045, 0.041, 0.046],
              300: [0.09, 0.05, 0.049, 0.043, 0.0425 if best_at_end else 0.047]}
    return fsm_models.OrderCurve(orders=orders, validation_error=errors,
                                 test_nrmse={100: 5.55, 200: 4.94, 300: 4.49}, seconds=1.0)


def test_the_linear_baseline_rows_come_from_the_wide_curve_and_say_where_its_best_lies():
    scores = _results()[0]
    rows = {r["quantity"]: r for r in fsm_findings.order_curve_claim_rows(_curve(), scores)}
    assert rows["linear model at 100 mV: order chosen by validation over 24-160"]["ours"] == 64
    assert rows["linear model at 300 mV: the chosen order lies inside 24-160"]["ours"] is True
    row = rows["test NRMSE, linear model at 200 mV (order 92, best of 24-160)"]
    assert row["ours"] == 4.94 and "working model (order 40): 5.00 %" in row["note"]
    line = fsm_findings.order_curve_summary_line(_curve(), scores)
    assert "64, 92, 92 (each inside the range)" in line
    # a curve whose best is its last order says so
    at_end = {r["quantity"]: r for r in fsm_findings.order_curve_claim_rows(
        _curve(best_at_end=True), scores)}
    assert at_end["linear model at 300 mV: the chosen order lies inside 24-160"]["ours"] is False
    assert "NOT all inside" in fsm_findings.order_curve_summary_line(_curve(True), scores)
