"""Needle geometry, drawing, shadow and segmentation masks.

The needle is a set of polygons in face units: the *pointing part* (pivot to tip), the
*counterweight* (behind the pivot) and the hub cap (a disc over the pivot). Polygons with straight
edges map exactly through a homography, so the ground-truth polygon and the mask drawn in a frame
are exact for any camera pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.synth import draw
from gauged.synth.params import NeedleParams
from gauged.synth.projection import apply_homography


@dataclass(frozen=True, slots=True)
class NeedleGeometry:
    """Needle polygons in face units at one angle. ``counterweight`` holds simple polygons (each
    filled on its own; a ring is one contour round the outer and back round the inner circle);
    ``hub`` approximates the hub cap; ``tip`` is the pointing end; the pivot is the origin."""

    angle: float
    pointing: np.ndarray  # (N, 2)
    counterweight: tuple[np.ndarray, ...]
    hub: np.ndarray  # (M, 2)
    tip: np.ndarray  # (2,)


def _rotate(points: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(points, dtype=float) @ np.array([[c, s], [-s, c]])


def _pointing_local(p: NeedleParams) -> np.ndarray:
    hb, ht, tip = p.width / 2.0, p.tip_width / 2.0, p.tip_radius
    if p.shape == "arrow":
        head = min(0.12, tip * 0.2)
        aw = max(hb * 2.5, 0.025)
        return np.array([[0, -hb], [tip - head, -hb], [tip - head, -aw], [tip, 0],
                         [tip - head, aw], [tip - head, hb], [0, hb]])
    if p.shape == "lance":
        wide = max(hb * 1.8, 0.03)
        return np.array([[0, -hb], [tip * 0.3, -wide], [tip, -ht], [tip, ht], [tip * 0.3, wide], [0, hb]])
    if p.shape == "line":
        return np.array([[0, -hb], [tip, -hb], [tip, hb], [0, hb]])
    # tapered: straight taper ending in a short point
    point = min(tip * 0.08, max(ht * 4.0, 0.01))
    return np.array([[0, -hb], [tip - point, -ht], [tip, 0], [tip - point, ht], [0, hb]])


def _counterweight_local(p: NeedleParams) -> tuple[np.ndarray, ...]:
    hb, tail, tw = p.width / 2.0, p.tail_length, p.tail_width
    stub = np.array([[-max(tail * 0.6, 0.04), -hb], [0, -hb], [0, hb], [-max(tail * 0.6, 0.04), hb]])
    if p.counterweight == "none":
        return (np.array([[-0.04, -hb], [0, -hb], [0, hb], [-0.04, hb]]),)
    if p.counterweight == "tail":
        return (np.array([[0, -hb], [-tail, -tw * 0.5], [-tail, tw * 0.5], [0, hb]]),)
    if p.counterweight == "paddle":
        return (np.array([[0, -hb], [-tail * 0.85, -tw], [-tail, -tw * 0.8], [-tail, tw * 0.8],
                          [-tail * 0.85, tw], [0, hb]]),)
    if p.counterweight == "disc":
        return stub, draw.circle_polygon((-tail, 0.0), tw, 32)
    # ring: one contour running round the outer circle and back round the inner one, so the hole
    # is a hole under any fill rule (the two bridge edges coincide)
    t = np.linspace(0.0, 2 * math.pi, 33)
    outer = np.column_stack([-tail + tw * np.cos(t), tw * np.sin(t)])
    inner = np.column_stack([-tail + 0.55 * tw * np.cos(t[::-1]), 0.55 * tw * np.sin(t[::-1])])
    return stub, np.vstack([outer, inner])


def needle_geometry(p: NeedleParams, angle: float) -> NeedleGeometry:
    """Polygons of needle ``p`` pointing at dial angle ``angle`` (radians)."""
    pointing = _rotate(_pointing_local(p), angle)
    cw = tuple(_rotate(poly, angle) for poly in _counterweight_local(p))
    hub = draw.circle_polygon((0.0, 0.0), p.hub_radius, 40)
    tip = np.array([math.cos(angle), math.sin(angle)]) * p.tip_radius
    return NeedleGeometry(angle, pointing, cw, hub, tip)


def _fill_each(img: np.ndarray, polys: list[np.ndarray], color: tuple | float) -> None:
    """Fill polygons one by one (a single fillPoly call would XOR their overlaps)."""
    for poly in polys:
        draw.fill_polygon(img, poly, color)


SUPERSAMPLE = 4  # OpenCV's anti-aliasing biases thin shapes by up to 0.3 degrees; 4x coverage does not


def coverage(polys: list[np.ndarray], shape: tuple[int, int]) -> tuple[np.ndarray, int, int]:
    """Area coverage in [0, 1] of the union of ``polys`` (image px) over the pixels of an image of
    ``shape`` (height, width): float32 (h, w) over the polygons' box, and that box's top-left (x0, y0)."""
    allpts = np.vstack(polys)
    h, w = shape
    x0, y0 = max(0, int(allpts[:, 0].min()) - 2), max(0, int(allpts[:, 1].min()) - 2)
    x1, y1 = min(w, int(allpts[:, 0].max()) + 3), min(h, int(allpts[:, 1].max()) + 3)
    if x1 <= x0 or y1 <= y0:
        return np.zeros((0, 0), np.float32), 0, 0
    k = SUPERSAMPLE if (x1 - x0) * (y1 - y0) < 250_000 else 2
    big = np.zeros(((y1 - y0) * k, (x1 - x0) * k), np.uint8)
    origin = np.array([x0, y0], dtype=float)
    for poly in polys:
        draw.fill_polygon(big, (poly - origin) * k, 255)
    cover = cv2.resize(big, (x1 - x0, y1 - y0), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0
    return cover, x0, y0


def _fill_supersampled(img: np.ndarray, polys: list[np.ndarray], color: tuple) -> None:
    cover, x0, y0 = coverage(polys, img.shape[:2])
    if cover.size:
        draw.blend(img, cover, color, x0, y0)


def draw_needle(img: np.ndarray, geom: NeedleGeometry, p: NeedleParams, rf: float) -> None:
    """Draw shadow, needle and hub into the dial raster ``img`` (size, size, 3) uint8 in place."""
    c = img.shape[0] / 2.0
    to_px = lambda pts: c + rf * np.asarray(pts)  # noqa: E731 - tiny local transform
    if p.shadow_strength > 0:
        off = np.array(p.shadow_offset)
        shapes = [to_px(geom.pointing + off)] + [to_px(q + off) for q in geom.counterweight] + [to_px(geom.hub + off)]
        allpts = np.vstack(shapes)
        sigma = max(0.5, p.shadow_blur * rf)
        pad = int(3 * sigma) + 2
        x0 = max(0, int(allpts[:, 0].min()) - pad)
        y0 = max(0, int(allpts[:, 1].min()) - pad)
        x1 = min(img.shape[1], int(allpts[:, 0].max()) + pad)
        y1 = min(img.shape[0], int(allpts[:, 1].max()) + pad)
        if x1 > x0 and y1 > y0:
            mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
            shift = np.array([x0, y0], dtype=float)
            _fill_each(mask, [q - shift for q in shapes], 255)
            mask = cv2.GaussianBlur(mask, (0, 0), sigma).astype(np.float32) * (p.shadow_strength / 255.0)
            roi = img[y0:y1, x0:x1].astype(np.float32)
            img[y0:y1, x0:x1] = np.clip(roi * (1.0 - mask[..., None]) + 0.5, 0, 255).astype(np.uint8)
    _fill_supersampled(img, [to_px(geom.pointing)] + [to_px(q) for q in geom.counterweight], p.color)
    hub_px = c + 0.0
    draw.fill_circle(img, (hub_px, hub_px), rf * p.hub_radius, p.hub_color)
    if p.hub_style == "chrome":
        hi = tuple(min(255, int(v * 0.5 + 140)) for v in p.hub_color)
        draw.fill_circle(img, (hub_px - rf * p.hub_radius * 0.25, hub_px - rf * p.hub_radius * 0.25),
                         rf * p.hub_radius * 0.45, hi)
    elif p.hub_style == "screw":
        inner = tuple(int(v * 0.6) for v in p.hub_color)
        draw.fill_circle(img, (hub_px, hub_px), rf * p.hub_radius * 0.55, inner)
        slot = _rotate(np.array([[-1, -0.12], [1, -0.12], [1, 0.12], [-1, 0.12]]) * p.hub_radius * 0.5, geom.angle + 0.6)
        draw.fill_polygon(img, to_px(slot), (20, 20, 20))


def needle_label_map(geom: NeedleGeometry, h: np.ndarray, shape: tuple[int, int],
                     occluder: np.ndarray | None = None) -> np.ndarray:
    """Segmentation of the needle drawn through ``h`` (face units -> image px) in an image of
    ``shape`` (height, width): uint8 with 0 background, 1 pointing part, 2 counterweight; a pixel
    belongs to a part when that part covers at least half of it. The hub cap hides both;
    ``occluder`` (uint8, 255 = hidden) hides whatever covers the gauge."""
    labels = np.zeros(shape, np.uint8)
    parts = [(2, [apply_homography(h, q) for q in geom.counterweight]), (1, [apply_homography(h, geom.pointing)])]
    for label, polys in parts:
        cover, x0, y0 = coverage(polys, shape)
        if cover.size:
            roi = labels[y0:y0 + cover.shape[0], x0:x0 + cover.shape[1]]
            roi[cover >= 0.5] = label
    hub = np.zeros(shape, np.uint8)
    draw.fill_polygon(hub, apply_homography(h, geom.hub), 255)
    labels[hub >= 128] = 0
    if occluder is not None:
        labels[occluder >= 128] = 0
    return labels
