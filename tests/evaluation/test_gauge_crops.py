"""The reader's view of a photo: a gauge crop, its label cut with it, and the crop's logits mapped back."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from gauged.evaluation.gauge_crops import best_gauge_crop, crop_logits_in_frame, crop_mask
from gauged.evaluation.model_metrics import mask_iou
from gauged.reader.stages.crop import crop_gauge


def _frame_with_needle(height: int = 300, width: int = 400) -> np.ndarray:
    mask = np.zeros((height, width), np.uint8)
    cv2.line(mask, (170, 160), (245, 95), 1, thickness=5)
    return mask


@pytest.mark.parametrize("box", [(120.0, 60.0, 300.0, 240.0), (150.0, 80.0, 260.0, 190.0), (-20.0, 40.0, 330.0, 390.0)])
def test_a_mask_cut_to_a_crop_and_mapped_back_is_the_mask(box):
    mask = _frame_with_needle()
    frame = np.dstack([mask * 255] * 3).astype(np.uint8)
    crop = crop_gauge(frame, box, 256, pad=0.08)
    cut = crop_mask(mask, crop, 256)
    # The label cut with the crop lies where the crop's own pixels show the needle.
    assert mask_iou(cut > 0, crop.image[:, :, 0] > 127) > 0.9
    # Logits at the crop model's stride-2 grid: +4 on needle cells, -4 elsewhere; back in the frame.
    grid = cv2.resize(cut.astype(np.float32), (128, 128), interpolation=cv2.INTER_AREA)
    back = crop_logits_in_frame(8 * grid - 4, crop, 256, mask.shape) > 0
    assert mask_iou(back, mask > 0) > 0.8
    assert not back[:, :5].any() or box[0] < 0  # outside the crop, no needle


def test_outside_the_crop_is_never_needle():
    crop = crop_gauge(np.zeros((300, 400, 3), np.uint8), (150.0, 80.0, 260.0, 190.0), 256)
    back = crop_logits_in_frame(np.full((128, 128), 5.0, np.float32), crop, 256, (300, 400)) > 0
    x0, y0, x1, y1 = crop.box
    assert back[int(y0) + 2:int(y1) - 2, int(x0) + 2:int(x1) - 2].all()
    assert not back[:, : int(x0) - 1].any() and not back[: int(y0) - 1].any()


def test_the_shipped_detector_crops_a_rendered_gauge():
    from gauged.evaluation.gauge_crops import shipped_detector
    from gauged.synth.crop import render_crop

    sample = render_crop(7000003, 448)
    crop = best_gauge_crop(shipped_detector(threads=1), sample.image, 256)
    assert crop is not None and crop.image.shape == (256, 256, 3)
    assert best_gauge_crop(shipped_detector(threads=1), np.full((300, 300, 3), 128, np.uint8), 256) is None
