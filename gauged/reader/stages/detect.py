"""Gauge detection on a full frame: letterbox, run the detector, decode CenterNet maps to boxes.

The detector (``gauged/models/detector.onnx``) outputs, at stride 8 of its square input, a centre
heatmap logit, the log of box width and height in cells, and the centre's sub-cell offset (logit)
(Zhou et al. 2019, "Objects as Points", Sec. 4). Boxes are decoded at heatmap peaks and mapped back
through the letterbox to frame pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from gauged.geometry.boxes import box_iou
from gauged.reader.onnx_model import OnnxModel, to_model_input
from gauged.reader.stages.keypoints import sigmoid
from gauged.types import GaugeDetection, StageFailure

STAGE = "detect"
REASONS = ("no_gauge", "gauge_not_found")  # the second is the gauge runner's: no detection associated
LETTERBOX_FILL = 114  # grey padding, as used in training


@dataclass(frozen=True)
class Letterbox:
    """``frame_xy = (input_xy - (dx, dy)) / scale`` for an input of ``size`` x ``size``."""

    scale: float
    dx: float
    dy: float
    size: int

    @classmethod
    def fit(cls, width: int, height: int, size: int) -> Letterbox:
        scale = size / max(width, height)
        return cls(scale, (size - width * scale) / 2, (size - height * scale) / 2, size)

    def apply(self, image: np.ndarray) -> np.ndarray:
        """Resize (H, W, 3) ``image`` into the centred square, padded with grey."""
        matrix = np.array([[self.scale, 0.0, self.dx + 0.5 * self.scale - 0.5],
                           [0.0, self.scale, self.dy + 0.5 * self.scale - 0.5]])
        interpolation = cv2.INTER_AREA if self.scale < 1 else cv2.INTER_LINEAR
        if interpolation == cv2.INTER_AREA:
            h, w = image.shape[:2]
            small = cv2.resize(image, (max(1, round(w * self.scale)), max(1, round(h * self.scale))),
                               interpolation=cv2.INTER_AREA)
            out = np.full((self.size, self.size, 3), LETTERBOX_FILL, np.uint8)
            x0, y0 = int(round(self.dx)), int(round(self.dy))
            out[y0:y0 + small.shape[0], x0:x0 + small.shape[1]] = small[: self.size - y0, : self.size - x0]
            return out
        return cv2.warpAffine(image, matrix, (self.size, self.size), flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=(LETTERBOX_FILL,) * 3)

    def boxes_to_frame(self, boxes: np.ndarray) -> np.ndarray:
        boxes = np.asarray(boxes, float).reshape(-1, 4)
        return (boxes - np.array([self.dx, self.dy, self.dx, self.dy])) / self.scale


def decode_detections(maps: np.ndarray, stride: int, threshold: float = 0.3, max_gauges: int = 16,
                      nms_iou: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """(5, H, W) detector maps -> boxes (N, 4) in input pixels and scores (N,), best first."""
    if maps.ndim != 3 or maps.shape[0] != 5:
        raise ValueError(f"expected (5, H, W) detector maps, got {maps.shape}")
    heat = sigmoid(maps[0].astype(np.float32))
    local_max = cv2.dilate(heat, np.ones((3, 3), np.uint8))
    ys, xs = np.nonzero((heat >= local_max) & (heat >= threshold))
    order = np.argsort(-heat[ys, xs], kind="stable")
    boxes, scores = [], []
    for y, x in zip(ys[order], xs[order]):
        w, h = np.exp(maps[1:3, y, x].clip(-5, 7)) * stride
        ox, oy = sigmoid(maps[3:5, y, x])
        cx, cy = (x + ox) * stride, (y + oy) * stride
        box = np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])
        if any(box_iou(box, kept) > nms_iou for kept in boxes):
            continue
        boxes.append(box)
        scores.append(float(heat[y, x]))
        if len(boxes) == max_gauges:
            break
    return np.asarray(boxes, float).reshape(-1, 4), np.asarray(scores, float)


class GaugeDetector:
    """The shipped detector: ``detect(image)`` returns gauge boxes in frame pixels, best first."""

    def __init__(self, model: OnnxModel, threshold: float = 0.3):
        self.model = model
        self.threshold = threshold
        self.stride = int(model.metadata.get("stride", 8))

    def detect(self, image: np.ndarray) -> list[GaugeDetection] | StageFailure:
        if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8:
            raise ValueError(f"image must be (H, W, 3) uint8, got {image.dtype} {image.shape}")
        letterbox = Letterbox.fit(image.shape[1], image.shape[0], self.model.input_size)
        maps = self.model(to_model_input(letterbox.apply(image)))
        boxes, scores = decode_detections(maps, self.stride, self.threshold)
        if len(boxes) == 0:
            return StageFailure(STAGE, "no_gauge", f"no gauge above score {self.threshold:g}")
        frame_boxes = letterbox.boxes_to_frame(boxes)
        height, width = image.shape[:2]
        frame_boxes[:, [0, 2]] = frame_boxes[:, [0, 2]].clip(0, width)
        frame_boxes[:, [1, 3]] = frame_boxes[:, [1, 3]].clip(0, height)
        return [GaugeDetection(tuple(float(v) for v in box), score) for box, score in zip(frame_boxes, scores)]
