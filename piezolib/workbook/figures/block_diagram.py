"""The engine of the paper's signal-flow block diagrams (Fig. 1, 2, 3, 5, 9).

:func:`block_diagram` lays out boxes, summing junctions, wires with their
signal names and dashed frames on a grid of diagram units, in the workbook
style (:mod:`piezolib.workbook.style`), and sizes the figure from the drawing
so that text is always the same size; :mod:`piezolib.workbook.figures.diagrams`
holds the paper's diagrams drawn with it.
"""

import matplotlib as mpl
import matplotlib.pyplot as plt
import numpy as np

from piezolib.workbook.style import PALETTE, use_style

__all__ = ["DIAGRAM_UNIT_IN", "block_diagram"]

#: Size of one diagram unit [inch]; the figure is sized from the drawing.
DIAGRAM_UNIT_IN = 0.5
_BOX_STYLE = dict(boxstyle="round,pad=0.04", fc=PALETTE.box_fill, ec=PALETTE.primary, lw=1.2)
_FONT = 8.0           # box text [pt]
_SIGNAL_FONT = 7.5    # signal names [pt]
_R_SUM = 0.17         # summing junction radius [units]


def _text_size(text, fontsize):
    """Width and height [diagram units] of ``text`` in DejaVu Sans (a safe over-estimate)."""
    lines = text.splitlines() or [""]
    em = fontsize / 72.0 / DIAGRAM_UNIT_IN
    return 0.62 * em * max(len(line) for line in lines), 1.25 * em * len(lines)


