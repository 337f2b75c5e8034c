"""The shipped ONNX models on fixed renders they never trained on (seeds 5,000,000+): sane outputs.

Not accuracy figures (those come from ``gauged eval models``, see gauged/models/README.md), but a
guard that the files in the package load, take their inputs and find what is plainly there.
"""

from __future__ import annotations

import numpy as np
import pytest

from gauged.evaluation.model_metrics import match_points
from gauged.geometry.boxes import box_iou
from gauged.reader.stages.detect import GaugeDetector
from gauged.reader.factory import CROP_MODEL, DETECTOR_MODEL
from gauged.reader.stages.keypoints import decode_crop_maps
from gauged.reader.onnx_model import OnnxModel, packaged_model_path, to_model_input
from gauged.synth.crop import render_crop
from gauged.synth.scene import render_scene
from gauged.training.prerender import synth_points
from gauged.types import StageFailure

SEEDS = (5_000_001, 5_000_002, 5_000_003, 5_000_004)


def _model(name: str) -> OnnxModel:
    path = packaged_model_path(name)
    if not path.is_file():
        pytest.skip(f"gauged/models/{name} is not shipped")
    return OnnxModel(path, threads=1)


def test_detector_finds_the_gauges_of_clean_scenes():
    detector = GaugeDetector(_model(DETECTOR_MODEL))
    found = labelled = 0
    for seed in SEEDS:
        scene = render_scene(seed, 1280, 720, n_gauges=2, clean=True)
        detections = detector.detect(scene.image)
        boxes = [] if isinstance(detections, StageFailure) else [d.box for d in detections]
        for gauge in scene.record["gauges"]:
            labelled += 1
            found += any(box_iou(gauge["box"], b) >= 0.5 for b in boxes)
    assert found >= 0.75 * labelled, f"{found} of {labelled} gauges found at IoU 0.5"


def test_detector_boxes_a_gauge_that_fills_the_frame():
    """Close-ups (one gauge filling most of the image, as in photos taken to read a dial): the
    detector boxes the gauge whole, front and case, as the real substation labels do."""
    detector = GaugeDetector(_model(DETECTOR_MODEL))
    ious = []
    for seed in SEEDS:
        crop = render_crop(seed, 448, masks=False)
        detections = detector.detect(crop.image)
        boxes = [] if isinstance(detections, StageFailure) else [d.box for d in detections]
        ious.append(max((box_iou(crop.truth["box"], b) for b in boxes), default=0.0))
    assert min(ious) >= 0.5 and np.mean(ious) >= 0.75, ious


def test_crop_model_finds_notches_ends_and_needle_of_clean_crops():
    crop = _model(CROP_MODEL)
    size = crop.input_size
    recall, needle_ok = [], 0
    for seed in SEEDS:
        sample = render_crop(seed, size, clean=True)
        points = synth_points(sample.truth)
        logits = crop(to_model_input(sample.image))
        assert logits.shape == (7, size // 2, size // 2) and np.isfinite(logits).all()
        keypoints = decode_crop_maps(logits, size, require_notches=False)
        match = match_points(keypoints.major.points, np.asarray(points["major"]).reshape(-1, 2), 8.0 * size / 448)
        recall.append(match.matched / max(1, match.labelled))
        truth_needle = sample.needle_mask[::2, ::2] == 1
        predicted = logits[-1] > 0
        needle_ok += (predicted & truth_needle).sum() >= 0.3 * truth_needle.sum()
    assert np.mean(recall) >= 0.6, f"major-notch recall {recall}"
    assert needle_ok >= len(SEEDS) - 1, f"needle found on {needle_ok} of {len(SEEDS)} crops"


def test_eval_models_counts_every_shipped_onnx_file_within_15_mb(tmp_path):
    from gauged.evaluation.models import evaluate_models, format_models
    from gauged.reader.factory import MINUS_NET_MODEL, NOTCH_CHECK_MODEL, NUMBER_NET_MODEL, OCR_DET_INT8_MODEL

    for name in (CROP_MODEL, DETECTOR_MODEL, NOTCH_CHECK_MODEL, OCR_DET_INT8_MODEL, NUMBER_NET_MODEL, MINUS_NET_MODEL):
        if not packaged_model_path(name).is_file():
            pytest.skip(f"gauged/models/{name} is not shipped")
    result = evaluate_models(tmp_path, None, threads=1)  # no datasets: sizes and speeds only
    assert result["files"] == [CROP_MODEL, DETECTOR_MODEL, NOTCH_CHECK_MODEL, OCR_DET_INT8_MODEL, NUMBER_NET_MODEL,
                               MINUS_NET_MODEL]
    assert sorted(result["files"]) == sorted(p.name for p in packaged_model_path(CROP_MODEL).parent.glob("*.onnx"))
    expected = sum(packaged_model_path(n).stat().st_size for n in result["files"]) / 2**20
    assert result["files_mb"] == round(expected, 2) and result["files_mb"] <= 15.0  # issue 4's limit
    assert OCR_DET_INT8_MODEL in format_models(result)


def test_notch_metrics_split_the_crops_captured_small_from_those_at_full_size(tmp_path):
    from gauged.evaluation.models import notch_metrics, render_scale
    from gauged.synth.crop import render_crop
    from gauged.training.prerender import _render_synth_one
    from gauged.training.shards import write_crop_shard

    # seeds 3-6 at 128 px: the engine renders seed 3 at 30 px and upsamples it, the others at full size
    scales = {seed: 1.0 / render_crop(seed, 128, masks=False).output_scale for seed in range(3, 7)}
    assert all(render_scale(f"synth/{seed}", 128) == pytest.approx(s) for seed, s in scales.items())
    assert render_scale("real/needle-polygons/x.jpg", 128) is None
    small = sum(s < 1.0 for s in scales.values())
    assert 0 < small < len(scales)
    write_crop_shard(tmp_path, (_render_synth_one((seed, 128)) for seed in scales), len(scales), 128)
    result = notch_metrics(_model(CROP_MODEL), tmp_path)
    parts = result["by_capture"]
    assert (parts["upsampled"]["crops"], parts["full size"]["crops"]) == (small, len(scales) - small)
    assert result["crops"] == len(scales)
