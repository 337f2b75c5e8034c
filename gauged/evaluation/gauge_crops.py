"""The crop model's view of a photo the reader's way: detect the gauge, cut its square crop, and map
the crop model's needle logits back onto the photo.

The reader never gives the crop model a whole photo: it crops the detected gauge first (as Reitsma
et al. do). Training shards (``prerender needles --crop-with-detector``), validation during training
and ``gauged eval models`` use these same two functions, so all three see what the reader sees.
"""

from __future__ import annotations

import cv2
import numpy as np

from gauged.reader.stages.crop import Crop, crop_gauge
from gauged.reader.stages.detect import GaugeDetector
from gauged.types import StageFailure

READER_CROP_PAD = 0.08  # the reader's default (GaugeReader crop_pad)


def shipped_detector(threads: int = 2) -> GaugeDetector:
    """The packaged gauge detector (``gauged/models/detector.onnx``)."""
    from gauged.reader.factory import DETECTOR_MODEL
    from gauged.reader.onnx_model import OnnxModel, packaged_model_path

    return GaugeDetector(OnnxModel(packaged_model_path(DETECTOR_MODEL), threads=threads))


def best_gauge_crop(detector: GaugeDetector, image: np.ndarray, size: int, pad: float = READER_CROP_PAD) -> Crop | None:
    """The ``size``-px square crop of the detector's best gauge in ``image``, or None when the
    detector finds none (or only one too small to crop)."""
    found = detector.detect(image)
    if isinstance(found, StageFailure):
        return None
    crop = crop_gauge(image, found[0].box, size, pad)
    return None if isinstance(crop, StageFailure) else crop


def crop_logits_in_frame(logits: np.ndarray, crop: Crop, crop_size: int, shape: tuple[int, ...],
                         outside: float = -20.0) -> np.ndarray:
    """A (g, g) logit map over a ``crop_size``-px crop, resampled bilinearly onto the (H, W) frame
    ``shape[:2]`` it was cut from (cells of crop_size / g px, :func:`_cell_to_frame_index`); frame
    pixels outside the crop get ``outside``."""
    logits = np.asarray(logits, np.float32)
    height, width = shape[:2]
    return cv2.warpAffine(logits, _cell_to_frame_index(crop, crop_size / logits.shape[1]), (width, height),
                          flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=float(outside))


def crop_mask(mask: np.ndarray, crop: Crop, crop_size: int) -> np.ndarray:
    """A (H, W) {0, 1} frame mask cut to ``crop``'s square at ``crop_size`` px (coverage cut at a half;
    outside the frame is 0), the label that goes with ``crop.image``."""
    # Coverage by area, then cut at a half: a thin needle keeps its width better than nearest sampling.
    coverage = cv2.warpAffine(mask.astype(np.float32), _cell_to_frame_index(crop, 1.0), (crop_size, crop_size),
                              flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_CONSTANT, borderValue=0.0)
    return (coverage >= 0.5).astype(np.uint8)


def _cell_to_frame_index(crop: Crop, step: float) -> np.ndarray:
    """The 2x3 map from the index of a cell ``step`` crop pixels wide to the frame pixel index under
    its centre: cell j covers crop pixels [j step, (j + 1) step), centred at crop (j + 0.5) step,
    frame ``crop.to_frame`` of that, index that minus 0.5 (pixel centres at +0.5)."""
    scale, x0, y0 = crop.to_frame[0, 0], crop.to_frame[0, 2], crop.to_frame[1, 2]
    k = scale * step
    return np.array([[k, 0.0, x0 + 0.5 * k - 0.5], [0.0, k, y0 + 0.5 * k - 0.5]])
