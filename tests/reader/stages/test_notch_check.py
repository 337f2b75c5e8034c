"""The notch check's inputs, its threshold, and the shipped file on engine crops whose notches are known."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from gauged.reader.factory import CROP_MODEL, NOTCH_CHECK_MODEL
from gauged.reader.onnx_model import (
    ModelNotAvailable,
    OnnxModel,
    packaged_model_path,
    to_model_input,
)
from gauged.reader.stages.keypoints import CROP_CHANNELS, Peaks, decode_crop_maps
from gauged.reader.stages.notch_check import (
    PATCH,
    NotchCheck,
    notch_windows,
    peak_features,
)

SIZE = 64
shipped = pytest.mark.skipif(not (packaged_model_path(NOTCH_CHECK_MODEL).is_file() and packaged_model_path(CROP_MODEL).is_file()),
                             reason="gauged/models/notch_check.onnx or crop.onnx is not shipped")


def test_a_window_is_centred_on_its_peak_at_both_resolutions():
    image = np.zeros((SIZE, SIZE, 3), np.float32)
    image[20:22, 30:32, 0] = 1.0  # a red 2x2 block, one cell of the half-resolution crop
    logits = np.full((len(CROP_CHANNELS), SIZE // 2, SIZE // 2), -20.0, np.float32)
    logits[CROP_CHANNELS.index("numbers")] = 20.0
    (window,) = notch_windows(image, logits, np.array([[31.0, 21.0]]))  # the block's centre: pixel (31, 21)
    assert window.shape == (10, PATCH, PATCH)
    centre = PATCH // 2
    assert window[0, centre - 1:centre + 1, centre - 1:centre + 1].min() == 1.0  # red, full resolution
    assert window[0].sum() == 4.0
    assert window[5, centre, centre] == pytest.approx(1.0) and window[5].sum() == pytest.approx(1.0)  # red, half
    assert window[3].max() == pytest.approx(0.0, abs=1e-6)  # P(major) is nil everywhere
    assert window[4, centre, centre] == pytest.approx(1.0)  # P(numbers) is one inside the crop


def test_a_window_past_the_crops_edge_is_padded_with_zeros():
    image = np.ones((SIZE, SIZE, 3), np.float32)
    logits = np.zeros((len(CROP_CHANNELS), SIZE // 2, SIZE // 2), np.float32)
    (window,) = notch_windows(image, logits, np.array([[2.0, 2.0]]))
    centre = PATCH // 2
    assert window[:, :centre - 2].max() == 0.0 and window[:, :, :centre - 2].max() == 0.0
    assert window[0, centre:, centre:].min() == 1.0
    assert window[3, centre, centre] == pytest.approx(0.5)


def test_peak_features_measure_each_radius_against_the_median_about_the_pivot():
    peaks = Peaks(np.array([[60.0, 50.0], [50.0, 30.0], [35.0, 50.0]]), np.array([0.9, 0.5, 0.4]))
    pivot = Peaks(np.array([[50.0, 50.0]]), np.array([0.8]))
    features = peak_features(peaks, pivot, 100)
    assert features.shape == (3, 3) and features.dtype == np.float32
    assert features[:, 0].tolist() == pytest.approx([0.9, 0.5, 0.4])
    assert features[:, 1].tolist() == pytest.approx([10 / 15, 20 / 15, 1.0])
    assert features[:, 2].tolist() == pytest.approx([3 / 32] * 3)
    centred = peak_features(peaks, Peaks(np.zeros((0, 2)), np.zeros(0)), 100)  # no pivot: the crop's centre
    assert centred[:, 1].tolist() == pytest.approx([10 / 15, 20 / 15, 1.0])


def test_a_missing_file_or_a_threshold_outside_zero_to_one_is_refused(tmp_path):
    with pytest.raises(ModelNotAvailable, match="notch_check.onnx"):
        NotchCheck(tmp_path / "notch_check.onnx")
    if packaged_model_path(NOTCH_CHECK_MODEL).is_file():
        with pytest.raises(ValueError, match="threshold"):
            NotchCheck(packaged_model_path(NOTCH_CHECK_MODEL), threshold=1.5)


@shipped
def test_a_crop_and_logits_that_do_not_belong_together_are_refused():
    model_input, logits, keypoints, _, _ = _engine_crop(1_000_003)
    check = NotchCheck(packaged_model_path(NOTCH_CHECK_MODEL), threads=1)
    with pytest.raises(ValueError, match="notch check takes"):
        check(model_input[:128, :128], logits, keypoints)
    with pytest.raises(ValueError, match="notch check takes"):
        check(model_input, logits[:6], keypoints)


@functools.cache
def _crop_model() -> OnnxModel:
    return OnnxModel(packaged_model_path(CROP_MODEL), threads=1)


def _engine_crop(seed: int):
    from gauged.synth.crop import render_crop

    crop = _crop_model()
    rendered = render_crop(seed, crop.input_size, masks=False)
    model_input = to_model_input(rendered.image)
    logits = crop(model_input)
    majors = np.asarray([m["point"] for s in rendered.truth["scales"] for m in s["majors"] if m["visible"]], float)
    return model_input, logits, decode_crop_maps(logits, crop.input_size, require_notches=False), majors, crop.input_size


@shipped
@pytest.mark.parametrize("threshold", [0.0, 1.0])
def test_the_threshold_keeps_every_peak_or_none(threshold):
    model_input, logits, keypoints, _, _ = _engine_crop(1_000_003)
    checked = NotchCheck(packaged_model_path(NOTCH_CHECK_MODEL), threads=1, threshold=threshold)(model_input, logits, keypoints)
    assert len(checked.major) == (len(keypoints.major) if threshold == 0.0 else 0)
    assert np.all(np.diff(checked.major.scores) <= 0)  # best first
    assert checked.start is keypoints.start and checked.needle_prob is keypoints.needle_prob


@shipped
def test_the_check_drops_peaks_off_the_major_notches_and_keeps_those_on_them():
    """Held-out engine crops (the validation seeds): of the peaks on labelled major notches the check
    keeps nearly all, of the others it drops most."""
    check = NotchCheck(packaged_model_path(NOTCH_CHECK_MODEL), threads=1)
    on = [0, 0]
    off = [0, 0]
    for seed in range(1_000_000, 1_000_040):
        model_input, logits, keypoints, majors, size = _engine_crop(seed)
        p = check.probabilities(model_input, logits, keypoints)
        for point, prob in zip(keypoints.major.points.reshape(-1, 2), p):
            gap = np.min(np.linalg.norm(majors - point, axis=1)) if len(majors) else np.inf
            if gap <= 4 * size / 448:
                on[0], on[1] = on[0] + 1, on[1] + int(prob >= check.threshold)
            elif gap > 8 * size / 448:
                off[0], off[1] = off[0] + 1, off[1] + int(prob >= check.threshold)
    assert on[0] > 200 and off[0] > 30
    assert on[1] / on[0] > 0.8
    assert off[1] / off[0] < 0.5
