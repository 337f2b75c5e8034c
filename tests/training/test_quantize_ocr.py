"""The OCR detector's int8 copy is made from the reader's own detector inputs and names its source."""

from __future__ import annotations

import json

import pytest

pytest.importorskip("onnx", reason="the train extra (onnx) is not installed")

from gauged.reader.ocr.engine import (  # noqa: E402
    OcrEngine,
    OcrUnavailable,
    file_sha256,
    find_model_files,
)
from gauged.training.quantize_ocr import main  # noqa: E402


@pytest.mark.slow
def test_quantize_ocr_writes_an_int8_detector_the_engine_runs(tmp_path):
    import onnx

    try:
        source, _ = find_model_files()
    except OcrUnavailable as exc:
        pytest.skip(f"OCR engine not installed ({exc})")
    out = tmp_path / "ocr_det_int8.onnx"
    assert main(["--out", str(out), "--renders", "2"]) == 0
    model = onnx.load(str(out))
    meta = json.loads({p.key: p.value for p in model.metadata_props}["gauged"])
    assert meta["source_sha256"] == file_sha256(source)
    assert meta["calibration"]["renders"] == 2 and meta["calibration"]["detector_inputs"] >= 2
    ops = {node.op_type for node in model.graph.node}
    assert {"QuantizeLinear", "DequantizeLinear"} <= ops
    assert out.stat().st_size < 0.5 * source.stat().st_size  # int8 weights
    engine = OcrEngine(threads=1, int8_detector=out)
    assert engine.model_files[0] == out
