"""Square crops of one gauge, as the crop model sees them after detection, with exact ground truth
and a needle segmentation mask in crop pixels.

A crop is a small scene: the gauge fills 55-98 % of the square (detector boxes are loose or tight),
seen from up to 60 degrees off-axis, with a background, sometimes a neighbouring gauge or an
occluder, and the camera model. A third of the crops are rendered at 12-60 % of the output size
and upsampled, like crops of small, far gauges; their ground truth and mask stay exact at the
output size.

Example::

    >>> from gauged.synth.crop import render_crop
    >>> sample = render_crop(7, size=448)
    >>> sample.image.shape, sample.needle_mask.shape, sample.truth["value"]  # doctest: +SKIP
    ((448, 448, 3), (448, 448), 3.71)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from gauged.synth.backgrounds import background_kind
from gauged.synth.camera import sample_camera
from gauged.synth.dial import outer_radius
from gauged.synth.params import GaugeParams
from gauged.synth.projection import Pose, ellipse_box, pose_homography, project_circle
from gauged.synth.sampling import sample_gauge
from gauged.synth.scene import GaugePlacement, SceneSpec, render_frame, sample_pose


@dataclass
class CropSample:
    """``image`` (size, size, 3) uint8 BGR; ``truth`` the gauge record of :mod:`gauged.synth.truth`
    in crop pixels; ``needle_mask`` (size, size) uint8: 0 background, 1 pointing part of the
    needle, 2 counterweight (the hub cap and occluders hide both); ``spec`` what was rendered."""

    image: np.ndarray
    truth: dict[str, Any]
    needle_mask: np.ndarray | None
    params: GaugeParams
    spec: SceneSpec
    output_scale: float


def as_generator(rng: np.random.Generator | int) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def frame_gauge(pose: Pose, params: GaugeParams, size: float, fill: float, centre: tuple[float, float]) -> Pose:
    """Scale and move ``pose`` so the gauge front's box spans ``fill * size`` px, centred on ``centre``."""
    rb = outer_radius(params)
    x0, y0, x1, y1 = ellipse_box(project_circle(pose_homography(pose), 0.0, 0.0, rb))
    k = fill * size / max(x1 - x0, y1 - y0)
    off = ((x0 + x1) / 2 - pose.center[0]) * k, ((y0 + y1) / 2 - pose.center[1]) * k
    # scaling diameter and focal together scales the whole image about the pivot
    return replace(pose, center=(centre[0] - off[0], centre[1] - off[1]), diameter_px=pose.diameter_px * k,
                   focal_px=pose.focal_px * k)


def sample_crop_spec(rng: np.random.Generator, size: int = 448, *, clean: bool = False,
                     direction: str = "cw") -> tuple[SceneSpec, float]:
    """A one-gauge scene for a crop, and the upsampling factor to reach ``size``; ``direction`` is
    :func:`~gauged.synth.sampling.sample_gauge`'s (for the neighbour too)."""
    render = size
    if not clean and rng.random() < 0.33:
        render = max(24, int(round(size * rng.uniform(0.12, 0.6))))
    params = sample_gauge(rng, clean=clean, direction=direction)
    pose = sample_pose(rng, (0.0, 0.0), 100.0, 100.0 * rng.uniform(1.5, 10.0))
    fill = rng.uniform(0.55, 0.98)
    jitter = rng.uniform(-0.06, 0.06, 2) * render if not clean else np.zeros(2)
    pose = frame_gauge(pose, params, render, fill, (render / 2 + jitter[0], render / 2 + jitter[1]))
    gain, gradient = (1.0, (0.0, 0.0)) if clean else (rng.uniform(0.7, 1.15), tuple(float(g) for g in rng.normal(0, 0.15, 2)))
    placements = [GaugePlacement(params, pose, "g0", gain, gradient, rng.uniform(0.9, 1.2),
                                 0.0 if clean else rng.uniform(0.0, 0.6))]
    if not clean and rng.random() < 0.12:  # a neighbour peeking in at an edge
        a = rng.uniform(0, 2 * math.pi)
        d = pose.diameter_px * rng.uniform(0.5, 1.2)
        dist = render * 0.5 + d * rng.uniform(0.1, 0.45)
        centre = (render / 2 + dist * math.cos(a), render / 2 + dist * math.sin(a))
        placements.append(GaugePlacement(sample_gauge(rng, direction=direction), sample_pose(rng, centre, d, pose.focal_px),
                                         "g1"))
    spec = SceneSpec(render, render, background_kind(rng), int(rng.integers(2**31)), tuple(placements),
                     sample_camera(rng, clean=clean, scale=render / 448), 0 if clean else int(rng.random() < 0.2),
                     int(rng.integers(2**31)), int(rng.integers(2**31)))
    return spec, size / render


def render_crop(rng: np.random.Generator | int, size: int = 448, *, clean: bool = False, masks: bool = True,
                direction: str = "cw") -> CropSample:
    """Render one square crop of a random gauge (deterministic for a seed or a Generator state).

    ``clean=True`` gives a sharp, frontal-ish render with no glass, shadow, noise or compression
    (for tests and curricula); ``masks`` adds the needle label map; ``direction`` ("cw", "ccw",
    "mixed") is which way the scale rises.
    """
    gen = as_generator(rng)
    spec, scale = sample_crop_spec(gen, size, clean=clean, direction=direction)
    result = render_frame(spec, output_scale=scale, masks=masks)
    return CropSample(result.image, result.truths[0].to_dict(), result.needle_masks[0] if masks else None,
                      spec.gauges[0].params, spec, scale)
