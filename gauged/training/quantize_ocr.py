"""Quantize the OCR text detector to int8, calibrated on the inputs the reader really gives it.

    python -m gauged.training.quantize_ocr --needles ../shared/datasets/needle-polygons \
        --out gauged/models/ocr_det_int8.onnx

The PP-OCR text detector (DB) from the OCR wheel is the costliest network of a cold read: about
70 ms per call at 384 px on 2 cores, two to three calls per dial. Static int8 quantization
(onnxruntime QDQ, weights per channel, activations calibrated by their min/max) runs it 2.7x faster
on CPUs with VNNI instructions. The recogniser is left in float: quantizing it saved 11% of its time,
and its scores feed the OCR's thresholds.

Calibration inputs are recorded from the float reader itself, reading synthetic renders of seeds
no training or evaluation set uses (5,000,000 + i; only sanity tests render them) and, when given, real needle-polygons ``train``
photos: the detector sees the rectified rings, polar strips and hint windows the reader cuts, at the
sizes it cuts them. The output carries, in its ``gauged`` metadata, the SHA-256 of the float file
it was made from, so the engine uses it only with that file (:mod:`gauged.reader.ocr.engine`).

Needs the ``train`` extra (``onnx``); onnxruntime's quantization tools come with onnxruntime.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

log = logging.getLogger(__name__)

CALIBRATION_SEED = 5_000_000  # no training (0+, 20,000+), validation (1,000,000+) or dev/held-out set (7M, 9M); the shipped-model sanity tests render 5,000,001+ too
OPSET = 13  # DequantizeLinear's per-channel axis needs opset 13; the wheel's file is opset 11


class _Recording:
    """An onnxruntime session that keeps a copy of every input it is run on."""

    def __init__(self, session) -> None:
        self.session, self.inputs = session, []

    def run(self, outputs, feeds):
        self.inputs.append(np.array(next(iter(feeds.values()))))
        return self.session.run(outputs, feeds)

    def __getattr__(self, name):
        return getattr(self.session, name)


def calibration_images(renders: int, needles: Path | None, photos: int) -> list[np.ndarray]:
    from gauged.synth.crop import render_crop

    images = [render_crop(CALIBRATION_SEED + i, 448).image for i in range(renders)]
    if needles is not None:
        from gauged.training.real_data import load_needle_split

        stems: set[str] = set()
        for sample in load_needle_split(needles, "train"):
            stem = sample.image_path.name.split("_jpg.rf.")[0]  # 3 augmented copies per photo
            if stem not in stems and len(stems) < photos:
                stems.add(stem)
                images.append(cv2.imread(str(sample.image_path), cv2.IMREAD_COLOR))
    return images


def record_detector_inputs(images: list[np.ndarray], threads: int) -> list[np.ndarray]:
    """Every input the float text detector gets while the reader reads ``images``."""
    from gauged.config.model import ReaderConfig
    from gauged.reader.factory import build_reader

    reader = build_reader(ReaderConfig(threads=threads, ocr_int8_detector=False))
    if reader.ocr is None:
        raise SystemExit("the OCR models are not installed (see the README's install step)")
    recording = _Recording(reader.ocr.engine._det)
    reader.ocr.engine._det = recording
    for index, image in enumerate(images):
        reader.read_image(image)
        if (index + 1) % 20 == 0:
            log.info("read %d/%d calibration images, %d detector inputs", index + 1, len(images), len(recording.inputs))
    return recording.inputs


def quantize(source: Path, inputs: list[np.ndarray], out: Path, provenance: dict) -> None:
    import onnx
    from onnx import version_converter
    from onnxruntime.quantization import (
        CalibrationDataReader,
        CalibrationMethod,
        QuantFormat,
        QuantType,
        quantize_static,
    )
    from onnxruntime.quantization.shape_inference import quant_pre_process

    class Inputs(CalibrationDataReader):
        def __init__(self) -> None:
            self._it = iter(inputs)

        def get_next(self):
            x = next(self._it, None)
            return None if x is None else {"x": x}

    with tempfile.TemporaryDirectory() as tmp:
        converted, prepared = Path(tmp) / "det13.onnx", Path(tmp) / "det13_pre.onnx"
        onnx.save(version_converter.convert_version(onnx.load(str(source)), OPSET), str(converted))
        quant_pre_process(str(converted), str(prepared), skip_symbolic_shape=True)
        # reduce_range: 7-bit weights. With 8-bit ones, CPUs without VNNI (AVX2-only x86, common on plant
        # edge computers) saturate the u8 x s8 products' 16-bit sums, and the detector then misplaces
        # boxes by 15-46 px that VNNI machines find right; with 7 bits no sum can saturate.
        quantize_static(str(prepared), str(out), Inputs(), quant_format=QuantFormat.QDQ, per_channel=True,
                        reduce_range=True, activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8,
                        calibrate_method=CalibrationMethod.MinMax)
    model = onnx.load(str(out))
    meta = {p.key: p.value for p in model.metadata_props}
    meta["gauged"] = json.dumps(provenance)
    del model.metadata_props[:]
    for key, value in meta.items():
        model.metadata_props.add(key=key, value=value)
    onnx.save(model, str(out))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m gauged.training.quantize_ocr",
        description="Write an int8 copy of the OCR wheel's text detector, calibrated on the reader's own "
                    "detector inputs. The engine uses it only with the float file it was made from.")
    parser.add_argument("--out", type=Path, required=True, help="output .onnx (the shipped one: gauged/models/ocr_det_int8.onnx)")
    parser.add_argument("--renders", type=int, default=40, help="synthetic calibration renders (seeds 5,000,000+)")
    parser.add_argument("--needles", type=Path, default=None,
                        help="needle-polygons root: its train photos are calibration images too (optional)")
    parser.add_argument("--photos", type=int, default=40, help="distinct needle-polygons train photos used")
    parser.add_argument("--package", default="auto", help="OCR wheel whose detector is quantized (default: the one the reader uses)")
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    from gauged.reader.ocr.engine import file_sha256, find_model_files

    source, _ = find_model_files(args.package)
    images = calibration_images(args.renders, args.needles, args.photos)
    log.info("recording detector inputs on %d calibration images", len(images))
    inputs = record_detector_inputs(images, args.threads)
    log.info("quantizing %s on %d inputs", source.name, len(inputs))
    provenance = {
        "what": "int8 (QDQ, per-channel weights, min/max-calibrated activations) copy of an OCR text detector",
        "source_file": f"{source.parent.parent.name}/{source.parent.name}/{source.name}", "source_sha256": file_sha256(source),
        "calibration": {"renders": args.renders, "render_seed": CALIBRATION_SEED,
                        "needle_photos": len(images) - args.renders, "detector_inputs": len(inputs)},
        "command": "python -m gauged.training.quantize_ocr " + " ".join(argv if argv is not None else sys.argv[1:]),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    quantize(source, inputs, args.out, provenance)
    log.info("wrote %s (%.1f MB)", args.out, args.out.stat().st_size / 1e6)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
