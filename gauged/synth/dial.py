"""Draw the static part of a dial frontally: face, bands, notches, numbers, texts and bezel.

The dial raster is a square of ``size`` px with the pivot at its centre and ``rf`` px per face
unit; :func:`dial_to_units` is the map from its pixels to face units, so a homography from face
units to a frame composes with it to warp the raster into the frame. The needle and the glass are
drawn later (:mod:`gauged.synth.needle`, :mod:`gauged.synth.glass`) because they change per frame
or sit above the face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from gauged.synth import draw
from gauged.synth.fonts import text_mask
from gauged.synth.params import GaugeParams, ScaleParams, TextStyle
from gauged.synth.ranges import format_number, grid


@dataclass(frozen=True, slots=True)
class PlacedText:
    """A text printed on the dial. ``quad`` (4, 2) is its ink box in face units, corners in reading
    order (top-left, top-right, bottom-right, bottom-left of the text)."""

    text: str
    kind: str  # "number" | "unit" | "brand" | "serial" | "class" | "standard" | "other"
    quad: np.ndarray
    value: float | None = None
    scale: int | None = None


@dataclass(frozen=True, slots=True)
class DialRaster:
    """The static dial: ``image`` (size, size, 3) uint8 BGR, ``alpha`` (size, size) float32 silhouette
    of the whole gauge front, ``rf`` px per face unit, and the texts with their quads."""

    image: np.ndarray
    alpha: np.ndarray
    rf: float
    size: int
    texts: tuple[PlacedText, ...]


def outer_radius(params: GaugeParams) -> float:
    """Radius of the gauge front (face plus bezel) in face units."""
    return 1.0 + (params.bezel.width if params.bezel.style != "none" else 0.015)


def dial_size(params: GaugeParams, rf: float) -> int:
    return int(2 * math.ceil(outer_radius(params) * rf + 2))


def dial_to_units(size: int, rf: float) -> np.ndarray:
    """Homography (3, 3) from dial raster pixels to face units."""
    c = size / 2.0
    return np.array([[1.0 / rf, 0.0, -c / rf], [0.0, 1.0 / rf, -c / rf], [0.0, 0.0, 1.0]])


def units_to_dial(size: int, rf: float) -> np.ndarray:
    c = size / 2.0
    return np.array([[rf, 0.0, c], [0.0, rf, c], [0.0, 0.0, 1.0]])


def polar_grid(size: int, rf: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Radius (face units), cos and sin of the angle of every raster pixel centre; (size, size) float32."""
    coords = (np.arange(size, dtype=np.float32) + 0.5 - size / 2.0) / np.float32(rf)
    x, y = coords[None, :], coords[:, None]
    r = np.sqrt(x * x + y * y)
    inv = 1.0 / np.maximum(r, 1e-6)
    return r, x * inv, y * inv


def tick_extent(scale: ScaleParams, major: bool) -> tuple[float, float]:
    """Radial extent (r_in, r_out) of a notch in face units."""
    half_major = (scale.major_width * 1.3 if scale.major_style == "dot" else scale.major_length / 2.0)
    r = scale.radius
    if major:
        return r - half_major, r + half_major
    length = scale.minor_width * 2.6 if scale.minor_style == "dot" else scale.minor_length
    if scale.tick_side == "in":
        return r + half_major - length, r + half_major
    if scale.tick_side == "out":
        return r - half_major, r - half_major + length
    return r - length / 2.0, r + length / 2.0


