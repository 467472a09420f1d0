"""Figures of notebook 09 (mixed mu): mu for robust stability against the coefficient box,
with the coefficients as real blocks and as complex ones, and the trade-off of the mixed-mu
designs between robust performance and the box they keep stable.

``extra_mixed_mu_of`` and ``extra_mixed_tradeoff_of`` draw the same figures from the
results of :mod:`piezolib.problem.coefficient_box`."""

import numpy as np

from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure

__all__ = ["extra_mixed_mu", "extra_mixed_tradeoff", "extra_mixed_mu_of", "extra_mixed_tradeoff_of"]


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


def extra_mixed_tradeoff(scales, mu_upper, mu_lower, mu_bound, margins, spread, chosen=None):
    """Mixed-mu designs at several performance levels: robust performance and the stable box.

    Parameters
    ----------
    scales : array_like
        Performance scale of each design (factor on H_e and H_y), increasing.
    mu_upper, mu_lower : array_like
        Mixed mu_RP of each design (upper and lower bound) at the box ``spread``.
    mu_bound : array_like
        At each scale, a lower bound of mu_RP for every controller (the
        nominal-performance H-infinity optimum): no design can lie below it.
    margins : dict
        {label: array of exact parametric margins [-] per design}, e.g. one
        entry per computation delay.
    spread : float
        The box the designs are for [-] (drawn as the goal line of panel b).
    chosen : float, optional
        Scale of the deployed design (marked).

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_mixed_tradeoff.png``.
    """
    scales = np.asarray(scales, dtype=float)
    if scales.ndim != 1 or scales.size < 1 or np.any(scales <= 0):
        raise ValueError("scales must be a 1-D array of positive numbers")
    arrays = {}
    for name, values in (("mu_upper", mu_upper), ("mu_lower", mu_lower), ("mu_bound", mu_bound)):
        values = np.asarray(values, dtype=float)
        if values.shape != scales.shape or not np.all(np.isfinite(values)):
            raise ValueError(f"{name} must hold one finite value per scale")
        arrays[name] = values
    fig, (ax_mu, ax_margin) = new_figure(1, 2, figsize=(10, 4.2))
    ax_mu.plot(scales, arrays["mu_upper"], "o-", color="C0", label="design: mixed μ_RP, upper")
    ax_mu.plot(scales, arrays["mu_lower"], "x--", color="C0", label="design: lower bound")
    ax_mu.fill_between(scales, 0, arrays["mu_bound"], color="0.85",
                       label="no controller: below the\nnominal H∞ optimum")
    ax_mu.axhline(1.0, color="k", lw=0.8, ls=":")
    ax_mu.set_xlabel("performance scale (× H_e, H_y)")
    ax_mu.set_ylabel(f"μ_RP at ±{100 * spread:g} %")
    ax_mu.set_title("(a) robust performance; ≤ 1: certified")
    ax_mu.legend(fontsize=8)
    for k, (label, values) in enumerate(margins.items()):
        values = np.asarray(values, dtype=float)
        if values.shape != scales.shape:
            raise ValueError(f"margins[{label!r}] must hold one value per scale")
        ax_margin.plot(scales, 100 * values, "o-", color=f"C{k + 1}", label=label)
    ax_margin.axhline(100 * spread, color="k", lw=0.8, ls=":")
    ax_margin.set_xlabel("performance scale (× H_e, H_y)")
    ax_margin.set_ylabel("exact parametric margin [%]")
    ax_margin.set_title(f"(b) box kept stable; goal ±{100 * spread:g} %")
    if chosen is not None:
        for ax in (ax_mu, ax_margin):
            ax.axvline(chosen, color="0.4", lw=0.8, ls="--",
                       label="chosen: deployed" if ax is ax_margin else None)
    ax_margin.legend(fontsize=8)
    for ax in (ax_mu, ax_margin):
        ax.set_xscale("log")
    plotting.name_figure(fig, None, "mixed_tradeoff")
    return fig


def extra_mixed_mu_of(bounds, zoom=None):
    """:func:`extra_mixed_mu` of a :class:`piezolib.problem.coefficient_box.SpreadBounds`
    (its bounds, spread and exact real mu)."""
    if not all(hasattr(bounds, a) for a in ("omega", "real", "complex", "exact_real", "spread")):
        raise TypeError(f"bounds must be a SpreadBounds, got {type(bounds).__name__}")
    return extra_mixed_mu(bounds.omega, bounds.real.upper, bounds.real.lower,
                          bounds.complex.upper, bounds.complex.lower, bounds.spread,
                          exact=bounds.exact_real, zoom=zoom)


def extra_mixed_tradeoff_of(tradeoff, spread):
    """:func:`extra_mixed_tradeoff` of a :class:`piezolib.problem.coefficient_box.MixedTradeoff`
    (its table, the margins per delay and the chosen design, if any), for the box
    ``spread`` [-]."""
    if not all(hasattr(tradeoff, a) for a in ("table", "chosen", "margins")):
        raise TypeError(f"tradeoff must be a MixedTradeoff, got {type(tradeoff).__name__}")
    table = tradeoff.table
    return extra_mixed_tradeoff(
        table.index.to_numpy(), table["mu_RP upper"], table["mu_RP lower"],
        table["no controller below"], tradeoff.margins(), spread,
        chosen=None if tradeoff.chosen is None else tradeoff.chosen.performance_scale)
