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
