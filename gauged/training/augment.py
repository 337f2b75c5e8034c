"""Augmentations applied while training: geometric (with its labels) and photometric (numpy + cv2).

Renders already vary camera, light and blur; these add what a fixed set of images lacks — new
rotations, scales, colours and compression for every epoch — and, for the real photos, the only
variation they get. Never a mirror: a mirrored dial runs counter-clockwise, which no gauge does.
"""

from __future__ import annotations

import cv2
import numpy as np


def random_affine(size: int, rng: np.random.Generator, max_rotation_deg: float = 180.0,
                  scale_range: tuple[float, float] = (0.85, 1.15), max_shift: float = 0.06) -> np.ndarray:
    """A 2x3 affine (pixel-edge coordinates) rotating/scaling about the image centre and shifting."""
    angle = np.deg2rad(rng.uniform(-max_rotation_deg, max_rotation_deg))
    scale = rng.uniform(*scale_range)
    cos, sin = scale * np.cos(angle), scale * np.sin(angle)
    centre = size / 2
    shift = rng.uniform(-max_shift, max_shift, 2) * size
    return np.array([[cos, -sin, centre - cos * centre + sin * centre + shift[0]],
                     [sin, cos, centre - sin * centre - cos * centre + shift[1]]])


def warp_image(image: np.ndarray, matrix: np.ndarray, size: int, nearest: bool = False) -> np.ndarray:
    """Warp by a 2x3 affine given in pixel-edge coordinates (our convention) to ``size``²."""
    # cv2 maps pixel centres (integer indices); convert: edge = index + 0.5.
    to_index = matrix.copy()
    to_index[:, 2] += matrix[:, 0] * 0.5 + matrix[:, 1] * 0.5 - 0.5
    flags = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.warpAffine(image, to_index, (size, size), flags=flags, borderMode=cv2.BORDER_REFLECT_101)


def warp_points(points: np.ndarray | None, matrix: np.ndarray) -> np.ndarray | None:
    if points is None:
        return None
    pts = np.asarray(points, float).reshape(-1, 2)
    return pts @ matrix[:, :2].T + matrix[:, 2]


def photometric(image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Random brightness/contrast/gamma, colour cast, blur, noise and JPEG on a (H, W, 3) uint8 image."""
    out = image.astype(np.float32)
    if rng.random() < 0.8:
        out = out * rng.uniform(0.6, 1.3) + rng.uniform(-30, 30)
    if rng.random() < 0.5:
        out = out * rng.uniform(0.85, 1.15, 3)[None, None, :]
    if rng.random() < 0.3:
        gray = out.mean(axis=2, keepdims=True)
        out = gray + (out - gray) * rng.uniform(0.0, 1.0)
    out = out.clip(0, 255)
    if rng.random() < 0.4:
        gamma = rng.uniform(0.6, 1.6)
        out = 255.0 * (out / 255.0) ** gamma
    if rng.random() < 0.3:
        k = int(rng.choice([3, 5]))
        out = cv2.GaussianBlur(out, (k, k), 0)
    if rng.random() < 0.4:
        out = out + rng.normal(0, rng.uniform(2, 12), out.shape).astype(np.float32)
    out = out.clip(0, 255).astype(np.uint8)
    if rng.random() < 0.4:
        quality = int(rng.integers(25, 90))
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, quality])
        if ok:
            out = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out
