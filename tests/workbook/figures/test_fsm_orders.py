"""Figure of notebook 10's order validation curve: drawn, saved under its name, refused bad input."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib.problem import fsm_models
from piezolib.workbook import plotting
from piezolib.workbook.figures import fsm_orders as F


def test_the_committed_curve_is_drawn_with_each_levels_best_marked(tmp_path):
    curve = fsm_models.read_order_curve()
    fig = F.extra_fsm_order_curve(curve.orders, curve.percent(), candidates=(24, 48))
    assert plotting.save_figure(fig, tmp_path) == tmp_path / "extra_fsm_order_curve.png"
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert labels == [x for lv in (100, 200, 300)
                      for x in (f"{lv} mV", f"{lv} mV: best {curve.best(lv)}")]
    best = fig.axes[0].get_lines()[1]
    assert best.get_xdata()[0] == curve.best(100)
    assert best.get_ydata()[0] == pytest.approx(100 * min(curve.validation_error[100]))
    assert not text_overlaps(fig)
    plt.close(fig)


@pytest.mark.parametrize("orders, errors, candidates, match", [
    ([8], {"a": [1.0]}, None, "orders"),
    ([16, 8], {"a": [1.0, 2.0]}, None, "orders"),
    ([8, 16], {}, None, "validation_error_percent"),
    ([8, 16], {"a": [1.0]}, None, r"validation_error_percent\['a'\]"),
    ([8, 16], {"a": [1.0, np.nan]}, None, r"validation_error_percent\['a'\]"),
    ([8, 16], {"a": [1.0, 2.0]}, (16, 8), "candidates"),
])
def test_bad_input_is_refused_naming_the_argument(orders, errors, candidates, match):
    with pytest.raises((ValueError, TypeError), match=match):
        F.extra_fsm_order_curve(orders, errors, candidates=candidates)
