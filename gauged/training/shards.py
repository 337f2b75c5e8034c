"""Pre-rendered training sets on disk: render once, train many epochs (numpy memmaps + JSON lines).

A crop shard directory holds
    images.npy   (N, S, S, 3) uint8 BGR crops
    needle.npy   (N, S, S) uint8 needle mask: 0/1, or 255 where the needle is not labelled
    labels.jsonl one JSON object per crop: {"points": {channel: [[x, y], ...] | null}, "source": str}
A detector shard directory holds
    images.npy   (N, S, S, 3) uint8 BGR letterboxed frames
    labels.jsonl {"boxes": [[x0, y0, x1, y1], ...], "source": str} in letterboxed pixels
Points and boxes are in the project's pixel convention (see gauged/types.py).
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

UNLABELLED = 255


@dataclass
class CropSample:
    image: np.ndarray  # (S, S, 3) uint8
    points: dict[str, list[list[float]] | None]
    needle: np.ndarray | None  # (S, S) {0, 1} or None
    source: str


@dataclass
class DetectorSample:
    image: np.ndarray  # (S, S, 3) uint8 letterboxed
    boxes: list[list[float]]
    source: str


def write_crop_shard(directory: Path, samples: Iterable[CropSample], count: int, size: int) -> int:
    """Write up to ``count`` samples; returns how many were written (the arrays are trimmed to it)."""
    directory.mkdir(parents=True, exist_ok=True)
    images = np.lib.format.open_memmap(directory / "images.npy", "w+", np.uint8, (count, size, size, 3))
    needle = np.lib.format.open_memmap(directory / "needle.npy", "w+", np.uint8, (count, size, size))
    written = 0
    with (directory / "labels.jsonl").open("w") as labels:
        for sample in samples:
            if written == count:
                break
            images[written] = sample.image
            needle[written] = UNLABELLED if sample.needle is None else sample.needle
            labels.write(json.dumps({"points": sample.points, "source": sample.source}) + "\n")
            written += 1
    images.flush(), needle.flush()
    del images, needle
    if written < count:
        _trim(directory / "images.npy", written), _trim(directory / "needle.npy", written)
    return written


def write_detector_shard(directory: Path, samples: Iterable[DetectorSample], count: int, size: int) -> int:
    directory.mkdir(parents=True, exist_ok=True)
    images = np.lib.format.open_memmap(directory / "images.npy", "w+", np.uint8, (count, size, size, 3))
    written = 0
    with (directory / "labels.jsonl").open("w") as labels:
        for sample in samples:
            if written == count:
                break
            images[written] = sample.image
            labels.write(json.dumps({"boxes": sample.boxes, "source": sample.source}) + "\n")
            written += 1
    images.flush()
    del images
    if written < count:
        _trim(directory / "images.npy", written)
    return written


def _trim(path: Path, rows: int) -> None:
    array = np.load(path, mmap_mode="r")[:rows].copy()
    np.save(path, array)


@dataclass
class CropShard:
    images: np.ndarray
    needle: np.ndarray
    labels: list[dict]

    def __len__(self) -> int:
        return len(self.labels)

    def sample(self, index: int) -> CropSample:
        mask = self.needle[index]
        return CropSample(np.asarray(self.images[index]), self.labels[index]["points"],
                          None if mask[0, 0] == UNLABELLED and (mask == UNLABELLED).all() else np.asarray(mask),
                          self.labels[index]["source"])


@dataclass
class DetectorShard:
    images: np.ndarray
    labels: list[dict]

    def __len__(self) -> int:
        return len(self.labels)

    def sample(self, index: int) -> DetectorSample:
        return DetectorSample(np.asarray(self.images[index]), self.labels[index]["boxes"], self.labels[index]["source"])


def _labels(directory: Path) -> list[dict]:
    return [json.loads(line) for line in (directory / "labels.jsonl").read_text().splitlines() if line]


def open_crop_shard(directory: Path) -> CropShard:
    return CropShard(np.load(directory / "images.npy", mmap_mode="r"), np.load(directory / "needle.npy", mmap_mode="r"),
                     _labels(directory))


def open_detector_shard(directory: Path) -> DetectorShard:
    return DetectorShard(np.load(directory / "images.npy", mmap_mode="r"), _labels(directory))


def iter_indices(length: int, rng: np.random.Generator) -> Iterator[int]:
    yield from rng.permutation(length).tolist()
