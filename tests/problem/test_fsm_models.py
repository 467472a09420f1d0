"""The FSM benchmark's model steps: checks that can fail, tables on small synthetic BLAs."""

from types import SimpleNamespace

import control as ct
import numpy as np
import pytest

from piezolib import identification as ident
from piezolib.problem import fsm_benchmark as fsm
from piezolib.problem import fsm_models

F_HZ = np.array([10.0, 50.0, 700.0, 1000.0, 1200.0, 2000.0])


def _bla(G, var_noise=1.0, var_total=2.0):
    var = np.ones(G.shape)
    return SimpleNamespace(G=G, frequency_Hz=F_HZ, var_noise=var_noise * var,
                           var_total=var_total * var, var_distortion=(var_total - var_noise) * var,
                           std_noise=np.sqrt(var_noise * var), lines=np.arange(F_HZ.size),
                           n_groups=2, n_periods=2)


def _levels(G100, G200, G300, **variances):
    blas = {100: _bla(G100, **variances), 200: _bla(G200, **variances),
            300: _bla(G300, **variances)}
    return fsm_models.LevelBLAs(train={}, blas=blas, file_problems={})


def test_the_change_at_one_resonance_line_is_all_in_its_band():
    G = np.ones((3, 3, F_HZ.size), dtype=complex)
    G300 = G.copy()
    G300[..., 3] += 0.5                                   # the 1000 Hz line only
    change = fsm_models.level_change(_levels(G, G, G300))
    share = change.table.loc["share of the change's power [%]"]
    assert share["900-1100 Hz"] == pytest.approx(100.0)
    assert change.resonance_share_percent == pytest.approx(100.0)
    assert change.gain_ratio == pytest.approx([1.0, 1.0, 1.0])
    assert all(change.checks.values())


def test_a_change_in_gain_is_seen_at_low_frequency_and_fails_the_check():
    G = np.ones((3, 3, F_HZ.size), dtype=complex)
    change = fsm_models.level_change(_levels(G, G, 2 * G))
    assert change.gain_ratio == pytest.approx([2.0, 2.0, 2.0])
    assert not all(change.checks.values())               # a third of the change below 600 Hz


def test_bla_checks_fail_without_distortion():
    G = np.ones((3, 3, F_HZ.size), dtype=complex)
    data = _levels(G, G, G, var_noise=1.0, var_total=1.2)
    checks = data.checks
    assert not any(v for k, v in checks.items() if "1.5 x noise" in k)
    table = data.table()
    assert table.loc["total / noise variance", "200 mV"] == pytest.approx(1.2)
    assert table.loc["BLA change from 200 mV (rms) [%]", "100 mV"] == pytest.approx(0.0)


def _linear(scale):
    """LinearModels whose level models are the all-levels model times ``scale[level]``."""
    dt = 1 / fsm.SAMPLING_FREQUENCY_HZ
    base = ct.ss([[0.5]], np.ones((1, 3)), 1e-6 * np.ones((3, 1)), np.zeros((3, 3)), dt)
    models = {f"ours, order chosen (1), trained at {lv} mV": (lv, base * s)
              for lv, s in scale.items()}
    models["ours, one model for all levels (order 1)"] = ("all", base)
    selections = {lv: SimpleNamespace(order=1) for lv in scale}
    return fsm_models.LinearModels(models=models, selections=selections, baseline_order=28,
                                   G_all=np.zeros((3, 3, F_HZ.size)))


def test_the_level_spread_is_the_levels_relative_gain_and_is_covered():
    G = np.ones((3, 3, F_HZ.size), dtype=complex)
    G[2, 2] = 3.0                                         # the (3, 3) pair has the largest gain
    weight = fsm_models.level_spread_weight(_levels(G, G, G), _linear({100: 0.9, 200: 1.0,
                                                                        300: 1.2}))
    assert np.allclose(weight.envelope, 0.2)
    assert np.allclose(weight.relative_errors["100 mV"], 0.1)
    assert weight.checks["the pair is the diagonal pair with the largest peak gain"]
    assert weight.pair_label == "v_a3 → d_3"
    assert weight.coupling.loc["d_1", "v_a3"] == pytest.approx(1.0)
    G[0, 0] = 5.0                                         # now (1, 1) is larger: the check fails
    other = fsm_models.level_spread_weight(_levels(G, G, G), _linear({100: 0.9, 200: 1.0,
                                                                       300: 1.2}))
    assert not other.checks["the pair is the diagonal pair with the largest peak gain"]


def test_scores_checks_and_tables_from_scores():
    linear = _linear({100: 1.0, 200: 1.0, 300: 1.0})
    linear = fsm_models.LinearModels(models=linear.models, selections=linear.selections,
                                     baseline_order=1, G_all=linear.G_all)

    def score(level, nrmse_percent):
        return fsm.Score(level_mV=level, rmse_um=np.full(3, 0.1), nrmse=np.full(3, nrmse_percent
                                                                                 / 100))
    own = {100: 5.0, 200: 4.0, 300: 3.0}
    scores = {name: {lv: score(lv, own[lv] if lv == level or level == "all" else 20.0)
                     for lv in fsm.LEVELS_MV} for name, (level, _) in linear.models.items()}
    floors = {lv: score(lv, 1.0) for lv in fsm.LEVELS_MV}
    result = fsm_models.LinearScores(linear=linear, scores=scores, floors=floors,
                                     train_floors=floors, largest_pole_radius=0.5)
    assert all(result.checks.values())
    assert all(result.reference_checks.values())          # 5, 4, 3 below 8.38, 7.95, 5.63
    share = result.noise_share_table()
    assert share.loc["share of the squared error that is noise [%]", "100 mV"] == \
        pytest.approx(4.0)
    assert share.loc["model error without the noise [%]", "300 mV"] == pytest.approx(np.sqrt(8))
    unstable = fsm_models.LinearScores(linear=linear, scores=scores, floors=floors,
                                       train_floors=floors, largest_pole_radius=1.01)
    assert not unstable.checks["every linear model is stable"]


