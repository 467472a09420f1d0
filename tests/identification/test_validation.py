"""Validation tools: fit, whiteness, empirical frequency response, coefficient table."""

import control as ct
import numpy as np
import pytest
import scipy.signal as sg

from piezolib import identification as I
from piezolib import paper
from piezolib.robust import realize

FS = paper.SAMPLING_FREQUENCY_HZ


def test_fit_percent_and_whiteness():
    rng = np.random.default_rng(5)
    y = rng.standard_normal(4000)
    assert I.fit_percent(y, y) == 100.0
    assert I.fit_percent(y, np.full_like(y, y.mean())) == pytest.approx(0.0, abs=1e-12)
    assert I.whiteness(rng.standard_normal(20000)).passed
    coloured = sg.lfilter([1.0], [1.0, -0.5], rng.standard_normal(20000))
    result = I.whiteness(coloured)
    assert not result.passed and result.n_outside >= 4
    assert result.autocorrelation[0] == pytest.approx(0.5, abs=0.03)


def test_empirical_frequency_response_of_a_known_filter():
    u = np.random.default_rng(6).standard_normal(40000)
    y = I.zoh_simulate(paper.plant(), u, FS)
    w, h = I.empirical_frequency_response(u, y, FS)
    band = (w > 2e3) & (w < 2e4)
    ref = np.asarray(ct.c2d(realize(paper.plant()), 1 / FS, "zoh")(np.exp(1j * w[band] / FS)))
    assert np.max(np.abs(h[band] - ref.ravel()) / np.abs(ref.ravel())) < 0.05


def test_coefficient_table_of_the_published_plant():
    table = I.coefficient_table(paper.plant(), paper.plant())
    assert list(table.index) == [f"a{i}" for i in range(6)] + [f"b{i}" for i in range(4)]
    assert np.allclose(table["relative error"], 0, atol=1e-12)
