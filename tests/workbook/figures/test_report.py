"""Figure of notebook 07: the scorecard, drawn, saved and returned."""

import matplotlib.pyplot as plt
import pandas as pd
import pytest

from piezolib.workbook.figures import report as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


def test_scorecard_one_dot_per_numeric_claim(figures_dir):
    table = pd.DataFrame({"source": ["00_a", "00_a", "05_b", "05_b"],
                          "paper": ["0.81", "0.48", "True", "0"],
                          "ours": ["0.81", "0.82", "True", "1"],
                          "verdict": ["agrees", "differs", "agrees", "differs"]})
    fig = F.extra_reproduction_scorecard(table)
    assert (figures_dir / "extra_reproduction_scorecard.png").is_file()
    ax = fig.axes[0]
    agrees, differs = ax.collections
    assert len(agrees.get_offsets()) == 1 and len(differs.get_offsets()) == 1
    assert differs.get_offsets()[0][0] == pytest.approx(0.82 / 0.48)
    assert [t.get_text() for t in ax.get_yticklabels()] == ["00_a", "05_b"]
    plt.close(fig)
