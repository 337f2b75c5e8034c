"""Compose gauges into a camera frame: background, case and stem in 3-D, the dial warped through
its homography, occluders, camera effects; and the ground truth of every gauge.

A :class:`SceneSpec` is a complete, non-random description of a frame (the random draws happen in
:func:`sample_scene`), so rendering it twice gives the same bytes, and a sequence re-renders one
spec with other needle values, a little camera jitter and changing light
(:func:`render_frame` with a :class:`DialCache`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from gauged.synth import draw
from gauged.synth.backgrounds import background, background_kind
from gauged.synth.camera import CameraParams, apply_camera, sample_camera
from gauged.synth.clutter import draw_occluder
from gauged.synth.dial import DialRaster, dial_to_units, draw_dial, outer_radius
from gauged.synth.glass import GlassOverlay, apply_glass, glass_overlay
from gauged.synth.needle import NeedleGeometry, draw_needle, needle_geometry, needle_label_map
from gauged.synth.params import GaugeParams
from gauged.synth.projection import (Pose, apply_homography, ellipse_box, local_scale, pose_homography, pose_rotation,
                                     project_circle, project_points3d, to_cv, translation)
from gauged.synth.sampling import sample_gauge
from gauged.synth.truth import GaugeTruth, gauge_truth, image_record

MAX_RF = 320.0  # px per face unit of the dial raster; bigger faces are upsampled by the warp
MIN_RF = 12.0


@dataclass(frozen=True, slots=True)
class GaugePlacement:
    """A gauge in a scene: its parameters, pose, id, and local light (gain and its gradient per
    face diameter along x and y of the frame)."""

    params: GaugeParams
    pose: Pose
    gauge_id: str
    gain: float = 1.0
    gradient: tuple[float, float] = (0.0, 0.0)
    sharpness: float = 1.0  # dial raster resolution relative to what the frame needs
    shadow: float = 0.0  # strength of the shadow the gauge casts on what is behind it


@dataclass(frozen=True, slots=True)
class SceneSpec:
    width: int
    height: int
    background: str
    background_seed: int
    gauges: tuple[GaugePlacement, ...]
    camera: CameraParams
    occluders: int = 0
    occluder_seed: int = 0
    noise_seed: int = 0


@dataclass
class DialCache:
    """Static dial rasters and glass maps per gauge id, reused across the frames of a sequence."""

    rasters: dict[str, tuple[DialRaster, GlassOverlay]] = field(default_factory=dict)

    def get(self, placement: GaugePlacement) -> tuple[DialRaster, GlassOverlay]:
        key = placement.gauge_id
        if key not in self.rasters:
            self.rasters[key] = prepare_dial(placement)
        return self.rasters[key]


@dataclass
class FrameResult:
    """``image`` (H, W, 3) uint8 BGR; ``truths`` per gauge in spec order; ``needle_masks`` per gauge
    (uint8 label maps, see :func:`~gauged.synth.needle.needle_label_map`) when requested."""

    image: np.ndarray
    truths: list[GaugeTruth]
    needle_masks: list[np.ndarray] | None = None


def dial_resolution(placement: GaugePlacement) -> float:
    """px per face unit of the dial raster: the frame's largest local stretch, capped."""
    h = pose_homography(placement.pose)
    rf = local_scale(h) * 1.15 * placement.sharpness
    return float(min(MAX_RF, max(MIN_RF, rf)))


def prepare_dial(placement: GaugePlacement) -> tuple[DialRaster, GlassOverlay]:
    rf = dial_resolution(placement)
    raster = draw_dial(placement.params, rf)
    return raster, glass_overlay(placement.params, rf, raster.size)


def _light_vector(params: GaugeParams, pose: Pose) -> np.ndarray:
    la = params.glass.light_angle
    v = pose_rotation(pose) @ np.array([math.cos(la), math.sin(la), 0.0]) + np.array([0.0, 0.0, -1.2])
    return -v / np.linalg.norm(v)  # towards the light


