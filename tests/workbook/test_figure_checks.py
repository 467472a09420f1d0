"""The tests' figure check: colliding texts, texts on wires, legends and tags over curves."""

import matplotlib.pyplot as plt
import pytest

from figure_checks import text_overlaps
from piezolib.workbook.figures.block_diagram import block_diagram
from piezolib.workbook.style import new_figure


def test_text_overlaps_finds_colliding_texts_wires_and_legends():
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1], label="rising")
    ax.text(0.5, 0.5, "on the curve")                        # a tag drawn over its curve
    ax.text(0.1, 0.9, "first label")
    ax.text(0.12, 0.9, "second label")                       # on top of the first
    found = text_overlaps(fig)
    assert any("'first label' overlaps 'second label'" in f for f in found)
    assert any("'on the curve' covers the curve 'rising'" in f for f in found)
    plt.close(fig)

    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1], label="rising")
    ax.legend(loc="center")                                  # over the diagonal
    assert any(f.startswith("legend covers the curve 'rising'")
               for f in text_overlaps(fig))
    ax.legend(loc="upper left")                              # the empty corner
    assert text_overlaps(fig) == []
    plt.close(fig)

    fig = block_diagram({"a": (0.0, 0.0, "A"), "b": (4.0, 0.0, "B")},
                                 [("a", "b", "x")])
    fig.axes[0].text(2.0, 0.0, "on the wire", ha="center", va="center")
    assert any("wire crosses text 'on the wire'" in f for f in text_overlaps(fig))
    plt.close(fig)
    with pytest.raises(TypeError, match="Figure"):
        text_overlaps("figure")
