"""One figure style for the workbook, one units rule, one way to save figures.

Figures are named after the paper's numbering, ``figures/figNN_<what>.png``
(e.g. ``fig04_chirp_validation.png``); figures with no counterpart in the
paper are saved as ``figures/extra_<what>.png``.

Units rule
----------
Figure functions write plain ASCII (``"x [um]"``, ``"mu_RP"``, ``"omega_e"``,
``"+-5 %"``); :func:`save_figure` passes every text of the figure through
:func:`unit_text` once, so that every saved figure spells micrometres
``µm``, the structured singular value ``μ``, angular frequency ``ω`` and
``±`` the same way.  Frequencies are in rad/s (models, grids) or Hz
(trajectories), voltages in V, times in s or ms, as in the units table of
:mod:`piezolib.problem.paper`.

:func:`block_diagram` draws the signal-flow diagrams (Fig. 1, 2, 3, 5, 9) and
:func:`text_overlaps` finds texts that collide with each other, with the
boxes and wires of a diagram, or legends drawn over curves.
"""

import io
import re

import matplotlib as mpl
import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np

from piezolib.files import atomic_write
from piezolib.workbook.outputs import figures_dir

__all__ = ["STYLE", "use_style", "new_figure", "save_figure", "same_picture", "PIXEL_TOLERANCE",
           "figure_path", "unit_text", "apply_unit_text", "db", "plot_magnitude", "block_diagram", "text_overlaps"]

#: rcParams of the workbook's figures (print-sized, readable at 100 %).
STYLE = {
    "figure.figsize": (7.0, 4.2),
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "savefig.bbox": "tight",
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.35,
    "grid.linewidth": 0.5,
    "lines.linewidth": 1.3,
    "axes.prop_cycle": mpl.cycler(color=["#1f4e79", "#c0504d", "#4f8f3a", "#8064a2",
                                         "#d08a00", "#4bacc6", "#7f7f7f"]),
    # no timestamps or version strings in the files: reruns give identical PNGs
    "svg.hashsalt": "piezolib",
}

_WHAT = re.compile(r"^[a-z0-9][a-z0-9_]*$")

#: The units rule: (pattern, replacement) applied in order by :func:`unit_text`.
_UNIT_RULES = [
    (re.compile(r"(?<![A-Za-z\\])um(?![A-Za-z])"), "µm"),        # 3 um/V, [um], nm stays
    (re.compile(r"(?<![A-Za-z\\])mu(?![A-Za-z])"), "μ"),               # mu, mu_RP, mu(M)
    (re.compile(r"(?<![A-Za-z\\])omega(?![A-Za-z])"), "ω"),
    (re.compile(r"(?<![A-Za-z\\])Delta(?![A-Za-z])"), "Δ"),
    (re.compile(r"\+-"), "±"),
    (re.compile(r"<="), "≤"),
    (re.compile(r">="), "≥"),
    (re.compile(r" -> "), " → "),
]


def use_style():
    """Apply :data:`STYLE` to matplotlib's global rcParams."""
    mpl.rcParams.update(STYLE)


def new_figure(nrows=1, ncols=1, **kwargs):
    """``plt.subplots`` in the workbook style (``constrained`` layout)."""
    use_style()
    kwargs.setdefault("layout", "constrained")
    return plt.subplots(nrows, ncols, **kwargs)


