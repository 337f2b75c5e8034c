"""Keypoints of a gauge crop from the crop model's maps: notches, needle tip/pivot, number centres.

The crop model (``gauged/models/crop.onnx``) outputs logits at stride 2 for the channels
``start, end, major, tip, pivot, numbers, needle``. Peaks are found as local maxima of the sigmoid
map above a threshold and refined to sub-cell accuracy by a parabola through the log-probabilities of each
peak and its neighbours — the equivalent, for blob-shaped heatmaps, of the paper's Mean-Shift clustering
of above-threshold pixels (Reitsma et al., Sec. 3.2), at a fraction of its cost. Each point carries
its peak probability as confidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from gauged.types import StageFailure

STAGE = "keypoints"
REASONS = ("no_notches",)
NUMBER_SURE = 0.5  # number-centre peaks above this score check the scale's number grid
CROP_CHANNELS = ("start", "end", "major", "tip", "pivot", "numbers", "needle")


@dataclass(frozen=True)
class Peaks:
    """Points (N, 2) in crop pixels (project convention) with their confidences (N,), best first."""

    points: np.ndarray
    scores: np.ndarray

    def __len__(self) -> int:
        return len(self.scores)

    def best(self) -> tuple[np.ndarray, float] | None:
        return (self.points[0], float(self.scores[0])) if len(self) else None


@dataclass(frozen=True)
class CropKeypoints:
    """Everything the crop model says about one crop, in crop pixel coordinates."""

    start: Peaks
    end: Peaks
    major: Peaks
    tip: Peaks
    pivot: Peaks
    numbers: Peaks
    needle_prob: np.ndarray  # (H, W) float32 in [0, 1] at the model's output stride
    stride: int


def sigmoid(x: np.ndarray) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-x))


def find_peaks(prob: np.ndarray, stride: int, threshold: float = 0.3, max_peaks: int = 64,
               min_distance_cells: int = 1) -> Peaks:
    """Local maxima of a (H, W) probability map above ``threshold``, refined to sub-cell accuracy.

    A cell is a peak when it equals the maximum of its ``(2d+1)²`` neighbourhood. Its position is
    refined per axis by a parabola through the log-probabilities around it, converted to input pixels
    (cell ``(i, j)`` has its centre at ``stride * (i + 0.5)``).

    >>> m = np.zeros((8, 8), np.float32); m[3, 5] = 0.9
    >>> find_peaks(m, stride=2).points.tolist()
    [[11.0, 7.0]]
    """
    if prob.ndim != 2:
        raise ValueError(f"prob must be (H, W), got {prob.shape}")
    size = 2 * min_distance_cells + 1
    local_max = cv2.dilate(prob, np.ones((size, size), np.uint8))
    ys, xs = np.nonzero((prob >= local_max) & (prob >= threshold))
    if len(xs) == 0:
        return Peaks(np.zeros((0, 2)), np.zeros(0))
    scores = prob[ys, xs]
    order = np.argsort(-scores, kind="stable")
    # Plateaus (a peak centred between cells) give several equal maxima: keep the first of each cluster.
    kept: list[int] = []
    for index in order:
        if all(max(abs(ys[index] - ys[k]), abs(xs[index] - xs[k])) > min_distance_cells for k in kept):
            kept.append(index)
            if len(kept) == max_peaks:
                break
    ys, xs, scores = ys[kept], xs[kept], scores[kept]
    # Sub-cell refinement: a parabola through the log-probabilities of the peak and its two
    # neighbours on each axis, exact for Gaussian-shaped peaks (the shape the model is trained on).
    logp = np.log(np.pad(prob, 1, mode="edge").astype(np.float64).clip(1e-6, None))
    points = np.empty((len(xs), 2))
    for k, (y, x) in enumerate(zip(ys + 1, xs + 1)):
        points[k] = (stride * (x - 1 + 0.5 + _vertex(logp[y, x - 1], logp[y, x], logp[y, x + 1])),
                     stride * (y - 1 + 0.5 + _vertex(logp[y - 1, x], logp[y, x], logp[y + 1, x])))
    return Peaks(points, scores.astype(np.float64))


def _vertex(left: float, centre: float, right: float) -> float:
    """Offset in (-0.5, 0.5) of the vertex of the parabola through three equally spaced samples."""
    curvature = left - 2 * centre + right
    if curvature >= 0:  # flat or not a maximum: keep the cell centre
        return 0.0
    return float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))


def decode_crop_maps(logits: np.ndarray, crop_size: int, threshold: float = 0.3,
                     require_notches: bool = True) -> CropKeypoints | StageFailure:
    """Turn the crop model's (7, H, W) logits into keypoints.

    Fails (``no_notches``) when no notch is found at all, unless ``require_notches`` is False (a
    locked scale needs only the needle and the pivot).
    """
    if logits.ndim != 3 or logits.shape[0] != len(CROP_CHANNELS):
        raise ValueError(f"expected ({len(CROP_CHANNELS)}, H, W) logits, got {logits.shape}")
    stride = crop_size // logits.shape[-1]
    prob = sigmoid(logits.astype(np.float32))
    maps = dict(zip(CROP_CHANNELS, prob))
    single = {name: find_peaks(maps[name], stride, threshold, max_peaks=4, min_distance_cells=3)
              for name in ("start", "end", "tip", "pivot")}
    major = find_peaks(maps["major"], stride, threshold, max_peaks=64, min_distance_cells=2)
    numbers = find_peaks(maps["numbers"], stride, threshold, max_peaks=32, min_distance_cells=3)
    if require_notches and len(major) + len(single["start"]) + len(single["end"]) == 0:
        return StageFailure(STAGE, "no_notches", "the crop model found no scale notch above threshold")
    return CropKeypoints(start=single["start"], end=single["end"], major=major, tip=single["tip"],
                         pivot=single["pivot"], numbers=numbers, needle_prob=maps["needle"], stride=stride)


def sure_numbers(numbers: Peaks) -> np.ndarray:
    """(N, 2) crop px: the number-centre peaks confident enough to check a scale's number grid."""
    return numbers.points[numbers.scores >= NUMBER_SURE]
