"""Margin figure of notebook 06: Nyquist plots near -1 and the sampled loop against delay."""

import numpy as np

from piezolib.robust.discrete import discretize
from piezolib.robust.lti import frequency_grid, realize
from piezolib.robust.margins import delay_tolerance, loop_margins
from piezolib.workbook import plotting
from piezolib.workbook.style import new_figure

__all__ = ["extra_margins"]


def extra_margins(G, controllers, fs, delays=(0, 1, 2, 3), omega=None):
    """Nyquist plots of L = G K around -1 with the disk margin, and spectral radius vs delay.

    Parameters
    ----------
    G : control.LTI
        Plant u_c [V] -> v_y [V].
    controllers : dict
        {name: continuous-time K (v_e [V] -> u_b [V])}.
    fs : float
        Loop rate [Hz] of the sampled loop (Tustin K, zero-order-hold G).
    delays : sequence of int
        Computation delays [samples] of panel (b).
    omega : array_like, optional
        Nyquist grid [rad/s]; default 1 ... 1e6 rad/s.

    Returns
    -------
    matplotlib.figure.Figure
        Saved as ``extra_margins.png``.
    """
    omega = frequency_grid(1.0, 1e6, 4000) if omega is None else np.asarray(omega, float)
    fig, (ax, bx) = new_figure(1, 2, figsize=(10, 5.4))
    # designs often coincide: wide solid, medium dashed, thin dotted keep each one visible
    styles = [dict(ls="-", lw=3.0, alpha=0.55, marker="o", ms=9),
              dict(ls="--", lw=1.6, alpha=1.0, marker="s", ms=6),
              dict(ls=":", lw=1.2, alpha=1.0, marker="^", ms=5)]
    Gr = realize(G)
    theta = np.linspace(0, 2 * np.pi, 200)
    ax.plot(np.cos(theta), np.sin(theta), color="0.75", lw=0.8, label="unit circle")
    for k, (name, K) in enumerate(controllers.items()):
        L = np.ravel(Gr(1j * omega)) * np.ravel(realize(K)(1j * omega))
        m = loop_margins(G, K)
        style = styles[k % len(styles)]
        line, = ax.plot(L.real, L.imag, ls=style["ls"], lw=style["lw"], alpha=style["alpha"],
                        label=f"{name}: PM {m.phase_margin_deg:.0f} deg, disk alpha {m.disk_margin:.2f}")
        # the balanced disk margin: every f in the disk keeps the loop stable; -1/f is
        # the disk that L must avoid, centred on the real axis
        a = m.disk_margin / 2
        lo, hi = -(1 + a) / (1 - a) if a < 1 else -np.inf, -(1 - a) / (1 + a)
        if np.isfinite(lo):
            c, r = (lo + hi) / 2, (hi - lo) / 2
            ax.plot(c + r * np.cos(theta), r * np.sin(theta), ls="--", lw=0.8,
                    color=line.get_color())
        tol = delay_tolerance(G, discretize(K, fs).K, delays=delays)
        bx.plot(tol.delays, tol.spectral_radius, color=line.get_color(), **style,
                label=f"{name}: delay margin {tol.delay_margin_samples:.2f} samples")
    ax.plot([-1], [0], "k+", ms=10)
    ax.set_xlim(-3, 1.5)
    ax.set_ylim(-2.5, 2.5)
    ax.set_aspect("equal")
    ax.set_xlabel("Re L(jw)")
    ax.set_ylabel("Im L(jw)")
    ax.set_title("(a) Nyquist plot near -1 (dashed: disk the loop avoids)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.14))
    bx.axhline(1.0, color="k", lw=0.8, ls=":")
    bx.set_xticks(list(delays))
    bx.set_xlabel("computation delay [samples]")
    bx.set_ylabel("spectral radius of the sampled loop")
    bx.set_title(f"(b) sampled loop at {fs / 1e3:g} kHz (unstable above 1)")
    bx.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.14))
    plotting.name_figure(fig, None, "margins")
    return fig
