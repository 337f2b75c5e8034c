"""A second look at each major-notch peak: is it a major notch, or a minor tick, a number, a near miss?

The crop model's ``major`` map fires on the minor and medium ticks between the major notches too
(docs: gauged/models/README.md): on held-out renders a fifth of its peaks are not major
notches, and the ring the reader fits through them bends. The notch check (``notch_check.onnx``,
trained by :mod:`gauged.training.notch_check`) is a small CNN that looks at each peak again, with
more context than a heatmap cell has: two windows of :data:`PATCH` pixels centred on the peak, one
at the crop's resolution and one at half of it (a tick and its neighbours), each with the crop's RGB
and the model's ``major`` and ``numbers`` probabilities, plus three numbers about the peak (its
score, its distance from the pivot against the median peak's, how many peaks the crop has). It
returns the probability that the peak is a labelled major notch; peaks under the file's threshold
are dropped, and the kept ones carry that probability as their confidence.

This stage is pure: crop, logits and keypoints in, keypoints out.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from gauged.reader.onnx_model import load_session
from gauged.reader.stages.keypoints import CROP_CHANNELS, CropKeypoints, Peaks, sigmoid

PATCH = 40  # window side in pixels, at the crop's resolution and at half of it
MAP_CHANNELS = (CROP_CHANNELS.index("major"), CROP_CHANNELS.index("numbers"))
PEAK_COUNT_SCALE = 32.0  # the peak-count feature is len(peaks) / this


def notch_windows(image_rgb01: np.ndarray, logits: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(N, 10, PATCH, PATCH) float32 inputs of the notch check for peaks ``points`` (N, 2) of a crop.

    ``image_rgb01`` is the crop model's input (S, S, 3) and ``logits`` its (7, S/2, S/2) output.
    Channels: RGB, P(major), P(numbers) in a window at the crop's resolution, then the same five
    in a window of the crop halved; windows reaching past the crop's edge are padded with zeros.
    Row and column ``PATCH // 2`` of each window hold the pixel the point lies in (pixel ``i`` spans
    ``[i, i + 1)``, the project's convention).
    """
    size = image_rgb01.shape[0]
    prob = sigmoid(logits[list(MAP_CHANNELS)].astype(np.float32))
    maps = cv2.resize(prob.transpose(1, 2, 0), (size, size), interpolation=cv2.INTER_LINEAR)
    full = np.concatenate([image_rgb01.astype(np.float32, copy=False), maps], -1)
    half = cv2.resize(full, (size // 2, size // 2), interpolation=cv2.INTER_AREA)
    depth = full.shape[-1]
    out = np.zeros((len(points), PATCH, PATCH, 2 * depth), np.float32)
    for k, (x, y) in enumerate(np.asarray(points, float).reshape(-1, 2)):
        _paste(out[k, :, :, :depth], full, x, y)
        _paste(out[k, :, :, depth:], half, x / 2, y / 2)
    return np.ascontiguousarray(out.transpose(0, 3, 1, 2))


def _paste(window: np.ndarray, source: np.ndarray, x: float, y: float) -> None:
    """Copy the part of ``source`` inside the window centred on the pixel holding (x, y) into ``window``."""
    left, top = int(np.floor(x)) - PATCH // 2, int(np.floor(y)) - PATCH // 2
    x0, y0 = max(left, 0), max(top, 0)
    x1, y1 = min(left + PATCH, source.shape[1]), min(top + PATCH, source.shape[0])
    if x1 > x0 and y1 > y0:
        window[y0 - top:y1 - top, x0 - left:x1 - left] = source[y0:y1, x0:x1]


def peak_features(peaks: Peaks, pivot: Peaks, size: int) -> np.ndarray:
    """(N, 3) float32: each peak's score, its distance from the pivot peak (the crop's centre when
    there is none) over the median peak's, and the number of peaks over :data:`PEAK_COUNT_SCALE`."""
    points = peaks.points.reshape(-1, 2)
    centre = pivot.points[0] if len(pivot) else np.array([size / 2, size / 2])
    radii = np.linalg.norm(points - centre, axis=1)
    relative = radii / (np.median(radii) + 1e-6) if len(radii) else radii
    count = np.full(len(points), len(points) / PEAK_COUNT_SCALE)
    return np.stack([peaks.scores, relative, count], 1).astype(np.float32).reshape(-1, 3)


class NotchCheck:
    """The ``notch_check.onnx`` session, created once; call it on a crop's model input, logits and keypoints."""

    def __init__(self, path: Path, threads: int = 1, threshold: float | None = None):
        self.session, self.metadata = load_session(path, threads)
        self.threshold = float(self.metadata.get("threshold", 0.5) if threshold is None else threshold)
        if not 0.0 <= self.threshold <= 1.0:
            raise ValueError(f"notch check threshold must be in [0, 1], got {self.threshold}")
        self.path = path

    def probabilities(self, image_rgb01: np.ndarray, logits: np.ndarray, keypoints: CropKeypoints) -> np.ndarray:
        """P(labelled major notch) for each of ``keypoints.major``'s peaks, (N,) float."""
        size = image_rgb01.shape[0]
        if image_rgb01.shape != (size, size, 3) or logits.shape != (len(CROP_CHANNELS), size // 2, size // 2):
            raise ValueError(f"the notch check takes a crop model's (S, S, 3) input and its ({len(CROP_CHANNELS)}, S/2, S/2) "
                             f"logits, got {image_rgb01.shape} and {logits.shape}")
        if not len(keypoints.major):
            return np.zeros(0)
        windows = notch_windows(image_rgb01, logits, keypoints.major.points)
        features = peak_features(keypoints.major, keypoints.pivot, image_rgb01.shape[0])
        (out,) = self.session.run(None, {"windows": windows, "features": features})
        return sigmoid(out.reshape(-1).astype(np.float64))

    def __call__(self, image_rgb01: np.ndarray, logits: np.ndarray, keypoints: CropKeypoints) -> CropKeypoints:
        """``keypoints`` with the major peaks the check doubts dropped; the kept ones, best first,
        carry the check's probability as their confidence."""
        p = self.probabilities(image_rgb01, logits, keypoints)
        keep = np.flatnonzero(p >= self.threshold)
        keep = keep[np.argsort(-p[keep], kind="stable")]
        major = Peaks(keypoints.major.points.reshape(-1, 2)[keep], p[keep])
        return replace(keypoints, major=major)