def _draw_solid(frame: np.ndarray, pose: Pose, jitter: np.ndarray, quads3d: np.ndarray, centre: np.ndarray,
                color, light: np.ndarray) -> None:
    """Fill the camera-facing faces of a convex solid: ``quads3d`` (Q, 4, 3) in face units around ``centre``."""
    rot = pose_rotation(pose)
    mids = quads3d.mean(axis=1)
    normals = np.cross(quads3d[:, 1] - quads3d[:, 0], quads3d[:, 3] - quads3d[:, 0])
    normals *= np.sign(np.einsum("ij,ij->i", normals, mids - centre))[:, None]  # outward
    normals_cam = normals @ rot.T
    mids_cam = mids @ rot.T + np.array([0.0, 0.0, pose.distance])
    facing = np.einsum("ij,ij->i", normals_cam, mids_cam) < 0
    if not facing.any():
        return
    unit = normals_cam / (np.linalg.norm(normals_cam, axis=1, keepdims=True) + 1e-12)
    shades = 0.35 + 0.75 * np.maximum(0.0, unit @ light)
    pts = apply_homography(jitter, project_points3d(pose, quads3d.reshape(-1, 3))).reshape(-1, 4, 2)
    for q, shade in zip(pts[facing], shades[facing]):
        draw.fill_polygon(frame, q, tuple(float(min(255.0, c * shade)) for c in color))


