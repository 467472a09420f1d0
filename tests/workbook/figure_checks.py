"""A figure check the tests share: texts that collide in a drawn figure.

:func:`text_overlaps` finds texts that collide with each other, with the boxes
and wires of a block diagram, or legends drawn over curves; the tests of every
figure function assert it finds nothing.  (On pytest's ``pythonpath``, like
``tests/robust``'s test-data modules.)
"""

import matplotlib as mpl
import numpy as np

__all__ = ["text_overlaps"]


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
