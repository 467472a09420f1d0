"""Model choice by validation and the feedforward cross-check."""

import numpy as np
import pytest

from piezolib import hysteresis as hy
from piezolib import signals

FS = 10_000.0
PI = hy.PIModel(tuple(0.3 * np.arange(6)), (0.8, 0.2, 0.0, 0.15, 0.1, 0.05), x0=-0.1)
DAHL = hy.DahlModel(3.0, 4.0, 0.0, 0.2 * 4 / 30, 30.0, 1.1, form="bliman_sorine")


def record(model, A=3.0, periods=4):
    t, v = signals.triangle(A, 10.0, fs=FS, periods=periods)
    return v, model.simulate(v)


def test_split_record_cuts_at_a_turning_point():
    v, x = record(PI)
    (v_fit, x_fit), (v_all, x_all, first) = hy.split_record(v, x, 0.5)
    assert v_fit.size == first + 1 and v_all is not None
    assert v[first] in (v.min(), v.max())                  # a reversal
    assert abs(first - v.size / 2) <= 500
    with pytest.raises(ValueError, match="no turning point"):
        hy.split_record(np.arange(20.0), np.arange(20.0))
    with pytest.raises(ValueError, match="strictly between"):
        hy.split_record(v, x, 1.0)


def test_validation_prefers_the_true_model():
    v, x = record(PI)
    fit_part, validation = hy.split_record(v, x, 0.5)
    pi = hy.fit_pi([fit_part], thresholds=PI.thresholds)
    table = hy.validation_table({"PI": pi.model, "Dahl": DAHL}, [validation, (v, x)])
    assert table.loc[("PI", 0), "RMS %"] < 1e-8
    assert table.loc[("Dahl", 0), "RMS %"] > 1.0
    assert table.loc[("PI", 0), "hysteresis % model"] == pytest.approx(
        table.loc[("PI", 0), "hysteresis % data"], abs=1e-8)
    assert set(table.columns) >= {"max %", "loop width data", "loop width model", "pooled RMS %"}
    pooled = hy.pooled_rms(table)
    assert list(pooled.index) == ["PI", "Dahl"] and pooled.idxmin() == "PI"
    assert pooled["Dahl"] == pytest.approx(np.sqrt(np.mean(table.loc["Dahl", "RMS %"] ** 2)))
    with pytest.raises(TypeError, match="simulate"):
        hy.validation_table({"bad": object()}, [validation])


def test_cross_check_diagonal_is_exact_and_off_diagonal_is_not():
    t, x_r = signals.triangle(3.0, 10.0, fs=FS, periods=2)
    models = {"PI": PI, "Dahl": DAHL}
    table = hy.cross_check(models, models, x_r, first=1000)
    assert table.loc[("PI", "PI"), "RMS %"] < 1e-9
    assert table.loc[("Dahl", "Dahl"), "RMS %"] < 1e-9
    assert table.loc[("PI", "Dahl"), "hysteresis %"] > 1.0
    linear = hy.cross_check({"PI": PI}, {"straight": lambda u: 0.5 * u}, x_r)
    assert linear.loc[("PI", "straight"), "hysteresis %"] > 1.0
    with pytest.raises(ValueError, match="constant"):
        hy.cross_check(models, models, np.ones(100))
