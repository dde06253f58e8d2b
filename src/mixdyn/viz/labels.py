"""Names placed beside their points without covering each other: a greedy placement of text
boxes (in display units, e.g. points) around their anchors, inside a frame."""

from __future__ import annotations

import numpy as np

#: Where a box may sit around its anchor, tried in this order: ``(side, row)``, its centre
#: ``side`` (gap + half its width) to the right (1), left (-1) or over the anchor (0), and
#: ``row`` (its height + gap) above; right-up first, as a reader expects a name, then rows
#: stacked beside the anchor.
_SPOTS = ((1, 0.5), (1, -0.5), (-1, 0.5), (-1, -0.5), (0, 1.0), (0, -1.0),
          (1, 1.5), (1, -1.5), (-1, 1.5), (-1, -1.5), (1, 2.5), (1, -2.5), (-1, 2.5),
          (-1, -2.5), (0, 2.0), (0, -2.0))  # fmt: skip


def _overlap(a: np.ndarray, b: np.ndarray) -> float:
    """Area shared by boxes ``(x0, y0, x1, y1)``."""
    w = min(a[2], b[2]) - max(a[0], b[0])
    h = min(a[3], b[3]) - max(a[1], b[1])
    return max(w, 0.0) * max(h, 0.0)


def place(anchors, sizes, frame, *, gap: float = 3.0, obstacles=()) -> np.ndarray:
    """Boxes for labels beside their anchors, each where it covers no box placed before it,
    no obstacle and stays inside ``frame``; where no spot is free, the one that covers least.

    Args:
        anchors: (n, 2) the labelled points [display units].
        sizes: (n, 2) each label's width and height.
        frame: ``(x0, y0, x1, y1)`` the boxes stay inside.
        gap: the distance between an anchor and its box.
        obstacles: boxes ``(x0, y0, x1, y1)`` not to cover (markers, a legend).

    Returns:
        (n, 4) each label's box ``(x0, y0, x1, y1)``, in the order given.
    """
    anchors = np.asarray(anchors, dtype=float).reshape(-1, 2)
    sizes = np.asarray(sizes, dtype=float).reshape(-1, 2)
    taken = [np.asarray(o, dtype=float) for o in obstacles]
    out = np.zeros((len(anchors), 4))
    for i, ((x, y), (w, h)) in enumerate(zip(anchors, sizes, strict=True)):
        best, cost = None, np.inf
        for side, row in _SPOTS:
            cx = x + side * (gap + w / 2)
            cy = y + row * (h + gap)
            box = np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])
            outside = (
                max(frame[0] - box[0], 0) + max(box[2] - frame[2], 0)
                + max(frame[1] - box[1], 0) + max(box[3] - frame[3], 0)
            )  # fmt: skip
            c = sum(_overlap(box, t) for t in taken) + 1e3 * outside * (w + h)
            if c < cost:
                best, cost = box, c
            if c == 0:
                break
        out[i] = best
        taken.append(best)
    return out


__all__ = ["place"]