def test_steps_refuse_what_is_not_their_input():
    with pytest.raises(TypeError, match="blas"):
        fsm_models.fit_linear_models({}, (4,), 28)
    with pytest.raises(TypeError, match="linear"):
        fsm_models.score_linear_models(None)


def test_committed_order_curve_reaches_the_fits_largest_order():
    curve = fsm_models.read_order_curve()
    assert curve.orders == fsm_models.WIDE_ORDERS
    assert curve.orders[-1] == ident.MAX_ROWS - 8
    for lv in fsm.LEVELS_MV:
        assert len(curve.validation_error[lv]) == len(curve.orders)
        # the committed best order's validation error is the curve's minimum
        assert curve.validation_error[lv][curve.orders.index(curve.best(lv))] == \
            min(curve.validation_error[lv])
    assert "order" in curve.table().index.name


def test_each_levels_best_order_lies_strictly_inside_the_committed_curve():
    curve = fsm_models.read_order_curve()
    for lv in fsm.LEVELS_MV:
        assert curve.orders[0] < curve.best(lv) < curve.orders[-1], lv
        assert curve.interior(lv)
        # the choice does not hang on the curve's jitter: no lower order within 0.1 points
        assert curve.smallest_within(lv, 1e-3) == curve.best(lv)
    # the working models' candidates are the curve's first points
    assert curve.selection(300, (24, 32, 40, 48)).order == 40


def _curve(errors_300=(0.09, 0.05, 0.04, 0.06)):
    orders = (8, 16, 24, 32)
    errors = {100: [0.09, 0.05, 0.06, 0.07], 200: [0.09, 0.08, 0.05, 0.045],
              300: list(errors_300)}
    return fsm_models.OrderCurve(orders=orders, validation_error=errors,
                                 test_nrmse={100: 5.0, 200: 4.0, 300: 3.0}, seconds=1.0)


def test_a_curve_says_where_its_best_lies_and_chooses_among_a_subset():
    curve = _curve()
    assert [curve.best(lv) for lv in fsm.LEVELS_MV] == [16, 32, 24]
    assert curve.interior(100) and not curve.interior(200)        # 200 mV: best at the top
    assert curve.margin(100) == pytest.approx(0.01)
    sel = curve.selection(200, (8, 16, 24))
    assert sel.order == 24 and list(sel.orders) == [8, 16, 24]
    assert np.allclose(sel.validation_error, [0.09, 0.08, 0.05])
    # the smallest order within a tolerance of the minimum
    assert curve.smallest_within(200, 0.0) == 32 and curve.smallest_within(200, 0.006) == 24
    assert set(curve.percent()) == {"100 mV", "200 mV", "300 mV"}
    assert "AT THE END" in curve.description()
    with pytest.raises(ValueError, match="orders: .*not on the curve"):
        curve.selection(100, (8, 12))
    with pytest.raises(ValueError, match="level_mV"):
        curve.selection(150, (8,))
    with pytest.raises(ValueError, match="tolerance"):
        curve.smallest_within(100, -1.0)


def test_fit_linear_models_reads_the_choice_from_a_curve():
    """Given a curve, only the chosen orders are fitted: the choice is the curve's."""
    z = np.exp(2j * np.pi * F_HZ / fsm.SAMPLING_FREQUENCY_HZ)
    G = np.empty((3, 3, F_HZ.size), dtype=complex)
    G[...] = 1e-6 * 0.5 / (z - 0.5)
    groups = (G, G)
    blas = {lv: SimpleNamespace(**vars(_bla(G)), G_groups=groups) for lv in fsm.LEVELS_MV}
    data = fsm_models.LevelBLAs(train={}, blas=blas, file_problems={})
    curve = _curve(errors_300=(0.05, 0.09, 0.09, 0.09))
    linear = fsm_models.fit_linear_models(data, (8, 16), 4, curve=curve)
    assert {lv: s.order for lv, s in linear.selections.items()} == {100: 16, 200: 16, 300: 8}
    assert linear.chosen(300) in linear.models and linear.at_baseline(300) in linear.models
    assert linear.order_all == 16
    with pytest.raises(ValueError, match="orders: .*not on the curve"):
        fsm_models.fit_linear_models(data, (8, 12), 4, curve=curve)
    with pytest.raises(TypeError, match="curve"):
        fsm_models.fit_linear_models(data, (8, 16), 4, curve={})


@pytest.mark.slow
def test_rederived_order_curve_lands_on_the_committed_one():
    committed = fsm_models.read_order_curve()
    curve = fsm_models.derive_order_curve(fsm_models.level_blas(), committed.orders)
    for lv in fsm.LEVELS_MV:
        assert curve.best(lv) == committed.best(lv)
        assert np.allclose(curve.validation_error[lv], committed.validation_error[lv], atol=1e-5)
        assert abs(curve.test_nrmse[lv] - committed.test_nrmse[lv]) < 0.01


@pytest.mark.slow
def test_the_working_models_choice_read_from_the_curve_is_the_one_fitting_every_candidate():
    data = fsm_models.level_blas()
    orders = (24, 32, 40, 48)
    fitted = fsm_models.fit_linear_models(data, orders, 28)
    read = fsm_models.fit_linear_models(data, orders, 28, curve=fsm_models.read_order_curve())
    for lv in fsm.LEVELS_MV:
        assert fitted.selections[lv].order == read.selections[lv].order
        assert np.allclose(fitted.selections[lv].validation_error,
                           read.selections[lv].validation_error, atol=1e-5)
