"""Build the shipped reader from the packaged models (the only place that knows their file names)."""

from __future__ import annotations

import logging
from pathlib import Path

from gauged.config.model import ReaderConfig
from gauged.reader.onnx_model import ModelNotAvailable, OnnxModel, packaged_model_path
from gauged.reader.evidence import Calibration
from gauged.reader.pipeline import GaugeReader
from gauged.reader.stages.detect import GaugeDetector
from gauged.reader.stages.notch_check import NotchCheck

log = logging.getLogger(__name__)

CROP_MODEL = "crop.onnx"
DETECTOR_MODEL = "detector.onnx"
OCR_DET_INT8_MODEL = "ocr_det_int8.onnx"  # int8 copy of the OCR wheel's text detector (gauged.training.quantize_ocr)
NUMBER_NET_MODEL = "numbers.onnx"  # the scale-number recogniser (gauged.training.number_lines)
MINUS_NET_MODEL = "minus.onnx"  # the minus-sign classifier of the minus look (gauged.training.minus_lines)
NOTCH_CHECK_MODEL = "notch_check.onnx"  # the second look at the major-notch peaks (gauged.training.notch_check)


def model_path(name: str, models_dir: Path | None = None) -> Path:
    """``models_dir/name`` when a folder is given (a candidate model), else the shipped file."""
    return Path(models_dir) / name if models_dir is not None else packaged_model_path(name)


def helper_model_path(name: str, models_dir: Path | None = None) -> Path:
    """A helper model's file (the number net, the int8 text detector, the notch check): ``models_dir/name``
    when a candidate folder holds one, else the shipped file, so a folder with a candidate crop model
    alone is read with the shipped helpers."""
    if models_dir is not None and (candidate := Path(models_dir) / name).is_file():
        return candidate
    return packaged_model_path(name)


def _optional(name: str, config: ReaderConfig) -> Path | None:
    """A helper model's file, or None (with a warning that says what is lost) when it is missing."""
    path = helper_model_path(name, config.models_dir)
    if path.is_file():
        return path
    log.warning("model file %s is missing; the reader runs without it (see gauged/models/README.md)", path)
    return None


def build_reader(config: ReaderConfig) -> GaugeReader:
    """The reader; raises :class:`ModelNotAvailable` when the crop model is missing.

    Without the detector model, gauges need an ROI, and a photo is read as one gauge filling it.
    """
    crop = OnnxModel(model_path(CROP_MODEL, config.models_dir), config.threads)
    try:
        detector = GaugeDetector(OnnxModel(model_path(DETECTOR_MODEL, config.models_dir), config.threads))
    except ModelNotAvailable as exc:
        log.warning("%s; gauges without an roi cannot be found, photos are read as one gauge", exc)
        detector = None
    notch_check = None
    if config.notch_check:
        try:
            notch_check = NotchCheck(helper_model_path(NOTCH_CHECK_MODEL, config.models_dir), config.threads)
        except ModelNotAvailable as exc:
            log.warning("%s; every major-notch peak of the crop model is used", exc)
    from gauged.reader.ocr.engine import OcrUnavailable
    from gauged.reader.stages.ocr import ScaleTextReader

    try:
        ocr = ScaleTextReader(threads=config.threads,
                              int8_detector=helper_model_path(OCR_DET_INT8_MODEL, config.models_dir) if config.ocr_int8_detector else None,
                              number_net=helper_model_path(NUMBER_NET_MODEL, config.models_dir) if config.ocr_number_net else None,
                              minus_net=_optional(MINUS_NET_MODEL, config) if config.ocr_minus_net else None)
    except OcrUnavailable as exc:  # OCR is optional when every gauge has a configured scale
        log.warning("OCR is not available (%s): gauges without a configured scale cannot be read", exc)
        ocr = None
    return GaugeReader(crop, detector, ocr, config.min_confidence, notch_check=notch_check,
                       calibration=Calibration.load())