def unit_text(text):
    """Spell units and symbols of a plain-ASCII label the workbook's way.

    Parameters
    ----------
    text : str
        E.g. ``"x = 3 um/V * v_y [um]"``.

    Returns
    -------
    str
        ``um`` -> ``µm``, ``mu`` -> ``μ``, ``omega`` -> ``ω``, ``Delta`` ->
        ``Δ``, ``+-`` -> ``±``, ``<=`` -> ``≤``, ``>=`` -> ``≥``, `` -> `` ->
        `` → ``; words containing these
        letters (``maximum``, ``sum``, ``mu-law``) are left alone, and so is
        any text holding mathtext (``$``).

    Examples
    --------
    >>> unit_text("x [um], mu_RP at omega = 1 rad/s, +-5 %")
    'x [µm], μ_RP at ω = 1 rad/s, ±5 %'
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be a str, got {type(text).__name__}")
    if "$" in text:
        return text
    for pattern, replacement in _UNIT_RULES:
        text = pattern.sub(replacement, text)
    return text


def apply_unit_text(fig):
    """Apply :func:`unit_text` to every text of ``fig`` (in place) and return ``fig``."""
    if not isinstance(fig, mpl.figure.Figure):
        raise TypeError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    for text in fig.findobj(mpl.text.Text):
        old = text.get_text()
        new = unit_text(old)
        if new != old:
            text.set_text(new)
    return fig


def figure_path(number, what):
    """Path of figure ``number`` (paper numbering, or None) showing ``what``."""
    if not isinstance(what, str) or not _WHAT.match(what):
        raise ValueError("what must be a lower-case identifier such as "
                         f"'chirp_validation', got {what!r}")
    if number is None:
        return figures_dir() / f"extra_{what}.png"
    if isinstance(number, bool) or not isinstance(number, (int, np.integer)) or not 1 <= number <= 99:
        raise ValueError(f"number must be a paper figure number 1..99 or None, got {number!r}")
    return figures_dir() / f"fig{int(number):02d}_{what}.png"


def save_figure(fig, number, what):
    """Apply the units rule to ``fig``, save it as ``figures/figNN_<what>.png``, return the path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    number : int or None
        The paper's figure number; ``None`` for a figure of the workbook's own.
    what : str
        Short lower-case description, e.g. ``"step_responses"``.
    """
    if not isinstance(fig, mpl.figure.Figure):
        raise TypeError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    path = figure_path(number, what)
    apply_unit_text(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", metadata={"Software": None})
    png = buffer.getvalue()
    if path.is_file() and same_picture(path.read_bytes(), png):
        return path         # the same figure up to antialiasing: leave the file as it is
    return atomic_write(path, png)


#: Largest change of any colour channel (0 ... 1) that :func:`same_picture` ignores.
PIXEL_TOLERANCE = 0.25


def same_picture(first, second, tolerance=PIXEL_TOLERANCE):
    """True when two PNG images (bytes) show the same figure.

    Same size, and no pixel differs by more than ``tolerance`` in any
    channel.  A curve that another machine's rounding moves by a small
    fraction of a pixel only changes the shades of its antialiased edge
    (seen: at most 0.19); a curve, a marker or a text that moved by a
    visible amount changes some pixel by more than a quarter.
    """
    a, b = (mpimg.imread(io.BytesIO(x), format="png") for x in (first, second))
    return a.shape == b.shape and float(np.max(np.abs(a - b), initial=0.0)) <= tolerance


def db(x):
    """Magnitude in decibels, 20 log10 |x|."""
    return 20 * np.log10(np.abs(x))


def plot_magnitude(ax, omega, response, label=None, **kwargs):
    """Plot |response| in dB against omega [rad/s] on a log axis."""
    line, = ax.semilogx(omega, db(response), label=label, **kwargs)
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("magnitude [dB]")
    return line


# --------------------------------------------------------------------------- block diagrams
#: Size of one diagram unit [inch]; the figure is sized from the drawing.
DIAGRAM_UNIT_IN = 0.5
_BOX_STYLE = dict(boxstyle="round,pad=0.04", fc="#eef3f8", ec="#1f4e79", lw=1.2)
_WIRE_COLOR = "#333333"
_SIGNAL_COLOR = "#7a1f1f"
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
            ax.add_patch(mpl.patches.Circle((x, y), _R_SUM, fill=False, lw=1.2, ec="#1f4e79"))
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
        # the whole wire as one line (what text_overlaps checks), stopping short of the head
        tail = path.copy()
        last = tail[-1] - tail[-2]
        tail[-1] -= 0.1 * last / max(np.hypot(*last), 1e-9)
        ax.plot(tail[:, 0], tail[:, 1], color=_WIRE_COLOR, lw=1.0, solid_capstyle="butt")
        ax.annotate("", xy=path[-1], xytext=path[-2],
                    arrowprops=dict(arrowstyle="-|>" if opts.get("arrow", True) else "-",
                                    lw=1.0, color=_WIRE_COLOR, shrinkA=0, shrinkB=0))
        if opts.get("dot"):
            ax.plot(*path[0], "o", ms=3.2, color=_WIRE_COLOR)
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
                    color=_SIGNAL_COLOR, **align)
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
                    fontsize=10, fontweight="bold", color=_WIRE_COLOR)
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


# --------------------------------------------------------------------------- readability checks
def _drawn_texts(fig):
    """The visible, non-empty texts of ``fig`` that a draw puts on the canvas."""
    hidden = set()
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            scale = axis.get_transform()
            lo, hi = sorted(scale.transform(np.asarray(axis.get_view_interval(), float)))
            tol = 1e-9 * max(hi - lo, 1e-300)
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                loc = float(scale.transform(np.array([tick.get_loc()], float))[0])
                if not (ax.axison and axis.get_visible() and lo - tol <= loc <= hi + tol):
                    hidden.update((id(tick.label1), id(tick.label2)))
    texts = []
    for text in fig.findobj(mpl.text.Text):
        if id(text) in hidden or not text.get_visible() or not text.get_text().strip():
            continue
        parent = text.axes
        if parent is not None and not parent.get_visible():
            continue
        texts.append(text)
    return texts


def _shrunk(bbox, px):
    return mpl.transforms.Bbox.from_extents(bbox.x0 + px, bbox.y0 + px,
                                            bbox.x1 - px, bbox.y1 - px)


def _crosses(bbox, xy):
    """True when the polyline ``xy`` (display coordinates) enters ``bbox``."""
    if len(xy) == 1:
        return bool(bbox.contains(*xy[0]))
    path = mpl.path.Path(xy)
    return bool(path.intersects_bbox(bbox, filled=False))


def text_overlaps(fig, margin_px=1.0):
    """Texts of ``fig`` that collide, after a draw with the figure's renderer.

    Three kinds of collision are reported: two texts whose bounding boxes
    overlap; in a frameless axes (a block diagram), a text crossed by a wire
    or cutting a box edge (a box's own label lies inside it); and a legend or
    an axes text drawn over a data curve of its axes (lines in data
    coordinates with at least two points inside the axes; ``axhline`` /
    ``axvline`` reference lines and line collections are not checked).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    margin_px : float, optional
        Boxes are shrunk by this many pixels before testing, so touching
        boxes do not count.

    Returns
    -------
    list of str
        One line per collision, empty when the figure is clean.
    """
    if not isinstance(fig, mpl.figure.Figure):
        raise TypeError(f"fig must be a matplotlib Figure, got {type(fig).__name__}")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    texts = _drawn_texts(fig)
    boxes = [_shrunk(t.get_window_extent(renderer), margin_px) for t in texts]
    found = []
    for i in range(len(texts)):
        for j in range(i + 1, len(texts)):
            if boxes[i].width > 0 and boxes[j].width > 0 and boxes[i].overlaps(boxes[j]):
                found.append(f"text {texts[i].get_text()!r} overlaps {texts[j].get_text()!r}")
    for ax in fig.axes:
        own = [(t, b) for t, b in zip(texts, boxes) if t.axes is ax and t in ax.texts]
        if not ax.axison:
            for line in ax.lines:
                xy = line.get_transform().transform(line.get_xydata())
                found += [f"wire crosses text {t.get_text()!r}" for t, b in own
                          if len(xy) > 1 and _crosses(b, xy)]
            for patch in ax.patches:
                edge = patch.get_window_extent(renderer)
                for t, b in own:
                    inside = edge.contains(b.x0, b.y0) and edge.contains(b.x1, b.y1)
                    if edge.overlaps(b) and not inside:
                        found.append(f"text {t.get_text()!r} cuts a box edge")
            continue
        covers = [(f"text {t.get_text()!r}", b) for t, b in own]
        legend = ax.get_legend()
        if legend is not None and legend.get_visible():
            covers.append(("legend", _shrunk(legend.get_window_extent(renderer), margin_px)))
        clip = ax.get_window_extent(renderer)
        for line in ax.lines:
            if line.get_transform() != ax.transData:
                continue        # axhline / axvline: reference lines, readable behind a legend
            xy = line.get_transform().transform(line.get_xydata())
            keep = np.all(np.isfinite(xy), axis=1)
            keep &= (xy[:, 0] >= clip.x0) & (xy[:, 0] <= clip.x1)
            keep &= (xy[:, 1] >= clip.y0) & (xy[:, 1] <= clip.y1)
            if keep.sum() < 2 or line.get_linestyle() in ("None", "", " ") and \
                    line.get_marker() in ("None", "", " ", None):
                continue
            for what, b in covers:
                if _crosses(b, xy[keep]) if line.get_linestyle() not in ("None", "", " ") \
                        else any(b.contains(*p) for p in xy[keep]):
                    found.append(f"{what} covers the curve {line.get_label()!r} "
                                 f"in {ax.get_title()!r}")
    return found
