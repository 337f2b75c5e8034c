from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gauged.reader.stages.keypoints import CROP_CHANNELS, decode_crop_maps, find_peaks
from gauged.training.targets import gaussian_heatmap


@settings(max_examples=60, deadline=None)
@given(x=st.floats(8, 248), y=st.floats(8, 248), stride=st.sampled_from([2, 4]))
def test_find_peaks_recovers_gaussian_centre_subpixel(x, y, stride):
    heat = gaussian_heatmap(np.array([[x, y]]), (256 // stride, 256 // stride), stride, 1.5)
    peaks = find_peaks(heat, stride)
    assert len(peaks) == 1
    assert np.allclose(peaks.points[0], (x, y), atol=0.05 * stride)


def test_find_peaks_orders_by_score_and_applies_threshold():
    heat = gaussian_heatmap(np.array([[40.0, 40.0], [200.0, 100.0]]), (128, 128), 2, 1.5)
    heat[20:40, 100:120] *= 0.5
    peaks = find_peaks(heat, 2, threshold=0.3)
    assert np.allclose(peaks.points[0], (40, 40), atol=0.1)
    assert peaks.scores[0] >= peaks.scores[1]
    assert len(find_peaks(heat, 2, threshold=0.99)) == 0


def test_find_peaks_rejects_wrong_shape():
    with pytest.raises(ValueError):
        find_peaks(np.zeros((2, 8, 8)), 2)


def test_decode_crop_maps_no_notches_failure():
    logits = np.full((len(CROP_CHANNELS), 128, 128), -8.0, np.float32)
    failure = decode_crop_maps(logits, 256)
    assert not failure and failure.stage == "keypoints" and failure.reason == "no_notches"


def test_decode_crop_maps_finds_channels():
    logits = np.full((len(CROP_CHANNELS), 128, 128), -8.0, np.float32)
    heat = gaussian_heatmap(np.array([[60.0, 190.0]]), (128, 128), 2, 1.5)
    logits[0] = np.log(heat.clip(1e-4, 1 - 1e-4) / (1 - heat.clip(1e-4, 1 - 1e-4)))
    keypoints = decode_crop_maps(logits, 256)
    assert np.allclose(keypoints.start.points[0], (60, 190), atol=0.2)
    assert len(keypoints.end) == 0 and keypoints.stride == 2
