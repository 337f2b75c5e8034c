"""Loaders of the real photo sets in ``../shared/datasets`` (never shipped; read in place).

- ``needle-polygons``: Roboflow YOLO-segmentation labels of the pointing part of the needle.
  The train split holds three augmented copies of each photo (``<stem>_jpg.rf.<hash>.jpg``);
  :func:`photo_group` gives the stem so splits never put copies of one photo on both sides.
- ``substation-dials``: 1920x1080 inspection frames with a 1-bit dial-face mask and a box each.

Pure numpy/cv2, so evaluation and tests use it without torch.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

_RF_SUFFIX = re.compile(r"_(jpg|jpeg|png)\.rf\.[0-9a-f]+$", re.IGNORECASE)


def photo_group(image_path: Path) -> str:
    """The source-photo stem of a Roboflow export name (augmented copies share it)."""
    return _RF_SUFFIX.sub("", image_path.stem)


@dataclass(frozen=True)
class NeedleSample:
    """One photo with its labelled needle polygon(s), in pixel coordinates of the image."""

    image_path: Path
    polygons: tuple[np.ndarray, ...]  # each (K, 2) float, pixels

    def load(self) -> tuple[np.ndarray, np.ndarray]:
        """(image (H, W, 3) uint8 BGR, needle mask (H, W) uint8 in {0, 1})."""
        image = cv2.imread(str(self.image_path), cv2.IMREAD_COLOR)
        if image is None:
            raise OSError(f"cannot decode {self.image_path}")
        return image, rasterize_polygons(self.polygons, image.shape[:2])


def rasterize_polygons(polygons: tuple[np.ndarray, ...], shape: tuple[int, int]) -> np.ndarray:
    """Fill polygons given in pixel coordinates (pixel centres at +0.5) into a (H, W) uint8 mask."""
    mask = np.zeros(shape, np.uint8)
    for poly in polygons:
        # cv2 fills at integer pixel indices, whose centres are at +0.5 in our convention.
        pts = np.round((poly - 0.5) * 16).astype(np.int32)
        cv2.fillPoly(mask, [pts], 1, lineType=cv2.LINE_8, shift=4)
    return mask


def load_needle_split(root: Path, split: str) -> list[NeedleSample]:
    """All labelled photos of ``needle-polygons/<split>`` (``train`` or ``valid``), sorted by name."""
    image_dir, label_dir = root / split / "images", root / split / "labels"
    if not image_dir.is_dir():
        raise FileNotFoundError(f"no needle-polygons split at {image_dir}")
    samples = []
    for image_path in sorted(image_dir.iterdir()):
        label_path = label_dir / (image_path.stem + ".txt")
        if not label_path.is_file():
            continue
        size = _image_size(image_path)
        polygons = []
        for line in label_path.read_text().splitlines():
            values = line.split()
            if len(values) < 7:
                continue
            coords = np.asarray(values[1:], float).reshape(-1, 2)
            polygons.append(coords * np.asarray(size, float))
        if polygons:
            samples.append(NeedleSample(image_path, tuple(polygons)))
    return samples


def _image_size(path: Path) -> tuple[int, int]:
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    return int(image.shape[1]), int(image.shape[0])


@dataclass(frozen=True)
class DialSample:
    """One substation frame with its labelled dial box (x0, y0, x1, y1) and face mask."""

    image_path: Path
    mask_path: Path
    box: tuple[float, float, float, float]


def load_substation_dials(root: Path) -> list[DialSample]:
    """All frames of ``substation-dials`` in numeric order of their names."""
    boxes = json.loads((root / "boxes.json").read_text())
    samples = []
    for name, box in boxes.items():
        stem = Path(name).stem
        samples.append(DialSample(root / "images" / name, root / "masks" / f"{stem}.png", tuple(float(v) for v in box)))
    return sorted(samples, key=lambda s: int(re.sub(r"\D", "", s.image_path.stem) or 0))
