"""Objects around gauges: pipes, cables, boxes, signs, valve hand-wheels and bolted flanges.

Used twice: in backgrounds (where round hand-wheels and flanges are hard negatives for a gauge
detector) and as foreground occluders in front of gauges. Every function draws into a uint8 BGR
image in place and, when given one, into a uint8 coverage ``mask`` (255 = covered), so the scene
can tell which gauge pixels stay visible.
"""

from __future__ import annotations

import math

import numpy as np

from gauged.synth import draw
from gauged.synth.fonts import FONT_KEYS, text_mask

# mostly bare or grey-painted steel; the coloured ones are muted like weathered paint
PIPE_COLORS = ((165, 165, 165), (135, 135, 140), (185, 190, 190), (110, 110, 110), (70, 70, 150), (60, 115, 160),
               (85, 115, 85), (140, 110, 80), (55, 55, 55), (90, 140, 170))


def _both(img: np.ndarray, mask: np.ndarray | None, poly: np.ndarray, color) -> None:
    draw.fill_polygon(img, poly, color)
    if mask is not None:
        draw.fill_polygon(mask, poly, 255)


def _shade(color, k: float) -> tuple[float, float, float]:
    return tuple(float(min(255.0, max(0.0, c * k))) for c in color)


def draw_pipe(img: np.ndarray, rng: np.random.Generator, mask: np.ndarray | None, through: tuple[float, float] | None = None,
              radius: float | None = None) -> None:
    """A straight pipe with cylindrical shading across the image (through ``through`` if given)."""
    h, w = img.shape[:2]
    if through is None:
        through = (rng.uniform(0, w), rng.uniform(0, h))
    angle = rng.choice([0.0, math.pi / 2]) if rng.random() < 0.8 else rng.uniform(0, math.pi)
    angle += rng.normal(0, 0.02)
    size = max(h, w)
    radius = radius or rng.uniform(min(6.0, 0.02 * size), max(7.0, 0.06 * size))
    color = PIPE_COLORS[int(rng.integers(len(PIPE_COLORS)))]
    d = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-d[1], d[0]])
    length = 2.0 * (h + w)
    c = np.asarray(through, float)
    strips = 9
    # brightness across the pipe: dark edges, a highlight off-centre (light from above)
    profile = [0.45, 0.65, 0.85, 1.05, 1.25, 1.1, 0.9, 0.7, 0.5]
    for i in range(strips):
        o0 = -radius + 2 * radius * i / strips
        o1 = o0 + 2 * radius / strips + 0.5
        poly = np.array([c - d * length + n * o0, c + d * length + n * o0, c + d * length + n * o1, c - d * length + n * o1])
        _both(img, mask, poly, _shade(color, profile[i]))
    if rng.random() < 0.5:  # a flange or a clamp along the pipe
        t = rng.uniform(-0.3, 0.3) * length / 2
        fw = rng.uniform(0.3, 0.8) * radius
        fr = radius * rng.uniform(1.2, 1.6)
        poly = np.array([c + d * (t - fw) - n * fr, c + d * (t + fw) - n * fr, c + d * (t + fw) + n * fr, c + d * (t - fw) + n * fr])
        _both(img, mask, poly, _shade(color, 0.85))


def draw_cable(img: np.ndarray, rng: np.random.Generator, mask: np.ndarray | None,
               through: tuple[float, float] | None = None) -> None:
    h, w = img.shape[:2]
    if through is None:
        through = (rng.uniform(0, w), rng.uniform(0, h))
    a = rng.uniform(0, math.pi)
    d = np.array([math.cos(a), math.sin(a)])
    t = np.linspace(-1, 1, 24)[:, None]
    span = rng.uniform(0.2, 0.8) * max(h, w)
    sag = np.array([-d[1], d[0]]) * rng.uniform(-0.15, 0.15) * span * (1 - t**2)
    pts = np.asarray(through) + d * t * span + sag
    width = float(rng.uniform(2, 0.012 * max(h, w) + 3))
    color = ((30, 30, 30), (40, 40, 160), (150, 150, 150), (30, 120, 200))[int(rng.integers(4))]
    draw.stroke_polyline(img, pts, color, width)
    if mask is not None:
        draw.stroke_polyline(mask, pts, 255, width)


def draw_handwheel(img: np.ndarray, rng: np.random.Generator, center: tuple[float, float], radius: float) -> None:
    """A round valve hand-wheel: a ring with spokes (round, like a gauge, but not one)."""
    color = ((40, 40, 180), (40, 40, 40), (60, 130, 200), (150, 150, 150))[int(rng.integers(4))]
    squash = rng.uniform(0.5, 1.0)
    t = np.linspace(0, 2 * math.pi, 64, endpoint=False)
    ring = lambda r: np.column_stack([center[0] + r * np.cos(t), center[1] + r * squash * np.sin(t)])  # noqa: E731
    draw.fill_polygons(img, [ring(radius), ring(radius * 0.82)[::-1]], color)
    for k in range(int(rng.integers(3, 6))):
        a = k * 2 * math.pi / 5 + rng.uniform(0, 1)
        p = np.array([[0.0, -0.05], [0.85, -0.05], [0.85, 0.05], [0.0, 0.05]]) * radius
        ca, sa = math.cos(a), math.sin(a)
        p = p @ np.array([[ca, sa], [-sa, ca]])
        p[:, 1] *= squash
        draw.fill_polygon(img, p + np.asarray(center), _shade(color, 0.8))
    draw.fill_circle(img, center, radius * 0.15, _shade(color, 0.6))


