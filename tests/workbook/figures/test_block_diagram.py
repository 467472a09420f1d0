"""The block-diagram engine: boxes, junctions, wires, signs and frames; bad input rejected."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from figure_checks import text_overlaps
from piezolib.workbook.figures.block_diagram import DIAGRAM_UNIT_IN, block_diagram


def test_block_diagram_draws_boxes_junctions_wires_and_signs():
    fig = block_diagram(
        {"a": (0.0, 0.0, "A"), "s": (3.0, 0.0, "o"), "b": (5.5, 0.0, "B\nsecond line")},
        [("a", "s", "x [V]", {"sign": "+"}), ((-2.0, 0.0), "a", "in"), ("s", "b", ""),
         ("b", "s", "fb", {"via": [(7.5, 0.0), (7.5, -1.5), (3.0, -1.5)], "sign": "-"})],
        title="t", frames=[(-1.0, -2.2, 8.0, 1.2, "frame")])
    ax = fig.axes[0]
    assert ax.get_title() == "t" and not ax.axison
    kinds = [type(p).__name__ for p in ax.patches]
    assert kinds.count("FancyBboxPatch") == 2 and kinds.count("Circle") == 1
    texts = [t.get_text() for t in ax.texts]
    assert {"x [V]", "in", "fb", "+", "\u2212", "frame", "B\nsecond line"} <= set(texts)
    # the figure is sized from the drawing: one diagram unit per DIAGRAM_UNIT_IN inch
    width = fig.get_size_inches()[0] / DIAGRAM_UNIT_IN
    assert width == pytest.approx(np.diff(ax.get_xlim())[0])
    assert text_overlaps(fig) == []
    plt.close(fig)


def test_block_diagram_rejects_bad_input():
    with pytest.raises(ValueError, match="blocks"):
        block_diagram({}, [])
    with pytest.raises(ValueError, match="kind"):
        block_diagram({"a": (0, 0, "A", "cloud")}, [])
    with pytest.raises(ValueError, match="not a block"):
        block_diagram({"a": (0, 0, "A")}, [("a", "nowhere", "")])
    with pytest.raises(ValueError, match="unknown wire options"):
        block_diagram({"a": (0, 0, "A")}, [((-1, 0), "a", "", {"colour": "r"})])
    plt.close("all")
