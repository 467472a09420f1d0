"""Figure of notebook 09: drawn, saved under its name, returned; bad input rejected."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib.workbook import plotting
from piezolib.workbook.figures import mixed_mu as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    yield tmp_path / "figures"
    plt.close("all")


def _curves():
    omega = np.logspace(2, 5, 60)
    peak = 1.0 / np.abs(1 - (omega / 6.8e3) ** 2 + 0.05j * omega / 6.8e3)
    return omega, 0.1 * peak, 0.09 * peak, 0.15 * peak, 0.15 * peak


def test_saves_and_draws_the_bounds(figures_dir):
    omega, ru, rl, cu, cl = _curves()
    fig = F.extra_mixed_mu(omega, ru, rl, cu, cl, 0.05, exact=rl)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_mixed_mu.png"
    ax_all, ax_zoom = fig.axes
    assert len(ax_all.get_lines()) == 6           # four bounds, the exact curve, mu = 1
    np.testing.assert_array_equal(ax_all.get_lines()[2].get_ydata(), ru)
    np.testing.assert_array_equal(ax_all.get_lines()[3].get_ydata(), rl)
    assert ax_all.get_yscale() == "log"
    lo, hi = ax_zoom.get_xlim()                     # zoom centred on the complex peak
    assert lo < 6.8e3 < hi and hi / lo == pytest.approx(1.6 ** 2, rel=0.05)
    assert len(fig.legends) == 1 and text_overlaps(fig) == []


def test_without_exact_and_with_zoom(figures_dir):
    omega, ru, rl, cu, cl = _curves()
    fig = F.extra_mixed_mu(omega, ru, rl, cu, cl, 0.05, zoom=(1e3, 2e4))
    assert len(fig.axes[0].get_lines()) == 5
    assert fig.axes[1].get_xlim() == pytest.approx((1e3, 2e4))


@pytest.mark.parametrize("which, bad, word", [
    (1, np.full(60, np.nan), "real_upper"),
    (2, np.ones(59), "real_lower"),
    (0, np.logspace(5, 2, 60), "omega"),
])
def test_bad_input_names_the_argument(figures_dir, which, bad, word):
    args = list(_curves())
    args[which] = bad
    with pytest.raises(ValueError, match=word):
        F.extra_mixed_mu(*args, 0.05)
    with pytest.raises(ValueError, match="spread"):
        F.extra_mixed_mu(*_curves(), -1.0)


def test_the_figures_of_the_coefficient_box_results(figures_dir):
    import pandas as pd
    from types import SimpleNamespace as Result

    omega, ru, rl, cu, cl = _curves()
    bounds = Result(omega=omega, real=Result(upper=ru, lower=rl), complex=Result(upper=cu, lower=cl),
                    exact_real=rl, spread=0.05)
    assert len(F.extra_mixed_mu_of(bounds).axes[0].get_lines()) == 6
    table = pd.DataFrame({"mu_RP upper": [0.8, 1.4], "mu_RP lower": [0.7, 1.3],
                          "no controller below": [0.2, 0.9]}, index=[0.5, 1.0])
    tradeoff = Result(table=table, chosen=None,
                      margins=lambda: {"delay 1": pd.Series([0.06, 0.05], index=table.index)})
    fig = F.extra_mixed_tradeoff_of(tradeoff, 0.05)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_mixed_tradeoff.png"
    with pytest.raises(TypeError, match="tradeoff"):
        F.extra_mixed_tradeoff_of(table, 0.05)
    with pytest.raises(TypeError, match="bounds"):
        F.extra_mixed_mu_of(table)
