"""Training targets of the crop model and the detector, drawn from ground-truth points (numpy only).

Keypoints become Gaussian peaks on a map at the model's output stride (CenterNet, Zhou et al. 2019,
Sec. 3: ``Y = exp(-((x - px)^2 + (y - py)^2) / (2 sigma^2))``, the maximum where peaks overlap).
Points are in input-pixel coordinates of the project's convention (pixel centres at +0.5); a map cell
``(i, j)`` at stride ``s`` covers input pixels ``[s*i, s*(i+1))`` and its centre is at ``s*(i + 0.5)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import cv2
import numpy as np

SIGMA_CELLS = 1.5  # width of a keypoint peak in the crop model's targets, in output cells


def gaussian_heatmap(points: np.ndarray, shape: tuple[int, int], stride: int, sigma_cells: float) -> np.ndarray:
    """(H, W) float32 map with a unit Gaussian peak at each of ``points`` (N, 2) input pixels."""
    heat = np.zeros(shape, np.float32)
    if len(points) == 0:
        return heat
    radius = int(math.ceil(3 * sigma_cells))
    height, width = shape
    for px, py in np.asarray(points, float).reshape(-1, 2):
        cx, cy = px / stride - 0.5, py / stride - 0.5  # in cell-centre coordinates
        ix, iy = int(round(cx)), int(round(cy))
        x0, x1 = max(0, ix - radius), min(width, ix + radius + 1)
        y0, y1 = max(0, iy - radius), min(height, iy + radius + 1)
        if x0 >= x1 or y0 >= y1:
            continue
        xs = np.arange(x0, x1, dtype=np.float32) - cx
        ys = np.arange(y0, y1, dtype=np.float32) - cy
        patch = np.exp(-(ys[:, None] ** 2 + xs[None, :] ** 2) / (2 * sigma_cells**2))
        np.maximum(heat[y0:y1, x0:x1], patch, out=heat[y0:y1, x0:x1])
    return heat


def downsample_mask(mask: np.ndarray, stride: int) -> np.ndarray:
    """(H, W) {0,1} mask -> (H/stride, W/stride) float32 coverage in [0, 1] (area average)."""
    height, width = mask.shape
    return cv2.resize(mask.astype(np.float32), (width // stride, height // stride), interpolation=cv2.INTER_AREA)


def arc_end_points(scale: Mapping) -> dict[str, list[list[float]] | None]:
    """The crop model's ``start`` and ``end`` labels of one Scale record of :mod:`gauged.synth.truth`.

    The channels are geometric, whichever way the printed values rise: ``start`` is the end of the
    scale's arc from which it runs clockwise on screen (lower left on an ordinary dial), ``end`` the
    clockwise-last end. The record's ``start``/``end`` are the notches of the minimum and maximum,
    so on a scale of ``direction`` "ccw" they swap; records without ``direction`` are clockwise.
    Each label is ``[point]``, ``[]`` when the record marks the notch hidden (labelled: none there),
    or ``None`` when the record has no such point (not labelled).

    >>> arc_end_points({"start": [10.0, 90.0], "end": [90.0, 90.0], "direction": "ccw", "start_visible": False})
    {'start': [[90.0, 90.0]], 'end': []}
    """
    keys = ("end", "start") if scale.get("direction") == "ccw" else ("start", "end")
    labels: dict[str, list[list[float]] | None] = {}
    for channel, key in zip(("start", "end"), keys):
        point = scale.get(key)
        if not point:
            labels[channel] = None
        else:
            labels[channel] = [point] if scale.get(f"{key}_visible", True) else []
    return labels


def crop_targets(points: dict[str, np.ndarray | None], needle_mask: np.ndarray | None, size: int,
                 channels: tuple[str, ...], stride: int = 2, sigma_cells: float = SIGMA_CELLS,
                 sigma_by_channel: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Targets (C, size/stride, size/stride) float32 and a per-channel validity vector (C,) float32.

    ``points`` maps each heatmap channel name to (N, 2) points, an empty array (labelled: none there)
    or ``None`` (not labelled: the channel is masked out of the loss). The last channel ``needle`` is
    the needle mask; ``needle_mask`` of ``None`` means not labelled. Heatmap peaks have the width
    ``sigma_cells``, or ``sigma_by_channel[name]`` for the channels it names.
    """
    sigma_by_channel = sigma_by_channel or {}
    out_shape = (size // stride, size // stride)
    target = np.zeros((len(channels), *out_shape), np.float32)
    valid = np.zeros(len(channels), np.float32)
    for index, name in enumerate(channels):
        if name == "needle":
            if needle_mask is not None:
                target[index] = downsample_mask(needle_mask, stride)
                valid[index] = 1.0
            continue
        pts = points.get(name)
        if pts is None:
            continue
        target[index] = gaussian_heatmap(np.asarray(pts, float).reshape(-1, 2), out_shape, stride,
                                         sigma_by_channel.get(name, sigma_cells))
        valid[index] = 1.0
    return target, valid


def detector_targets(boxes: np.ndarray, size: int, stride: int = 8, sigma_scale: float = 0.1
                     ) -> tuple[np.ndarray, np.ndarray]:
    """CenterNet targets for (N, 4) boxes in input pixels of a ``size`` x ``size`` letterboxed frame.

    Returns maps (5, size/stride, size/stride) float32 — centre heatmap, log box width and height in
    cells, centre offset within the cell — and a (size/stride, size/stride) weight that is 1 at each
    box's centre cell (where the regression is trained) and 0 elsewhere.
    """
    cells = size // stride
    maps = np.zeros((5, cells, cells), np.float32)
    weight = np.zeros((cells, cells), np.float32)
    for x0, y0, x1, y1 in np.asarray(boxes, float).reshape(-1, 4):
        w, h = (x1 - x0) / stride, (y1 - y0) / stride
        if w <= 0.5 or h <= 0.5:
            continue
        cx, cy = (x0 + x1) / 2 / stride, (y0 + y1) / 2 / stride  # in cells, edge-origin
        ix, iy = int(cx), int(cy)
        if not (0 <= ix < cells and 0 <= iy < cells):
            continue
        sigma = max(0.8, sigma_scale * math.sqrt(w * h))
        peak = gaussian_heatmap(np.array([[cx * stride, cy * stride]]), (cells, cells), stride, sigma)
        np.maximum(maps[0], peak, out=maps[0])
        maps[1:3, iy, ix] = (math.log(w), math.log(h))
        maps[3:5, iy, ix] = (cx - ix, cy - iy)
        weight[iy, ix] = 1.0
    return maps, weight

