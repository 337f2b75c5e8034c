"""Procedural backgrounds: painted walls, concrete, brushed or panelled metal, pipe racks,
foliage-like noise, sky with poles and wires, cluttered walls, and plain studio backdrops.

Each kind is a function ``(rng, height, width) -> (height, width, 3) uint8 BGR``; smooth parts are
drawn coarse and resized, so a 1280x720 background costs a few milliseconds.
"""

from __future__ import annotations

import cv2
import numpy as np

from gauged.synth import draw
from gauged.synth.clutter import draw_clutter_item, draw_pipe

WALL_COLORS = ((200, 200, 195), (170, 185, 190), (120, 150, 160), (150, 150, 150), (90, 110, 60), (60, 90, 150),
               (140, 120, 90), (210, 220, 225), (80, 80, 85))


def _tint(rng: np.random.Generator, base: tuple[int, int, int], spread: float = 3.0) -> np.ndarray:
    """``base`` made lighter or darker as a whole, with a little independent colour change (large
    independent changes turn greys lavender or green, which plant walls are not)."""
    shade = rng.normal(0, 4 * spread)
    return np.clip(np.asarray(base, np.float32) + shade + rng.normal(0, spread, 3), 0, 255).astype(np.float32)


def _u8(img: np.ndarray) -> np.ndarray:
    return np.clip(img, 0, 255).astype(np.uint8)


def _shade(rng: np.random.Generator, h: int, w: int, amount: float) -> np.ndarray:
    """A smooth illumination field in [1 - amount, 1 + amount/2]."""
    gx, gy = rng.normal(0, 1, 2)
    y = np.linspace(-1, 1, h, dtype=np.float32)[:, None]
    x = np.linspace(-1, 1, w, dtype=np.float32)[None, :]
    field = 0.5 * (gx * x + gy * y) / (abs(gx) + abs(gy) + 1e-6) + 0.5 * (draw.value_noise(rng, h, w, max(h, w) / 3) - 0.5)
    return 1.0 + amount * field


