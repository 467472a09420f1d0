"""Figure of notebook 09 (mixed mu): mu for robust stability against the coefficient box,
with the coefficients as real blocks and as complex ones."""

import numpy as np

from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure

__all__ = ["extra_mixed_mu"]


def extra_mixed_mu(omega, real_upper, real_lower, complex_upper, complex_lower, spread,
                   exact=None, zoom=None):
    """mu_RS(omega) of one loop with real and with complex coefficient blocks.

    Panel (a) shows the whole grid on log axes (where the upper and lower
    bounds of the real case part); panel (b) a linear zoom around the peak,
    with the robust-stability limit mu = 1.

    Parameters
    ----------
    omega : array_like
        Frequencies [rad/s], increasing.
    real_upper, real_lower : array_like
        Upper and lower bounds of mu [-] with real scalar blocks, on ``omega``.
    complex_upper, complex_lower : array_like
        The same with complex scalar blocks.
    spread : float
        Relative spread [-] the bounds were computed at (shown in the title).
    exact : array_like, optional
        Exact real mu [-] on ``omega`` (e.g. spread / stability gauge), drawn thin.
    zoom : tuple of float, optional
        Frequency range [rad/s] of panel (b); default a factor 1.6 either side
        of the peak of ``complex_upper``.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_mixed_mu.png``.

    Raises
    ------
    ValueError
        When an array does not match ``omega`` or a value is not finite.
    """
    omega = np.asarray(omega, dtype=float)
    if omega.ndim != 1 or omega.size < 2 or not np.all(np.isfinite(omega)) \
            or np.any(omega <= 0) or np.any(np.diff(omega) <= 0):
        raise ValueError("omega must be a 1-D increasing array of positive frequencies")
    curves = {}
    for name, values in (("real_upper", real_upper), ("real_lower", real_lower),
                         ("complex_upper", complex_upper), ("complex_lower", complex_lower),
                         ("exact", exact)):
        if values is None:
            continue
        values = np.asarray(values, dtype=float)
        if values.shape != omega.shape or not np.all(np.isfinite(values)) or np.any(values < 0):
            raise ValueError(f"{name} must hold one finite non-negative value per frequency")
        curves[name] = values
    if not np.isfinite(spread) or spread <= 0:
        raise ValueError(f"spread must be a positive number, got {spread!r}")
    if zoom is None:
        w_peak = omega[int(np.argmax(curves["complex_upper"]))]
        zoom = (w_peak / 1.6, w_peak * 1.6)

    fig, (ax_all, ax_zoom) = new_figure(1, 2, figsize=(10, 4.4))
    for ax in (ax_all, ax_zoom):
        ax.semilogx(omega, curves["complex_upper"], color="C1", lw=2.4, alpha=0.5,
                    label="complex blocks, upper")
        ax.semilogx(omega, curves["complex_lower"], color="C1", ls="--", lw=1.0,
                    label="complex blocks, lower")
        ax.semilogx(omega, curves["real_upper"], color="C0", lw=2.4, alpha=0.5,
                    label="real blocks, upper")
        ax.semilogx(omega, curves["real_lower"], color="C0", ls="--", lw=1.0,
                    label="real blocks, lower")
        if "exact" in curves:
            ax.semilogx(omega, curves["exact"], color="k", lw=0.6, label="exact (zero exclusion)")
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        ax.set_xlabel("frequency [rad/s]")
    ax_all.set_yscale("log")
    ax_all.set_xlim(omega[0], omega[-1])
    ax_all.set_ylabel("μ_RS")
    ax_all.set_title(f"(a) μ_RS at +-{100 * spread:g} % spread, log axes")
    # one legend below both panels: inside an axes it would cover the curves
    fig.legend(*ax_all.get_legend_handles_labels(), loc="outside lower center", ncol=3, fontsize=8)
    inside = (omega >= zoom[0]) & (omega <= zoom[1])
    top = max(float(curves["complex_upper"][inside].max(initial=1.0)), 1.0)
    ax_zoom.set_xlim(*zoom)
    ax_zoom.set_ylim(0.0, 1.15 * top)
    ax_zoom.set_title("(b) near the peak; μ = 1 is the stability limit")
    plotting.name_figure(fig, None, "mixed_mu")
    return fig
