"""Figures of notebook 04 (weights and generalized plant): the weight templates and Fig. 11."""

import numpy as np

from piezolib.problem import paper
from piezolib.robust.lti import frequency_grid
from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure, plot_magnitude
from piezolib.workbook.figures.audit import sensitivity_templates_figure

__all__ = ["extra_weight_templates", "fig11_sensitivity_templates_designs"]


def extra_weight_templates(error_params, output_params, omega=None,
                           factors=(0.5, 1.0, 2.0)):
    """The templates 1/|H_e| and 1/|H_y| of eq. 15 with their corner frequency varied.

    Parameters
    ----------
    error_params : piezolib.problem.paper.ErrorWeightParameters
    output_params : piezolib.problem.paper.OutputWeightParameters
    omega : array_like, optional
        Frequency grid [rad/s]; default 0.1 ... 1e9 rad/s, 3000 points.
    factors : sequence of float
        Multiples of omega_e and omega_y drawn (1 solid, the others dashed).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_weight_templates.png``.
    """
    omega = frequency_grid(1e-1, 1e9, 3000) if omega is None else omega
    s = 1j * omega
    fig, axes = new_figure(1, 2, figsize=(9, 3.6))
    for factor in factors:
        He_f = paper.error_weight(error_params, omega_e=error_params.omega_e * factor)
        plot_magnitude(axes[0], omega, 1 / np.ravel(He_f(s)),
                                label=f"omega_e x {factor:g}", ls="-" if factor == 1 else "--")
    for factor in factors:
        Hy_f = paper.output_weight(output_params, omega_y=output_params.omega_y * factor)
        plot_magnitude(axes[1], omega, 1 / np.ravel(Hy_f(s)),
                                label=f"omega_y x {factor:g}", ls="-" if factor == 1 else "--")
    axes[0].set_title("template on S: 1/|H_e|")
    axes[1].set_title("template on T: 1/|H_y|")
    axes[1].set_ylim(-200, 20)
    # the empty corners: 1/|H_e| rises to M_e at high frequency, 1/|H_y| falls from M_y
    axes[0].legend(loc="lower right")
    axes[1].legend(loc="lower left")
    plotting.name_figure(fig, None, "weight_templates")
    return fig


def fig11_sensitivity_templates_designs(loops, H_e, H_y, omega=None):
    """Fig. 11 for several controllers: |S| and |T| of each loop under the templates.

    Parameters
    ----------
    loops : dict
        ``{label: LoopFunctions}``, e.g. the published K and the workbook's.
    H_e, H_y : control.LTI
        Error and output weights (eq. 15).
    omega : array_like, optional
        Frequency grid [rad/s]; default 1 ... 1e7 rad/s, 3000 points.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``fig11_sensitivity_templates_designs.png``.
    """
    fig = sensitivity_templates_figure(loops, H_e, H_y, omega, template_color="k")
    plotting.name_figure(fig, 11, "sensitivity_templates_designs")
    return fig
