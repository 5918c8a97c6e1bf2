"""Layout checks of matplotlib figures, as a reader sees them (issue 24 item 2).

:func:`covered_data` lists every legend and boxed label that lies on plotted data (line
vertices and the segments between them, scatter points) in display coordinates;
:func:`clipped_artists` lists legends and labels that stick out of the figure; and
:func:`overlapping_texts` lists text labels drawn over each other (contour labels).  They work
on any Figure after a draw, so the tests can hold every figure the package makes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

_DENSE = 4000  # lines with more vertices are checked at their vertices only
_SUBSTEPS = 24  # points per segment of a sparser line


def _draw(fig: Figure) -> None:
    """Draw ``fig`` on an Agg canvas (a figure closed by pyplot has lost its canvas)."""
    if not hasattr(fig.canvas, "get_renderer"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    fig.canvas.draw()


def _boxes(fig: Figure) -> list[tuple[str, Bbox]]:
    """Display boxes of the legends and of the labels drawn with a background box."""
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    out: list[tuple[str, Bbox]] = []
    for legend in fig.legends:
        out.append(("figure legend", legend.get_window_extent(renderer)))
    for i, ax in enumerate(fig.get_axes()):
        name = ax.get_title() or ax.get_ylabel() or f"axes {i}"
        inner = ax.get_legend()
        if inner is not None and inner.get_visible():
            out.append((f"legend of {name!r}", inner.get_window_extent(renderer)))
        for text in ax.texts:
            if text.get_visible() and text.get_bbox_patch() is not None and text.get_text():
                out.append((f"label {text.get_text()[:40]!r} of {name!r}",
                            text.get_window_extent(renderer)))
    return out


def _data_points(ax: Any) -> list[tuple[str, np.ndarray]]:
    """(name, display points) of every line and scatter of ``ax``, clipped to the axes."""
    box = ax.get_window_extent()
    out: list[tuple[str, np.ndarray]] = []
    for line in ax.get_lines():
        if not line.get_visible():
            continue
        xy = np.asarray(line.get_xydata(), dtype=float)
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.shape[0] == 0:
            continue
        if 1 < xy.shape[0] <= _DENSE and line.get_linestyle() not in ("None", "", " "):
            f = np.linspace(0.0, 1.0, _SUBSTEPS, endpoint=False)
            seg = xy[:-1, None, :] + f[None, :, None] * (xy[1:] - xy[:-1])[:, None, :]
            xy = np.vstack([seg.reshape(-1, 2), xy[-1:]])
        out.append((f"line {line.get_label()!r}", line.get_transform().transform(xy)))
    for coll in ax.collections:
        if isinstance(coll, PathCollection) and coll.get_visible():
            offsets = np.asarray(coll.get_offsets(), dtype=float)
            if offsets.size:
                out.append(("points", coll.get_offset_transform().transform(offsets)))
    inside = []
    for name, pts in out:
        keep = ((pts[:, 0] >= box.x0) & (pts[:, 0] <= box.x1)
                & (pts[:, 1] >= box.y0) & (pts[:, 1] <= box.y1))
        inside.append((name, pts[keep]))
    return inside


def covered_data(fig: Figure, margin: float = 1.0) -> list[str]:
    """Which legend or boxed label covers which plotted data (empty: none).  ``margin``
    [pixels] shrinks each box so that data only touching its edge does not count."""
    _draw(fig)
    found = []
    data = [(ax, _data_points(ax)) for ax in fig.get_axes() if ax.get_visible()]
    for label, box in _boxes(fig):
        x0, y0, x1, y1 = box.x0 + margin, box.y0 + margin, box.x1 - margin, box.y1 - margin
        for _, series in data:
            for name, pts in series:
                n = int(np.count_nonzero((pts[:, 0] > x0) & (pts[:, 0] < x1)
                                         & (pts[:, 1] > y0) & (pts[:, 1] < y1)))
                if n:
                    found.append(f"{label} covers {n} points of {name}")
    return found


def clipped_artists(fig: Figure) -> list[str]:
    """Legends and boxed labels that stick out of the figure (cut off in the saved PNG)."""
    _draw(fig)
    page = fig.bbox
    return [f"{label} is cut off by the figure edge" for label, box in _boxes(fig)
            if box.x0 < page.x0 - 1 or box.x1 > page.x1 + 1 or box.y0 < page.y0 - 1
            or box.y1 > page.y1 + 1]


def _titles(fig: Figure) -> list[Any]:
    """The figure's titles and the axes' titles and axis labels."""
    texts = list(fig.texts)
    for ax in fig.get_axes():
        if ax.get_visible():
            # the centre, left and right titles (``set_title(loc=...)``)
            texts += [getattr(ax, name) for name in ("title", "_left_title", "_right_title")
                      if hasattr(ax, name)]
            texts += [ax.xaxis.label, ax.yaxis.label]
    return [t for t in texts if t.get_visible() and t.get_text().strip()]


def overlapping_texts(fig: Figure) -> list[str]:
    """Pairs of text labels inside one axes drawn over each other, and legends or boxed
    labels over a title or an axis label."""
    _draw(fig)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    found = []
    for label, box in _boxes(fig):
        for t in _titles(fig):
            if box.overlaps(t.get_window_extent(renderer)):
                found.append(f"{label} overlaps the text {t.get_text()[:40]!r}")
    for ax in fig.get_axes():
        texts = [t for t in ax.texts if t.get_visible() and t.get_text().strip()]
        boxes = [t.get_window_extent(renderer) for t in texts]
        for i in range(len(texts)):
            for j in range(i + 1, len(texts)):
                if boxes[i].overlaps(boxes[j]):
                    found.append(f"{texts[i].get_text()!r} overlaps {texts[j].get_text()!r}")
    return found