def block_diagram(blocks, wires, title=None, frames=()):
    """Draw a signal-flow block diagram in the workbook style and return the figure.

    Parameters
    ----------
    blocks : dict
        ``name -> (x, y, label)`` or ``(x, y, label, kind)`` [diagram units,
        1 unit = :data:`DIAGRAM_UNIT_IN` inch].  ``kind`` is ``"box"``
        (default; the box fits its label), ``"sum"`` (summing junction; the
        label ``"o"`` also means a junction) or ``"text"`` (a label without a
        box), or a dict ``{"kind": ..., "size": (width, height)}`` for a box
        of a given size.
    wires : list of tuple
        ``(start, stop, label)`` or ``(start, stop, label, options)``;
        ``start``/``stop`` are block names or ``(x, y)`` points.  ``options``
        may hold ``via`` (corner points of an orthogonal wire), ``side``
        (``"above"``, ``"below"``, ``"left"`` or ``"right"`` of the labelled
        segment; default above for horizontal, right for vertical),
        ``segment`` (index of the labelled segment; default the longest),
        ``sign`` (``"+"`` or ``"-"``, written beside the arrow head at a
        junction), ``dot`` (True: a branch dot at the start) and ``arrow``
        (False: no arrow head).
    title : str, optional
    frames : list of tuple, optional
        ``(x0, y0, x1, y1, label)``: dashed frames around groups of blocks,
        the label written inside the top-left corner.

    Returns
    -------
    matplotlib.figure.Figure
        One axes without frame, sized so that text is always ``8 pt``.
    """
    if not isinstance(blocks, dict) or not blocks:
        raise ValueError("blocks must be a non-empty dict name -> (x, y, label[, kind])")
    use_style()
    fig = plt.figure(layout=None)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    ax.set_aspect("equal")
    size, points = {}, []
    for name, spec in blocks.items():
        if len(spec) not in (3, 4):
            raise ValueError(f"blocks[{name!r}] must be (x, y, label[, kind]), got {spec!r}")
        x, y, label = spec[:3]
        extra = spec[3] if len(spec) == 4 else {}
        extra = {"kind": extra} if isinstance(extra, str) else dict(extra)
        kind = extra.get("kind", "sum" if label == "o" else "box")
        if kind == "sum":
            ax.add_patch(mpl.patches.Circle((x, y), _R_SUM, fill=False, lw=1.2, ec=PALETTE.primary))
            size[name] = (_R_SUM, _R_SUM)
        elif kind in ("box", "text"):
            w, h = _text_size(label, _FONT)
            w, h = extra.get("size", (w + 0.5, h + 0.3))
            if kind == "box":
                ax.add_patch(mpl.patches.FancyBboxPatch((x - w / 2, y - h / 2), w, h,
                                                        **_BOX_STYLE))
            ax.text(x, y, label, ha="center", va="center", fontsize=_FONT,
                    linespacing=1.25)
            size[name] = (w / 2 + 0.04, h / 2 + 0.04)
        else:
            raise ValueError(f"kind of block {name!r} must be 'box', 'sum' or 'text', "
                             f"got {kind!r}")
        points += [(x - size[name][0], y - size[name][1]), (x + size[name][0], y + size[name][1])]

    def centre(end):
        if isinstance(end, str):
            if end not in blocks:
                raise ValueError(f"wire end {end!r} is not a block")
            return np.array(blocks[end][:2], float)
        return np.asarray(end, float)

    def anchor(end, toward):
        if not isinstance(end, str):
            return np.asarray(end, float)
        c = centre(end)
        hw, hh = size[end]
        d = np.asarray(toward, float) - c
        if abs(d[0]) * hh >= abs(d[1]) * hw:      # through a vertical side
            return np.array([c[0] + np.sign(d[0]) * hw, c[1] + d[1] * hw / max(abs(d[0]), 1e-9)])
        return np.array([c[0] + d[0] * hh / max(abs(d[1]), 1e-9), c[1] + np.sign(d[1]) * hh])

    for wire in wires:
        if len(wire) not in (3, 4):
            raise ValueError(f"a wire must be (start, stop, label[, options]), got {wire!r}")
        start, stop, label = wire[:3]
        opts = dict(wire[3]) if len(wire) == 4 else {}
        unknown = set(opts) - {"via", "side", "segment", "sign", "dot", "arrow"}
        if unknown:
            raise ValueError(f"unknown wire options {sorted(unknown)} in {wire!r}")
        via = [np.asarray(p, float) for p in opts.get("via", [])]
        path = [anchor(start, via[0] if via else centre(stop))] + via
        path.append(anchor(stop, path[-1]))
        path = np.array(path)
        # the whole wire as one line (what the tests' overlap check sees), short of the head
        tail = path.copy()
        last = tail[-1] - tail[-2]
        tail[-1] -= 0.1 * last / max(np.hypot(*last), 1e-9)
        ax.plot(tail[:, 0], tail[:, 1], color=PALETTE.wire, lw=1.0, solid_capstyle="butt")
        ax.annotate("", xy=path[-1], xytext=path[-2],
                    arrowprops=dict(arrowstyle="-|>" if opts.get("arrow", True) else "-",
                                    lw=1.0, color=PALETTE.wire, shrinkA=0, shrinkB=0))
        if opts.get("dot"):
            ax.plot(*path[0], "o", ms=3.2, color=PALETTE.wire)
        lengths = np.hypot(*np.diff(path, axis=0).T)
        k = opts.get("segment", int(np.argmax(lengths)))
        a, b = path[k], path[k + 1]
        horizontal = abs(b[0] - a[0]) >= abs(b[1] - a[1])
        side = opts.get("side", "above" if horizontal else "right")
        if label:
            mid = (a + b) / 2
            offset, align = {"above": ((0, 0.1), dict(ha="center", va="bottom")),
                             "below": ((0, -0.1), dict(ha="center", va="top")),
                             "left": ((-0.1, 0), dict(ha="right", va="center")),
                             "right": ((0.1, 0), dict(ha="left", va="center"))}[side]
            ax.text(mid[0] + offset[0], mid[1] + offset[1], label, fontsize=_SIGNAL_FONT,
                    color=PALETTE.signal, **align)
            w, h = _text_size(label, _SIGNAL_FONT)
            x0 = {"above": mid[0] - w / 2, "below": mid[0] - w / 2,
                  "left": mid[0] - 0.1 - w, "right": mid[0] + 0.1}[side]
            y0 = {"above": mid[1] + 0.1, "below": mid[1] - 0.1 - h,
                  "left": mid[1] - h / 2, "right": mid[1] - h / 2}[side]
            points += [(x0, y0), (x0 + w, y0 + h)]
        if "sign" in opts:
            d = path[-1] - path[-2]
            d = d / max(np.hypot(*d), 1e-9)
            # beside the arrow head: above a horizontal wire, left of a vertical one
            normal = np.array([0.0, 0.22]) if abs(d[0]) >= abs(d[1]) else np.array([-0.22, 0.0])
            pos = path[-1] - 0.3 * d + normal
            ax.text(*pos, {"-": "\u2212", "+": "+"}[opts["sign"]], ha="center", va="center",
                    fontsize=10, fontweight="bold", color=PALETTE.wire)
        points += list(path)
    for x0, y0, x1, y1, label in frames:
        ax.add_patch(mpl.patches.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ls="--",
                                           lw=0.9, ec="0.45"))
        ax.text(x0 + 0.12, y1 - 0.1, label, ha="left", va="top", fontsize=_SIGNAL_FONT,
                color="0.3")
        points += [(x0, y0), (x1, y1)]
    points = np.array(points)
    lo, hi = points.min(axis=0) - 0.25, points.max(axis=0) + 0.25
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    extra = 0.0
    if title:
        ax.set_title(title, fontsize=9)
        extra = 0.35
    fig.set_size_inches((hi[0] - lo[0]) * DIAGRAM_UNIT_IN,
                        (hi[1] - lo[1]) * DIAGRAM_UNIT_IN + extra)
    ax.set_position((0, 0, 1, (hi[1] - lo[1]) * DIAGRAM_UNIT_IN / fig.get_size_inches()[1]))
    return fig
