from __future__ import annotations

import math

import numpy as np

from gauged.evaluation.model_metrics import angle_error_deg, mask_direction, mask_iou, match_points


def test_match_points_one_to_one_within_tolerance():
    labelled = np.array([[10, 10], [50, 50], [90, 90]], float)
    predicted = np.array([[11, 10], [10.5, 10.5], [52, 50], [200, 200]], float)
    match = match_points(predicted, labelled, tol_px=3)
    assert (match.labelled, match.predicted, match.matched, match.unassigned) == (3, 4, 2, 2)
    assert math.isclose(match.recall, 2 / 3)


def test_mask_iou_and_empty_masks():
    a = np.zeros((10, 10), bool); a[2:6, 2:6] = True
    b = np.zeros((10, 10), bool); b[4:8, 2:6] = True
    assert math.isclose(mask_iou(a, b), 8 / 24)
    assert mask_iou(np.zeros((3, 3)), np.zeros((3, 3))) == 1.0


def test_mask_direction_points_away_from_reference():
    mask = np.zeros((64, 64), bool)
    mask[31:33, 32:60] = True  # from the centre to the right
    assert angle_error_deg(mask_direction(mask, (32, 32)), 0.0) < 1.0
    assert angle_error_deg(mask_direction(mask, (63, 32)), math.pi) < 1.0
    assert mask_direction(np.zeros((8, 8), bool), (4, 4)) is None
