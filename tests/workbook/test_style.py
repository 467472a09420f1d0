"""The workbook's figure style: rcParams, the named colours, the units rule, magnitude plots."""

import re

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np
import pytest

from piezolib.workbook import style


def test_style_and_helpers():
    fig, ax = style.new_figure()
    assert mpl.rcParams["savefig.dpi"] == style.STYLE["savefig.dpi"]
    assert style.db(10.0) == pytest.approx(20.0)
    line = style.plot_magnitude(ax, np.array([1.0, 10.0]), np.array([1.0, 0.1]), label="x")
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
    assert style.unit_text(plain) == spelled
    assert style.unit_text(spelled) == spelled            # idempotent
    with pytest.raises(TypeError, match="text"):
        style.unit_text(3)


def test_apply_unit_text_respells_every_text_of_a_figure():
    fig, ax = style.new_figure()
    fig.suptitle("omega_e of the +-5 % set")
    tag = ax.text(0.5, 0.5, "|Delta| <= 1")
    assert style.apply_unit_text(fig) is fig
    assert fig.get_suptitle() == "ω_e of the ±5 % set" and tag.get_text() == "|Δ| ≤ 1"
    with pytest.raises(TypeError, match="Figure"):
        style.apply_unit_text("figure")
    plt.close(fig)


def test_palette_names_every_colour_of_the_cycle():
    colours = [getattr(style.PALETTE, f) for f in style.Palette.__dataclass_fields__]
    assert all(re.fullmatch(r"#[0-9a-f]{6}", c) for c in colours)
    assert len(set(colours)) == len(colours)                 # one name per colour
    assert style.STYLE["axes.prop_cycle"].by_key()["color"] == list(style.PALETTE.cycle)
    assert set(style.PALETTE.cycle) | set(style.PALETTE.peers) <= set(colours)
    with pytest.raises(AttributeError):
        style.PALETTE.primary = "#000000"                     # one palette for every figure
