"""Fonts of the renderer and a cache of rendered glyph strings.

Three families, all available without network or system packages:

- DejaVu subsets shipped in ``gauged/synth/fonts`` (see its README for provenance and licence);
- Pillow's built-in scalable font (``ImageFont.load_default(size=...)``, Pillow >= 10.1);
- OpenCV's Hershey vector fonts (``cv2.putText``), which look like engraved/plotted dial lettering.

:func:`text_mask` returns a float32 coverage mask of a string; masks are cached per (font, size,
text) because a dial repeats the same few strings and a sequence repeats whole dials.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, ImageDraw, ImageFont

FONT_DIR = Path(__file__).with_name("fonts")
MIN_SIZE_PX = 4.0  # below this glyphs are blobs anyway; keeps the cache small


@dataclass(frozen=True, slots=True)
class FontFace:
    """One renderable face. ``kind`` is ``ttf``, ``pil_default`` or ``hershey``."""

    key: str
    kind: str
    source: str | int = ""
    weight: float = 1.0  # Hershey stroke thickness relative to size
    ascii_only: bool = False


FONTS: dict[str, FontFace] = {f.key: f for f in (
    FontFace("sans", "ttf", "DejaVuSans.ttf"),
    FontFace("sans-bold", "ttf", "DejaVuSans-Bold.ttf"),
    FontFace("sans-condensed-bold", "ttf", "DejaVuSansCondensed-Bold.ttf"),
    FontFace("sans-condensed-oblique", "ttf", "DejaVuSansCondensed-Oblique.ttf"),
    FontFace("serif-bold", "ttf", "DejaVuSerif-Bold.ttf"),
    FontFace("serif-condensed", "ttf", "DejaVuSerifCondensed.ttf"),
    FontFace("mono-bold", "ttf", "DejaVuSansMono-Bold.ttf"),
    FontFace("pil-default", "pil_default"),
    FontFace("hershey-simplex", "hershey", cv2.FONT_HERSHEY_SIMPLEX, 0.07, True),
    FontFace("hershey-duplex", "hershey", cv2.FONT_HERSHEY_DUPLEX, 0.09, True),
    FontFace("hershey-complex", "hershey", cv2.FONT_HERSHEY_COMPLEX, 0.08, True),
    FontFace("hershey-triplex", "hershey", cv2.FONT_HERSHEY_TRIPLEX, 0.10, True),
    FontFace("hershey-plain-bold", "hershey", cv2.FONT_HERSHEY_PLAIN, 0.14, True),
)}
FONT_KEYS: tuple[str, ...] = tuple(FONTS)
FALLBACK = "sans"  # for strings a Hershey font cannot draw (degree sign, superscript two)


@functools.lru_cache(maxsize=64)
def _pil_font(key: str, size: float) -> ImageFont.FreeTypeFont:
    face = FONTS[key]
    if face.kind == "pil_default":
        return ImageFont.load_default(size=size)
    return ImageFont.truetype(str(FONT_DIR / str(face.source)), size=size)


def _render_pil(key: str, size: float, text: str) -> np.ndarray:
    font = _pil_font(key, size)
    x0, y0, x1, y1 = font.getbbox(text)
    pad = 2
    canvas = Image.new("L", (max(1, x1 - x0) + 2 * pad, max(1, y1 - y0) + 2 * pad), 0)
    ImageDraw.Draw(canvas).text((pad - x0, pad - y0), text, fill=255, font=font)
    return np.asarray(canvas, dtype=np.float32) / 255.0


def _render_hershey(face: FontFace, size: float, text: str) -> np.ndarray:
    # Hershey glyph cap height is about 22 px at scale 1; size is the em size like a TTF's.
    scale = 0.72 * size / 22.0
    if face.source == cv2.FONT_HERSHEY_PLAIN:
        scale *= 1.9
    thickness = max(1, int(round(face.weight * size)))
    (w, h), base = cv2.getTextSize(text, int(face.source), scale, thickness)
    pad = thickness + 2
    canvas = np.zeros((h + base + 2 * pad, w + 2 * pad), np.uint8)
    cv2.putText(canvas, text, (pad, pad + h), int(face.source), scale, 255, thickness, cv2.LINE_AA)
    return canvas.astype(np.float32) / 255.0


def _crop_to_ink(mask: np.ndarray, pad: int = 1) -> np.ndarray:
    ys, xs = np.nonzero(mask > 0.02)
    if len(xs) == 0:
        return np.zeros((1, 1), np.float32)
    y0, y1 = max(0, ys.min() - pad), min(mask.shape[0], ys.max() + 1 + pad)
    x0, x1 = max(0, xs.min() - pad), min(mask.shape[1], xs.max() + 1 + pad)
    return mask[y0:y1, x0:x1]


@functools.lru_cache(maxsize=8192)
def text_mask(key: str, size_px: float, text: str) -> np.ndarray:
    """Coverage mask of ``text`` in font ``key`` at em size ``size_px``.

    Returns a read-only (h, w) float32 array in [0, 1] cropped to the ink with a 1 px border, so
    the ink box is the mask box shrunk by 1 px. Sizes are quantised to 0.5 px.
    """
    size = max(MIN_SIZE_PX, round(size_px * 2.0) / 2.0)
    face = FONTS[key]
    if face.ascii_only and not text.isascii():
        face = FONTS[FALLBACK]
    if face.kind == "hershey":
        mask = _render_hershey(face, size, text)
    else:
        mask = _render_pil(face.key, size, text)
    mask = np.ascontiguousarray(_crop_to_ink(mask))
    mask.setflags(write=False)
    return mask
