"""Least-squares fit of the Dahl model (fit_dahl) and the selection rule (choose_fit)."""

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import signals

FS = 10_000.0
GAMMA_A = 30.0
PARAMS = dict(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4.0 / 30.0, gamma_a=GAMMA_A, g_a=0.95)


def model(form="bliman_sorine", **overrides):
    return hy.DahlModel(**{**PARAMS, **overrides}, form=form)


def triangle(peak, periods=2):
    return signals.triangle(peak, 10.0, fs=FS, periods=periods)


@pytest.mark.parametrize("form", hy.FORMS)
def test_fit_recovers_known_parameters(form):
    true = model(form, alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = []
    for amplitude in (1.0, 2.0, 3.0, 4.0):
        t, v = triangle(amplitude)
        loops.append((v, hy.simulate_dahl(true, v).x))
    fit = hy.fit_dahl(loops, gamma_a=GAMMA_A, form=form, stride=5)
    for name in ("alpha1", "alpha2", "beta2", "g_a"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-6), name
    assert fit.model.gamma_a == GAMMA_A and fit.model.beta1 == 0.0
    assert np.all(fit.rms_percent < 1e-6)
    assert len(fit.x_model) == 4 and fit.residuals[0].shape == loops[0][0].shape


def test_gamma_a_is_held_fixed():
    """Only beta2*gamma_a enters H: another gamma_a gives the same loops, beta2 rescaled."""
    true = model("bliman_sorine", alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = [(v, hy.simulate_dahl(true, v).x) for v in (triangle(A)[1] for A in (1.0, 3.0))]
    fit = hy.fit_dahl(loops, gamma_a=1.0, stride=5)
    assert fit.model.gamma_a == 1.0
    assert fit.model.beta2 == pytest.approx(true.beta2 * true.gamma_a, rel=1e-6)
    with pytest.raises(ValueError, match="gamma_a must be positive"):
        hy.fit_dahl(loops, gamma_a=0.0)


@pytest.mark.parametrize("form, start", [("bliman_sorine", "virgin"), ("bliman_sorine", "rest"),
                                         ("printed", "virgin")])
def test_fit_recovers_known_parameters_including_offset(form, start):
    true = model(form, alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9, x0=-0.15,
                 start=start)
    loops = []
    for amplitude in (1.0, 2.0, 3.0, 4.0):
        t, v = triangle(amplitude)
        loops.append((v, hy.simulate_dahl(true, v).x))
    fit = hy.fit_dahl(loops, gamma_a=GAMMA_A, form=form, offset=True, start=start, stride=5)
    for name in ("alpha1", "alpha2", "beta2", "g_a", "x0"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-6), name
    assert fit.offset and fit.model.start == start
    assert fit.pooled_rms_percent < 1e-6
    # the paper's form (no offset) cannot represent the shifted loops
    paper_form = hy.fit_dahl(loops, gamma_a=GAMMA_A, form=form, start=start, stride=5)
    assert paper_form.model.x0 == 0.0 and paper_form.worst_rms_percent > 0.1


def test_fit_reaches_the_first_order_limit():
    """A first-order-like model (alpha1 >> 2 sqrt(alpha2)) is recovered inside the bounds."""
    true = model("bliman_sorine", alpha1=300.0, alpha2=420.0, beta2=0.25 * 420.0 / 30.0,
                 g_a=1.25, x0=-0.15, start="rest")
    loops = [(v, hy.simulate_dahl(true, v).x) for v in
             (triangle(A)[1] for A in (1.0, 2.0, 3.0, 4.0))]
    fit = hy.fit_dahl(loops, gamma_a=GAMMA_A, offset=True, start="rest", discard=1000, stride=5)
    assert not np.any(fit.result.active_mask)                 # no parameter on a bound
    assert fit.pooled_rms_percent < 1e-4
    for name in ("g_a", "x0"):
        assert getattr(fit.model, name) == pytest.approx(getattr(true, name), rel=1e-4), name
    # the first-order quantities: rate alpha2/alpha1 and steady state b2 gamma_a / alpha2
    assert fit.model.alpha2 / fit.model.alpha1 == pytest.approx(1.4, rel=1e-3)
    assert fit.model.steady_state(1) == pytest.approx(0.25, rel=1e-4)


def test_fit_from_a_single_starting_point():
    true = model("bliman_sorine", alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = [(v, hy.simulate_dahl(true, v).x) for v in (triangle(A)[1] for A in (1.0, 3.0))]
    fit = hy.fit_dahl(loops, gamma_a=GAMMA_A, stride=5, initial=model("bliman_sorine"))
    assert fit.initial.alpha1 == PARAMS["alpha1"]
    assert fit.model.alpha1 == pytest.approx(true.alpha1, rel=1e-6)
    with pytest.raises(TypeError, match="initial must be a DahlModel"):
        hy.fit_dahl(loops, gamma_a=GAMMA_A, initial=PARAMS)


def test_choose_fit_takes_the_smallest_pooled_rms():
    fake = {key: type("Fit", (), {"pooled_rms_percent": value})()
            for key, value in (("a", 2.0), ("b", 0.5), ("c", 0.5), ("d", 3.0))}
    assert hy.choose_fit(fake) == "b"
    with pytest.raises(ValueError, match="at least one"):
        hy.choose_fit({})


def test_fit_single_loop_and_discard():
    true = model("bliman_sorine")
    t, v = triangle(3.0)
    x = hy.simulate_dahl(true, v).x
    fit = hy.fit_dahl((v, x), gamma_a=GAMMA_A, discard=1000)
    assert fit.residuals[0].size == v.size - 1000
    assert fit.model.g_a == pytest.approx(true.g_a, rel=1e-6)


def test_fit_rejects_records_without_a_full_cycle():
    ramp = np.linspace(0, 4, 500)
    with pytest.raises(ValueError, match="no full cycle"):
        hy.fit_dahl([(ramp, 0.9 * ramp)], gamma_a=GAMMA_A)
    t, v = triangle(4.0, periods=1)
    with pytest.raises(ValueError, match="no full cycle"):
        hy.fit_dahl([(v, 0.9 * v)], gamma_a=GAMMA_A, discard=600)
    with pytest.raises(ValueError, match="equal lengths"):
        hy.fit_dahl([(v, v[:-1])], gamma_a=GAMMA_A)
    with pytest.raises(ValueError, match="contains 1 non-finite"):
        hy.fit_dahl([(v, np.r_[np.nan, v[1:]])], gamma_a=GAMMA_A)
    with pytest.raises(TypeError, match=r"loops\[0\] must be a \(v, x\) pair"):
        hy.fit_dahl({10.0: (v, v)}, gamma_a=GAMMA_A)
    with pytest.raises(ValueError, match="starts must be >= 1"):
        hy.fit_dahl([(v, 0.9 * v)], gamma_a=GAMMA_A, starts=0)
    with pytest.raises(TypeError, match="offset must be True or False"):
        hy.fit_dahl([(v, 0.9 * v)], gamma_a=GAMMA_A, offset="yes")
    with pytest.raises(ValueError, match="start must be one of"):
        hy.fit_dahl([(v, 0.9 * v)], gamma_a=GAMMA_A, start="lowered")


def test_fit_progress_bar_counts_the_solves_and_changes_nothing(monkeypatch, capsys):
    from piezolib.hysteresis import fit as fit_module
    from piezolib.progress import progress

    bars = []

    def recording_progress(*args, **kwargs):
        bars.append(progress(*args, **kwargs))
        return bars[-1]

    true = model("bliman_sorine", alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = [(v, hy.simulate_dahl(true, v).x) for v in (triangle(A)[1] for A in (1.0, 3.0))]
    monkeypatch.setattr(fit_module, "progress", recording_progress)
    monkeypatch.setenv("PIEZOLIB_PROGRESS", "0")
    off = hy.fit_dahl(loops, gamma_a=GAMMA_A, stride=5, starts=2)
    assert capsys.readouterr().err == ""
    monkeypatch.setenv("PIEZOLIB_PROGRESS", "1")
    on = hy.fit_dahl(loops, gamma_a=GAMMA_A, stride=5, starts=2)
    assert on.model == off.model and on.initial == off.initial
    np.testing.assert_array_equal(on.result.x, off.result.x)
    assert "fit_dahl bliman_sorine" in capsys.readouterr().err
    bar = bars[-1]
    assert bar.total == 3 and bar.n == 3                  # two starts, then the polish
    assert bar.postfix.startswith("polishing the best start, best rms")
    single = hy.fit_dahl(loops, gamma_a=GAMMA_A, stride=5, initial=on.model)
    assert bars[-1].total == 1 and bars[-1].n == 1 and single.model.alpha1 > 0


def test_rescore_moves_a_fit_to_another_model_and_recomputes_its_errors():
    true = model(alpha1=2.0, alpha2=2.5, beta2=0.3 * 2.5 / 30.0, g_a=0.9)
    loops = [(v, hy.simulate_dahl(true, v).x) for v in (triangle(a)[1] for a in (1.0, 3.0))]
    fit = hy.fit_dahl(loops, gamma_a=GAMMA_A, stride=5)
    same = hy.rescore_dahl(fit, fit.model, loops)
    np.testing.assert_array_equal(same.rms, fit.rms)
    other = hy.rescore_dahl(fit, model(g_a=0.95), loops)      # 5 % off in gain
    assert other.model.g_a == 0.95 and np.all(other.rms_percent > 1.0)
    assert other.parameters == fit.parameters and other.result is fit.result
    with pytest.raises(ValueError, match="form and start"):
        hy.rescore_dahl(fit, model("printed"), loops)
    with pytest.raises(TypeError, match="DahlFit"):
        hy.rescore_dahl(fit.model, fit.model, loops)


def test_default_stride_keeps_at_most_max_fit_samples():
    """A long record is fitted on every k-th sample (turning points kept): the same fit as
    the explicit stride, and the reported residuals still cover every sample."""
    import warnings
    true = hy.DahlModel(alpha1=3.0, alpha2=4.0, beta1=0.0, beta2=0.2 * 4 / 30, gamma_a=30.0,
                        g_a=0.95, form="bliman_sorine")
    v = 2.0 + 2.0 * np.sin(np.linspace(0, 6 * np.pi, 4 * hy.MAX_FIT_SAMPLES + 1))
    x = hy.simulate_dahl(true, v).x
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hy.FitWarning)
        auto = hy.fit_dahl([(v, x)], gamma_a=30.0, starts=1)
        explicit = hy.fit_dahl([(v, x)], gamma_a=30.0, starts=1, stride=5)
    assert auto.model == explicit.model
    assert auto.residuals[0].size == v.size
