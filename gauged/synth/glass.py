"""What the cover glass does to a dial: bezel shadow, glare, reflections, dirt, scratches, fog and
condensation.

All effects together are one affine colour map ``out = in * mul + add`` over the dial raster, built
once per gauge (:func:`glass_overlay`) and applied per frame after the needle is drawn
(:func:`apply_glass`), so the needle sits under the glass like on a real gauge. Smooth components
are computed on a coarse grid and resized; the seed of the gauge makes them deterministic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.synth import draw
from gauged.synth.params import GaugeParams


@dataclass(frozen=True, slots=True)
class GlassOverlay:
    """``mul`` and ``add`` are (size, size, 1) float32 (grey: glass does not tint); ``None`` when
    the glass is perfectly clean."""

    mul: np.ndarray | None
    add: np.ndarray | None


def _coarse_grid(size: int, rf: float, cells: int) -> tuple[np.ndarray, np.ndarray]:
    coords = (np.arange(cells, dtype=np.float32) + 0.5) * (size / cells) - size / 2.0
    coords /= np.float32(rf)
    return coords[None, :], coords[:, None]


def glass_overlay(params: GaugeParams, rf: float, size: int) -> GlassOverlay:
    """Build the glass colour map of ``params`` for a dial raster of ``size`` px at ``rf`` px/unit."""
    g = params.glass
    rng = np.random.default_rng(params.texture_seed + 7919)
    if not (g.glare or g.reflections or g.dirt or g.specks or g.scratches or g.condensation or g.fog or g.rim_shadow
            or g.liquid):
        return GlassOverlay(None, None)
    cells = int(min(size, 96))
    x, y = _coarse_grid(size, rf, cells)
    r = np.sqrt(x * x + y * y)
    inside = np.clip((1.0 - r) * rf + 0.5, 0.0, 1.0)  # the glass covers the face opening only
    mul = np.ones((cells, cells), np.float32)
    add = np.zeros((cells, cells), np.float32)
    if g.rim_shadow > 0:
        la = g.light_angle
        ox, oy = -0.07 * math.cos(la), -0.07 * math.sin(la)  # shadow falls away from the light
        rs = np.sqrt((x - ox) ** 2 + (y - oy) ** 2)
        mul *= 1.0 - g.rim_shadow * np.clip((rs - 0.86) / 0.16, 0.0, 1.0) ** 1.5
    if g.glare > 0:
        ca, sa = math.cos(g.glare_angle), math.sin(g.glare_angle)
        dx, dy = x - g.glare_center[0], y - g.glare_center[1]
        u = (dx * ca + dy * sa) / g.glare_size[0]
        v = (-dx * sa + dy * ca) / g.glare_size[1]
        add += 255.0 * g.glare * np.exp(-(u * u + v * v) * 1.5)
    if g.reflections:
        refl = np.zeros((cells, cells), np.float32)
        for _ in range(g.reflections):
            cx, cy = rng.uniform(-0.8, 0.8, 2)
            w, h = rng.uniform(0.05, 0.35), rng.uniform(0.1, 0.6)
            ang = rng.uniform(0, math.pi)
            k = cells * rf / size  # coarse cells per face unit
            centre = (float((cx * rf + size / 2.0) * cells / size - 0.5), float((cy * rf + size / 2.0) * cells / size - 0.5))
            rect = cv2.boxPoints((centre, (float(w * k), float(h * k)), math.degrees(ang)))
            cv2.fillPoly(refl, [np.round(rect).astype(np.int32)], float(rng.uniform(0.3, 1.0)), cv2.LINE_AA)
        refl = cv2.GaussianBlur(refl, (0, 0), max(0.7, cells / 60.0))
        add += refl * 255.0 * 0.18
    if g.dirt > 0:
        noise = draw.fractal_noise(rng, cells, cells, cells / 5.0, octaves=3)
        mul *= 1.0 - g.dirt * noise ** 2
    if g.fog > 0:
        mul *= 1.0 - g.fog
        add += g.fog * 200.0 * (0.8 + 0.2 * draw.value_noise(rng, cells, cells, cells / 3.0))
    mul = 1.0 + (mul - 1.0) * inside
    add = add * inside
    mul_full = cv2.resize(mul, (size, size), interpolation=cv2.INTER_LINEAR)
    add_full = cv2.resize(add, (size, size), interpolation=cv2.INTER_LINEAR)
    _fine_detail(params, rng, rf, size, mul_full, add_full)
    if g.liquid:
        _liquid(params, rf, size, mul_full, add_full)
    return GlassOverlay(mul_full[..., None], add_full[..., None])


def _fine_detail(params: GaugeParams, rng: np.random.Generator, rf: float, size: int,
                 mul: np.ndarray, add: np.ndarray) -> None:
    """Specks, scratches and droplets: drawn at full resolution because they are small."""
    g = params.glass
    c = size / 2.0
    if g.specks:
        dark = np.zeros((size, size), np.uint8)
        for _ in range(g.specks):
            rr, a = math.sqrt(rng.uniform(0, 1)) * 0.97, rng.uniform(0, 2 * math.pi)
            draw.fill_circle(dark, (c + rf * rr * math.cos(a), c + rf * rr * math.sin(a)),
                             max(0.4, rf * rng.uniform(0.003, 0.012)), int(rng.integers(60, 200)))
        mul *= 1.0 - dark.astype(np.float32) / 255.0 * 0.8
    if g.scratches:
        light = np.zeros((size, size), np.uint8)
        for _ in range(g.scratches):
            p0 = rng.uniform(-0.9, 0.9, 2)
            d = rng.normal(size=2)
            d /= np.linalg.norm(d) + 1e-9
            ln = rng.uniform(0.1, 0.8)
            pts = np.array([p0, p0 + d * ln * 0.5 + rng.normal(0, 0.02, 2), p0 + d * ln])
            draw.stroke_polyline(light, c + rf * pts, int(rng.integers(40, 140)), 1)
        add += light.astype(np.float32) * 0.6
    if g.condensation > 0:
        drops = np.zeros((size, size), np.uint8)
        rims = np.zeros((size, size), np.uint8)
        count = int(g.condensation * 250)
        for _ in range(count):
            rr, a = math.sqrt(rng.uniform(0, 1)) * 0.98, rng.uniform(0, 2 * math.pi)
            # condensation gathers on the lower half of a vertical glass
            if math.sin(a) < -0.2 and rng.random() < 0.6:
                continue
            centre = (c + rf * rr * math.cos(a), c + rf * rr * math.sin(a))
            rad = rf * rng.uniform(0.006, 0.03)
            draw.fill_circle(drops, centre, rad, 255)
            draw.fill_circle(rims, (centre[0] - rad * 0.3, centre[1] - rad * 0.3), max(0.4, rad * 0.35), 255)
        d = drops.astype(np.float32) / 255.0
        mul *= 1.0 - 0.35 * d
        add += rims.astype(np.float32) * 0.5 + d * 40.0


def _liquid(params: GaugeParams, rf: float, size: int, mul: np.ndarray, add: np.ndarray) -> None:
    """A glycerine-filled case: the air bubble above the liquid is brighter, and the meniscus, curved
    up where it meets the glass, is a dark line."""
    y = params.glass.liquid  # < 0: above the pivot
    c = size / 2.0
    half = math.sqrt(max(1.0 - y * y, 0.0))
    xs = np.linspace(-half, half, 41)
    meniscus = y - 0.04 * (np.abs(xs) / max(half, 1e-6)) ** 6
    # the bubble: the chord left to right, then the face rim back over the top
    arc = np.linspace(math.atan2(meniscus[-1], half), math.atan2(meniscus[0], -half), 40)
    bubble = np.vstack([np.column_stack([xs, meniscus]), np.column_stack([np.cos(arc), np.sin(arc)])])
    mask = np.zeros((size, size), np.uint8)
    draw.fill_polygon(mask, c + rf * bubble, 255)
    add += mask.astype(np.float32) * (14.0 / 255.0)
    line = np.zeros((size, size), np.uint8)
    draw.stroke_polyline(line, c + rf * np.column_stack([xs, meniscus]), 255, max(1.0, rf * 0.012))
    mul *= 1.0 - 0.4 * line.astype(np.float32) / 255.0


def apply_glass(img: np.ndarray, overlay: GlassOverlay) -> np.ndarray:
    """``img * mul + add`` as uint8 (a new array); ``img`` unchanged when the glass is clean."""
    if overlay.mul is None:
        return img
    out = img.astype(np.float32) * overlay.mul + overlay.add
    return np.clip(out, 0, 255).astype(np.uint8)
