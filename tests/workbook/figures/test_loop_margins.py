"""Margin figure of notebook 06: drawn, saved as extra_margins.png, returned."""

import matplotlib.pyplot as plt
import pytest

from piezolib import paper
from piezolib.workbook import plotting
from piezolib.workbook.figures import loop_margins as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


def test_extra_margins(figures_dir):
    G, _, _, _, K = paper.problem()
    fig = F.extra_margins(G, {"published": K, "2 K": 2 * K}, paper.SAMPLING_FREQUENCY_HZ)
    assert plotting.save_figure(fig, figures_dir) == figures_dir / "extra_margins.png"
    a, b = fig.axes
    # one Nyquist curve (+ its disk) per controller besides the unit circle; one radius line each
    assert len(b.get_lines()) == 3                  # two controllers + the level 1
    radii = b.get_lines()[1].get_ydata()             # 2 K: unstable from 2 samples of delay on
    assert radii[0] < 1 < radii[2]
    assert "Nyquist" in a.get_title()
    plt.close(fig)
