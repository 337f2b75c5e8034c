"""Build the shipped reader from the packaged models (the only place that knows their file names)."""

from __future__ import annotations

import logging

from gauged.config.model import ReaderConfig
from gauged.reader.detect import GaugeDetector
from gauged.reader.onnx_model import OnnxModel, packaged_model_path
from gauged.reader.pipeline import GaugeReader

log = logging.getLogger(__name__)

CROP_MODEL = "crop.onnx"
DETECTOR_MODEL = "detector.onnx"


def build_reader(config: ReaderConfig) -> GaugeReader:
    """The reader with both models; raises :class:`ModelNotAvailable` naming a missing model file."""
    crop = OnnxModel(packaged_model_path(CROP_MODEL), config.threads)
    detector = GaugeDetector(OnnxModel(packaged_model_path(DETECTOR_MODEL), config.threads))
    ocr = None
    try:
        from gauged.reader.ocr import ScaleTextReader
    except ImportError as exc:  # OCR is optional when every gauge has a configured scale
        log.warning("OCR is not available (%s): gauges without a configured scale cannot be read", exc)
    else:
        ocr = ScaleTextReader(threads=config.threads)
    return GaugeReader(crop, detector, ocr, config.min_confidence)
