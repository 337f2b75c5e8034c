"""Where a dial's texts lie on its rectified circle, and which of them are scale numbers: the ring, the
main and inner scales, progressions, tick marks read as text, duplicates, parts and split boxes."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from gauged.geometry.rectify import (
    unrectify_points,
)
from gauged.reader.ocr.fragments import merge_fragments
from gauged.reader.ocr.numbers import filter_progression, parse_number
from gauged.reader.ocr.regions import RING, ink_box
from gauged.reader.ocr.text import TextBox
from gauged.reader.ocr.units import (
    match_unit,
)
from gauged.types import ScaleMarker

HINT_WINDOW = 0.6  # side of the local-detection window around a hint, in scale radii
PART_SURE = 0.9  # score of a text that its part, read alone inside it, gives way to (_dedupe)
PART_INSIDE = 0.8  # share of the part's box inside the whole's
PART_AREA = 6.0  # the whole's box at most this many times the part's (tilted "25" about "5": 4.6)
INNER_SCALE = 0.66  # scale radii: numbers nearer the centre are a secondary scale's (synthetic: main >= 0.69)
Circle = tuple[float, float, float]


def _accepts(box: TextBox, min_score: float) -> bool:
    """A reading worth keeping without trying other orientations: a number or a unit, confidently."""
    return box.score >= min_score and (bool(parse_number(box.text)) or bool(match_unit(box.text)))


def _maybe_turned(box: TextBox) -> bool:
    """Could this text be printed turned (radially)? Its box is upright-tall or tilted over 30 deg.

    Upright text on a rectified dial reads first time; words that do not parse are not re-read."""
    u = np.asarray(box.quad[1] - box.quad[0], float)
    tilt = abs(math.degrees(math.atan2(u[1], u[0])))
    return box.height > 1.25 * box.width or 30.0 < tilt < 150.0


def _turned(quad: np.ndarray, k: int) -> np.ndarray:
    """The quad's corners relabelled for its crop turned ``k`` x 90 degrees clockwise."""
    return np.roll(np.asarray(quad, np.float32), k, axis=0)


def _up(quad: np.ndarray) -> np.ndarray:
    q = np.asarray(quad, float)
    v = (q[0] + q[1] - q[2] - q[3]) / 2.0
    return v / max(float(np.linalg.norm(v)), 1e-9)


def _crop_box(matrix: np.ndarray, box: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """A box of the rectified view (``matrix``: crop px -> view px) in crop pixels: centred on its
    mapped centre, as wide and high as its mapped corners spread."""
    x0, y0, x1, y1 = box
    corners = unrectify_points(matrix, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]))
    (cx, cy), = unrectify_points(matrix, np.array([[(x0 + x1) / 2, (y0 + y1) / 2]]))
    hw, hh = np.ptp(corners, axis=0) / 2
    return (float(cx - hw), float(cy - hh), float(cx + hw), float(cy + hh))


def _radial_turn(quad: np.ndarray, circle: Circle) -> int:
    """The quarter turn (:func:`_turned`) that puts the top of the quad's text outward from the circle's
    centre, as radially printed numbers stand."""
    outward = np.asarray(quad, float).mean(axis=0) - np.asarray(circle[:2])
    outward /= max(float(np.linalg.norm(outward)), 1e-9)
    return max(range(4), key=lambda k: float(_up(_turned(quad, k)) @ outward))


def scale_markers(texts: Sequence[TextBox], circle: Circle) -> list[ScaleMarker]:
    """The numbers among ``texts`` (fragments merged) as markers in the same image: box centred on
    the text, ``angle`` its image angle about the circle's centre (not yet a dial angle)."""
    out = []
    for b in merge_fragments(texts):
        parsed = parse_number(b.text)
        if parsed and not parsed.fragment:
            cx, cy = b.center
            w, h = b.box[2] - b.box[0], b.box[3] - b.box[1]
            angle = math.atan2(cy - circle[1], cx - circle[0])
            out.append(ScaleMarker(b.text, parsed.value, (cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), angle,
                                   None, b.score, b.net_minus))
    return out


