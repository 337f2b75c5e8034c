from __future__ import annotations

import math

import numpy as np

from gauged.training.dial_renderer import render_crop, render_scene


def test_render_crop_is_deterministic():
    a_image, a_labels = render_crop(7, 96)
    b_image, b_labels = render_crop(7, 96)
    assert np.array_equal(a_image, b_image) and np.array_equal(a_labels.needle, b_labels.needle)
    assert all(np.array_equal(a_labels.points[k], b_labels.points[k]) for k in a_labels.points)


def test_render_crop_labels_are_consistent():
    for seed in range(8):
        image, labels = render_crop(seed, 128)
        pts = labels.points
        assert image.shape == (128, 128, 3) and labels.needle.shape == (128, 128)
        assert len(pts["major"]) >= 4 and len(pts["start"]) == len(pts["end"]) == 1
        assert np.allclose(pts["major"][0], pts["start"][0]) and np.allclose(pts["major"][-1], pts["end"][0])
        # the needle mask runs from the pivot towards the tip
        ys, xs = np.nonzero(labels.needle)
        assert len(xs) > 5
        pivot, tip = pts["pivot"][0], pts["tip"][0]
        axis = (tip - pivot) / np.linalg.norm(tip - pivot)
        along = (np.stack([xs + 0.5, ys + 0.5], 1) - pivot) @ axis
        assert along.max() > 0.8 * np.linalg.norm(tip - pivot)
        assert labels.min_value <= labels.value <= labels.max_value


def test_render_scene_boxes_lie_in_frame():
    image, boxes = render_scene(3, 320, 180)
    assert image.shape == (180, 320, 3)
    for x0, y0, x1, y1 in boxes:
        assert 0 <= x0 < x1 <= 320 and 0 <= y0 < y1 <= 180 and math.isfinite(x0)
