"""The paper's block diagrams (Fig. 1, 2, 3, 5 and 9), drawn in one style.

Signals carry the names and units of the units table of :mod:`piezolib.problem.paper`
(u_c, u_f, u_b, v_a, v_y, v_r, v_e in V; x, x_r in um), blocks name the
equations of the paper they stand for.  Every function draws with
:func:`piezolib.workbook.figures.block_diagram.block_diagram`, names the figure after the
paper's number and returns it.  Notebook 00 draws Fig. 1, 2 and 9, notebook
01 Fig. 3 and notebook 02 Fig. 5.
"""

from piezolib.problem import paper
from piezolib.workbook import plotting
from piezolib.workbook.figures.block_diagram import block_diagram

__all__ = ["fig01_control_loop", "fig02_experimental_loop", "fig03_identification_steps",
           "fig05_uncertain_plant", "fig09_general_configuration"]


def fig01_control_loop():
    """Fig. 1: the combined feedforward-feedback loop with its signals and units.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig01_control_loop.png``.
    """
    um_per_v = paper.UM_PER_VOLT
    blocks = {
        "ref": (2.2, 0.0, f"1/{um_per_v:g} V/um"),
        "sum_e": (5.6, 0.0, "o"),
        "K": (7.7, 0.0, "K(s)\neq. 24"),
        "ff": (7.7, 1.8, "Dahl feedforward\neq. 14"),
        "sum_u": (10.6, 0.0, "o"),
        "G": (14.1, 0.0, f"DAQ, amplifier x{paper.AMPLIFIER_GAIN:g},\npiezo stage, sensor:\n"
                         "G(s) eq. 4 + hysteresis"),
    }
    wires = [
        ((0.0, 0.0), "ref", "x_r [um]"),
        ("ref", "sum_e", "v_r [V]", {"sign": "+"}),
        ((3.45, 0.0), "ff", "v_r [V]", {"via": [(3.45, 1.8)], "dot": True}),
        ("sum_e", "K", "v_e [V]"),
        ("K", "sum_u", "u_b [V]", {"sign": "+"}),
        ("ff", "sum_u", "u_f [V]", {"via": [(10.6, 1.8)], "sign": "+"}),
        ("sum_u", "G", "u_c [V]"),
        ("G", (18.2, 0.0), "v_y [V]"),
        ((17.2, 0.0), "sum_e", f"v_y [V]   (x = {um_per_v:g} um/V * v_y)",
         {"via": [(17.2, -1.6), (5.6, -1.6)], "dot": True, "sign": "-"}),
    ]
    fig = block_diagram(blocks, wires)
    plotting.name_figure(fig, 1, "control_loop")
    return fig


def fig02_experimental_loop():
    """Fig. 2: the experimental loop, host computer to sensor and back.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig02_experimental_loop.png``.
    """
    fs_kHz = paper.SAMPLING_FREQUENCY_HZ / 1e3
    lo, hi = paper.SENSOR_OUTPUT_RANGE_V
    blocks = {
        "pc": (2.2, 0.0, f"host computer\nLabVIEW: K(s) and\nDahl feedforward,\n{fs_kHz:g} kHz"),
        "da": (7.0, 0.0, f"I/O module\nPXIe-6361\n{paper.DAQ_BITS}-bit D/A"),
        "amp": (11.6, 0.0, f"voltage amplifier\nE-505, gain {paper.AMPLIFIER_GAIN:g},\n"
                           f"{paper.AMPLIFIER_BANDWIDTH_HZ / 1e3:g} kHz"),
        "stage": (16.4, 0.0, f"piezo stage\nP-752.21,\n{paper.STAGE_TRAVEL_UM:g} um travel"),
        "sensor": (16.4, -3.2, f"capacitive sensor\nD-015, {lo:g} ... {hi:g} V,\n"
                               f"{paper.SENSOR_BANDWIDTH_HZ / 1e3:g} kHz"),
        "ad": (7.0, -3.2, f"I/O module\nPXIe-6361\n{paper.DAQ_BITS}-bit A/D"),
    }
    wires = [
        ("pc", "da", "u_c [V]"),
        ("da", "amp", "u_c [V]"),
        ("amp", "stage", "v_a [V]"),
        ("stage", "sensor", "x_a [um]"),
        ("sensor", "ad", "v_y [V]"),
        ("ad", "pc", "v_y [V]", {"via": [(2.2, -3.2)]}),
    ]
    fig = block_diagram(blocks, wires)
    plotting.name_figure(fig, 2, "experimental_loop")
    return fig


