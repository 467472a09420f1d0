"""Figure of notebook 07: the scorecard, drawn, saved and returned."""

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from piezolib.workbook import plotting
from piezolib.workbook.figures import scorecard as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


TABLE = pd.DataFrame({"source": ["00_a", "00_a", "05_b", "05_b", "05_b"],
                      "paper": ["0.81", "0.48", "True", "0", "10"],
                      "ours": ["0.81", "0.82", "True", "1", "11"],
                      "tolerance": ["+-0.01", "+-2%", "equal", "+-0.5", "+-20%"],
                      "verdict": ["agrees", "differs", "agrees", "differs", "agrees"]})


def test_scorecard_one_dot_and_one_band_per_numeric_claim(figures_dir):
    fig = F.extra_reproduction_scorecard(TABLE)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_reproduction_scorecard.png"
    ax = fig.axes[0]
    bands, agrees, differs = ax.collections
    assert len(agrees.get_offsets()) == 2 and len(differs.get_offsets()) == 1
    assert differs.get_offsets()[0][0] == pytest.approx(0.82 / 0.48)
    # the bands are the tolerances in ratio units: 0.81 +- 0.01, 0.48 +- 2 %, 10 +- 20 %
    ends = np.sort(np.array([seg[:, 0] for seg in bands.get_segments()]), axis=0)
    expected = np.sort(np.array([(0.8 / 0.81, 0.82 / 0.81), (0.98, 1.02), (0.8, 1.2)]), axis=0)
    np.testing.assert_allclose(ends, expected, rtol=1e-12)
    # counts match the table: drawn of all rows with that verdict
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "agrees: 2 drawn of 3" in labels and "differs: 1 drawn of 2" in labels
    assert [t.get_text() for t in ax.get_yticklabels()] == ["00_a", "05_b"]
    plt.close(fig)


def test_scorecard_needs_the_tolerance_column(figures_dir):
    with pytest.raises(ValueError, match="tolerance"):
        F.extra_reproduction_scorecard(TABLE.drop(columns="tolerance"))


def test_scorecard_axis_holds_every_dot_with_a_margin(figures_dir):
    # ratios far beyond the old fixed 1e-2 ... 1e2 axis: none sits on an edge
    table = pd.DataFrame({"source": ["06_c"] * 4,
                          "paper": ["0.44", "2", "1", "-3"],
                          "ours": ["0.003", "900", "1", "3"],       # the last changes sign
                          "tolerance": ["+-0.5", "+-20%", "+-1%", "+-1%"],
                          "verdict": ["differs", "differs", "agrees", "differs"]})
    fig = F.extra_reproduction_scorecard(table)
    ax = fig.axes[0]
    low, high = ax.get_xlim()
    dots = np.concatenate([c.get_offsets()[:, 0] for c in ax.collections[1:]])
    assert sorted(dots) == pytest.approx([0.003 / 0.44, 1.0, 450.0])   # no sign change drawn
    # a margin beyond the outermost dots, in decades of the log axis
    assert np.log10(dots.min() / low) >= 0.15 and np.log10(high / dots.max()) >= 0.15
    # the band 0.44 +- 0.5 reaches below zero: it runs to the left edge
    band_low = min(seg[:, 0].min() for seg in ax.collections[0].get_segments())
    assert band_low == pytest.approx(low)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "differs: 2 drawn of 3" in labels
    plt.close(fig)
