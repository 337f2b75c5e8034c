"""Photometric camera model: defocus and motion blur, exposure, white balance, vignetting, haze,
sensor noise, an on-screen-display caption, and JPEG compression.

:func:`sample_camera` draws a :class:`CameraParams`; :func:`apply_camera` turns a clean uint8 BGR
frame into what the camera would deliver. The per-frame noise comes from the Generator passed in,
so a sequence can keep the camera fixed and still have fresh noise on every frame.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, slots=True)
class CameraParams:
    exposure: float = 1.0  # linear gain
    gamma: float = 1.0
    white_balance: tuple[float, float, float] = (1.0, 1.0, 1.0)  # B, G, R gains
    vignette: float = 0.0  # darkening at the corners, 0..0.6
    defocus: float = 0.0  # disc blur radius in px
    motion: float = 0.0  # motion blur length in px
    motion_angle: float = 0.0
    noise: float = 0.0  # std of additive noise (0-255 scale) at mid grey
    haze: float = 0.0  # veil towards a grey-blue airlight, 0..0.4
    osd: str = ""  # caption burnt into the top-left corner, like inspection cameras do
    jpeg_quality: int | None = None


def sample_camera(rng: np.random.Generator, *, clean: bool = False, scale: float = 1.0) -> CameraParams:
    """Draw a camera. ``scale`` multiplies blur sizes (use the image size relative to 720p)."""
    if clean:
        return CameraParams()
    low_light = rng.random() < 0.1
    exposure = rng.uniform(0.25, 0.5) if low_light else min(1.5, math.exp(rng.normal(0.0, 0.2)))
    # white-balance errors lie mostly along blue-amber (colour temperature), little along green-magenta
    temperature, tint = rng.normal(0.0, 0.06), rng.normal(0.0, 0.015)
    wb = (math.exp(temperature), math.exp(tint), math.exp(-temperature))
    return CameraParams(
        exposure=exposure, gamma=math.exp(rng.normal(0.0, 0.12)), white_balance=wb,
        vignette=rng.uniform(0.0, 0.5) if rng.random() < 0.5 else 0.0,
        defocus=rng.uniform(0.5, 3.5) * scale if rng.random() < 0.3 else 0.0,
        motion=rng.uniform(1.0, 6.0) * scale if rng.random() < 0.12 else 0.0, motion_angle=rng.uniform(0, math.pi),
        noise=(rng.uniform(4, 14) if low_light else rng.uniform(0.0, 6.0)),
        haze=rng.uniform(0.05, 0.35) if rng.random() < 0.15 else 0.0,
        osd=_osd_caption(rng) if rng.random() < 0.1 else "",
        jpeg_quality=int(rng.integers(35, 96)) if rng.random() < 0.9 else None,
    )


def _osd_caption(rng: np.random.Generator) -> str:
    return f"CAM{int(rng.integers(1, 40)):02d}  2024-0{int(rng.integers(1, 10))}-1{int(rng.integers(0, 10))} " \
           f"{int(rng.integers(0, 24)):02d}:{int(rng.integers(0, 60)):02d}:{int(rng.integers(0, 60)):02d}"


def _motion_kernel(length: float, angle: float) -> np.ndarray:
    r = int(math.ceil(length / 2)) + 1
    k = np.zeros((2 * r + 1, 2 * r + 1), np.float32)
    dx, dy = math.cos(angle) * length / 2, math.sin(angle) * length / 2
    cv2.line(k, (int(round((r - dx) * 16)), int(round((r - dy) * 16))), (int(round((r + dx) * 16)), int(round((r + dy) * 16))),
             1.0, 1, cv2.LINE_AA, 4)
    return k / max(k.sum(), 1e-6)


def apply_optics(img: np.ndarray, cam: CameraParams) -> np.ndarray:
    """Blur only (defocus then motion); uint8 in, uint8 out."""
    if cam.defocus >= 0.6:
        # a Gaussian of matching spread stands in for the lens disc: separable, so ten times cheaper
        img = cv2.GaussianBlur(img, (0, 0), cam.defocus * 0.6, borderType=cv2.BORDER_REFLECT)
    if cam.motion >= 1.0:
        img = cv2.filter2D(img, -1, _motion_kernel(cam.motion, cam.motion_angle), borderType=cv2.BORDER_REFLECT)
    return img


def _tone_table(cam: CameraParams, gain: float) -> np.ndarray:
    """Per-channel lookup table (256, 1, 3) uint8 of haze, white balance, exposure and gamma."""
    v = np.arange(256, dtype=np.float64)[:, None] / 255.0
    air = np.array([0.82, 0.8, 0.76])[None, :]
    v = v * (1.0 - cam.haze) + cam.haze * air
    v = np.clip(v * np.asarray(cam.white_balance)[None, :] * (cam.exposure * gain), 0.0, 1.0) ** (1.0 / cam.gamma)
    return np.round(v * 255.0).astype(np.uint8).reshape(256, 1, 3)


def _vignette_map(height: int, width: int, strength: float) -> np.ndarray:
    """(height, width) float32 gain, 1 at the centre and 1 - strength at the corners."""
    gh, gw = max(2, height // 16), max(2, width // 16)  # smooth: compute coarse, resize
    y = (np.arange(gh, dtype=np.float32) + 0.5) / gh - 0.5
    x = (np.arange(gw, dtype=np.float32) + 0.5) / gw - 0.5
    r2 = (x[None, :] ** 2 + y[:, None] ** 2) * 2.0  # 1 at the corners
    coarse = 1.0 - np.float32(strength) * r2 * np.sqrt(r2)
    return cv2.resize(coarse, (width, height), interpolation=cv2.INTER_LINEAR)


_POOL_SIZE = 1 << 22


@functools.lru_cache(maxsize=1)
def _noise_pool() -> np.ndarray:
    """A fixed pool of standard normal samples; frames take random windows of it (drawing fresh
    normals for every pixel would cost more than the rest of the camera model)."""
    return np.random.default_rng(0x6A55).standard_normal(_POOL_SIZE, dtype=np.float32)


def _noise(rng: np.random.Generator, shape: tuple[int, ...], sigma: float) -> np.ndarray:
    n = int(np.prod(shape))
    pool = _noise_pool()
    if n > _POOL_SIZE:
        return rng.standard_normal(shape, dtype=np.float32) * np.float32(sigma)
    start = int(rng.integers(0, _POOL_SIZE - n + 1))
    return pool[start:start + n].reshape(shape) * np.float32(sigma)


def apply_camera(img: np.ndarray, cam: CameraParams, rng: np.random.Generator, *, gain: float = 1.0) -> np.ndarray:
    """Everything the camera does after the optics; ``gain`` multiplies the exposure (slow light
    changes of a sequence). uint8 BGR in, uint8 BGR out (JPEG-decoded when ``jpeg_quality`` is set)."""
    img = apply_optics(img, cam)
    h, w = img.shape[:2]
    out = cv2.LUT(img, _tone_table(cam, gain))
    if cam.vignette > 0:
        out = cv2.multiply(out, cv2.merge([_vignette_map(h, w, cam.vignette)] * 3), dtype=cv2.CV_8U)
    if cam.noise > 0:
        # luminance noise at full resolution, colour noise at half: demosaicing smears colour noise
        chroma = _noise(rng, ((h + 1) // 2, (w + 1) // 2, 3), cam.noise * 0.5)
        noise = cv2.resize(chroma, (w, h), interpolation=cv2.INTER_NEAREST)
        noise += _noise(rng, (h, w, 1), cam.noise)
        out = cv2.add(out, noise, dtype=cv2.CV_8U)  # saturating
    if cam.osd:
        scale = max(0.35, h / 1400.0)
        cv2.putText(out, cam.osd, (int(8 * scale), int(30 * scale)), cv2.FONT_HERSHEY_SIMPLEX, scale,
                    (235, 235, 235), max(1, int(2 * scale)), cv2.LINE_AA)
    if cam.jpeg_quality is not None:
        out = jpeg_roundtrip(out, cam.jpeg_quality)
    return out


def jpeg_roundtrip(img: np.ndarray, quality: int) -> np.ndarray:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError("JPEG encoding failed")
    return cv2.imdecode(buf, cv2.IMREAD_COLOR)