def scale_marks(scale: ScaleParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Values of the labelled, major and minor notches of a scale (minor excludes majors)."""
    labels = grid(scale.min, scale.max, scale.label_step)
    majors = np.union1d(grid(scale.min, scale.max, scale.major_step), labels)
    minors = grid(scale.min, scale.max, scale.minor_step) if scale.minor_style != "none" else np.zeros(0)
    minors = np.array([v for v in minors if np.min(np.abs(majors - v)) > scale.minor_step * 1e-3])
    return labels, majors, minors


def _tick_polygon(scale: ScaleParams, angle: float, r0: float, r1: float, width: float, style: str) -> np.ndarray:
    u = np.array([math.cos(angle), math.sin(angle)])
    n = np.array([-u[1], u[0]])
    if style == "dot":
        return draw.circle_polygon(tuple((0.5 * (r0 + r1)) * u), width * 1.3, 20)
    w0, w1 = width / 2.0, width / 2.0
    if style == "wedge":
        w0, w1 = width * 0.12, width * 0.9
        if scale.tick_side == "out":
            w0, w1 = w1, w0
    return np.array([r0 * u - w0 * n, r1 * u - w1 * n, r1 * u + w1 * n, r0 * u + w0 * n])


def _place_text(img: np.ndarray, text: str, style: TextStyle, center: tuple[float, float], rotation: float,
                rf: float) -> tuple[np.ndarray, tuple[float, float]]:
    """Draw ``text`` centred on ``center`` (face units), rotated; returns its ink quad in units and
    its ink half-size (w/2, h/2) in units."""
    mask = text_mask(style.font, style.size * rf, text)
    h, w = mask.shape
    c = units_to_dial(img.shape[0], rf) @ np.array([center[0], center[1], 1.0])
    ca, sa = math.cos(rotation), math.sin(rotation)
    rot = np.array([[ca, -sa], [sa, ca]])
    t = c[:2] - rot @ np.array([w / 2.0, h / 2.0])
    affine = np.column_stack([rot, t])
    draw.paste_mask(img, mask, affine, style.color)
    ink = np.array([[1, 1], [w - 1, 1], [w - 1, h - 1], [1, h - 1]], dtype=float)
    quad_px = ink @ rot.T + t
    quad = (quad_px - img.shape[0] / 2.0) / rf
    return quad, (max(w - 2, 1) / (2 * rf), max(h - 2, 1) / (2 * rf))


def _draw_scale(img: np.ndarray, scale: ScaleParams, index: int, rf: float) -> list[PlacedText]:
    c = img.shape[0] / 2.0
    to_px = lambda pts: c + rf * np.asarray(pts)  # noqa: E731 - tiny local transform
    for band in scale.bands:
        a0, a1 = sorted((scale.angle_of(band.start), scale.angle_of(band.end)))
        draw.fill_polygon(img, to_px(draw.annular_sector((0, 0), band.inner, band.outer, a0, a1)), band.color)
    labels, majors, minors = scale_marks(scale)
    if scale.baseline:
        edge = tick_extent(scale, True)
        r = edge[1] if scale.tick_side == "in" else edge[0] if scale.tick_side == "out" else scale.radius
        hw = scale.baseline_width / 2.0
        poly = draw.annular_sector((0, 0), r - hw, r + hw, *scale.arc, step=0.01)
        draw.fill_polygon(img, to_px(poly), scale.color)
    r0, r1 = tick_extent(scale, False)
    polys = [to_px(_tick_polygon(scale, scale.angle_of(v), r0, r1, scale.minor_width, scale.minor_style))
             for v in minors]
    r0, r1 = tick_extent(scale, True)
    polys += [to_px(_tick_polygon(scale, scale.angle_of(v), r0, r1, scale.major_width, scale.major_style))
              for v in majors]
    draw.fill_polygons(img, polys, scale.color)

    placed = []
    for v in labels:
        text = format_number(float(v), scale.decimals, scale.decimal_comma)
        angle = scale.angle_of(float(v))
        u = (math.cos(angle), math.sin(angle))
        rotation = angle + math.pi / 2.0 if scale.number_orientation == "tangent" else 0.0
        mask = text_mask(scale.numbers.font, scale.numbers.size * rf, text)
        hw, hh = max(mask.shape[1] - 2, 1) / (2 * rf), max(mask.shape[0] - 2, 1) / (2 * rf)
        extent = hh if rotation else abs(hw * u[0]) + abs(hh * u[1])
        if scale.number_side == "in":
            rc = r0 - scale.number_gap - extent
        else:
            rc = r1 + scale.number_gap + extent
        quad, _ = _place_text(img, text, scale.numbers, (rc * u[0], rc * u[1]), rotation, rf)
        placed.append(PlacedText(text, "number", quad, float(v), index))
    if scale.unit_pos is not None and scale.unit_style is not None:
        quad, _ = _place_text(img, scale.unit_text, scale.unit_style, scale.unit_pos, 0.0, rf)
        placed.append(PlacedText(scale.unit_text, "unit", quad, None, index))
    return placed


def _face(params: GaugeParams, size: int, rf: float, r: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    face = params.face
    shade = 1.0 - face.gradient * np.minimum(r, 1.0) ** 2
    if face.texture > 0:
        grain = draw.fractal_noise(rng, size, size, max(2.0, rf * 0.2), octaves=3)
        shade = shade * (1.0 + face.texture * (grain - 0.5) * 2.0)
    img = np.asarray(face.color, np.float32)[None, None, :] * shade[..., None]
    return np.clip(img, 0, 255).astype(np.uint8)


def _bezel_luminance(params: GaugeParams, size: int, rf: float, rng: np.random.Generator) -> np.ndarray:
    """Smooth shading of the bezel ring (style, light, profile), float32 (size, size).

    Computed on a half-resolution grid: it varies slowly; the sharp edges are added at full size.
    """
    half = max(8, size // 2)
    r, cos_p, sin_p = polar_grid(half, rf * half / size)
    bez = params.bezel
    width = outer_radius(params) - 1.0
    s = np.clip((r - 1.0) / width, 0.0, 1.0)
    light = params.glass.light_angle
    facing = cos_p * math.cos(light) + sin_p * math.sin(light)  # +1 on the rim side facing the light
    if bez.style in ("chrome", "brass"):
        phi0 = light + 0.7
        cos2 = cos_p * cos_p - sin_p * sin_p
        sin2 = 2.0 * cos_p * sin_p
        band = np.cos(np.float32(math.pi) * (1.6 * s - 0.3))
        lum = (0.55 + 0.32 * (cos2 * math.cos(2 * phi0) + sin2 * math.sin(2 * phi0)) * band
               + 0.22 * facing * (1.0 - 2.0 * s) + 0.12 * np.sin(np.float32(2 * math.pi) * s))
    elif bez.style == "black":
        lum = 0.55 + 0.45 * np.maximum(facing, 0.0) * np.sin(np.float32(math.pi) * s) ** 2
    elif bez.style == "steel":
        bins = draw.value_noise(rng, 1, 720, 3.0)[0]
        idx = ((np.arctan2(sin_p, cos_p) + math.pi) * (719 / (2 * math.pi))).astype(np.int32)
        lum = 0.8 + 0.15 * facing * (1.0 - 2.0 * s) + 0.12 * (bins[idx] - 0.5)
    else:  # painted, none
        lum = 0.8 + 0.2 * facing * (1.0 - 2.0 * s)
    # keep colour * lum within 255 so no later clipping is needed
    top = 255.0 / max(1.0, float(max(bez.color)))
    np.clip(lum, 0.0, min(1.6, top), out=lum)
    return cv2.resize(lum.astype(np.float32), (size, size), interpolation=cv2.INTER_LINEAR)


def _bezel(params: GaugeParams, img: np.ndarray, r: np.ndarray, rf: float, rng: np.random.Generator) -> np.ndarray:
    """Composite the bezel ring over ``img`` in place; returns the silhouette alpha."""
    bez = params.bezel
    size = img.shape[0]
    rb = outer_radius(params)
    width = rb - 1.0
    alpha = np.clip((rb - r) * rf + 0.5, 0.0, 1.0)
    ring = np.clip((r - 1.0) * rf + 0.5, 0.0, 1.0)
    lum = _bezel_luminance(params, size, rf, rng)
    if bez.lip > 0:  # the dark groove between face and bezel, sharp at full resolution
        lum *= 0.35 + 0.65 * np.clip((r - 1.0 - bez.lip) * rf + 0.5, 0.0, 1.0)
    lum *= 1.0 - 0.45 * np.clip((r - 1.0 - 0.85 * width) / (0.15 * width), 0.0, 1.0)
    col = (lum[..., None] * np.asarray(bez.color, np.float32)[None, None, :]).astype(np.uint8)
    img[:] = cv2.blendLinear(col, img, ring, 1.0 - ring)
    if bez.flange:
        c = size / 2.0
        light = params.glass.light_angle
        for k in range(3):
            a = light + k * 2.0 * math.pi / 3.0 + 0.5
            rr = 1.0 + width * 0.6
            draw.fill_circle(img, (c + rf * rr * math.cos(a), c + rf * rr * math.sin(a)), rf * width * 0.18, (30, 30, 30))
    return alpha


def draw_dial(params: GaugeParams, rf: float) -> DialRaster:
    """Render the static dial of ``params`` at ``rf`` px per face unit (deterministic)."""
    size = dial_size(params, rf)
    rng = np.random.default_rng(params.texture_seed)
    r, _, _ = polar_grid(size, rf)
    img = _face(params, size, rf, r, rng)
    placed: list[PlacedText] = []
    for i, scale in enumerate(params.scales):
        placed += _draw_scale(img, scale, i, rf)
    for item in params.texts:
        quad, _ = _place_text(img, item.text, item.style, item.center, item.rotation, rf)
        placed.append(PlacedText(item.text, item.kind, quad))
    c = size / 2.0
    for sx, sy in params.screws:
        centre = (c + rf * sx, c + rf * sy)
        draw.fill_circle(img, centre, rf * params.screw_radius, (70, 120, 150))
        draw.fill_circle(img, (centre[0] - rf * params.screw_radius * 0.3, centre[1] - rf * params.screw_radius * 0.3),
                         rf * params.screw_radius * 0.45, (150, 200, 225))
    if params.stop_pin is not None:
        a, rad, pin = params.stop_pin
        centre = (c + rf * rad * math.cos(a), c + rf * rad * math.sin(a))
        draw.fill_circle(img, centre, rf * pin, (90, 90, 90))
        draw.fill_circle(img, (centre[0] - rf * pin * 0.3, centre[1] - rf * pin * 0.3), rf * pin * 0.45, (200, 200, 200))
    alpha = _bezel(params, img, r, rf, rng)
    return DialRaster(img, alpha.astype(np.float32), rf, size, tuple(placed))
