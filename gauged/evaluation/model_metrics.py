"""Metrics of the models against labels (numpy only, shared by training validation and ``gauged eval``).

- Notches: a predicted point matches a labelled one within ``tol_px`` (greedy by distance, one to one);
  recall = matched / labelled, unassigned = unmatched predictions / predictions (Reitsma et al. Tab. 2).
- Needle: mask IoU, and the direction of the needle axis (PCA of the mask pixels) oriented away from a
  reference point (the dial centre, or the image centre for photos whose centre is not labelled).
- Detection: box IoU of the best-matching detection per labelled box, recall at IoU 0.5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gauged.geometry.boxes import box_iou


@dataclass(frozen=True)
class PointMatch:
    labelled: int
    predicted: int
    matched: int

    @property
    def recall(self) -> float:
        return self.matched / self.labelled if self.labelled else 1.0

    @property
    def unassigned(self) -> int:
        return self.predicted - self.matched


def match_points(predicted: np.ndarray, labelled: np.ndarray, tol_px: float) -> PointMatch:
    """Greedy one-to-one matching of (N, 2) predictions to (M, 2) labels within ``tol_px``."""
    predicted = np.asarray(predicted, float).reshape(-1, 2)
    labelled = np.asarray(labelled, float).reshape(-1, 2)
    if len(predicted) == 0 or len(labelled) == 0:
        return PointMatch(len(labelled), len(predicted), 0)
    dist = np.linalg.norm(predicted[:, None, :] - labelled[None, :, :], axis=2)
    matched, used_p, used_l = 0, set(), set()
    for flat in np.argsort(dist, axis=None):
        i, j = divmod(int(flat), dist.shape[1])
        if dist[i, j] > tol_px:
            break
        if i in used_p or j in used_l:
            continue
        used_p.add(i), used_l.add(j)
        matched += 1
    return PointMatch(len(labelled), len(predicted), matched)


def mask_iou(predicted: np.ndarray, labelled: np.ndarray) -> float:
    """IoU of two boolean masks of the same shape (1.0 when both are empty)."""
    predicted, labelled = predicted.astype(bool), labelled.astype(bool)
    union = np.logical_or(predicted, labelled).sum()
    return float(np.logical_and(predicted, labelled).sum() / union) if union else 1.0


def needle_mask_at(logits: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The needle mask at a label's own resolution: the (h, w) logit map resized bilinearly to
    ``shape[:2]`` (cell centres kept aligned) and cut at probability 0.5. Measuring IoU at the output
    grid instead would charge the model for the grid's own quantisation of a thin needle."""
    import cv2

    height, width = shape[:2]
    return cv2.resize(np.asarray(logits, np.float32), (width, height), interpolation=cv2.INTER_LINEAR) > 0


def mask_direction(mask: np.ndarray, reference: tuple[float, float]) -> float | None:
    """Angle (radians, image convention) of the mask's main axis, pointing away from ``reference``.

    None when the mask has fewer than 5 pixels. The axis is the first principal component of the
    pixel centres; of its two directions the one whose far end lies farther from ``reference`` wins.
    """
    ys, xs = np.nonzero(mask)
    if len(xs) < 5:
        return None
    points = np.stack([xs + 0.5, ys + 0.5], axis=1)
    centroid = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centroid, full_matrices=False)
    axis = vt[0]
    along = (points - centroid) @ axis
    far_plus = centroid + along.max() * axis
    far_minus = centroid + along.min() * axis
    ref = np.asarray(reference, float)
    if np.linalg.norm(far_minus - ref) > np.linalg.norm(far_plus - ref):
        axis = -axis
    return math.atan2(axis[1], axis[0])


def angle_error_deg(a: float, b: float) -> float:
    return abs(math.degrees(math.remainder(a - b, 2 * math.pi)))


def best_iou(label_box, predicted_boxes) -> float:
    return max((box_iou(label_box, p) for p in predicted_boxes), default=0.0)
