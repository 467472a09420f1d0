"""The workbook's figure style, units rule, figure naming, block diagrams and text check."""

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib.workbook import plotting


def test_figures_are_named_then_saved_where_the_caller_says(tmp_path):
    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1])
    with pytest.raises(ValueError, match="no file name"):
        plotting.save_figure(fig, tmp_path)           # a figure no figure function named
    assert plotting.name_figure(fig, 10, "step_responses") is fig
    path = plotting.save_figure(fig, tmp_path / "figures")
    assert path == tmp_path / "figures" / "fig10_step_responses.png" and path.is_file()
    plotting.name_figure(fig, None, "view")
    assert plotting.save_figure(fig, str(tmp_path)).name == "extra_view.png"
    plt.close(fig)
    with pytest.raises(ValueError, match="what"):
        plotting.figure_name(4, "Bad Name")
    with pytest.raises(ValueError, match="number"):
        plotting.figure_name(0, "ok")
    with pytest.raises(TypeError, match="Figure"):
        plotting.name_figure("figure", 1, "ok")
    with pytest.raises(TypeError, match="Figure"):
        plotting.save_figure("figure", tmp_path)
    with pytest.raises(TypeError, match="directory"):
        plotting.save_figure(fig, None)


def test_style_and_helpers():
    fig, ax = plotting.new_figure()
    assert mpl.rcParams["savefig.dpi"] == plotting.STYLE["savefig.dpi"]
    assert plotting.db(10.0) == pytest.approx(20.0)
    line = plotting.plot_magnitude(ax, np.array([1.0, 10.0]), np.array([1.0, 0.1]), label="x")
    np.testing.assert_allclose(line.get_ydata(), [0.0, -20.0])
    assert ax.get_xscale() == "log" and ax.get_xlabel() == "frequency [rad/s]"
    plt.close(fig)


@pytest.mark.parametrize("plain, spelled", [
    ("x = 3 um/V * v_y [um]", "x = 3 µm/V * v_y [µm]"),
    ("mu_RP and mu(M11); mu-synthesis", "μ_RP and μ(M11); μ-synthesis"),
    ("omega_e x 2 [rad/s]", "ω_e x 2 [rad/s]"),
    ("|Delta| <= 1, +-5 %", "|Δ| ≤ 1, ±5 %"),
    ("(a) S: v_r -> v_e", "(a) S: v_r → v_e"),
    ("maximum sum, 12um, nm, drum, mute", "maximum sum, 12µm, nm, drum, mute"),
    ("$\\mu$ stays mathtext um", "$\\mu$ stays mathtext um"),
])
def test_unit_text_spells_units_once(plain, spelled):
    assert plotting.unit_text(plain) == spelled
    assert plotting.unit_text(spelled) == spelled            # idempotent
    with pytest.raises(TypeError, match="text"):
        plotting.unit_text(3)


def test_save_figure_applies_the_units_rule(tmp_path):
    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1], label="+-1 um")
    ax.set(xlabel="x [um]", title="mu bound")
    ax.legend()
    plotting.save_figure(plotting.name_figure(fig, None, "units"), tmp_path)
    assert ax.get_xlabel() == "x [µm]" and ax.get_title() == "μ bound"
    assert ax.get_legend().get_texts()[0].get_text() == "±1 µm"
    plt.close(fig)


def test_block_diagram_draws_boxes_junctions_wires_and_signs():
    fig = plotting.block_diagram(
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
    width = fig.get_size_inches()[0] / plotting.DIAGRAM_UNIT_IN
    assert width == pytest.approx(np.diff(ax.get_xlim())[0])
    assert plotting.text_overlaps(fig) == []
    plt.close(fig)


def test_block_diagram_rejects_bad_input():
    with pytest.raises(ValueError, match="blocks"):
        plotting.block_diagram({}, [])
    with pytest.raises(ValueError, match="kind"):
        plotting.block_diagram({"a": (0, 0, "A", "cloud")}, [])
    with pytest.raises(ValueError, match="not a block"):
        plotting.block_diagram({"a": (0, 0, "A")}, [("a", "nowhere", "")])
    with pytest.raises(ValueError, match="unknown wire options"):
        plotting.block_diagram({"a": (0, 0, "A")}, [((-1, 0), "a", "", {"colour": "r"})])
    plt.close("all")


def test_text_overlaps_finds_colliding_texts_wires_and_legends():
    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1], label="rising")
    ax.text(0.5, 0.5, "on the curve")                        # a tag drawn over its curve
    ax.text(0.1, 0.9, "first label")
    ax.text(0.12, 0.9, "second label")                       # on top of the first
    found = plotting.text_overlaps(fig)
    assert any("'first label' overlaps 'second label'" in f for f in found)
    assert any("'on the curve' covers the curve 'rising'" in f for f in found)
    plt.close(fig)

    fig, ax = plotting.new_figure()
    ax.plot([0, 1], [0, 1], label="rising")
    ax.legend(loc="center")                                  # over the diagonal
    assert any(f.startswith("legend covers the curve 'rising'")
               for f in plotting.text_overlaps(fig))
    ax.legend(loc="upper left")                              # the empty corner
    assert plotting.text_overlaps(fig) == []
    plt.close(fig)

    fig = plotting.block_diagram({"a": (0.0, 0.0, "A"), "b": (4.0, 0.0, "B")},
                                 [("a", "b", "x")])
    fig.axes[0].text(2.0, 0.0, "on the wire", ha="center", va="center")
    assert any("wire crosses text 'on the wire'" in f for f in plotting.text_overlaps(fig))
    plt.close(fig)
    with pytest.raises(TypeError, match="Figure"):
        plotting.text_overlaps("figure")


def test_a_figure_is_rewritten_only_when_it_visibly_changed(tmp_path):
    x = np.linspace(0.0, 1.0, 50)

    def draw(shift):
        fig, ax = plt.subplots(figsize=(3, 2), dpi=100)
        ax.plot(x, x ** 2 + shift)
        ax.set_xlim(0, 1)
        ax.set_ylim(-0.1, 1.1)
        path = plotting.save_figure(plotting.name_figure(fig, None, "rewrite"), tmp_path)
        plt.close(fig)
        return path.read_bytes()

    first = draw(0.0)
    # 1e-9 of the axis: the rounding of another machine, far below a pixel
    assert draw(1e-9) == first
    # a tenth of the axis: about 14 pixels, a change a reader sees
    moved = draw(0.1)
    assert moved != first and not plotting.same_picture(first, moved)
    assert plotting.same_picture(first, first)
