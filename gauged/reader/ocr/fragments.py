"""Scale numbers split by the text detector into pieces ("1" and "6" of a "16"): merged back into one box."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gauged.reader.ocr.numbers import MAX_DIGITS, PITCH, parse_number
from gauged.reader.ocr.text import TextBox


def merge_fragments(boxes: Sequence[TextBox], gap: float = 0.6, align: float = 0.35) -> list[TextBox]:
    """Join text boxes that are pieces of one number ("0" + ".6", "1" + "6", "-" + "30").

    Two boxes merge when both texts parse as numbers or fragments, they are neighbours along the
    left box's reading direction (gap under ``gap`` x text height), their centres are aligned across
    it (offset under ``align`` x height), their heights agree within a factor 1.6, and the joined text
    parses. Boxes are (H, W) image-space quads; the result keeps unmerged boxes unchanged.
    """
    items = list(boxes)
    merged = True
    while merged:
        merged = False
        for i, a in enumerate(items):
            for j, b in enumerate(items):
                if i == j or not _mergeable(a, b, gap, align):
                    continue
                joined = TextBox(a.text + b.text, min(a.score, b.score), _hull_quad(a.quad, b.quad))
                items = [x for k, x in enumerate(items) if k not in (i, j)] + [joined]
                merged = True
                break
            if merged:
                break
    return items


def _mergeable(a: TextBox, b: TextBox, gap: float, align: float) -> bool:
    pa, pb = parse_number(a.text), parse_number(b.text)
    if not pa or not pb or not parse_number(a.text + b.text):
        return False
    if len((a.text + b.text).replace(" ", "")) > MAX_DIGITS + 2:
        return False
    u = a.quad[1] - a.quad[0]
    length = float(np.linalg.norm(u))
    if length < 1e-6:
        return False
    u = u / length
    v = np.array([-u[1], u[0]])
    ha, hb = a.height, b.height
    if not (1 / 1.6 <= hb / max(ha, 1e-6) <= 1.6):
        return False
    h = max(ha, hb)
    a_right = float(np.max((a.quad - a.quad[0]) @ u))
    b_left = float(np.min((b.quad - a.quad[0]) @ u))
    b_right = float(np.max((b.quad - a.quad[0]) @ u))
    across = abs(float((np.asarray(b.center) - np.asarray(a.center)) @ v))
    if not (b_right > a_right and -0.3 * h <= b_left - a_right <= gap * h and across <= align * h):
        return False
    # The detector's boxes are padded, so close separate numbers ("1", "2", "3" on a short scale) can
    # come within the gap; the characters' own spacing tells them apart: the last character of ``a``
    # and the first of ``b`` (each box split evenly by its characters) are a digit pitch apart.
    a_left = float(np.min((a.quad - a.quad[0]) @ u))
    last_a = a_right - 0.5 * (a_right - a_left) / max(1, len(a.text))
    first_b = b_left + 0.5 * (b_right - b_left) / max(1, len(b.text))
    return first_b - last_a <= PITCH * h


def _hull_quad(qa: np.ndarray, qb: np.ndarray) -> np.ndarray:
    """The quad spanning two reading-direction-aligned quads (a's orientation, both extents)."""
    u = qa[1] - qa[0]
    u = u / max(float(np.linalg.norm(u)), 1e-9)
    v = np.array([-u[1], u[0]])
    pts = np.vstack([qa, qb]) - qa[0]
    s, t = pts @ u, pts @ v
    o = qa[0]
    corners = [(s.min(), t.min()), (s.max(), t.min()), (s.max(), t.max()), (s.min(), t.max())]
    return np.array([o + x * u + y * v for x, y in corners], np.float32)
