"""Figure of notebook 11 and of ``python -m piezolib sweep``: the Pareto front of a sweep."""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from figure_checks import text_overlaps
from piezolib.workbook import plotting
from piezolib.workbook.figures import sweeps as F

TABLE = pd.DataFrame({
    "point": [1, 2, 3, 4, 5],
    "mu_RP": [0.90, 0.95, 1.10, 1.00, np.nan],
    "tracking_error_50Hz_percent": [5.6, 5.5, 5.3, 5.7, np.nan],
    "tracking_error_50Hz_low_percent": [5.58, 5.48, 5.28, 5.68, np.nan],
    "tracking_error_50Hz_high_percent": [5.62, 5.52, 5.32, 5.72, np.nan],
    "controller_states": [4, 6, 4, 6, 4],
    "pareto": [True, True, True, False, False]})


@pytest.fixture
def figures_dir(tmp_path):
    yield tmp_path / "figures"
    plt.close("all")


def test_one_marker_per_order_the_front_joined_and_failed_points_counted(figures_dir):
    fig = F.extra_sweep_pareto(TABLE, title="sweep demo")
    path = plotting.save_figure(fig, figures_dir)
    assert path == figures_dir / "extra_sweep_pareto.png"
    ax = fig.axes[0]
    scatters = [c for c in ax.collections if c.get_label().startswith("controller states")]
    assert [len(c.get_offsets()) for c in scatters] == [2, 2]        # 4 and 6 states
    front = next(line for line in ax.lines if line.get_label().startswith("Pareto front"))
    assert list(front.get_xdata()) == [0.90, 0.95, 1.10]
    assert sorted(t.get_text() for t in ax.texts) == ["1", "2", "3"]
    assert "4 designs, 1 failed (not drawn)" in ax.get_title()
    assert ax.get_xlabel() == "μ_RP (delay-aware problem)"          # the units rule applied
    assert text_overlaps(fig) == []


def test_the_figure_needs_the_sweep_columns():
    with pytest.raises(ValueError, match="pareto"):
        F.extra_sweep_pareto(TABLE.drop(columns="pareto"))
    with pytest.raises(TypeError, match="table"):
        F.extra_sweep_pareto(TABLE.to_dict())