def fig03_identification_steps():
    """Fig. 3: the four steps of the identification of G(s) (Sec. III-A).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig03_identification_steps.png``.
    """
    blocks = {
        "I": (2.0, 0.0, "Step I\nchirp excitation,\nopen loop,\nsmall amplitude"),
        "II": (6.8, 0.0, "Step II\nstructure:\n6 poles, 3 zeros"),
        "III": (11.4, 0.0, "Step III\nRLS estimation\n(eq. 1-3)"),
        "IV": (16.0, 0.0, "Step IV\nvalidation:\nresidual white?\n(Fig. 4)"),
        "G": (20.4, 0.0, "G(s)\neq. 4"),
    }
    wires = [
        ("I", "II", "u_c, v_y [V]"),
        ("II", "III", "regressor"),
        ("III", "IV", "estimate"),
        ("IV", "G", "yes"),
        ("IV", "II", "no: change the structure",
         {"via": [(16.0, -2.0), (6.8, -2.0)], "side": "below"}),
    ]
    fig = block_diagram(blocks, wires)
    plotting.name_figure(fig, 3, "identification_steps")
    return fig


def fig05_uncertain_plant():
    """Fig. 5: the uncertain plant G_Delta = G (1 + H_m Delta) of eq. 5.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig05_uncertain_plant.png``.
    """
    blocks = {
        "Hm": (4.6, 2.0, "H_m(s)\neq. 8"),
        "D": (7.6, 2.0, "Delta(s)\n|Delta| <= 1"),
        "sum": (10.0, 0.0, "o"),
        "G": (12.4, 0.0, "G(s)\neq. 4"),
    }
    wires = [
        ((0.0, 0.0), "sum", "u_b [V]", {"sign": "+"}),
        ((2.4, 0.0), "Hm", "", {"via": [(2.4, 2.0)], "dot": True}),
        ("Hm", "D", "y_Delta"),
        ("D", "sum", "u_Delta", {"via": [(10.0, 2.0)], "sign": "+"}),
        ("sum", "G", ""),
        ("G", (16.2, 0.0), "v_y [V]"),
    ]
    frames = [(1.6, -0.9, 13.8, 3.35, "G_Delta(s) = G(s) (1 + H_m(s) Delta(s))")]
    fig = block_diagram(blocks, wires, frames=frames)
    plotting.name_figure(fig, 5, "uncertain_plant")
    return fig


def fig09_general_configuration():
    """Fig. 9: the general control configuration of the mu-synthesis (P, K, Delta).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig09_general_configuration.png``.
    """
    left, right = 4.26, 7.74                      # edges of P [diagram units]
    blocks = {
        "P": (6.0, 0.0, "P(s)\neq. 16\n(G, H_m,\nH_e, H_y)", {"size": (3.4, 3.0)}),
        "D": (6.0, 3.1, "Delta(s)"),
        "K": (6.0, -3.1, "K(s)\neq. 24"),
    }
    wires = [
        ((right, 1.1), "D", "y_Delta", {"via": [(9.4, 1.1), (9.4, 3.1)], "segment": 0}),
        ("D", (left, 1.1), "u_Delta", {"via": [(2.6, 3.1), (2.6, 1.1)], "segment": 2}),
        ((0.6, 0.0), (left, 0.0), "v_r [V]"),
        ((right, 0.35), (11.6, 0.35), "y_1 = H_e v_e"),
        ((right, -0.35), (11.6, -0.35), "y_2 = H_y v_y", {"side": "below"}),
        ((right, -1.1), "K", "v_e [V]", {"via": [(9.4, -1.1), (9.4, -3.1)], "segment": 1}),
        ("K", (left, -1.1), "u_b [V]", {"via": [(2.6, -3.1), (2.6, -1.1)], "segment": 2,
                                        "side": "below"}),
    ]
    fig = block_diagram(blocks, wires)
    plotting.name_figure(fig, 9, "general_configuration")
    return fig