def wall(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    base = _tint(rng, WALL_COLORS[int(rng.integers(len(WALL_COLORS)))])
    grain = draw.fractal_noise(rng, h, w, 60.0, 4)
    img = _u8(base[None, None, :] * (_shade(rng, h, w, 0.35) * (0.92 + 0.16 * grain))[..., None])
    if rng.random() < 0.5:  # tiles or panel seams
        step = int(rng.integers(60, 260))
        seam = tuple(float(v) for v in base * 0.6)
        for x in range(int(rng.integers(0, step)), w, step):
            cv2.line(img, (x, 0), (x, h), seam, int(rng.integers(1, 4)))
        if rng.random() < 0.6:
            for y in range(int(rng.integers(0, step)), h, step):
                cv2.line(img, (0, y), (w, y), seam, int(rng.integers(1, 4)))
    return np.clip(img, 0, 255).astype(np.uint8)


def studio(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """A plain light backdrop with a soft gradient, like the product photos in public gauge datasets."""
    base = _tint(rng, (235, 235, 235), 6)
    return _u8(base[None, None, :] * _shade(rng, h, w, 0.15)[..., None])


def concrete(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    base = _tint(rng, (150, 155, 158))
    n = draw.fractal_noise(rng, h, w, 120.0, 5)
    speck = rng.random((h // 2, w // 2), dtype=np.float32)
    speck = cv2.resize((speck > 0.97).astype(np.float32), (w, h), interpolation=cv2.INTER_LINEAR)
    lum = (0.75 + 0.4 * n - 0.25 * speck) * _shade(rng, h, w, 0.3)
    img = _u8(base[None, None, :] * lum[..., None])
    for _ in range(int(rng.integers(0, 3))):  # cracks
        pts = np.cumsum(rng.normal(0, 4, (30, 2)), axis=0) + rng.uniform(0, [w, h])
        draw.stroke_polyline(img, pts, tuple(float(v) for v in base * 0.45), 1)
    return np.clip(img, 0, 255).astype(np.uint8)


def metal(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    base = _tint(rng, (165, 165, 160))
    streak = rng.random((max(2, h // 2), 8), dtype=np.float32)
    streak = cv2.resize(streak, (w, h), interpolation=cv2.INTER_LINEAR)
    if rng.random() < 0.5:
        streak = cv2.resize(cv2.resize(rng.random((8, max(2, w // 2)), dtype=np.float32), (w, h)), (w, h))
    lum = (0.8 + 0.2 * streak) * _shade(rng, h, w, 0.5)
    img = _u8(base[None, None, :] * lum[..., None])
    if rng.random() < 0.6:  # panels with rivets
        step = int(rng.integers(120, 400))
        for x in range(int(rng.integers(0, step)), w, step):
            cv2.line(img, (x, 0), (x, h), tuple(float(v) for v in base * 0.5), 2)
            for y in range(10, h, 40):
                draw.fill_circle(img, (x + 12.5, y + 0.5), 3.5, tuple(float(v) for v in base * 1.15))
    return np.clip(img, 0, 255).astype(np.uint8)


def foliage(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """Leaves seen out of focus: clumps of light and dark greens with dark gaps."""
    leaves = draw.fractal_noise(rng, h, w, rng.uniform(4, 12), 3)
    tone = draw.value_noise(rng, h, w, max(h, w) / 4)
    dark = _tint(rng, (35, 70, 45), 8)
    light = _tint(rng, (70, 150, 110), 12)
    yellow = np.array([60.0, 160.0, 150.0], np.float32)
    t = np.clip((leaves - 0.25) * 1.6, 0, 1)[..., None]
    img = dark + (light - dark) * t
    img += (yellow - img) * (0.4 * tone)[..., None]
    gaps = (leaves < 0.3)[..., None]
    img = np.where(gaps, img * 0.45, img)
    return _u8(img)


def sky(rng: np.random.Generator, h: int, w: int) -> np.ndarray:
    """Overcast sky with poles, lattice and wires: the substation-inspection look."""
    top, bottom = _tint(rng, (222, 212, 200), 5), _tint(rng, (195, 195, 190), 6)
    t = np.linspace(0, 1, h, dtype=np.float32)[:, None, None]
    img = top * (1 - t) + bottom * t + np.zeros((1, w, 1), np.float32)
    if rng.random() < 0.5:  # distant tree line
        line = h * rng.uniform(0.55, 0.9) + 30 * (draw.value_noise(rng, 1, w, 40.0)[0] - 0.5)
        ys = np.arange(h, dtype=np.float32)[:, None]
        m = np.clip(ys - line[None, :], 0, 1)[..., None]
        img = img * (1 - m) + m * _tint(rng, (70, 110, 80), 15)
    img = _u8(img)
    for _ in range(int(rng.integers(0, 4))):
        x0 = rng.uniform(0, w)
        lean = rng.normal(0, 0.05) * h
        wd = rng.uniform(4, 25)
        col = tuple(float(v) for v in _tint(rng, (90, 95, 100), 20))
        draw.fill_polygon(img, np.array([[x0, 0], [x0 + wd, 0], [x0 + wd + lean, h], [x0 + lean, h]]), col)
    for _ in range(int(rng.integers(0, 5))):
        y0, y1 = rng.uniform(0, h * 0.6, 2)
        xs = np.linspace(0, w, 20)
        sag = rng.uniform(5, 60)
        ys = y0 + (y1 - y0) * xs / w + sag * np.sin(np.pi * xs / w)
        draw.stroke_polyline(img, np.column_stack([xs, ys]), (60.0, 60.0, 60.0), 1)
    return np.clip(img, 0, 255).astype(np.uint8)


TEXTURES = {"wall": wall, "concrete": concrete, "metal": metal, "foliage": foliage, "sky": sky, "studio": studio}
WEIGHTS = {"wall": 0.16, "concrete": 0.11, "metal": 0.13, "foliage": 0.08, "sky": 0.1, "pipes": 0.16, "clutter": 0.16,
           "studio": 0.1}


def background_kind(rng: np.random.Generator) -> str:
    names = list(WEIGHTS)
    p = np.array([WEIGHTS[k] for k in names])
    return names[int(rng.choice(len(names), p=p / p.sum()))]


def background(rng: np.random.Generator, height: int, width: int, kind: str | None = None) -> tuple[np.ndarray, str]:
    """A random background of the given kind (or a random kind); returns (image, kind).

    Textures are computed at half resolution (they are smooth) and objects drawn at full resolution.
    """
    kind = kind or background_kind(rng)
    texture = kind
    if kind == "pipes":
        texture = "wall" if rng.random() < 0.6 else "concrete"
    elif kind == "clutter":
        texture = "wall" if rng.random() < 0.5 else "metal"
    small = TEXTURES[texture](rng, max(8, height // 2), max(8, width // 2))
    img = cv2.resize(small, (width, height), interpolation=cv2.INTER_LINEAR)
    if kind == "pipes":
        for _ in range(int(rng.integers(1, 5))):
            draw_pipe(img, rng, None)
    elif kind == "clutter":
        for _ in range(int(rng.integers(4, 14))):
            draw_clutter_item(img, rng)
    if rng.random() < 0.5:  # depth of field: backgrounds are rarely sharp
        img = cv2.GaussianBlur(img, (0, 0), float(rng.uniform(0.8, 4.0)) * max(height, width) / 1280)
    return img, kind