def draw_flange(img: np.ndarray, rng: np.random.Generator, center: tuple[float, float], radius: float) -> None:
    """A blind flange with a bolt circle."""
    color = _shade(PIPE_COLORS[int(rng.integers(len(PIPE_COLORS)))], 0.9)
    draw.fill_circle(img, center, radius, color)
    draw.fill_circle(img, center, radius * 0.7, _shade(color, 0.85))
    bolts = int(rng.integers(4, 9))
    for k in range(bolts):
        a = 2 * math.pi * k / bolts
        draw.fill_circle(img, (center[0] + 0.85 * radius * math.cos(a), center[1] + 0.85 * radius * math.sin(a)),
                         radius * 0.08, _shade(color, 0.5))


def draw_sign(img: np.ndarray, rng: np.random.Generator, center: tuple[float, float], size: float) -> None:
    """A rectangular sign or label with a few words (text distractors outside any gauge)."""
    bg = ((240, 240, 240), (40, 200, 240), (40, 40, 200), (200, 120, 30))[int(rng.integers(4))]
    fg = (20, 20, 20) if sum(bg) > 400 else (245, 245, 245)
    w, h = size * rng.uniform(1.0, 2.2), size * rng.uniform(0.4, 0.9)
    x0, y0 = center[0] - w / 2, center[1] - h / 2
    draw.fill_polygon(img, np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]), bg)
    word = ("DANGER", "P-101", "VALVE 3", "PN16", "STEAM", "N2", "AIR 8 bar", "DN50", "PUMP A")[int(rng.integers(9))]
    mask = text_mask(FONT_KEYS[int(rng.integers(len(FONT_KEYS)))], h * 0.45, word)
    scale = min(1.0, (w * 0.9) / max(mask.shape[1], 1))
    affine = np.array([[scale, 0.0, center[0] - scale * mask.shape[1] / 2], [0.0, scale, center[1] - scale * mask.shape[0] / 2]])
    draw.paste_mask(img, mask, affine, fg)


def draw_box(img: np.ndarray, rng: np.random.Generator, mask: np.ndarray | None, center: tuple[float, float], size: float) -> None:
    """A shaded box, bracket or junction box face."""
    color = ((90, 90, 95), (40, 90, 160), (160, 160, 160), (50, 50, 50), (70, 120, 60))[int(rng.integers(5))]
    w, h = size * rng.uniform(0.5, 2.0), size * rng.uniform(0.5, 2.0)
    x0, y0 = center[0] - w / 2, center[1] - h / 2
    _both(img, mask, np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]), color)
    d = size * 0.15
    _both(img, mask, np.array([[x0 + w, y0], [x0 + w + d, y0 - d], [x0 + w + d, y0 + h - d], [x0 + w, y0 + h]]), _shade(color, 0.7))


def draw_clutter_item(img: np.ndarray, rng: np.random.Generator) -> None:
    h, w = img.shape[:2]
    c = (float(rng.uniform(0, w)), float(rng.uniform(0, h)))
    size = float(rng.uniform(0.03, 0.2) * max(h, w))
    kind = int(rng.integers(6))
    if kind == 0:
        draw_handwheel(img, rng, c, size / 2)
    elif kind == 1:
        draw_flange(img, rng, c, size / 2)
    elif kind == 2:
        draw_sign(img, rng, c, size)
    elif kind == 3:
        draw_cable(img, rng, None, c)
    else:
        draw_box(img, rng, None, c, size)


def draw_occluder(img: np.ndarray, mask: np.ndarray, rng: np.random.Generator, box: tuple[float, float, float, float]) -> None:
    """Something in front of the gauge in ``box``: crosses part of it, rarely the whole face."""
    x0, y0, x1, y1 = box
    size = max(x1 - x0, y1 - y0)
    # a point near the gauge's edge, so the occluder usually covers only a part of it
    a = rng.uniform(0, 2 * math.pi)
    r = rng.uniform(0.35, 0.75) * size
    p = ((x0 + x1) / 2 + r * math.cos(a), (y0 + y1) / 2 + r * math.sin(a))
    kind = int(rng.integers(3))
    if kind == 0:
        draw_pipe(img, rng, mask, p, radius=rng.uniform(0.05, 0.2) * size)
    elif kind == 1:
        draw_cable(img, rng, mask, p)
    else:
        draw_box(img, rng, mask, p, rng.uniform(0.2, 0.5) * size)