def _radius(m: ScaleMarker, circle: Circle) -> float:
    return math.dist(((m.box[0] + m.box[2]) / 2, (m.box[1] + m.box[3]) / 2), circle[:2])


def _progression_size(texts: list[TextBox], circle: Circle, gap: float = math.pi / 2) -> int:
    """How many of ``texts`` the best arithmetic progression keeps (0 when none); ``gap`` is the
    image angle of the scale's gap."""
    markers = scale_markers(texts, circle)
    if len(markers) < 3:
        return len(markers)
    fit = filter_progression(markers, gap_angle=gap, radii=[_radius(m, circle) for m in markers])
    return len(fit.kept) if fit else 0


def keep_progressions(markers: list[ScaleMarker], circle: Circle, gap: float = math.pi / 2) -> list[ScaleMarker]:
    """Markers of up to two scales (each an arithmetic progression; the second from what the first
    rejected, for dials with concentric scales), or all markers when no progression is found.
    ``gap`` is the image angle of the scale's gap."""
    fit = filter_progression(markers, gap_angle=gap, radii=[_radius(m, circle) for m in markers])
    if not fit:
        return markers
    kept = list(fit.kept)
    rest = [m for m, reason in fit.rejected if reason in ("off_progression", "radius_outlier")]
    if len(rest) >= 3:
        second = filter_progression(rest, gap_angle=gap, radii=[_radius(m, circle) for m in rest])
        if second:
            kept += list(second.kept)
    return kept


def _tick_mark(box: TextBox, circle: Circle) -> bool:
    """A "1" that is really a scale tick: one stroke lying across the scale circle, pointing at
    the centre (printed ones sit inside or outside the circle, not on it)."""
    if box.text.strip() not in ("1", "l", "I", "|", "!", "i", "-", "—", "_"):
        return False
    q = np.asarray(box.quad, float)
    c = np.array(box.center) - np.array(circle[:2])
    dist = float(np.linalg.norm(c))
    along = np.abs((q - np.array(circle[:2])) @ (c / max(dist, 1e-9)))
    straddles = along.min() <= circle[2] <= along.max()
    return straddles or abs(dist - circle[2]) < 0.03 * circle[2]


def _square(image: np.ndarray, cx: float, cy: float, half: float) -> tuple[np.ndarray, int, int]:
    """The part of ``image`` in the square of half-side ``half`` px about ``(cx, cy)``, and its origin."""
    x0, y0 = max(0, int(cx - half)), max(0, int(cy - half))
    return image[y0: int(math.ceil(cy + half)), x0: int(math.ceil(cx + half))], x0, y0


def _hint_window(image: np.ndarray, hx: float, hy: float, r: float) -> tuple[np.ndarray, int, int] | None:
    """The window of side :data:`HINT_WINDOW` radii around a hint, and its origin; None when tiny."""
    half = 0.5 * HINT_WINDOW * r
    x0, y0 = max(0, int(hx - half)), max(0, int(hy - half))
    win = image[y0: int(hy + half) + 1, x0: int(hx + half) + 1]
    return None if win.shape[0] < 8 or win.shape[1] < 8 else (win, x0, y0)


def _ink_quads(image: np.ndarray, points: Sequence[tuple[float, float]], r: float) -> list[np.ndarray]:
    """The quads (image px) of the ink at each point that has some, in the hint window around it."""
    return [quad for quad, _ in _inks(image, points, r)]


def _inks(image: np.ndarray, points: Sequence[tuple[float, float]], r: float) -> list[tuple[np.ndarray, bool]]:
    """The quad (image px) of the ink at each point that has some, in the hint window around it, and
    whether it is one glyph of a turned number (:class:`gauged.reader.ocr.regions.Ink`)."""
    out = []
    for hx, hy in points:
        window = _hint_window(image, hx, hy, r)
        if window is None:
            continue
        win, x0, y0 = window
        ink = ink_box(win, (hx - x0, hy - y0), r)
        if ink is not None:
            bx0, by0, bx1, by1 = ink.box
            quad = np.float32([[bx0, by0], [bx1, by0], [bx1, by1], [bx0, by1]]) + np.float32([x0, y0])
            out.append((quad, ink.turned_part))
    return out