def _box3d(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> np.ndarray:
    """The six faces of an axis-aligned box as (4, 3) quads."""
    v = lambda x, y, z: np.array([x, y, z], float)  # noqa: E731 - tiny constructor
    return np.array([[v(x0, y0, z0), v(x0, y1, z0), v(x1, y1, z0), v(x1, y0, z0)],
                     [v(x0, y0, z1), v(x1, y0, z1), v(x1, y1, z1), v(x0, y1, z1)],
                     [v(x0, y0, z0), v(x1, y0, z0), v(x1, y0, z1), v(x0, y0, z1)],
                     [v(x0, y1, z0), v(x0, y1, z1), v(x1, y1, z1), v(x1, y1, z0)],
                     [v(x0, y0, z0), v(x0, y0, z1), v(x0, y1, z1), v(x0, y1, z0)],
                     [v(x1, y0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, y0, z1)]])


def _drop_shadow(frame: np.ndarray, outline: np.ndarray, offset: np.ndarray, sigma: float, strength: float) -> None:
    """Darken the frame under the convex hull of ``outline`` shifted by ``offset`` (soft edge).

    The mask is drawn and blurred at reduced resolution: a blur of sigma s loses nothing at 1/(s/3).
    """
    pts = outline + offset
    pad = int(3 * sigma) + 2
    H, W = frame.shape[:2]
    x0, y0 = max(0, int(pts[:, 0].min()) - pad), max(0, int(pts[:, 1].min()) - pad)
    x1, y1 = min(W, int(pts[:, 0].max()) + pad), min(H, int(pts[:, 1].max()) + pad)
    if x1 <= x0 or y1 <= y0:
        return
    k = max(1.0, sigma / 3.0)
    sw, sh = max(1, int(math.ceil((x1 - x0) / k))), max(1, int(math.ceil((y1 - y0) / k)))
    mask = np.zeros((sh, sw), np.uint8)
    hull = cv2.convexHull(pts.astype(np.float32)).reshape(-1, 2)
    draw.fill_polygon(mask, (hull - np.array([x0, y0])) / k, 255)
    mask = cv2.GaussianBlur(mask, (0, 0), max(0.5, sigma / k))
    mask = cv2.resize(mask, (x1 - x0, y1 - y0), interpolation=cv2.INTER_LINEAR).astype(np.float32)
    mask *= np.float32(strength / 255.0)
    roi = frame[y0:y1, x0:x1].astype(np.float32)
    frame[y0:y1, x0:x1] = (roi * (1.0 - mask[..., None]) + 0.5).astype(np.uint8)


def draw_body(frame: np.ndarray, params: GaugeParams, pose: Pose, jitter: np.ndarray, shadow: float = 0.0) -> np.ndarray:
    """Draw the gauge's shadow, the stem and the cylindrical case behind the front; returns the
    case outline (N, 2) in frame px."""
    bez = params.bezel
    rb = outer_radius(params)
    light = _light_vector(params, pose)
    k = 48
    t = np.linspace(0.0, 2 * math.pi, k + 1)
    front = np.column_stack([rb * np.cos(t), rb * np.sin(t), np.zeros_like(t)])
    back = np.column_stack([0.97 * rb * np.cos(t), 0.97 * rb * np.sin(t), np.full_like(t, bez.case_depth)])
    outline = apply_homography(jitter, np.vstack([project_points3d(pose, front[:-1]), project_points3d(pose, back[:-1])]))
    if shadow > 0:
        la = params.glass.light_angle + pose.roll
        d = pose.diameter_px
        _drop_shadow(frame, outline, -0.08 * d * np.array([math.cos(la), math.sin(la)]), 0.05 * d, shadow)
    if bez.stem == "bottom":
        sw = 0.14
        z0 = bez.case_depth * 0.5 - sw
        length = 0.5
        stem_centre = np.array([0.0, rb + length / 2, z0 + sw])
        _draw_solid(frame, pose, jitter, _box3d(-sw, sw, rb * 0.9, rb + length, z0, z0 + 2 * sw), stem_centre,
                    bez.stem_color, light)
        _draw_solid(frame, pose, jitter, _box3d(-1.8 * sw, 1.8 * sw, rb + length * 0.3, rb + length * 0.6,
                                                 z0 - 0.6 * sw, z0 + 2.6 * sw), stem_centre, bez.stem_color, light)
    quads = np.stack([front[:-1], back[:-1], back[1:], front[1:]], axis=1)
    _draw_solid(frame, pose, jitter, quads, np.array([0.0, 0.0, bez.case_depth / 2]), bez.case_color, light)
    return outline


def _composite_dial(frame: np.ndarray, idmap: np.ndarray, index: int, placement: GaugePlacement, dial: np.ndarray,
                    alpha: np.ndarray, rf: float, h_units: np.ndarray) -> int:
    """Warp the dial raster into the frame and blend it; returns the silhouette area in px."""
    H, W = frame.shape[:2]
    rb = outer_radius(placement.params)
    x0, y0, x1, y1 = ellipse_box(project_circle(h_units, 0.0, 0.0, rb))
    area = math.pi / 4 * (x1 - x0) * (y1 - y0)
    x0, y0 = max(0, int(math.floor(x0)) - 1), max(0, int(math.floor(y0)) - 1)
    x1, y1 = min(W, int(math.ceil(x1)) + 1), min(H, int(math.ceil(y1)) + 1)
    if x1 <= x0 or y1 <= y0:
        return int(area)
    h_roi = translation(-x0, -y0) @ h_units @ dial_to_units(dial.shape[0], rf)
    m = to_cv(h_roi)
    size = (x1 - x0, y1 - y0)
    warped = cv2.warpPerspective(dial, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    a = cv2.warpPerspective(alpha, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    if placement.gradient != (0.0, 0.0):
        cx, cy = apply_homography(h_units, np.zeros((1, 2)))[0]
        d = max(placement.pose.diameter_px, 1.0)
        xs = (np.arange(x0, x1, dtype=np.float32) + 0.5 - cx) / d
        ys = (np.arange(y0, y1, dtype=np.float32) + 0.5 - cy) / d
        gain = placement.gain * (1.0 + placement.gradient[0] * xs[None, :] + placement.gradient[1] * ys[:, None])
        warped = cv2.multiply(warped, cv2.merge([gain, gain, gain]), dtype=cv2.CV_8U)  # saturating
    elif placement.gain != 1.0:
        warped = cv2.convertScaleAbs(warped, alpha=placement.gain)
    roi = frame[y0:y1, x0:x1]
    frame[y0:y1, x0:x1] = cv2.blendLinear(warped, roi, a, 1.0 - a)
    idmap[y0:y1, x0:x1][a > 0.5] = index
    return int(area)


def render_frame(spec: SceneSpec, *, cache: DialCache | None = None, values: dict[str, tuple[float, bool]] | None = None,
                 jitter: np.ndarray | None = None, light: float = 1.0, background_image: np.ndarray | None = None,
                 noise_rng: np.random.Generator | None = None, output_scale: float = 1.0,
                 masks: bool = False) -> FrameResult:
    """Render ``spec``. ``values`` maps gauge id -> (value, at_stop) to move needles; ``jitter`` is
    a (3, 3) image-plane homography of camera shake; ``light`` scales the exposure;
    ``output_scale`` upsamples the rendered frame (simulating a low-resolution source) while the
    truth and needle masks stay exact at the output size."""
    cache = cache or DialCache()
    jit = np.eye(3) if jitter is None else jitter
    W, H = spec.width, spec.height
    if background_image is None:
        background_image, _ = background(np.random.default_rng(spec.background_seed), H, W, spec.background)
    frame = background_image.copy()
    if jitter is not None:
        frame = cv2.warpPerspective(frame, to_cv(jit), (W, H), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    idmap = np.full((H, W), -1, np.int16)
    order = sorted(range(len(spec.gauges)), key=lambda i: spec.gauges[i].pose.diameter_px)
    geoms: dict[int, tuple[GaugeParams, NeedleGeometry, np.ndarray, np.ndarray, int, DialRaster]] = {}
    for i in order:
        pl = spec.gauges[i]
        params = pl.params
        if values and pl.gauge_id in values:
            params = params.with_value(*values[pl.gauge_id])
        h_units = jit @ pose_homography(pl.pose)
        body = draw_body(frame, params, pl.pose, jit, pl.shadow)
        raster, glass = cache.get(pl)
        dial = raster.image.copy()
        geom = needle_geometry(params.needle, params.needle_angle)
        draw_needle(dial, geom, params.needle, raster.rf)
        dial = apply_glass(dial, glass)
        area = _composite_dial(frame, idmap, i, pl, dial, raster.alpha, raster.rf, h_units)
        geoms[i] = (params, geom, h_units, body, area, raster)
    occluded = np.zeros((H, W), np.uint8)
    if spec.occluders and spec.gauges:
        orng = np.random.default_rng(spec.occluder_seed)
        for _ in range(spec.occluders):
            pl = spec.gauges[int(orng.integers(len(spec.gauges)))]
            cx, cy = pl.pose.center
            r = pl.pose.diameter_px / 2
            draw_occluder(frame, occluded, orng, (cx - r, cy - r, cx + r, cy + r))
        idmap[occluded > 127] = -1
    image = apply_camera(frame, spec.camera, noise_rng or np.random.default_rng(spec.noise_seed), gain=light)
    out_w, out_h = W, H
    if output_scale != 1.0:
        out_w, out_h = int(round(W * output_scale)), int(round(H * output_scale))
        image = cv2.resize(image, (out_w, out_h), interpolation=cv2.INTER_CUBIC)
        scale_h = np.diag([out_w / W, out_h / H, 1.0])
    else:
        scale_h = np.eye(3)
    counts = np.bincount((idmap.ravel() + 1).astype(np.int64), minlength=len(spec.gauges) + 1)
    truths, label_maps = [], []
    for i, pl in enumerate(spec.gauges):
        params, geom, h_units, body, area, raster = geoms[i]
        h_out = scale_h @ h_units
        visible = float(counts[i + 1]) / max(area, 1)
        truths.append(gauge_truth(params, raster.texts, geom, h_out, apply_homography(scale_h, body), (out_w, out_h),
                                  pl.gauge_id, min(1.0, visible), pl.pose.diameter_px * scale_h[0, 0],
                                  front=idmap == i, front_scale=W / out_w))
        if masks:  # hidden: whatever is not this gauge's front (occluders, other gauges in front)
            hidden = np.where(idmap == i, 0, 255).astype(np.uint8)
            if output_scale != 1.0:
                hidden = cv2.resize(hidden, (out_w, out_h), interpolation=cv2.INTER_LINEAR)
            label_maps.append(needle_label_map(geom, h_out, (out_h, out_w), hidden))
    return FrameResult(image, truths, label_maps if masks else None)


def sample_pose(rng: np.random.Generator, center: tuple[float, float], diameter: float, focal: float) -> Pose:
    """A camera pose: mostly near-frontal, up to 60 degrees off-axis; mostly upright."""
    tilt = math.radians(rng.uniform(0, 15) if rng.random() < 0.4 else rng.uniform(10, 60))
    roll = rng.normal(0, 0.12) if rng.random() < 0.75 else rng.uniform(-math.pi, math.pi)
    return Pose(center, diameter, tilt, rng.uniform(0, 2 * math.pi), roll, focal)


def sample_scene(rng: np.random.Generator, width: int = 1280, height: int = 720, *, n_gauges: int | None = None,
                 clean: bool = False, direction: str = "cw") -> SceneSpec:
    """A random scene of several gauges (0 to 6) with partial occlusion and a random camera;
    ``direction`` is :func:`~gauged.synth.sampling.sample_gauge`'s, for every gauge."""
    if n_gauges is None:
        n_gauges = int(rng.choice(7, p=[0.03, 0.3, 0.25, 0.2, 0.11, 0.06, 0.05]))
    focal = width * rng.uniform(0.6, 2.5)
    placements: list[GaugePlacement] = []
    circles: list[tuple[float, float, float]] = []
    # now and then a close-up gauge bigger than the frame (face diameters reach 1000 px)
    hi = 1000.0 if rng.random() < 0.1 else min(1000.0, 0.9 * height)
    for k in range(n_gauges):
        for _ in range(30):
            top = hi if k == 0 else hi / (1 + 0.6 * n_gauges)
            d = math.exp(rng.uniform(math.log(40.0), math.log(max(41.0, top))))
            cx = rng.uniform(-0.1 * d, width + 0.1 * d)
            cy = rng.uniform(-0.1 * d, height + 0.1 * d)
            if all(math.hypot(cx - x, cy - y) > 0.75 * (d / 2 + r) * 1.25 for x, y, r in circles):
                break
        else:
            continue
        circles.append((cx, cy, d / 2))
        params = sample_gauge(rng, clean=clean, direction=direction)
        pose = sample_pose(rng, (cx, cy), d, max(focal, 0.8 * d))
        gradient = (0.0, 0.0) if clean else tuple(float(g) for g in rng.normal(0, 0.15, 2))
        placements.append(GaugePlacement(params, pose, f"g{len(placements)}", 1.0 if clean else rng.uniform(0.7, 1.15),
                                         gradient, rng.uniform(0.9, 1.2), 0.0 if clean else rng.uniform(0.0, 0.6)))
    return SceneSpec(width, height, background_kind(rng), int(rng.integers(2**31)), tuple(placements),
                     sample_camera(rng, clean=clean, scale=height / 720),
                     0 if clean else int(rng.poisson(0.5)), int(rng.integers(2**31)), int(rng.integers(2**31)))


@dataclass
class SceneSample:
    """A rendered scene: ``image`` (height, width, 3) uint8 BGR and its ground-truth ``record``
    (the image record of :mod:`gauged.synth.truth`, ``image`` left ``None``)."""

    image: np.ndarray
    record: dict
    spec: SceneSpec


def render_scene(rng: np.random.Generator | int, width: int = 1280, height: int = 720, *, n_gauges: int | None = None,
                 clean: bool = False, direction: str = "cw") -> SceneSample:
    """Render a random full frame with several gauges (deterministic for a seed or Generator state);
    ``direction`` ("cw", "ccw", "mixed") is which way the gauges' scales rise."""
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    spec = sample_scene(gen, width, height, n_gauges=n_gauges, clean=clean, direction=direction)
    result = render_frame(spec)
    return SceneSample(result.image, image_record(result.truths, width, height), spec)
