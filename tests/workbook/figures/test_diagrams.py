"""The block diagrams (Fig. 1, 2, 3, 5, 9): saved under the paper's numbers, signals with units."""

import matplotlib.pyplot as plt
import pytest

from figure_checks import text_overlaps
from piezolib.workbook import plotting
from piezolib.workbook.figures import diagrams as F


@pytest.fixture
def figures_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("PIEZOLIB_ROOT", str(tmp_path))
    return tmp_path / "figures"


# function -> (file, texts that must appear, as saved through the units rule)
EXPECTED = {
    "fig01_control_loop": ("fig01_control_loop.png",
                           {"x_r [µm]", "v_r [V]", "v_e [V]", "u_b [V]", "u_f [V]", "u_c [V]",
                            "v_y [V]", "K(s)\neq. 24", "Dahl feedforward\neq. 14", "\u2212"}),
    "fig02_experimental_loop": ("fig02_experimental_loop.png",
                                {"u_c [V]", "v_a [V]", "x_a [µm]", "v_y [V]"}),
    "fig03_identification_steps": ("fig03_identification_steps.png",
                                   {"u_c, v_y [V]", "yes", "no: change the structure"}),
    "fig05_uncertain_plant": ("fig05_uncertain_plant.png",
                              {"u_b [V]", "y_Δ", "u_Δ", "v_y [V]", "H_m(s)\neq. 8",
                               "Δ(s)\n|Δ| ≤ 1"}),
    "fig09_general_configuration": ("fig09_general_configuration.png",
                                    {"u_Δ", "y_Δ", "v_r [V]", "v_e [V]", "u_b [V]",
                                     "y_1 = H_e v_e", "y_2 = H_y v_y", "Δ(s)"}),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_diagram_is_saved_with_its_signals_and_nothing_collides(figures_dir, name):
    fig = getattr(F, name)()
    file, texts = EXPECTED[name]
    assert plotting.save_figure(fig, figures_dir) == figures_dir / file
    drawn = {t.get_text() for t in fig.axes[0].texts}
    assert texts <= drawn, texts - drawn
    assert not any("um]" in t or " mu" in t for t in drawn)      # one spelling of the units
    assert text_overlaps(fig) == []
    plt.close(fig)


def test_fig01_feedback_enters_with_a_minus_sign(figures_dir):
    fig = F.fig01_control_loop()
    signs = [t for t in fig.axes[0].texts if t.get_text() in ("+", "\u2212")]
    assert sorted(t.get_text() for t in signs) == ["+", "+", "+", "\u2212"]
    plt.close(fig)