def _ring_texts(boxes: Sequence[TextBox], circle: Circle) -> list[TextBox]:
    """The texts centred in the ring :data:`RING` that are not scale ticks read as "1"."""
    return [b for b in boxes if _in_ring(b.center, circle) and not _tick_mark(b, circle)]


def _main_scale(box: TextBox, circle: Circle) -> bool:
    """Whether a text sits where the main scale's numbers do, not deep inside (:data:`INNER_SCALE`)."""
    return math.dist(box.center, circle[:2]) >= INNER_SCALE * circle[2]


def _on_main_scale(p: tuple[float, float], circle: Circle) -> bool:
    """In the ring :data:`RING` but not deep inside it, where a secondary scale's numbers are."""
    return _in_ring(p, circle) and math.dist(p, circle[:2]) >= INNER_SCALE * circle[2]


def _in_ring(p: tuple[float, float], circle: Circle) -> bool:
    d = math.dist(p, circle[:2]) / circle[2]
    return RING[0] <= d <= RING[1]


def _explains(box: TextBox, p: tuple[float, float], tol: float) -> bool:
    x0, y0, x1, y1 = box.box
    return x0 - tol <= p[0] <= x1 + tol and y0 - tol <= p[1] <= y1 + tol


def _dedupe(boxes: list[TextBox]) -> list[TextBox]:
    """One box per place: of boxes whose centres are within half a text height, the best scored.

    A box that reads part of the text of a box around its centre gives way to it, whatever their
    scores: the ink box at a hint held only the "5" of a tilted "25", read with score 1.0 against
    the detector's 0.99 (a synthetic render, refused with 2 agreeing numbers of 6).
    """
    boxes = [b for b in boxes if not any(_part_of(b, o) for o in boxes)]
    out: list[TextBox] = []
    for b in sorted(boxes, key=lambda b: -b.score):
        if all(math.dist(b.center, o.center) > 0.5 * max(b.height, o.height, 1.0) for o in out):
            out.append(b)
    return out


def _part_of(box: TextBox, other: TextBox) -> bool:
    """Does ``box`` read a proper part of the digits of confidently read ``other``, and lie inside it?

    Less confident longer readings are more often two numbers in one box ("4600" for 40 and 60,
    score 0.67) than one number whose part was read alone. Inside means most of ``box``'s area, in
    an ``other`` at most :data:`PART_AREA` times as large (a real thermometer's loose 160 px box
    read "20" also held the "0" printed below it).
    """
    part, whole = re.sub(r"\D", "", box.text), re.sub(r"\D", "", other.text)
    if other.score < PART_SURE or not part or len(part) >= len(whole) or part not in whole:
        return False
    (x0, y0, x1, y1), (u0, v0, u1, v1) = box.box, other.box
    inside = max(0.0, min(x1, u1) - max(x0, u0)) * max(0.0, min(y1, v1) - max(y0, v0))
    area = max((x1 - x0) * (y1 - y0), 1e-9)
    return inside >= PART_INSIDE * area and (u1 - u0) * (v1 - v0) <= PART_AREA * area


def _split_spaced(boxes: list[TextBox]) -> list[TextBox]:
    """Split "200 220" (two numbers in one detection) into two boxes, by character position."""
    out = []
    for b in boxes:
        tokens = b.text.split()
        # "1 6" stays one number (16 or 1.6 with a lost point); "200 220" is two
        if len(tokens) < 2 or any(len(t) < 2 or not parse_number(t) or parse_number(t).fragment for t in tokens):
            out.append(b)
            continue
        q = np.asarray(b.quad, np.float32)
        n = len(b.text)
        pos = 0
        for t in tokens:
            start = b.text.index(t, pos)
            end = start + len(t)
            pos = end
            a0, a1 = start / n, end / n
            top0, top1 = q[0] + a0 * (q[1] - q[0]), q[0] + a1 * (q[1] - q[0])
            bot0, bot1 = q[3] + a0 * (q[2] - q[3]), q[3] + a1 * (q[2] - q[3])
            out.append(TextBox(t, b.score, np.stack([top0, top1, bot1, bot0]), t, b.score))
    return out
